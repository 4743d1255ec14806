"""Impact records read chunk by chunk and decimated as they arrive: memory bounded by the result.

:func:`read_record_streamed` is :func:`rigidid.io.records.read_record` for the
modal estimation: it runs the same checks (columns, numbers, finite, uniform
time, no dead channel, decay) block by block while it reads, and feeds every
block to a streaming FIR decimator
(:class:`~rigidid.core.timedomain.preprocess.Decimator`), so the full-rate
record is never held whole. What it returns is the record decimated by a
*pre-factor* ``q0``; the estimation then chooses its own factor on that
(decimation in two stages, ``q0`` while reading and the rest after).

How ``q0`` is chosen, when the caller does not fix it: from the first
:data:`HEAD_ROWS` rows of the first record, the impact is located and the
content range of the decay after it measured, exactly as the estimation does
it on the whole record (:func:`~rigidid.core.timedomain.preprocess.find_impact`,
:func:`~rigidid.core.timedomain.preprocess.content_range`); ``q0`` is
:data:`PRE_SAFETY` times smaller than the factor that content would give
(so the new Nyquist frequency stays 16 times above the highest frequency seen
in the head, not 4), keeps at least :data:`PULSE_SAMPLES` samples per
:data:`PULSE_WIDTH` (the impact is still located to a fraction of its
pulse) and is at most :data:`MAX_PRE_FACTOR`. The choice depends on the
first :data:`HEAD_ROWS` rows only, so it is the same whatever the file's
format. Records of at most :data:`HEAD_ROWS` rows are not pre-decimated
(``q0 = 1``: the same data as :func:`~rigidid.io.records.read_record`). The
records of one estimation share the first record's ``q0``.

Time is checked block by block against the median step of the first block
(:func:`~rigidid.io.records.read_record` takes the median of all steps: the
two differ only on records whose step changes), with the same allowance for
the digits written and the same messages. The decay check runs on the
pre-decimated record; its rows are mapped back to the file's lines.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rigidid.errors import InputError
from rigidid.io.columns import column as _column
from rigidid.io.columns import column_order
from rigidid.io.columns import row as _where
from rigidid.progress import ProgressCallback

READ_CONTENT_ROWS = 1 << 18
"""Rows of free decay the reader's content spectrum covers (2^18; the estimation's own spectrum of a
whole record covers 2^16): the second stage's factor comes from it, and a longer span resolves
the modes' leakage better at high rates (8 x 10^7 rows at 500 kHz: content to 1709 Hz against
1831 Hz, a second stage of 3 against 2, 18 MB held against 27 MB)."""

__all__ = [
    "HEAD_ROWS",
    "MAX_PRE_FACTOR",
    "PRE_SAFETY",
    "PULSE_SAMPLES",
    "PULSE_WIDTH",
    "StreamedRecord",
    "read_record_streamed",
    "read_records_streamed",
    "second_factor",
]

Array = NDArray[np.float64]

HEAD_ROWS = 1 << 16
"""Rows of the first record from which the pre-factor is chosen (held raw until then)."""

MAX_PRE_FACTOR = 64
"""Largest pre-decimation factor."""

PULSE_WIDTH = 0.005
"""The impact pulse width the estimation assumes by default (s)."""

PULSE_SAMPLES = 16
"""The pre-decimated record keeps at least this many samples per :data:`PULSE_WIDTH`."""

PRE_SAFETY = 4
"""The pre-factor is this many times below the factor the head's content allows."""

_BLOCK = 1 << 14


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
        ``content_spectrum`` of the first :data:`READ_CONTENT_ROWS` (2^18) raw samples of the free
        decay (the impact located in the first :data:`HEAD_ROWS` rows), accumulated
        while reading, at the file's sample rate (the estimation's own spectrum of a
        whole record covers 2^16). None for a record of at most :data:`HEAD_ROWS`
        rows (read whole, the estimation measures it).
    stages : (int, int)
        The pre-factor and the second stage's factor (1: none; see the
        `cascade` option of :func:`read_record_streamed`); `factor` is their
        product.
    clipped : ndarray of bool or None
        Per channel, whether its peak is a flat top at the raw rate
        (:class:`~rigidid.core.timedomain.clipping.PeakCount`).
    dt_uncertainty : float
        Bound on the error of `dt` from the rounding of the time column as
        written (s, at `dt`'s rate;
        :func:`~rigidid.core.timedomain.stamps.interval_uncertainty`).
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


