"""Lagged products of free decays: the Gram matrices both estimators start from.

The block Hankel matrix of a record with ``L + 1`` block rows has
``(L + 1) * channels`` rows and about as many columns as the record has
samples. Both the AR fit and the ERA only need its Gram matrix, whose blocks
are lagged products of the record with itself; they are accumulated here from
``L + 1`` matrix products of the record with shifted views of itself, so the
memory used is that of the result, whatever the record length.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ["lagged_gram"]

Array = NDArray[np.float64]


def _edge_outer(a: Array, b: Array) -> Array:
    """Stack of outer products ``a[u] b[u]^T``, shape (len, r, r)."""
    result: Array = a[:, :, None] * b[:, None, :]
    return result


def lagged_gram(records: Sequence[Array], lags: int) -> tuple[Array, int]:
    """Gram matrix of the block Hankel matrix of several records, without forming it.

    Parameters
    ----------
    records : sequence of ndarray, shape (n_k, r)
        Free decays with the same ``r`` channels (any units).
    lags : int
        ``L``: the Hankel matrix has block rows ``0 .. L``.

    Returns
    -------
    gram : ndarray, shape ((L + 1) r, (L + 1) r)
        Block ``(i, j)`` is ``sum_k sum_{t=0}^{n_k - L - 1} y_k[t + i] y_k[t + j]^T``:
        the product ``H H^T`` of the Hankel matrix ``H`` whose column ``t`` is
        ``[y[t]; y[t + 1]; ...; y[t + L]]``, the records side by side.
    columns : int
        Number of Hankel columns summed over the records, ``sum_k (n_k - L)``
        (records shorter than ``L + 1`` samples are skipped).

    Notes
    -----
    For each lag ``d`` the full product ``sum_u y[u + d] y[u]^T`` is one matrix
    product of shifted views (no copy); each block is that product minus at
    most ``L`` outer products at the two ends of the record. Cost
    ``O(n (L + 1) r^2)``, memory ``O((L + 1)^2 r^2)`` besides the records.
    """
    if not records:
        raise ValueError("no records")
    r = records[0].shape[1]
    size = (lags + 1) * r
    gram = np.zeros((size, size))
    columns = 0
    for y in records:
        n = y.shape[0]
        cols = n - lags
        if cols <= 0:
            continue
        columns += cols
        for d in range(lags + 1):
            full = y[d:].T @ y[: n - d]
            m = lags - d
            # head[j] = sum_{u<j} y[u+d] y[u]^T and tail[j] = sum_{u=cols+j}^{n-1-d}, j = 0..m
            head = np.zeros((m + 1, r, r))
            tail = np.zeros((m + 1, r, r))
            if m > 0:
                np.cumsum(_edge_outer(y[d : d + m], y[:m]), axis=0, out=head[1:])
                outer_tail = _edge_outer(y[cols + d : cols + d + m], y[cols : cols + m])
                tail[:m] = np.cumsum(outer_tail[::-1], axis=0)[::-1]
            for j in range(m + 1):
                i = j + d
                block = full - head[j] - tail[j]
                gram[i * r : (i + 1) * r, j * r : (j + 1) * r] += block
                if d:
                    gram[j * r : (j + 1) * r, i * r : (i + 1) * r] += block.T
    return gram, columns
