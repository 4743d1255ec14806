"""DC offsets and linear drift of impact records: measured, judged and taken out.

An accelerometer's chain adds a constant offset (bias of the amplifier, the sensor's
zero) and a slow drift (temperature, the discharge of an AC coupling) to every
channel. Both are nuisance terms of the free decays of eq. (19) of [1]: a pole at
zero frequency (a double one for the drift), which is not a mode of the body but
keeps a record from decaying. The acceleration of a body that starts and ends at
rest integrates to zero (its velocity returns to zero) and so does its first moment
(the displacement returns to zero), so over a whole record that has decayed the line
fitted by least squares to a channel is its offset and drift, not its motion.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["TAIL_GAIN", "TREND_RATIO", "Trend", "fit_trend", "remove_trend", "trend_matters"]

Array = NDArray[np.float64]

TREND_RATIO = 1.0
"""A trend matters when its largest value over the record exceeds this many times the RMS
of the last 10 % of the detrended channel (about the noise level once the record has
decayed): a clean record's fitted line is about ``2 / sqrt(n)`` of the noise."""

TAIL_GAIN = 2.0
"""Taking a trend out must divide the RMS of the record's last 10 % by at least this."""

_BLOCK = 1 << 16  # rows per block of the sums


@dataclass(frozen=True)
class Trend:
    """Per channel, ``offset + slope k`` at row ``k`` of a record.

    Attributes
    ----------
    offset : ndarray, shape (p,)
        Value at row 0 (the record's units).
    slope : ndarray, shape (p,)
        Change per row.
    """

    offset: Array
    slope: Array

    def values(self, first: int, n: int) -> Array:
        """The trend at rows ``first .. first + n - 1``, shape (n, p)."""
        k = np.arange(first, first + n, dtype=float)[:, None]
        out: Array = self.offset[None, :] + k * self.slope[None, :]
        return out

    def rescaled(self, origin: int, step: int) -> Trend:
        """This trend of a decimated record (row ``k`` is raw row ``origin + k step``) in raw rows."""
        slope = self.slope / step
        return Trend(self.offset - slope * origin, slope)


def fit_trend(data: Array) -> Trend:
    """The least-squares line through each channel of a record.

    Parameters
    ----------
    data : ndarray, shape (n, p)
        Samples by channels.

    Returns
    -------
    Trend
        Offset and slope per channel (sums over row blocks: no temporary the
        size of the record).
    """
    n, p = data.shape
    if n < 2:
        return Trend(np.mean(data, axis=0) if n else np.zeros(p), np.zeros(p))
    sy, sky = np.zeros(p), np.zeros(p)
    for lo in range(0, n, _BLOCK):
        block = data[lo : lo + _BLOCK]
        k = np.arange(lo, lo + block.shape[0], dtype=float) - 0.5 * (n - 1)  # centred rows
        sy += block.sum(axis=0)
        sky += k @ block
    skk = n * (n * n - 1) / 12.0  # sum of the centred rows' squares
    slope = sky / skk
    offset = sy / n - slope * 0.5 * (n - 1)
    return Trend(offset, slope)


def remove_trend(data: Array, trend: Trend, first: int = 0) -> Array:
    """`data` (rows ``first ...`` of the record `trend` was fitted to) less the trend, a new array."""
    out = np.array(data, dtype=float, copy=True)
    for lo in range(0, out.shape[0], _BLOCK):
        block = out[lo : lo + _BLOCK]
        block -= trend.values(first + lo, block.shape[0])
    return out


def trend_matters(raw: Array, detrended: Array, trend: Trend) -> NDArray[np.bool_]:
    """Per channel, whether the trend stands out of the noise and explains the record's tail.

    Parameters
    ----------
    raw : ndarray, shape (n, p)
        The record.
    detrended : ndarray, shape (n, p)
        The record less `trend` (:func:`remove_trend`).
    trend : Trend
        The record's trend (:func:`fit_trend`).

    Returns
    -------
    ndarray of bool, shape (p,)
        True where the trend's largest value exceeds :data:`TREND_RATIO` times the RMS
        of the last 10 % of the detrended channel, and taking it out divides that RMS
        by at least :data:`TAIL_GAIN` (the tail is the trend: a record cut before it has
        decayed, whose line is its motion, keeps its samples).
    """
    n = detrended.shape[0]
    k = n - max(2, n // 10)
    peak = np.max(np.abs(raw), axis=0) if n else np.ones(raw.shape[1])
    unit = np.where(peak > 0.0, peak, 1.0)  # per channel: squares of records of 1e300 or 1e-300 stay finite
    rms = np.sqrt(np.mean((detrended[k:] / unit) ** 2, axis=0))
    before = np.sqrt(np.mean((raw[k:] / unit) ** 2, axis=0))
    largest = np.maximum(np.abs(trend.offset), np.abs(trend.offset + trend.slope * (n - 1))) / unit
    result: NDArray[np.bool_] = (largest > TREND_RATIO * rms) & (before > TAIL_GAIN * rms)
    return result
