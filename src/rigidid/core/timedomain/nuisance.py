"""Modes that are not rigid-body modes, taken out of the records before the output-error refit.

The refit (:mod:`rigidid.core.timedomain.refine`) models the six rigid-body modes of eq. (19)
of [1] only. An elastic mode in the band (a mode of the estimate that :func:`rigidid.api.identification`
did not use) is free decay too, which the refit cannot explain: its normalised cost then rises
far above 1 and the refit is rejected. :func:`subtract_modes` fits every estimated mode's free
decay to each record by linear least squares (poles fixed at the estimate, one complex
amplitude per mode and channel, one offset per channel) and subtracts the part of the unused
modes, so the refit sees rigid-body motion and noise.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["subtract_modes"]

Array = NDArray[np.float64]

#: Rows per block of the normal equations (bounds the memory of the design to a few MB).
BLOCK_ROWS = 65536


def _design(t: Array, poles: NDArray[np.complex128]) -> Array:
    """``[Re e^{lambda t}, -Im e^{lambda t}, 1]``: shape (n, 2 m + 1)."""
    e = np.exp(np.outer(t, poles))
    return np.hstack([e.real, -e.imag, np.ones((t.size, 1))])


def subtract_modes(
    records: Sequence[ArrayLike],
    dt: float,
    starts: Sequence[int],
    poles: ArrayLike,
    remove: ArrayLike,
) -> list[Array]:
    """The records with the free decay of the modes in `remove` subtracted.

    Parameters
    ----------
    records : sequence of array_like, shape (n_k, p)
        Samples by channels, one record per impact.
    dt : float
        Sample interval (s).
    starts : sequence of int
        First sample of each record's free decay.
    poles : array_like of complex, shape (m,)
        Every mode the records hold (rad/s, ``Im > 0``), e.g. the modal estimate's.
    remove : array_like of bool, shape (m,)
        The modes to take out.

    Returns
    -------
    list of ndarray, shape (n_k, p)
        Copies of the records; from each start on, the least-squares free decay
        ``Re(a_ck exp(lambda_k t))`` of the removed modes is subtracted (before
        the start, nothing changes).

    Notes
    -----
    Per record, all ``m`` modes and an offset are fitted together (``2 m + 1``
    real unknowns per channel, normal equations accumulated in blocks of
    :data:`BLOCK_ROWS` rows, columns scaled to unit norm), so a removed mode does
    not absorb the kept modes' motion. The poles are not refitted: an error
    ``delta`` in a removed pole leaves a residual of about ``delta t`` times its
    amplitude, small beside the noise when the pole comes from the same records.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(2000) / 200.0
    >>> lam = np.array([-0.5 + 2j * np.pi * 3.0, -0.8 + 2j * np.pi * 11.0])
    >>> y = np.column_stack([np.exp(lam[0] * t).real + 0.3 * np.exp(lam[1] * t).imag] * 2)
    >>> out = subtract_modes([y], 1 / 200.0, [0], lam, [False, True])[0]
    >>> bool(np.allclose(out, np.exp(lam[0] * t).real[:, None]))
    True
    """
    lam = np.asarray(poles, dtype=complex).ravel()
    drop = np.asarray(remove, dtype=bool).ravel()
    if drop.shape != lam.shape:
        raise ValueError(f"remove has {drop.size} entries for {lam.size} poles")
    m = lam.size
    cols = np.concatenate([drop, drop, [False]])
    out: list[Array] = []
    for rec, start in zip(records, starts, strict=True):
        y = np.array(rec, dtype=float, copy=True)
        if not drop.any() or y.shape[0] - start < 2 * m + 1:
            out.append(y)
            continue
        n = y.shape[0] - start
        gram = np.zeros((2 * m + 1, 2 * m + 1))
        rhs = np.zeros((2 * m + 1, y.shape[1]))
        for a in range(0, n, BLOCK_ROWS):
            d = _design(np.arange(a, min(a + BLOCK_ROWS, n)) * dt, lam)
            gram += d.T @ d
            rhs += d.T @ y[start + a : start + a + d.shape[0]]
        scale = np.sqrt(np.diag(gram))
        scale = np.where(scale > 0.0, scale, 1.0)
        coef = np.linalg.lstsq(gram / np.outer(scale, scale), rhs / scale[:, None], rcond=None)[0]
        coef = coef / scale[:, None]
        for a in range(0, n, BLOCK_ROWS):
            d = _design(np.arange(a, min(a + BLOCK_ROWS, n)) * dt, lam)
            y[start + a : start + a + d.shape[0]] -= d[:, cols] @ coef[cols]
        out.append(y)
    return out
