"""The report's summed spectrum of record files, read in row blocks (``report --records`` on long records).

:func:`summed_spectrum_streamed` gives what :func:`rigidid.core.spectrum.summed_spectrum`
gives on the whole records (Welch's average: periodic Hann window, segments of
``segment`` rows overlapping by half, each segment's mean removed, one-sided density),
holding one block of rows and one spectrum per channel: the files are opened here
(:func:`~rigidid.io.records.sources.open_source`), the spectra computed by
:func:`rigidid.core.timedomain.streaming.record_power`.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from rigidid.core.timedomain.streaming import hann_window, power_density, record_power
from rigidid.io.records.checks import layout_ids
from rigidid.io.records.sources import open_source, values_of
from rigidid.progress import ProgressCallback

__all__ = ["summed_spectrum_streamed"]

Array = NDArray[np.float64]


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
    n = int(segment)
    window = hann_window(n)
    total = np.zeros(n // 2 + 1)
    for p in paths:
        path = Path(p)
        source = open_source(path, layout_ids(sensor_ids, str(path)), progress)
        try:
            total += record_power(values_of(source), len(sensor_ids), window)
        except ValueError as exc:
            raise ValueError(f"{path.name}: {exc}") from None
    return power_density(total, window, dt)
