"""Small linear-algebra kernels shared by the numerical core."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["solve_rows"]

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
