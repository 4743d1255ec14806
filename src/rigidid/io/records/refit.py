"""The refit's data read from record files in row blocks (the second pass of ``identify --records``).

The modal estimate (the first pass, :mod:`rigidid.io.records.streamed`) gives each
impact's onset and free-decay start in the files' rows and its decimation factor.
This pass opens every record file again (:func:`~rigidid.io.records.sources.open_source`)
and hands its blocks to :mod:`rigidid.core.timedomain.streaming`:
:func:`~rigidid.core.timedomain.streaming.locate_impacts` finds the impacts on the
raw rows, :func:`~rigidid.core.timedomain.streaming.prepared_decays` builds what
:func:`rigidid.core.timedomain.refine.prepare_decays` builds from whole records.
Memory: one block of rows plus the decays held, whatever the records' length. The
records were checked by the first pass; this one does not check them again.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Iterator, Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from rigidid.core.timedomain.preprocess import Impact
from rigidid.core.timedomain.refine import PreparedDecays
from rigidid.core.timedomain.streaming import locate_impacts as _locate
from rigidid.core.timedomain.streaming import located_decays, prepared_decays, prepared_from
from rigidid.core.timedomain.trend import Trend
from rigidid.io.records.checks import layout_ids
from rigidid.io.records.sources import in_range, open_source
from rigidid.progress import ProgressCallback

__all__ = ["locate_and_read", "locate_impacts", "read_prepared_decays"]

Array = NDArray[np.float64]


def _opener(
    paths: Sequence[str | os.PathLike[str]],
    sensor_ids: Sequence[str],
    progress: ProgressCallback | None,
    trends: Sequence[Trend | None] | None = None,
) -> Callable[[int], Iterable[Array]]:
    """``records(i)``: the row blocks of file ``i`` (opened when called), scaled by the power of two the first
    file opened chooses (:func:`~rigidid.io.records.sources.in_range`: records of 1e300 or 1e-300), less the
    file's trend when it has one (in the scaled values, as the streamed read found it)."""
    shared: list[int] = []

    def records(i: int) -> Iterable[Array]:
        path = Path(paths[i])
        source = open_source(path, layout_ids(sensor_ids, str(path)), progress)
        blocks, exponent = in_range(source.blocks, shared[0] if shared else None)
        shared[:] = [exponent]
        values = (values for _, values in blocks)
        trend = None if trends is None else trends[i]
        return values if trend is None else _detrended(values, trend)

    return records


def _detrended(blocks: Iterable[Array], trend: Trend) -> Iterator[Array]:
    row = 0
    for values in blocks:
        yield values - trend.values(row, values.shape[0])
        row += values.shape[0]


def locate_impacts(
    paths: Sequence[str | os.PathLike[str]],
    sensor_ids: Sequence[str],
    dt: float,
    near: Sequence[Impact],
    reach: int,
    *,
    progress: ProgressCallback | None = None,
    trends: Sequence[Trend | None] | None = None,
) -> list[Impact] | None:
    """The impacts :func:`~rigidid.core.timedomain.preprocess.find_impact` finds on the raw records, read in row blocks.

    Parameters
    ----------
    paths : sequence of path-like
        One record file per impact.
    sensor_ids : sequence of str
        The layout's sensor ids.
    dt : float
        The files' sample interval (s).
    near : sequence of Impact
        Where the decimated records put each impact (in the files' rows).
    reach : int
        Raw rows the true onset may lie before ``near.onset`` and the true
        decay start after ``near.start`` (the decimation filters' reach).
    progress : ProgressCallback, optional
        Reading progress.
    trends : sequence of Trend or None, optional
        Per file, the DC offset and drift to take out of its rows
        (:attr:`~rigidid.io.records.streamed.StreamedRecord.trend`).

    Returns
    -------
    list of Impact or None
        The raw records' impacts; None when the rows held cannot prove it
        (:func:`rigidid.core.timedomain.streaming.locate_impacts`): the
        caller then reads the records whole.
    """
    if len(paths) != len(near):
        raise ValueError(f"{len(paths)} record files for {len(near)} impacts")
    return _locate(_opener(paths, sensor_ids, progress, trends), len(sensor_ids), dt, near, reach)


