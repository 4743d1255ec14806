"""The summed power spectrum of impact records: what the stabilisation diagram is drawn over."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["summed_spectrum"]

Array = NDArray[np.float64]


def summed_spectrum(records: Sequence[ArrayLike], dt: float, *, segment: int = 4096) -> tuple[Array, Array]:
    """Power spectral density summed over every channel of every record (Welch's average).

    Parameters
    ----------
    records : sequence of array_like, each shape (samples, channels)
        Impact records with one sample interval.
    dt : float
        Sample interval (s).
    segment : int
        Longest segment of Welch's method (samples); shorter records use their
        own length.

    Returns
    -------
    frequency_hz : ndarray, shape (m,)
        From 0 to the Nyquist frequency.
    power : ndarray, shape (m,)
        Sum over channels and records of each channel's one-sided PSD
        (channel unit squared per Hz), mean removed, Hann window, half overlap.

    Notes
    -----
    The sum of the spectra peaks at every mode that any channel sees in any
    record, which is what the stabilisation diagram's poles should line up with.
    The average is :func:`rigidid.core.timedomain.streaming.record_power` over each
    whole record (the same numbers as ``scipy.signal.welch(..., detrend="constant")``,
    without importing ``scipy.signal``, about a second of start-up).
    """
    from rigidid.core.timedomain.streaming import hann_window, power_density, record_power

    if not records or not dt > 0.0:
        raise ValueError("need at least one record and a positive sample interval")
    arrays = [np.atleast_2d(np.asarray(r, dtype=float).T).T for r in records]
    n = min(segment, *(a.shape[0] for a in arrays))
    window = hann_window(n)
    total = np.zeros(n // 2 + 1)
    for a in arrays:
        total += record_power([a], a.shape[1], window)
    return power_density(total, window, dt)
