"""The report's summed spectrum of record files, read in row blocks (``report --records`` on long records).

:func:`summed_spectrum_streamed` gives what :func:`rigidid.core.spectrum.summed_spectrum`
gives on the whole records (Welch's average: periodic Hann window, segments of
``segment`` rows overlapping by half, each segment's mean removed, one-sided density),
holding one block of rows and one spectrum per channel.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from rigidid.progress import ProgressCallback

__all__ = ["summed_spectrum_streamed"]

Array = NDArray[np.float64]


def _record_power(path: Path, wanted: list[str], n: int, window: Array, progress: ProgressCallback | None) -> Array:
    """Sum over channels of the mean of ``|rfft((x_s - mean) w)|^2`` over every Welch segment of one file."""
    from rigidid.core.timedomain.preprocess import segment_power
    from rigidid.io.records.streamed import open_source

    step = n - n // 2
    source = open_source(path, wanted, progress)
    power = np.zeros((n // 2 + 1, len(wanted)))
    count = 0
    buffer = np.empty((0, len(wanted)))
    base = 0  # file row of buffer[0]
    following = 0  # file row of the next segment's start
    for _, values in source.blocks:
        part = np.concatenate([buffer, values]) if buffer.shape[0] else values
        last = base + part.shape[0] - n  # the last start whose segment is complete
        if last >= following:
            starts = np.arange(following, last + 1, step, dtype=np.intp)
            power += segment_power(np.array(part, dtype=float), starts - base, window)
            count += starts.size
            following = int(starts[-1]) + step
        keep = max(0, following - base)
        buffer = np.array(part[keep:], dtype=float)
        base += keep
    if count == 0:
        raise ValueError(f"{path.name}: shorter than one segment of {n} rows")
    return np.asarray(power.sum(axis=1) / count)


def summed_spectrum_streamed(
    paths: Sequence[str | os.PathLike[str]],
    sensor_ids: Sequence[str],
    dt: float,
    *,
    segment: int = 4096,
    progress: ProgressCallback | None = None,
) -> tuple[Array, Array]:
    """:func:`rigidid.core.spectrum.summed_spectrum` of record files, read in row blocks.

    Parameters
    ----------
    paths : sequence of path-like
        One record file per impact (checked already: this pass does not check them).
    sensor_ids : sequence of str
        The layout's sensor ids.
    dt : float
        The files' sample interval (s).
    segment : int
        Welch segment (rows); every record must hold at least one.
    progress : ProgressCallback, optional
        Reading progress.

    Returns
    -------
    frequency_hz : ndarray, shape (segment // 2 + 1,)
    power : ndarray, shape (segment // 2 + 1,)
        Summed one-sided power spectral density (channel unit squared per Hz).

    Raises
    ------
    ValueError
        A record shorter than `segment` rows (the whole-record routine then
        shortens the segment: read such records whole).
    """
    from rigidid.io.records.read import layout_ids

    n = int(segment)
    k = np.arange(n)
    window = 0.5 - 0.5 * np.cos(2.0 * np.pi * k / n)  # periodic Hann, as scipy.signal.get_window("hann", n)
    total = np.zeros(n // 2 + 1)
    for path in paths:
        total += _record_power(Path(path), layout_ids(sensor_ids, str(path)), n, window, progress)
    density = total / ((1.0 / dt) * float(np.sum(window * window)))
    density[1 : (n + 1) // 2] *= 2.0  # one-sided: DC (and Nyquist for even n) once
    return np.asarray(np.fft.rfftfreq(n, dt), dtype=float), density