def read_prepared_decays(
    paths: Sequence[str | os.PathLike[str]],
    sensor_ids: Sequence[str],
    dt: float,
    *,
    starts: Sequence[int],
    onsets: Sequence[int],
    factor: int,
    progress: ProgressCallback | None = None,
    trends: Sequence[Trend | None] | None = None,
) -> PreparedDecays:
    """:func:`~rigidid.core.timedomain.refine.prepare_decays` of record files, read in row blocks.

    Parameters
    ----------
    paths : sequence of path-like
        One record file per impact (formats of :func:`rigidid.io.records.read_record`).
    sensor_ids : sequence of str
        The layout's sensor ids (columns in this order).
    dt : float
        The files' sample interval (s).
    starts, onsets : sequence of int
        Per file, the impact's free-decay start and onset, in the file's rows (from 0).
    factor : int
        The modal estimate's total decimation factor.
    progress : ProgressCallback, optional
        Reading progress.
    trends : sequence of Trend or None, optional
        As for :func:`locate_impacts`.

    Returns
    -------
    PreparedDecays
        The same as ``prepare_decays(records, dt, starts, onsets, factor)`` on
        the whole records (:func:`rigidid.core.timedomain.streaming.prepared_decays`;
        the fit's factor is taken from the rows each file's header or size tells).

    Raises
    ------
    InputError
        Records too short for the refinement (or for the fit's filter).
    """
    rows = []
    for p in paths:
        path = Path(p)
        rows.append(open_source(path, layout_ids(sensor_ids, str(path)), None).rows)  # a CSV's: from its size
    records = _opener(paths, sensor_ids, progress, trends)
    return prepared_decays(records, rows, len(sensor_ids), dt, starts=starts, onsets=onsets, factor=factor)


def _rows(paths: Sequence[str | os.PathLike[str]], sensor_ids: Sequence[str]) -> list[int]:
    """Each file's rows as its header or size tells (a CSV's estimated from its size)."""
    return [open_source(Path(p), layout_ids(sensor_ids, str(p)), None).rows for p in paths]


def locate_and_read(
    paths: Sequence[str | os.PathLike[str]],
    sensor_ids: Sequence[str],
    dt: float,
    near: Sequence[Impact],
    reach: int,
    *,
    factor: int,
    progress: ProgressCallback | None = None,
    trends: Sequence[Trend | None] | None = None,
) -> tuple[list[Impact], Callable[[], PreparedDecays]] | None:
    """:func:`locate_impacts`, and :func:`read_prepared_decays` in the same read of each file when it can.

    Parameters
    ----------
    paths, sensor_ids, dt, near, reach, progress, trends
        As for :func:`locate_impacts`.
    factor : int
        As for :func:`read_prepared_decays`.

    Returns
    -------
    (list of Impact, callable) or None
        None when :func:`locate_impacts` gives None. Otherwise the impacts and
        ``data()``, :func:`read_prepared_decays`'s answer with them (it raises what
        that raises); the files are read a second time, by ``data()``, only when the
        decays could not be taken on the way
        (:func:`rigidid.core.timedomain.streaming.located_decays`).
    """
    if len(paths) != len(near):
        raise ValueError(f"{len(paths)} record files for {len(near)} impacts")
    rows = _rows(paths, sensor_ids)
    records = _opener(paths, sensor_ids, progress, trends)
    found = located_decays(records, rows, len(sensor_ids), dt, near, reach, factor)
    if found is None:
        return None
    impacts, passes, q = found

    def data() -> PreparedDecays:
        if passes is not None:
            return prepared_from(passes, len(sensor_ids), dt, q)
        starts, onsets = [i.start for i in impacts], [i.onset for i in impacts]
        return prepared_decays(records, rows, len(sensor_ids), dt, starts=starts, onsets=onsets, factor=factor)

    return impacts, data
