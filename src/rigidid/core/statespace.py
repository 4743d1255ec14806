"""From modal parameters to the system matrices ``M^-1 K`` and ``M^-1 C``.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.errors import IdentificationError, InputError

__all__ = [
    "modal_from_poles",
    "poles_from_modal",
    "state_matrices",
    "state_matrices_paper",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]


def poles_from_modal(frequency_hz: ArrayLike, damping_ratio: ArrayLike) -> CArray:
    """Poles with positive imaginary part from natural frequency and damping ratio.

    Parameters
    ----------
    frequency_hz : array_like, shape (n,)
        Undamped natural frequencies ``|lambda| / (2 pi)`` (Hz), positive.
    damping_ratio : array_like, shape (n,)
        ``-Re(lambda) / |lambda|``, in ``[0, 1)``.

    Returns
    -------
    ndarray of complex, shape (n,)
        ``lambda = omega (-zeta + i sqrt(1 - zeta^2))`` in rad/s.

    Raises
    ------
    InputError
        For a non-positive frequency or a damping ratio outside ``[0, 1)``
        (over-damped modes have no oscillating pair and are not supported).
    """
    f = np.asarray(frequency_hz, dtype=float)
    z = np.asarray(damping_ratio, dtype=float)
    if np.any(~np.isfinite(f) | (f <= 0.0)):
        raise InputError("natural frequencies must be positive and finite")
    if np.any(~np.isfinite(z) | (z < 0.0) | (z >= 1.0)):
        raise InputError("damping ratios must lie in [0, 1)")
    w = 2.0 * np.pi * f
    result: CArray = w * (-z + 1j * np.sqrt(1.0 - z * z))
    return result


def modal_from_poles(poles: ArrayLike) -> tuple[Array, Array]:
    """Natural frequency (Hz) and damping ratio of poles (rad/s); inverse of :func:`poles_from_modal`.

    Parameters
    ----------
    poles : array_like of complex, shape (n,)
        Poles ``lambda`` (rad/s).

    Returns
    -------
    frequency_hz, damping_ratio : ndarray, shape (n,)
    """
    lam = np.asarray(poles, dtype=complex)
    w = np.abs(lam)
    return w / (2.0 * np.pi), -lam.real / w


def _check_square(poles: CArray, shapes: CArray) -> None:
    n = poles.shape[0]
    if shapes.shape != (n, n):
        raise InputError(f"need as many modes as coordinates; got shapes {shapes.shape} and {n} poles")


def state_matrices(poles: ArrayLike, shapes: ArrayLike) -> tuple[Array, Array]:
    """Exact ``M^-1 K`` and ``M^-1 C`` from complex modes and their conjugates, eq. (19) of [1].

    Parameters
    ----------
    poles : array_like of complex, shape (n,)
        One pole of each conjugate pair (rad/s), ``Im > 0``.
    shapes : array_like of complex, shape (n, n)
        Column ``k`` is the mode shape of pole ``k`` in the ``n`` generalised
        coordinates (any complex scaling per mode).

    Returns
    -------
    stiffness, damping : ndarray, shape (n, n)
        ``M^-1 K`` and ``M^-1 C``: the state matrix
        ``[[-M^-1 C, -M^-1 K], [I, 0]] = V diag(mu) V^-1`` with
        ``V = [L mu; L]`` over the ``2n`` modes (each mode and its conjugate).

    Raises
    ------
    IdentificationError
        If ``V`` is singular (repeated poles with parallel shapes, a zero shape).

    Notes
    -----
    Exact for non-proportional damping, unlike eqs. (23)-(26), and invariant to
    the scaling of each mode shape. ``V^-1`` is never formed: the product is
    obtained with one linear solve.
    """
    lam = np.asarray(poles, dtype=complex).ravel()
    phi = np.asarray(shapes, dtype=complex)
    _check_square(lam, phi)
    n = lam.shape[0]
    mu = np.concatenate([lam, lam.conj()])
    ell = np.hstack([phi, phi.conj()])
    v = np.vstack([ell * mu, ell])
    # A = V diag(mu) V^-1  <=>  A^T = V^-T (V diag(mu))^T
    try:
        a_t = np.linalg.solve(v.T, (v * mu).T)
    except np.linalg.LinAlgError as exc:
        raise IdentificationError("the modes do not span the rigid-body motion (singular modal matrix)") from exc
    a = a_t.T.real
    return -a[:n, n:].copy(), -a[:n, :n].copy()


def state_matrices_paper(poles: ArrayLike, shapes: ArrayLike) -> tuple[Array, Array]:
    """``M^-1 K`` and ``M^-1 C`` by the paper's shortcut, eqs. (25) and (26) of [1].

    Parameters
    ----------
    poles : array_like of complex, shape (n,)
        One pole of each conjugate pair (rad/s).
    shapes : array_like of complex, shape (n, n)
        Mode shapes in the generalised coordinates, one column per pole.

    Returns
    -------
    stiffness, damping : ndarray, shape (n, n)
        ``X conj(X)`` and ``-2 Re(X)`` with ``X = L1 mu1 L1^-1``.

    Notes
    -----
    Exact only when ``X`` and its conjugate commute (proportional damping, real
    shapes). With a few per cent of non-proportional damping ``M^-1 C`` can be
    off by tens of per cent. Kept so that results can be compared with the paper.
    """
    lam = np.asarray(poles, dtype=complex).ravel()
    phi = np.asarray(shapes, dtype=complex)
    _check_square(lam, phi)
    try:
        x = np.linalg.solve(phi.T, (phi * lam).T).T
    except np.linalg.LinAlgError as exc:
        raise IdentificationError("the modes do not span the rigid-body motion (singular modal matrix)") from exc
    return (x @ x.conj()).real, -2.0 * x.real
