"""Impact records read block by block and decimated as they arrive: memory bounded by the result.

:func:`read_record_streamed` is :func:`rigidid.io.records.read_record` for the
modal estimation: it runs the same checks (columns, numbers, finite, uniform
time, no dead channel, decay) block by block while it reads
(:mod:`rigidid.io.records.checks`), and feeds every block to
:class:`~rigidid.core.timedomain.streaming.StreamingDecimation`, so the
full-rate record is never held whole. What it returns is the record decimated
by a *pre-factor* ``q0`` (chosen from the head of the first record, see
:mod:`rigidid.core.timedomain.streaming`); the estimation then chooses its own
factor on that (decimation in two stages, ``q0`` while reading and the rest
after). The choice depends on the first
:data:`~rigidid.core.timedomain.streaming.HEAD_ROWS` rows only, so it is the
same whatever the file's format; shorter records are not pre-decimated (the
same data as :func:`~rigidid.io.records.read_record`). The records of one
estimation share the first record's ``q0``.

Time is checked block by block against the median step of the first block
(:class:`~rigidid.io.records.checks.TimeCheck`). The decay check runs on the
pre-decimated record; its rows are mapped back to the file's lines.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from rigidid.core.timedomain.streaming import (
    CapturedDecay,
    Decimated,
    StreamingDecimation,
    second_factor,
    spectra_content,
)
from rigidid.core.timedomain.trend import Trend
from rigidid.errors import InputError
from rigidid.io.records.checks import MIN_ROWS, TimeCheck, check_decay, layout_ids, take_out_trend
from rigidid.io.records.columns import column as _column
from rigidid.io.records.columns import row as _where
from rigidid.io.records.sources import BlockSource, in_range, open_source
from rigidid.progress import ProgressCallback

__all__ = ["StreamedRecord", "read_record_streamed", "read_records_streamed"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class StreamedRecord:
    """A record after streamed reading and pre-decimation.

    Attributes
    ----------
    data : ndarray, shape (m, sensors)
        The record decimated by `factor`, columns in layout order.
    dt : float
        Sample interval of `data` (s): `factor` times the file's.
    factor : int
        Total decimation factor while reading (1: the record as read).
    offset : int
        Raw row (from 0) of ``data[0]``; row ``k`` of `data` is raw row
        ``offset + k factor``.
    rows : int
        Data rows in the file.
    energy : ndarray, shape (m,)
        ``channel_energy(data)`` (computed once, for the decay check and the impact).
    spectrum : (ndarray, ndarray) or None
        ``content_spectrum`` of the first 2^18 raw samples of the free decay
        (:data:`~rigidid.core.timedomain.streaming.READ_CONTENT_ROWS`; the impact located in the
        first :data:`~rigidid.core.timedomain.streaming.HEAD_ROWS` rows), accumulated while
        reading, at the file's sample rate (the estimation's own spectrum of a whole record
        covers 2^16). None for a record of at most ``HEAD_ROWS``
        rows (read whole, the estimation measures it).
    stages : (int, int)
        The pre-factor and the second stage's factor (1: none; see the
        `cascade` option of :func:`read_record_streamed`); `factor` is their
        product.
    dt_uncertainty : float
        Bound on the error of `dt` from the rounding of the time column as
        written (s, at `dt`'s rate;
        :func:`~rigidid.core.timedomain.stamps.interval_uncertainty`).
    clipped : ndarray of bool or None
        Per channel, whether its peak is a flat top at the raw rate
        (:class:`~rigidid.core.timedomain.clipping.PeakCount`).
    clip_last : ndarray of int or None
        Per channel, the last raw row (from 0) at its peak: a flat top ending before the free decay
        (an overload during the hammer's pulse) leaves the decay unclipped.
    trend : Trend or None
        The DC offset and drift taken out of `data`, in the file's rows
        (:func:`~rigidid.io.records.checks.take_out_trend`); None: none mattered.
    scale_exponent : int
        The values as read were multiplied by ``2**scale_exponent`` (exactly) before anything else:
        0 unless the first block with a nonzero value peaks outside ``[2^-200, 2^200]``, so that
        squares neither overflow nor underflow (records of 1e300 or 1e-300). Every estimate of
        :mod:`rigidid.core.timedomain` is unchanged by a factor common to the records of one test.
    captured : CapturedDecay or None
        The refit's impact and decay, read on the way (the `capture` option of
        :func:`read_record_streamed`); None when not asked, when the head held no impact that
        the whole record proves, or when a trend was taken out (the capture saw the rows with it).
    """

    data: Array
    dt: float
    factor: int
    offset: int
    rows: int
    energy: Array
    spectrum: tuple[Array, Array] | None = None
    stages: tuple[int, int] = (1, 1)
    dt_uncertainty: float = 0.0
    clipped: NDArray[np.bool_] | None = None
    trend: Trend | None = None
    scale_exponent: int = 0
    captured: CapturedDecay | None = None
    clip_last: NDArray[np.int64] | None = None


def read_record_streamed(
    path: str | os.PathLike[str],
    sensor_ids: Sequence[str],
    *,
    factor: int | None = None,
    f_limit: float | None = None,
    progress: ProgressCallback | None = None,
    cascade: bool = False,
    second: int | None = None,
    keep_rows: int | None = None,
    scale_exponent: int | None = None,
    capture: Sequence[int] | None = None,
) -> StreamedRecord:
    """Read one impact record block by block, checking it and decimating it as it arrives.

    Parameters
    ----------
    path : str or path-like
        A CSV or binary record (the formats of :func:`rigidid.io.records.read_record`).
    sensor_ids : sequence of str
        The layout's sensor ids.
    factor : int, optional
        Pre-decimation factor; default: chosen from the head of the record
        (module documentation).
    f_limit : float, optional
        Highest frequency of interest (Hz, the upper edge of the user's band):
        caps the content the pre-factor must keep.
    progress : ProgressCallback, optional
        ``("reading <file name>", bytes or rows done, total)``.
    cascade : bool
        Decimate in a second stage while reading too, by the factor the
        estimation would choose (:func:`~rigidid.core.timedomain.streaming.second_factor`), as
        soon as the content spectrum is complete (2^18 rows of decay): only the
        record at the estimation's rate is then held. Applied only when the
        record is long enough (at least twice the rows the estimation
        requires) and `factor` is not given; ``stages`` says whether it was.
    second : int, optional
        A second-stage factor fixed by the caller (the first record's, for
        the others), applied from the first row.
    keep_rows : int, optional
        An automatic pre-factor leaves at least this many rows of the record
        (of its rows as the file's size tells them): for a caller that
        decimates further by a factor of its own (the refit, which fits the
        decays at the smallest factor its row budget allows).
    scale_exponent : int, optional
        Multiply the values by ``2**scale_exponent`` (another record's, so that the records of one
        test share it); default: chosen from the record (see :class:`StreamedRecord`).
    capture : sequence of int, optional
        Read the refit's impact and decay on the way (``captured``): the rows of the test's
        other records as known before reading
        (:class:`~rigidid.core.timedomain.streaming.StreamingDecimation`'s `capture`).

    Returns
    -------
    StreamedRecord

    Raises
    ------
    InputError
        The errors of :func:`rigidid.io.records.read_record`, naming the file,
        row and column; and a record too short for `factor`.
    """
    src = str(path)
    wanted = layout_ids(sensor_ids, src)
    source = open_source(Path(path), wanted, progress)
    from rigidid.core.timedomain.clipping import PeakCount

    times = TimeCheck(source.line_of, source.time_tokens, src)
    tops = PeakCount(len(wanted))  # each channel's peak, and the samples at it (a flat top: clipped)

    def check(t: Array, values: Array) -> None:
        times.add(t)
        tops.add(values)

    stream = StreamingDecimation(source.rows, len(wanted), factor=factor, f_limit=f_limit,
                                 cascade=cascade, second=second, keep_rows=keep_rows, capture=capture)  # fmt: skip
    blocks, exponent = in_range(source.blocks, scale_exponent)
    stream.run(blocks, check)
    dt = _checked_dt(source, times, tops.peak, wanted, src)
    try:
        done = stream.finish(dt)
    except InputError as exc:
        raise InputError(exc.message, source=src) from None
    data, trend = take_out_trend(done.data, src, wanted)
    if trend is not None:
        from rigidid.core.timedomain.preprocess import channel_energy

        done = replace(done, data=data, energy=channel_energy(data), captured=None)
        trend = trend.rescaled(done.offset, done.factor)
    _check_streamed_decay(done, source.line_of(times.rows), src)
    dt_error = _stamp_uncertainty(source, times) if source.dt is None else 0.0
    return StreamedRecord(
        done.data, dt * done.factor, done.factor, done.offset, times.rows, done.energy, done.spectrum, done.stages,
        dt_error * done.factor, tops.clipped(), trend, exponent, done.captured, tops.last,
    )  # fmt: skip


def _stamp_uncertainty(source: BlockSource, times: TimeCheck) -> float:
    """Bound on the error of the interval from the digits the time column is written with."""
    from rigidid.core.timedomain.stamps import interval_uncertainty, token_resolution

    resolution = min((token_resolution(token) for token in source.time_tokens()), default=0.0)
    return interval_uncertainty(resolution, times.rows, max(abs(times.first), abs(times.last)))


def _checked_dt(source: BlockSource, times: TimeCheck, peaks: Array, wanted: list[str], src: str) -> float:
    """The sample interval once every block is read; raise for too few rows or a channel that reads zero."""
    n = times.rows
    if n < MIN_ROWS:
        last = source.line_of(n)(n - 1) if n else 1
        raise InputError(f"{n} data rows; a record needs at least {MIN_ROWS}", source=src, location=_where(last))
    dt = times.dt() if source.dt is None else float(source.dt)
    for i, name in enumerate(wanted):
        if not peaks[i] > 0.0:
            raise InputError(f"sensor {name!r} reads zero in every row", source=src, location=_column(name))
    return dt


def _check_streamed_decay(done: Decimated, line_of: Callable[[int], int], src: str) -> None:
    """:func:`~rigidid.io.records.checks.check_decay` on the decimated record, its rows named by the file's lines."""
    data, total, offset = done.data, done.factor, done.offset
    check_decay(data, lambda k: line_of(offset + (k if k >= 0 else data.shape[0] + k) * total), src, done.energy)


def read_records_streamed(
    paths: Sequence[str | os.PathLike[str]],
    sensor_ids: Sequence[str],
    factor: int | None = None,
    f_limit: float | None = None,
    progress: ProgressCallback | None = None,
    *,
    cascade: bool = False,
    keep_rows: int | None = None,
    capture: bool = False,
) -> tuple[list[StreamedRecord], tuple[float, float] | None]:
    """The records of one estimation, read with :func:`read_record_streamed` at one rate.

    Parameters
    ----------
    paths : sequence of path-like
        One record per impact.
    sensor_ids : sequence of str
        The layout's sensor ids.
    factor : int, optional
        The user's decimation factor (no second stage then).
    f_limit : float, optional
        Upper edge of the user's band (Hz).
    progress : ProgressCallback, optional
        Reading progress.
    cascade : bool
        Let the first record choose a second stage (``cascade`` of
        :func:`read_record_streamed`); the others take it. When the content
        of all records together asks the estimation for another factor than
        the first record's alone, they are read again without it.
    keep_rows : int, optional
        See :func:`read_record_streamed` (the first record's pre-factor is
        everyone's).
    capture : bool
        Read the refit's impacts and decays on the way (each record's ``captured``).

    Returns
    -------
    records : list of StreamedRecord
        At one total factor.
    content : (float, float) or None
        ``content_range`` of the records' free decays from the spectra measured
        while reading (None: some record too short for it).

    Raises
    ------
    InputError
        As :func:`read_record_streamed`; records of different sample intervals.
    """
    others = _others(paths, sensor_ids) if capture else None
    first = read_record_streamed(paths[0], sensor_ids, factor=factor, f_limit=f_limit, progress=progress,
                                 cascade=cascade and factor is None, keep_rows=keep_rows,
                                 capture=None if others is None else others(0))  # fmt: skip
    q0, q2 = first.stages
    streamed = [first]
    streamed += [read_record_streamed(p, sensor_ids, factor=q0, second=q2, progress=progress,
                                      scale_exponent=first.scale_exponent,
                                      capture=None if others is None else others(i + 1))
                 for i, p in enumerate(paths[1:])]  # fmt: skip
    from rigidid.core.timedomain.stamps import common_interval, different_intervals

    total = streamed[0].factor
    dts = [r.dt for r in streamed]
    common, same = common_interval(dts, [r.dt_uncertainty for r in streamed])
    if not same:
        raise InputError(different_intervals([d / total for d in dts], [r.dt_uncertainty / total for r in streamed]),
                         source="records")  # fmt: skip
    streamed = [r if r.dt == common else replace(r, dt=common) for r in streamed]
    dts = [common] * len(streamed)
    content = spectra_content([r.spectrum for r in streamed], dts[0] / total)
    if q2 > 1 and (content is None or second_factor(content[1], dts[0] / total, q0, f_limit) != q2):
        del streamed, first
        return read_records_streamed(paths, sensor_ids, factor, f_limit, progress, cascade=False, keep_rows=keep_rows,
                                     capture=capture)  # fmt: skip
    return streamed, content


def _others(paths: Sequence[str | os.PathLike[str]], sensor_ids: Sequence[str]) -> Callable[[int], list[int]]:
    """``others(i)``: the rows of every record but ``i`` as their headers or sizes tell (a CSV's from its size)."""
    rows = [open_source(Path(p), layout_ids(sensor_ids, str(p)), None).rows for p in paths]
    return lambda i: rows[:i] + rows[i + 1 :]
