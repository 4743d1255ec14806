"""Small linear-algebra kernels shared by the numerical core, and its one rank tolerance.

Every rank decision (is a layout, a mount design or an information matrix singular?)
and every pseudo-inverse (the covariance of a fit whose information matrix is
singular in some direction) counts a singular value as zero when it is below
``1000 max(n, 6) eps s_max``, ``n`` the larger dimension of the matrix: a thousand
times LAPACK's usual tolerance, so that matrices singular in exact arithmetic count
as singular after the rounding of their inputs (coordinates written to a few
digits, FRFs and modes estimated from data).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["numerical_rank", "pseudo_inverse", "rank_tolerance", "solve_rows", "svd"]

Array = NDArray[np.float64]
BArray = NDArray[np.bool_]


def solve_rows(a: NDArray[Any], b: NDArray[Any]) -> tuple[NDArray[Any], BArray]:
    """Stacked ``solve(a[i], b[i])`` that survives singular rows.

    Parameters
    ----------
    a : ndarray, shape (B, n, n)
        Square matrices.
    b : ndarray, shape (B, n, k)
        Right-hand sides.

    Returns
    -------
    x : ndarray, shape (B, n, k)
        Solutions; NaN in the rows whose matrix is singular.
    ok : ndarray of bool, shape (B,)
        False for those rows.

    Examples
    --------
    >>> a = np.stack([np.eye(2), np.zeros((2, 2))])
    >>> x, ok = solve_rows(a, np.ones((2, 2, 1)))
    >>> ok.tolist(), x[0, :, 0].tolist()
    ([True, False], [1.0, 1.0])
    """
    ok = np.ones(a.shape[0], dtype=bool)
    try:
        x: NDArray[Any] = np.linalg.solve(a, b)
        return x, ok
    except np.linalg.LinAlgError:
        out = np.full(b.shape, np.nan, dtype=np.result_type(a, b))
        for i in range(a.shape[0]):
            try:
                out[i] = np.linalg.solve(a[i], b[i])
            except np.linalg.LinAlgError:
                ok[i] = False
        return out, ok


_FACTOR = 1e3
"""How many times LAPACK's usual tolerance (``max(n) eps s_max``) the cut lies above it."""


def rank_tolerance(largest: ArrayLike, rows: int) -> NDArray[np.float64]:
    """The singular value below which a matrix with ``rows`` rows counts as rank deficient.

    Parameters
    ----------
    largest : array_like, shape (...)
        The largest singular value of each matrix.
    rows : int
        The larger dimension of the matrices (at least 6 is used).

    Returns
    -------
    ndarray, shape (...)
        ``1000 max(rows, 6) eps largest``.

    Examples
    --------
    >>> float(rank_tolerance(1.0, 6)) < 2e-12
    True
    """
    tol: NDArray[np.float64] = _FACTOR * max(int(rows), 6) * np.finfo(float).eps * np.asarray(largest, dtype=float)
    return tol


def numerical_rank(singular_values: ArrayLike, rows: int) -> NDArray[np.intp]:
    """Numerical rank of stacked matrices from their singular values.

    Parameters
    ----------
    singular_values : array_like, shape (..., k)
        Singular values of ``(..., rows, k)`` matrices, descending.
    rows : int
        Number of rows of each matrix.

    Returns
    -------
    ndarray of int, shape (...)
        How many singular values exceed :func:`rank_tolerance` of the largest.

    Examples
    --------
    >>> int(numerical_rank([3.0, 1.0, 1e-17], 6))
    2
    """
    s = np.asarray(singular_values, dtype=float)
    top = s[..., :1] if s.shape[-1] else np.zeros((*s.shape[:-1], 1))
    rank: NDArray[np.intp] = np.sum(s > rank_tolerance(top, rows), axis=-1)
    return rank


def pseudo_inverse(matrix: ArrayLike, *, symmetric: bool = False) -> tuple[Array, int]:
    """Moore-Penrose pseudo-inverse cut at the one rank tolerance, and the rank kept.

    Parameters
    ----------
    matrix : array_like, shape (m, n)
        The matrix; an information matrix ``J^T J`` or a covariance when `symmetric`.
    symmetric : bool, optional
        The matrix is symmetric positive semi-definite: its eigen-decomposition is
        used (negative eigenvalues of rounding count as zero).

    Returns
    -------
    inverse : ndarray, shape (n, m)
        ``V diag(1/s) U^T`` over the singular values above :func:`rank_tolerance`.
    rank : int
        How many singular values were kept.

    Examples
    --------
    >>> inv, rank = pseudo_inverse([[2.0, 0.0], [0.0, 0.0]], symmetric=True)
    >>> rank, float(inv[0, 0]), float(inv[1, 1])
    (1, 0.5, 0.0)
    """
    a = np.asarray(matrix, dtype=float)
    rows = max(a.shape) if a.size else 0
    if a.size == 0:
        return np.zeros(a.shape[::-1]), 0
    if symmetric:
        w, v = np.linalg.eigh(0.5 * (a + a.T))
        keep = w > rank_tolerance(max(float(w[-1]), 0.0), rows)
        inverse: Array = (v[:, keep] / w[keep]) @ v[:, keep].T
        return inverse, int(np.sum(keep))
    u, s, vt = svd(a, full_matrices=False)
    keep = s > rank_tolerance(s[0], rows)
    inverse = (vt[keep].T / s[keep]) @ u[:, keep].T
    return inverse, int(np.sum(keep))


def svd(matrix: ArrayLike, full_matrices: bool = True) -> tuple[Array, Array, Array]:
    """``U, s, V^T`` of a real matrix, by LAPACK's divide and conquer, else its QR iteration.

    numpy's ``svd`` (``gesdd``) can fail to converge on a matrix with singular values down at the
    rounding floor (an R factor of exactly dependent columns: the sensors' errors the records do not
    determine, chain_matrix's "all" cell seed 1005), where ``gesvd`` converges; it is tried then.

    Parameters
    ----------
    matrix : array_like, shape (n, m)
    full_matrices : bool
        As numpy's.

    Returns
    -------
    u : ndarray, shape (n, n) or (n, k)
    s : ndarray, shape (k,)
        Descending.
    vt : ndarray, shape (m, m) or (k, m)
    """
    a = np.asarray(matrix, dtype=float)
    try:
        u, s, vt = np.linalg.svd(a, full_matrices=full_matrices)
    except np.linalg.LinAlgError:
        from scipy.linalg import svd as qr_iteration

        u, s, vt = qr_iteration(a, full_matrices=full_matrices, lapack_driver="gesvd")
    return u, s, vt