class _Source:
    """Blocks of (time, data) with the file's row-to-line map."""

    def __init__(
        self,
        blocks: Iterator[tuple[Array, Array]],
        rows: int,
        line_of: Callable[[int], Callable[[int], int]],
        time_tokens: Callable[[], list[str]],
        dt: float | None = None,
    ) -> None:
        self.blocks, self.rows, self.line_of, self.time_tokens, self.dt = blocks, rows, line_of, time_tokens, dt


def open_source(path: Path, wanted: list[str], progress: ProgressCallback | None) -> _Source:
    """A record file's row blocks (CSV or binary, by its suffix), its sensor columns in the order of `wanted`."""
    from rigidid.io.records import is_binary_record

    src = str(path)
    if is_binary_record(path, src):
        return _binary_source(path, wanted, src, progress)
    return _csv_source(path, wanted, progress)


def _csv_source(path: Path, wanted: list[str], progress: ProgressCallback | None) -> _Source:
    from rigidid.io.csv_records import CsvHead, csv_blocks

    gen = csv_blocks(path, wanted, progress)
    head = next(gen)
    assert isinstance(head, CsvHead)

    def blocks() -> Iterator[tuple[Array, Array]]:
        for item in gen:
            assert not isinstance(item, CsvHead)
            yield item

    return _Source(blocks(), head.rows, head.line_of, head.time_tokens)


def _binary_source(path: Path, wanted: list[str], src: str, progress: ProgressCallback | None) -> _Source:
    from rigidid.io.binary_records import named_blocks, npy_blocks, read_binary

    if path.suffix.lower() == ".npy" and path.is_file():
        found = npy_blocks(path, _BLOCK)
        if found is not None:
            return _npy_source(path, wanted, src, progress, *found)
    named = named_blocks(path, _BLOCK)  # .npz and .h5 of the data/channels layout: row blocks
    if named is not None:
        names, n, step, field = named.names, named.rows, named.dt, named.field
        parts = named.blocks
        try:
            order = column_order(names, named.count, wanted, src, field)
        except InputError:
            parts.close()
            raise
    else:
        raw = read_binary(path)
        order = column_order(raw.names, raw.data.shape[1], wanted, src, raw.field)
        n = raw.data.shape[0]
        step = raw.dt if raw.time is None else None

        def whole() -> Iterator[tuple[Array | None, Array]]:
            for start in range(0, n, _BLOCK):
                yield (None if raw.time is None else raw.time[start : start + _BLOCK]), raw.data[start : start + _BLOCK]

        parts = whole()
    task = f"reading {path.name}"

    def blocks() -> Iterator[tuple[Array, Array]]:
        start = 0
        for time_part, values in parts:
            stop = start + values.shape[0]
            values = values if order == list(range(values.shape[1])) else values[:, order]
            t = time_part if time_part is not None else np.arange(start, stop, dtype=float) * float(step or 0.0)
            finite = np.isfinite(values).all(axis=1) & np.isfinite(t)
            if not finite.all():
                k = int(np.flatnonzero(~finite)[0])
                name = "time" if not np.isfinite(t[k]) else wanted[int(np.argmin(np.isfinite(values[k])))]
                raise InputError(
                    "a value is NaN or infinite", source=src, location=f"{_where(start + k + 1)}, {_column(name)}"
                )
            if progress is not None:
                progress(task, float(stop), float(n))
            yield t, values
            start = stop

    return _Source(blocks(), n, lambda _n: lambda k: (k if k >= 0 else _n + k) + 1, list, step)


