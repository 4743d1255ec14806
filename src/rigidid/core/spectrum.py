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
    """
    from scipy.signal import welch

    if not records or not dt > 0.0:
        raise ValueError("need at least one record and a positive sample interval")
    arrays = [np.atleast_2d(np.asarray(r, dtype=float).T).T for r in records]
    n = min(segment, *(a.shape[0] for a in arrays))
    freq: Array | None = None
    total: Array | None = None
    for a in arrays:
        f, p = welch(a, fs=1.0 / dt, nperseg=n, axis=0, detrend="constant")
        summed = np.sum(p, axis=1)
        freq, total = (f, summed) if total is None else (freq, total + summed)
    assert freq is not None and total is not None
    return np.asarray(freq, dtype=float), np.asarray(total, dtype=float)
