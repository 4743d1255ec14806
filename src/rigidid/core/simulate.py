"""Forward model: a rigid body on elastic mounts, its modes as sensors see them.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.geometry import sensor_matrix, transfer_matrix
from rigidid.core.statespace import state_matrix
from rigidid.errors import InputError

__all__ = ["Body", "Modes", "Mount", "add_noise", "body_modes", "system_matrices"]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]


def _as_matrix3(value: ArrayLike, what: str) -> Array:
    a = np.asarray(value, dtype=float)
    if a.shape == (3,):
        return np.diag(a)
    if a.shape == (3, 3):
        return a.copy()
    raise InputError(f"{what} must be 3 values (per axis) or a 3x3 matrix, got shape {a.shape}")


@dataclass(frozen=True)
class Mount:
    """A massless elastic support acting at one point.

    Attributes
    ----------
    position : ndarray, shape (3,)
        Where the mount acts on the body (length).
    stiffness : ndarray, shape (3, 3)
        Translational stiffness matrix (mass / s^2), symmetric.
    damping : ndarray, shape (3, 3)
        Viscous damping matrix (mass / s), symmetric.
    """

    position: Array
    stiffness: Array
    damping: Array

    @classmethod
    def from_values(cls, position: ArrayLike, stiffness: ArrayLike, damping: ArrayLike = (0.0, 0.0, 0.0)) -> Mount:
        """Build a mount from per-axis values (3,) or full (3, 3) matrices."""
        return cls(
            np.asarray(position, dtype=float).reshape(3),
            _as_matrix3(stiffness, "mount stiffness"),
            _as_matrix3(damping, "mount damping"),
        )


@dataclass(frozen=True)
class Body:
    """A rigid body on mounts, the truth a test tries to recover.

    Attributes
    ----------
    mass : float
        Mass (mass unit).
    center_of_gravity : ndarray, shape (3,)
        Position of the CG (length).
    inertia_tensor : ndarray, shape (3, 3)
        Inertia tensor about the CG (mass length^2); off-diagonal entries are
        minus the products of inertia.
    mounts : tuple of Mount
        The supports.
    """

    mass: float
    center_of_gravity: Array
    inertia_tensor: Array
    mounts: tuple[Mount, ...]


@dataclass(frozen=True)
class Modes:
    """Modal parameters of the (underdamped) modes of a system.

    Attributes
    ----------
    poles : ndarray of complex, shape (n,)
        One pole per conjugate pair, ``Im > 0`` (rad/s), ascending frequency.
    shapes : ndarray of complex, shape (p, n)
        Column ``k`` is the shape of mode ``k`` at the ``p`` sensors, each value
        as the sensor reads it along its own direction.
    """

    poles: CArray
    shapes: CArray


def system_matrices(body: Body) -> tuple[Array, Array, Array]:
    """Mass, stiffness and damping matrices at the CG, eq. (1) of [1].

    Parameters
    ----------
    body : Body
        The rigid body and its mounts.

    Returns
    -------
    mass, stiffness, damping : ndarray, shape (6, 6)
        ``M_g = diag(m I, J)`` and ``K_g = sum T_k^T k_k T_k`` (likewise
        ``C_g``) with ``T_k = [I, -S(r_k - g)]`` the motion of mount ``k``.
    """
    g = np.asarray(body.center_of_gravity, dtype=float)
    m = np.zeros((6, 6))
    m[:3, :3] = body.mass * np.eye(3)
    m[3:, 3:] = body.inertia_tensor
    k = np.zeros((6, 6))
    c = np.zeros((6, 6))
    for mount in body.mounts:
        t = transfer_matrix(mount.position - g)[:3]
        k += t.T @ mount.stiffness @ t
        c += t.T @ mount.damping @ t
    return m, k, c


def body_modes(body: Body, positions: ArrayLike, directions: ArrayLike) -> Modes:
    """The six rigid-body modes of a body on mounts, as the sensors read them.

    Parameters
    ----------
    body : Body
        Truth: mass, CG, inertia and mounts.
    positions : array_like, shape (p, 3)
        Sensor locations (length).
    directions : array_like, shape (p, 3)
        Unit measuring axes.

    Returns
    -------
    Modes
        Six poles (rad/s, ascending frequency) and shapes ``T_mg phi`` at the
        sensors, each scaled so that its largest value is ``1 + 0j``.

    Raises
    ------
    InputError
        If the system is not positive definite and underdamped (a mode without
        an oscillating pair, or unstable).
    """
    try:
        a = state_matrix(*system_matrices(body))
    except np.linalg.LinAlgError as exc:
        raise InputError("the mass matrix is singular") from exc
    mu, vec = np.linalg.eig(a)
    upper = mu.imag > 1e-9 * np.abs(mu).max()
    if upper.sum() != 6 or np.any(mu.real > 0.0):
        raise InputError("the body on its mounts must have six stable, underdamped modes")
    lam = mu[upper]
    phi = vec[6:, upper]
    order = np.argsort(np.abs(lam))
    lam, phi = lam[order], phi[:, order]
    t = sensor_matrix(positions, directions, body.center_of_gravity)
    psi = t @ phi
    peak = psi[np.argmax(np.abs(psi), axis=0), np.arange(psi.shape[1])]
    return Modes(lam, psi / peak)


def add_noise(
    modes: Modes,
    *,
    frequency: float = 0.0,
    damping: float = 0.0,
    shape: float = 0.0,
    seed: int | None = None,
    rng: np.random.Generator | None = None,
) -> Modes:
    """Perturb modal parameters with Gaussian noise, as a measurement would.

    Parameters
    ----------
    modes : Modes
        Exact modes.
    frequency : float
        Relative standard deviation of each natural frequency (0.001 = 0.1 %).
    damping : float
        Relative standard deviation of each damping ratio.
    shape : float
        Standard deviation of complex Gaussian noise added to each shape value,
        relative to the RMS value of that mode shape (real and imaginary parts
        each get ``shape / sqrt(2)``).
    seed : int, optional
        Seed of the random generator (ignored when `rng` is given).
    rng : numpy.random.Generator, optional
        Generator to draw from.

    Returns
    -------
    Modes
        The perturbed modes (damping ratios clipped to ``[0, 0.999]``).
    """
    from rigidid.core.statespace import modal_from_poles, poles_from_modal

    gen = rng if rng is not None else np.random.default_rng(seed)
    f, z = modal_from_poles(modes.poles)
    n = f.shape[0]
    f = f * (1.0 + frequency * gen.standard_normal(n))
    z = np.clip(z * (1.0 + damping * gen.standard_normal(n)), 0.0, 0.999)
    psi = modes.shapes
    rms = np.sqrt(np.mean(np.abs(psi) ** 2, axis=0))
    noise = (gen.standard_normal(psi.shape) + 1j * gen.standard_normal(psi.shape)) / np.sqrt(2.0)
    return Modes(poles_from_modal(f, z), psi + shape * rms * noise)
