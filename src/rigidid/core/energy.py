"""Modal kinetic-energy distribution: the decoupling table of a mount system.

For each rigid-body mode, the table says which fraction of the mode's kinetic
energy lies in each of the six motions of the body at its centre of gravity:
translations ``x, y, z`` and rotations ``rx, ry, rz``. A mode with 95 % of its
energy in ``z`` is a well decoupled bounce mode; an engine-mount engineer reads
the table row by row to see how clean each mode is.

Definition
----------
With the mass matrix per unit mass at the CG, ``M = diag(I3, J / m)``, and a
mode's CG motion ``phi`` (6 complex values), the fraction of DOF ``i`` is::

    e_i = Re(conj(phi_i) (M phi)_i) / (phi^H M phi)

For a real mode this is the classical definition. For a complex
(non-proportionally damped) mode, the motion is ``Re(phi exp(i omega t))``;
its kinetic energy averaged over one cycle of oscillation (the slow decay
``exp(-zeta omega t)`` within the cycle ignored) is ``omega^2 / 4`` times
``phi^H M phi``, and ``e_i`` is DOF ``i``'s share of that average. Each row
sums to 1 and is invariant to the (complex) scaling of the mode.

Off-diagonal entries of ``J / m`` (products of inertia) couple the rotations:
the share of a rotation includes half of its cross terms with the other
rotations and can then be negative. In the principal frame of inertia
(:func:`kinetic_energy_distribution_principal`) ``M`` is diagonal and every
fraction is non-negative.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.identify import principal_axes
from rigidid.errors import InputError

__all__ = [
    "DOF_LABELS",
    "PRINCIPAL_DOF_LABELS",
    "kinetic_energy_distribution",
    "kinetic_energy_distribution_principal",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

DOF_LABELS: tuple[str, ...] = ("x", "y", "z", "rx", "ry", "rz")
"""Column labels of :func:`kinetic_energy_distribution`."""

PRINCIPAL_DOF_LABELS: tuple[str, ...] = ("x", "y", "z", "r1", "r2", "r3")
"""Column labels of :func:`kinetic_energy_distribution_principal` (``r_k``: about principal axis ``k``)."""


def _check(inertia_per_mass: ArrayLike, shapes: ArrayLike) -> tuple[Array, CArray]:
    j = np.asarray(inertia_per_mass, dtype=float)
    phi = np.asarray(shapes, dtype=complex)
    if j.shape != (3, 3):
        raise InputError(f"inertia per mass must be 3x3, got shape {j.shape}")
    if phi.ndim != 2 or phi.shape[0] != 6:
        raise InputError(f"shapes must be (6, modes) CG motions, got shape {phi.shape}")
    if not (np.all(np.isfinite(j)) and np.all(np.isfinite(phi))):
        raise InputError("inertia and shapes must be finite")
    return 0.5 * (j + j.T), phi


def _fractions(mass: Array, phi: CArray) -> Array:
    weighted = mass @ phi
    parts = np.real(np.conj(phi) * weighted)
    total = np.sum(parts, axis=0)
    bad = np.flatnonzero(~(total > 0.0))
    if bad.size:
        raise InputError(
            f"mode {bad[0] + 1} has no positive kinetic energy (zero shape, or inertia not positive definite)"
        )
    result: Array = (parts / total).T
    return result


def kinetic_energy_distribution(inertia_per_mass: ArrayLike, shapes: ArrayLike) -> Array:
    """Fraction of each mode's kinetic energy in x, y, z, rx, ry, rz at the CG.

    Parameters
    ----------
    inertia_per_mass : array_like, shape (3, 3)
        Inertia tensor about the CG divided by mass (length^2), in the same
        axes as `shapes` (symmetrised here).
    shapes : array_like of complex, shape (6, n)
        Column ``k``: motion of the CG in mode ``k``, ``(x, y, z)`` in length
        units and ``(rx, ry, rz)`` in radians (for instance the shapes of
        :meth:`rigidid.core.identify.Identification.model_modes`). Any scaling.

    Returns
    -------
    ndarray, shape (n, 6)
        Row ``k``: fractions of mode ``k``'s (cycle-averaged) kinetic energy,
        columns in the order of :data:`DOF_LABELS`; each row sums to 1.
        Rotational entries may be negative when `inertia_per_mass` has
        products of inertia (see the module notes).

    Raises
    ------
    InputError
        Wrong shapes, non-finite values, or a mode without positive kinetic
        energy (a zero shape, or an inertia that is not positive definite).
    """
    j, phi = _check(inertia_per_mass, shapes)
    mass = np.eye(6)
    mass[3:, 3:] = j
    return _fractions(mass, phi)


def kinetic_energy_distribution_principal(inertia_per_mass: ArrayLike, shapes: ArrayLike) -> Array:
    """Kinetic-energy fractions with the rotations taken about the principal axes.

    Parameters
    ----------
    inertia_per_mass : array_like, shape (3, 3)
        Inertia tensor about the CG divided by mass (length^2).
    shapes : array_like of complex, shape (6, n)
        CG motions as in :func:`kinetic_energy_distribution` (length, rad).

    Returns
    -------
    ndarray, shape (n, 6)
        Row ``k``: fractions of mode ``k``'s kinetic energy, columns
        :data:`PRINCIPAL_DOF_LABELS`: translations along the layout's
        ``x, y, z`` (unchanged), then rotations about principal axes 1, 2, 3
        (ascending principal moments, axes as in
        :func:`rigidid.core.identify.principal_axes`). ``M`` is diagonal in
        these coordinates, so every fraction is non-negative when the inertia
        is positive definite; each row sums to 1.

    Raises
    ------
    InputError
        As :func:`kinetic_energy_distribution`.

    Notes
    -----
    Only the rotational DOFs are rotated, ``theta' = R^T theta`` with ``R``
    the principal axes as columns; translations are already decoupled in
    mass (``M`` is ``I3`` in any axes) and stay in the test's axes. The
    kinetic energy of each mode is the same in both tables; only its split
    between the rotations differs.
    """
    j, phi = _check(inertia_per_mass, shapes)
    moments, axes = principal_axes(j)
    rotated = phi.copy()
    rotated[3:, :] = axes.T @ phi[3:, :]
    return _fractions(np.diag(np.concatenate([np.ones(3), moments])), rotated)
