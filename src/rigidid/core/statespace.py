"""From modal parameters to the system matrices ``M^-1 K`` and ``M^-1 C``.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.linalg import solve_rows
from rigidid.errors import IdentificationError, InputError

__all__ = [
    "mac_matrix",
    "modal_from_poles",
    "poles_from_modal",
    "state_matrices",
    "state_matrices_batch",
    "state_matrices_paper",
    "state_matrix",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

SINGULAR_CONDITION = 1e12
"""Condition number of the modal matrix ``V`` of eq. (19) above which the modes count as
not spanning the motion. Two modes with one pole and one shape give about 4e16; the
bundled samples give 3-6, and 200 random bodies with 0.1 % damping (pairs down to 0.4 %
apart) at most 28."""


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

    Examples
    --------
    >>> lam = poles_from_modal([10.0], [0.05])
    >>> [round(float(x), 6) for x in modal_from_poles(lam)[0]], float(modal_from_poles(lam)[1][0])
    ([10.0], 0.05)
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
    obtained with one linear solve (:func:`state_matrices_batch`).

    Examples
    --------
    One undamped mode at 1 rad/s: ``M^-1 K = 1``, ``M^-1 C = 0``.

    >>> k, c = state_matrices([1j], [[1.0]])
    >>> round(float(k[0, 0]), 12), abs(round(float(c[0, 0]), 12))
    (1.0, 0.0)
    """
    lam = np.asarray(poles, dtype=complex).ravel()
    phi = np.asarray(shapes, dtype=complex)
    _check_square(lam, phi)
    q, p, ok = state_matrices_batch(lam[None], phi[None])
    if not ok[0]:
        raise IdentificationError("the modes do not span the rigid-body motion (singular modal matrix)")
    return q[0], p[0]


def state_matrices_batch(poles: CArray, shapes: CArray) -> tuple[Array, Array, NDArray[np.bool_]]:
    """Eq. (19) of [1] for a stack of tests; see :func:`state_matrices`.

    Parameters
    ----------
    poles : ndarray of complex, shape (B, n)
    shapes : ndarray of complex, shape (B, n, n)

    Returns
    -------
    stiffness, damping : ndarray, shape (B, n, n)
        ``M^-1 K`` and ``M^-1 C`` of each test (NaN where it failed).
    ok : ndarray of bool, shape (B,)
        False where ``V`` is singular (condition above
        :data:`SINGULAR_CONDITION`) or the result not finite.
    """
    n = poles.shape[-1]
    mu = np.concatenate([poles, poles.conj()], axis=-1)
    ell = np.concatenate([shapes, shapes.conj()], axis=-1)
    v = np.concatenate([ell * mu[:, None, :], ell], axis=-2)
    # A = V diag(mu) V^-1  <=>  A^T = V^-T (V diag(mu))^T
    a_t, ok = solve_rows(np.swapaxes(v, -1, -2), np.swapaxes(v * mu[:, None, :], -1, -2))
    a = np.swapaxes(a_t, -1, -2).real
    ok &= np.all(np.isfinite(a), axis=(-1, -2))
    with np.errstate(divide="ignore", invalid="ignore"):
        ok &= np.linalg.cond(v) < SINGULAR_CONDITION
    return np.ascontiguousarray(-a[:, :n, n:]), np.ascontiguousarray(-a[:, :n, :n]), ok


def state_matrix(mass: ArrayLike, stiffness: ArrayLike, damping: ArrayLike) -> Array:
    """First-order state matrix ``[[-M^-1 C, -M^-1 K], [I, 0]]`` of eq. (1) of [1].

    Parameters
    ----------
    mass, stiffness, damping : array_like, shape (n, n)
        ``M`` (regular), ``K`` and ``C`` in the same coordinates.

    Returns
    -------
    ndarray, shape (2 n, 2 n)
        Its eigenvalues are the poles; the lower half of an eigenvector is the
        mode shape, the upper half the pole times it.

    Raises
    ------
    numpy.linalg.LinAlgError
        If ``M`` is singular.

    Examples
    --------
    >>> state_matrix([[2.0]], [[8.0]], [[0.0]]).tolist()
    [[-0.0, -4.0], [1.0, 0.0]]
    """
    m = np.asarray(mass, dtype=float)
    n = m.shape[0]
    rhs = np.hstack([np.asarray(damping, dtype=float), np.asarray(stiffness, dtype=float)])
    return np.vstack([-np.linalg.solve(m, rhs), np.hstack([np.eye(n), np.zeros((n, n))])])


def mac_matrix(a: CArray, b: CArray) -> Array:
    """Modal assurance criterion between the columns of two shape matrices.

    Parameters
    ----------
    a : ndarray of complex, shape (r, k)
    b : ndarray of complex, shape (r, l)

    Returns
    -------
    ndarray, shape (k, l)
        ``|a_i^H b_j|^2 / (|a_i|^2 |b_j|^2)``, in ``[0, 1]`` (0 for a zero shape).

    Examples
    --------
    >>> mac_matrix(np.array([[1.0], [1j]]), np.array([[2.0], [2j]])).round(12).tolist()
    [[1.0]]
    """
    num = np.abs(a.conj().T @ b) ** 2
    den = np.outer(np.sum(np.abs(a) ** 2, axis=0), np.sum(np.abs(b) ** 2, axis=0))
    result: Array = np.divide(num, den, out=np.zeros_like(num), where=den > 0.0)
    return result


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
