"""Clipped (overloaded) channels of impact records: flat tops at the channel's peak.

An accelerometer or an input stage driven beyond its range returns its full-scale
value for as long as the overload lasts: the record's largest magnitude is then
reached by several samples, all equal. The free decay of a body on mounts,
sampled a few tens of times per period, reaches its peak once; two samples at
the same largest magnitude are chance, three are an overload. A clipped
channel misstates the motion of every mode during the overload, biasing the
estimated shapes (issue 22: inertia 15 % off at a clip of 30 % of the peak),
so it is named and left out of the fit rather than absorbed. An overload during
the hammer's pulse only, where the acceleration peaks, leaves the free decay the
fit reads unclipped: the channel is then kept (``starts`` of
:func:`clipped_channels`; a slow recovery of the input stage after it is not seen).

The count is kept block by block (:class:`PeakCount`), so a reader can follow
it while it streams a file at its raw rate.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["CLIP_SAMPLES", "PEAK_TOLERANCE", "PeakCount", "clipped_channels"]

Array = NDArray[np.float64]

CLIP_SAMPLES = 3
"""Samples at a channel's largest magnitude that make it clipped."""

PEAK_TOLERANCE = 1e-9
"""Relative distance from the largest magnitude within which a sample is at it (the
rounding of values written as text)."""


class PeakCount:
    """Each channel's largest magnitude and how many samples reach it, fed block by block.

    Parameters
    ----------
    channels : int
        Columns of the blocks.
    """

    def __init__(self, channels: int) -> None:
        self.peak = np.zeros(channels)
        self.count = np.zeros(channels, dtype=np.int64)
        self.last = np.full(channels, -1, dtype=np.int64)  # the last row (from 0) at the peak
        self.rows = 0

    def add(self, block: ArrayLike) -> None:
        """Take in a block of samples (rows) by channels."""
        x = np.abs(np.asarray(block, dtype=float))
        n = x.shape[0]
        if n == 0:
            return
        top = x.max(axis=0)
        at = x >= top * (1.0 - PEAK_TOLERANCE)
        at_top = at.sum(axis=0)
        last = self.rows + n - 1 - np.argmax(at[::-1], axis=0)
        higher = top > self.peak * (1.0 + PEAK_TOLERANCE)
        same = ~higher & (top >= self.peak * (1.0 - PEAK_TOLERANCE))
        self.count = np.where(higher, at_top, np.where(same, self.count + at_top, self.count))
        self.last = np.where(higher | same, last, self.last)
        self.peak = np.where(higher, top, self.peak)
        self.rows += n

    def clipped(self, after: int = 0) -> NDArray[np.bool_]:
        """Channels whose peak is reached by at least :data:`CLIP_SAMPLES` samples (a zero channel is not),
        the last of them at row `after` or later (a flat top only before `after`: not clipped there)."""
        return (self.count >= CLIP_SAMPLES) & (self.peak > 0.0) & (self.last >= after)


def clipped_channels(records: Sequence[ArrayLike], starts: Sequence[int] | None = None) -> NDArray[np.bool_]:
    """Channels clipped in any of the records.

    Parameters
    ----------
    records : sequence of array_like, shape (n_k, p)
        Samples by channels, one record per impact, at the rate they were
        acquired (decimation smooths flat tops away).
    starts : sequence of int, optional
        Per record, the first row of the free decay: a channel whose flat top
        ends before it (an overload during the hammer's pulse, where the
        acceleration peaks) is not clipped in the decay the fit reads. None: anywhere.

    Returns
    -------
    ndarray of bool, shape (p,)
        True for a channel whose largest magnitude, in some record, is reached
        by :data:`CLIP_SAMPLES` or more samples.

    Notes
    -----
    A channel quantised so coarsely that its peak spans a few codes (a sensor
    far below its range) can be taken for clipped; its signal is then near the
    quantisation noise anyway.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(400) / 400.0
    >>> y = np.exp(-3 * t) * np.sin(2 * np.pi * 9 * t)
    >>> clipped_channels([np.column_stack([y, np.clip(y, -0.6, 0.6)])]).tolist()
    [False, True]
    """
    out: NDArray[np.bool_] | None = None
    for k, record in enumerate(records):
        count = PeakCount(np.asarray(record).shape[1])
        count.add(record)
        mask = count.clipped(0 if starts is None else int(starts[k]))
        out = mask if out is None else out | mask
    return np.zeros(0, dtype=bool) if out is None else out