def _npy_source(
    path: Path, wanted: list[str], src: str, progress: ProgressCallback | None, n: int, columns: int, raw: Any
) -> _Source:
    """A plain ``.npy`` record (time, then the sensors in layout order) read block by block."""
    if columns - 1 != len(wanted):
        raw.close()
        raise InputError(
            f"{columns - 1} sensor columns after time, the layout has {len(wanted)} sensors",
            source=src,
            location="columns",
        )
    task = f"reading {path.name}"

    def blocks() -> Iterator[tuple[Array, Array]]:
        done = 0
        try:
            for table in raw:
                finite = np.isfinite(table).all(axis=1)
                if not finite.all():
                    k = int(np.flatnonzero(~finite)[0])
                    j = int(np.argmin(np.isfinite(table[k])))
                    name = "time" if j == 0 else wanted[j - 1]
                    raise InputError(
                        "a value is NaN or infinite", source=src, location=f"{_where(done + k + 1)}, {_column(name)}"
                    )
                done += table.shape[0]
                if progress is not None:
                    progress(task, float(done), float(n))
                yield np.ascontiguousarray(table[:, 0]), np.ascontiguousarray(table[:, 1:])
        finally:
            raw.close()  # the file, also when a bad value stops the reading

    return _Source(blocks(), n, lambda _n: lambda k: (k if k >= 0 else _n + k) + 1, list)


class _TimeCheck:
    """The uniform-time check of :func:`rigidid.io.records.read_record`, block by block."""

    def __init__(self, source: _Source, src: str) -> None:
        self.source, self.src = source, src
        self.first = math.nan
        self.last = math.nan
        self.rows = 0
        self.typical = math.nan
        self.allowed: float | None = None

    def add(self, t: Array) -> None:
        from rigidid.io.records import TIME_TOLERANCE, _resolution

        if t.shape[0] == 0:
            return
        if self.rows == 0:
            self.first = float(t[0])
            steps = np.diff(t)
        else:
            steps = np.diff(np.concatenate([[self.last], t]))
        if math.isnan(self.typical) and steps.size:
            self.typical = float(np.median(steps))
            if not self.typical > 0.0:
                raise InputError(
                    "time does not increase from the first to the last row", source=self.src, location=_column("time")
                )
        if steps.size:
            deviation = np.abs(steps - self.typical)
            tolerance = TIME_TOLERANCE * self.typical
            bad = np.flatnonzero(deviation > (tolerance if self.allowed is None else self.allowed))
            if bad.size and self.allowed is None:
                resolution = min((_resolution(token) for token in self.source.time_tokens()), default=0.0)
                if resolution > 0.5 * self.typical:
                    raise InputError(
                        f"time is written with too few digits (to {resolution:g} s) for the sample interval "
                        f"{self.typical:.6g} s",
                        source=self.src,
                        location=_column("time"),
                    )
                self.allowed = max(tolerance, resolution) * (1.0 + 1e-6)
                bad = np.flatnonzero(deviation > self.allowed)
            if bad.size:
                k = int(bad[0])
                row = self.rows + k - (1 if self.rows else 0) + 1  # data row (from 0) of the step's end
                raise InputError(
                    f"time step {steps[k]:.6g} s differs from the sample interval {self.typical:.6g} s by more than "
                    f"{100 * TIME_TOLERANCE:g} % (time must be uniformly sampled and increasing)",
                    source=self.src,
                    location=_where(self.source.line_of(self.rows + t.shape[0])(row)),
                )
        self.last = float(t[-1])
        self.rows += t.shape[0]

    def dt(self) -> float:
        dt = (self.last - self.first) / (self.rows - 1)
        if not dt > 0.0:
            raise InputError(
                "time does not increase from the first to the last row", source=self.src, location=_column("time")
            )
        return dt

    def uncertainty(self) -> float:
        """Bound on the error of :meth:`dt` from the digits the time column is written with."""
        from rigidid.core.timedomain.stamps import interval_uncertainty, token_resolution

        resolution = min((token_resolution(token) for token in self.source.time_tokens()), default=0.0)
        return interval_uncertainty(resolution, self.rows, max(abs(self.first), abs(self.last)))


class _Welch:
    """``content_spectrum`` of the decay ``record[start : start + READ_CONTENT_ROWS]`` fed block by block.

    The segments (4096 samples, half overlap, Hann window, mean removed) are
    transformed as soon as they are complete; each channel's sum is divided by
    the variance of its whole part at the end, as
    :func:`~rigidid.core.timedomain.preprocess.content_spectrum` does.
    """

    SEG = 4096
    SPAN = READ_CONTENT_ROWS

    def __init__(self, start: int, dt: float, channels: int) -> None:
        self.start, self.dt = start, dt
        self.window = np.hanning(self.SEG + 2)[1:-1]
        self.power = np.zeros((channels, self.SEG // 2 + 1))
        self.segments = 0
        self.sums = np.zeros(channels)
        self.squares = np.zeros(channels)
        self.count = 0
        self.buffer = np.empty((0, channels))
        self.buffer_at = start  # raw row of buffer[0]
        self.next = start  # raw row where the next segment starts

    def add(self, values: Array, first_row: int) -> None:
        """Feed raw rows ``first_row ...`` (blocks in order)."""
        end = self.start + self.SPAN
        lo, hi = max(first_row, self.start), min(first_row + values.shape[0], end)
        if hi <= lo:
            return
        part = values[lo - first_row : hi - first_row]
        self.sums += part.sum(axis=0)
        self.squares += np.einsum("ij,ij->j", part, part)
        self.count += part.shape[0]
        self.buffer = np.concatenate([self.buffer, part]) if self.buffer.shape[0] else part
        starts = []
        while self.next + self.SEG <= hi:
            starts.append(self.next - self.buffer_at)
            self.next += self.SEG // 2
        if starts:
            from rigidid.core.timedomain.preprocess import segment_power

            self.power += segment_power(self.buffer, np.asarray(starts), self.window).T
            self.segments += len(starts)
        drop = self.next - self.buffer_at
        self.buffer = self.buffer[drop:].copy()
        self.buffer_at = self.next

    def complete(self, rows: int) -> bool:
        """Whether the spectrum is final once `rows` raw rows have been fed."""
        return rows >= self.start + self.SPAN

    def spectrum(self) -> tuple[Array, Array] | None:
        """Frequencies and the summed normalised spectrum (None: decay shorter than a segment)."""
        if self.segments == 0 or self.count < self.SEG:
            return None
        var = self.squares / self.count - (self.sums / self.count) ** 2
        keep = var > 0.0
        total = (self.power[keep] / self.segments / var[keep, None]).sum(axis=0)
        freqs: Array = np.asarray(np.fft.rfftfreq(self.SEG, self.dt), dtype=float)
        return freqs, total


def _head_content(head: Array, time: Array) -> tuple[float, tuple[Array, Array], int] | None:
    """Sample interval, content spectrum of the decay in the head and the decay's start (None: none found)."""
    from rigidid.core.timedomain.preprocess import content_spectrum, find_impact

    dt = float(time[-1] - time[0]) / (time.shape[0] - 1)
    if not dt > 0.0:
        return None
    try:
        start = find_impact(head, dt).start
    except InputError:  # an all-zero head: the checks after reading will say what is wrong
        return None
    freqs, total = content_spectrum([head[start:]], dt)
    return (dt, (freqs, total), start) if total.size else None


def _pre_factor(dt: float, spectrum: tuple[Array, Array], f_limit: float | None) -> int:
    """The pre-decimation factor from the content of the head (see the module documentation)."""
    from rigidid.core.timedomain.preprocess import content_from_spectrum, decimation_for

    f_high = content_from_spectrum(*spectrum, 0.5 / dt)[1]
    if f_limit is not None:
        f_high = min(f_high, f_limit)
    first = decimation_for(f_high, dt)
    cap = max(1, min(first // PRE_SAFETY, int(PULSE_WIDTH / (PULSE_SAMPLES * dt)), MAX_PRE_FACTOR))
    # a divisor of the factor the content gives, if one is near the cap: the two stages then add up to it
    divisor = next((d for d in range(cap, 0, -1) if first % d == 0), 1)
    return divisor if 2 * divisor >= cap else cap


def second_factor(f_high: float, dt: float, factor: int, f_limit: float | None = None) -> int:
    """The factor the estimation decimates a record pre-decimated by `factor` by (its first choice).

    Parameters
    ----------
    f_high : float
        Highest frequency standing out of the noise (Hz, ``content_range``).
    dt : float
        The file's sample interval (s).
    factor : int
        Pre-decimation factor.
    f_limit : float, optional
        Upper edge of the user's band (Hz).

    Returns
    -------
    int
        ``decimation_for(min(f_high, f_limit), dt * factor)`` with the
        estimation's margin: what
        :func:`~rigidid.core.timedomain.estimate.decimation_factors` tries
        first on a long record.
    """
    from rigidid.core.timedomain.estimate import _DECIMATION_MARGIN
    from rigidid.core.timedomain.preprocess import decimation_for

    if f_limit is not None:
        f_high = min(f_high, f_limit)
    return decimation_for(f_high, dt * factor, margin=_DECIMATION_MARGIN)


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
        estimation would choose (:func:`second_factor`), as soon as the
        content spectrum is complete (:data:`READ_CONTENT_ROWS` rows of decay): only the
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

    Returns
    -------
    StreamedRecord

    Raises
    ------
    InputError
        The errors of :func:`rigidid.io.records.read_record`, naming the file,
        row and column; and a record too short for `factor`.
    """
    from rigidid.core.timedomain.clipping import PeakCount
    from rigidid.core.timedomain.preprocess import FIR_HALF_LENGTH, Decimator, channel_energy
    from rigidid.io.records import MIN_ROWS, _check_decay, layout_ids

    src = str(path)
    wanted = layout_ids(sensor_ids, src)
    source = open_source(Path(path), wanted, progress)
    times = _TimeCheck(source, src)
    tops = PeakCount(len(wanted))  # each channel's peak, and the samples at it (a flat top: clipped)
    pending: list[tuple[Array, Array]] = []
    blocks = iter(source.blocks)
    held = 0  # hold the head raw: its content chooses the factor and is the estimation's
    for t, values in blocks:
        pending.append((t, values))
        held += t.shape[0]
        if held > HEAD_ROWS:
            break
    welch: _Welch | None = None
    if held > HEAD_ROWS:  # longer than the head (a shorter record is read whole, not pre-decimated)
        head = np.concatenate([v for _, v in pending])[:HEAD_ROWS]
        found = _head_content(head, np.concatenate([t for t, _ in pending])[:HEAD_ROWS])
        del head
        if found is not None:
            welch = _Welch(found[2], found[0], len(wanted))
            if factor is None:
                factor = _pre_factor(found[0], found[1], f_limit)
                if keep_rows is not None:
                    factor = max(1, min(factor, source.rows // max(1, keep_rows)))
    if factor is None:
        factor = 1
    auto = cascade and second is None and factor > 1
    stream = Decimator(factor, len(wanted))
    stage2 = Decimator(second, len(wanted)) if second is not None and second > 1 and factor > 1 else None
    total = factor * (stage2.factor if stage2 is not None else 1)
    capacity = source.rows // total + 2 * FIR_HALF_LENGTH + 16
    out = np.empty((capacity, len(wanted)))
    filled = 0

    def emit(done: Array) -> None:
        nonlocal out, capacity, filled
        if filled + done.shape[0] > capacity:  # the row count of a CSV was estimated from its size
            capacity = max(filled + done.shape[0], int(capacity * 1.25))
            grown = np.empty((capacity, len(wanted)))
            grown[:filled] = out[:filled]
            out = grown
        out[filled : filled + done.shape[0]] = done
        filled += done.shape[0]

    def feed(t: Array, values: Array) -> None:
        nonlocal out, capacity, filled, stage2, auto, total
        if welch is not None:
            welch.add(values, times.rows)
        times.add(t)
        tops.add(values)
        done = stream.push(values)
        emit(done if stage2 is None else stage2.push(done))
        if auto and welch is not None and welch.complete(times.rows):
            auto = False  # the content is known: start the second stage on what is held
            spectrum = welch.spectrum()
            if spectrum is None:
                return
            from rigidid.core.timedomain.estimate import _MIN_DECIMATED_SAMPLES
            from rigidid.core.timedomain.preprocess import content_from_spectrum

            q2 = second_factor(content_from_spectrum(*spectrum, 0.5 / welch.dt)[1], welch.dt, factor, f_limit)
            if q2 > 1 and (source.rows - welch.start) // factor >= 2 * q2 * _MIN_DECIMATED_SAMPLES:
                stage2 = Decimator(q2, len(wanted))
                held = stage2.push(out[:filled])
                total = factor * q2
                capacity = max(source.rows // total + 2 * FIR_HALF_LENGTH + 16, held.shape[0])
                out, filled = np.empty((capacity, len(wanted))), 0
                emit(held)

    for t, values in pending:
        feed(t, values)
    pending.clear()
    for t, values in blocks:
        feed(t, values)
    n = times.rows
    line_of = source.line_of(n)
    if n < MIN_ROWS:
        last = line_of(n - 1) if n else 1
        raise InputError(f"{n} data rows; a record needs at least {MIN_ROWS}", source=src, location=_where(last))
    dt = times.dt() if source.dt is None else float(source.dt)
    dt_error = times.uncertainty() if source.dt is None else 0.0
    for i, name in enumerate(wanted):
        if not tops.peak[i] > 0.0:
            raise InputError(f"sensor {name!r} reads zero in every row", source=src, location=_column(name))
    try:
        stream.finish()
        if stage2 is not None:
            stage2.finish()
    except InputError as exc:
        raise InputError(exc.message, source=src) from None
    data = out[:filled]
    offset = FIR_HALF_LENGTH * factor if factor > 1 else 0
    if stage2 is not None:
        offset += FIR_HALF_LENGTH * total
    energy = channel_energy(data)
    _check_decay(data, lambda k: line_of(offset + (k if k >= 0 else data.shape[0] + k) * total), src, energy)
    spectrum = welch.spectrum() if welch is not None else None
    stages = (factor, total // factor)
    clipped = tops.clipped()
    return StreamedRecord(data, dt * total, total, offset, n, energy, spectrum, stages, dt_error * total, clipped)


def _content(streamed: Sequence[StreamedRecord], dt: float) -> tuple[float, float] | None:
    """The content range from the spectra measured on the raw records (None: let the estimation measure it)."""
    from rigidid.core.timedomain.preprocess import content_from_spectrum

    spectra = [r.spectrum for r in streamed]
    if any(s is None for s in spectra) or len({s[1].shape for s in spectra if s is not None}) != 1:
        return None
    total = np.sum([s[1] for s in spectra if s is not None], axis=0)
    return content_from_spectrum(spectra[0][0], total, 0.5 / dt) if spectra[0] is not None else None


def read_records_streamed(
    paths: Sequence[str | os.PathLike[str]],
    sensor_ids: Sequence[str],
    factor: int | None = None,
    f_limit: float | None = None,
    progress: ProgressCallback | None = None,
    *,
    cascade: bool = False,
    keep_rows: int | None = None,
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
    first = read_record_streamed(paths[0], sensor_ids, factor=factor, f_limit=f_limit, progress=progress,
                                 cascade=cascade and factor is None, keep_rows=keep_rows)  # fmt: skip
    q0, q2 = first.stages
    streamed = [first]
    streamed += [read_record_streamed(p, sensor_ids, factor=q0, second=q2, progress=progress) for p in paths[1:]]
    from rigidid.core.timedomain.stamps import common_interval, different_intervals

    total = streamed[0].factor
    dts = [r.dt for r in streamed]
    common, same = common_interval(dts, [r.dt_uncertainty for r in streamed])
    if not same:
        raise InputError(different_intervals([d / total for d in dts], [r.dt_uncertainty / total for r in streamed]),
                         source="records")  # fmt: skip
    streamed = [r if r.dt == common else replace(r, dt=common) for r in streamed]
    dts = [common] * len(streamed)
    content = _content(streamed, dts[0] / total)
    if q2 > 1 and (content is None or second_factor(content[1], dts[0] / total, q0, f_limit) != q2):
        del streamed, first
        return read_records_streamed(paths, sensor_ids, factor, f_limit, progress, cascade=False, keep_rows=keep_rows)
    return streamed, content
