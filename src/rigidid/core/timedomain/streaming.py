"""Records processed as their rows arrive: streaming decimation, content spectrum, impact location, prepared decays.

Every function here takes a record as blocks of rows in order (an iterable of
arrays ``(rows, channels)``, from :mod:`rigidid.io.records.sources` or any other
producer) and its sample interval; none opens a file. Each gives what the
whole-record routine of :mod:`~rigidid.core.timedomain.preprocess` or
:mod:`~rigidid.core.timedomain.refine` gives, holding one block and its result:

- :class:`StreamingDecimation`: the record decimated by a *pre-factor* ``q0``
  chosen from its head (and, with ``cascade``, by a second stage chosen from
  the content spectrum of the first :data:`READ_CONTENT_ROWS` rows of decay);
  :class:`ContentWelch` that spectrum fed block by block;
- :func:`locate_impact`: :func:`~rigidid.core.timedomain.preprocess.find_impact`
  on the raw rows around a known impact, the rest bounded by block maxima;
- :func:`decay_pass` / :func:`prepared_decays`:
  :func:`~rigidid.core.timedomain.refine.prepare_decays` of records in blocks;
- :func:`record_power` / :func:`power_density`:
  :func:`rigidid.core.spectrum.summed_spectrum` of records in blocks.

How ``q0`` is chosen, when the caller does not fix it: from the first
:data:`HEAD_ROWS` rows of the first record, the impact is located and the
content range of the decay after it measured, exactly as the estimation does
it on the whole record (:func:`~rigidid.core.timedomain.preprocess.find_impact`,
:func:`~rigidid.core.timedomain.preprocess.content_range`); ``q0`` is
:data:`PRE_SAFETY` times smaller than the factor that content would give (so
the new Nyquist frequency stays 16 times above the highest frequency seen in
the head, not 4), keeps at least :data:`PULSE_SAMPLES` samples per
:data:`PULSE_WIDTH` (the impact is still located to a fraction of its pulse)
and is at most :data:`MAX_PRE_FACTOR`. Records of at most :data:`HEAD_ROWS`
rows are not pre-decimated (``q0 = 1``).

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994 (the records of Section 3).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from rigidid.core.timedomain import estimate
from rigidid.core.timedomain.preprocess import (
    FIR_HALF_LENGTH,
    Decimator,
    Impact,
    channel_energy,
    content_from_spectrum,
    content_spectrum,
    decimation_for,
    energy_bound,
    find_impact,
    segment_power,
)
from rigidid.core.timedomain.pretrigger import PRE_HELD
from rigidid.core.timedomain.refine import MAX_ROWS, PreparedDecays, cut_decays, fit_factor, pretrigger_sigma
from rigidid.errors import InputError

__all__ = [
    "AFTER_ROWS",
    "HEAD_ROWS",
    "MAX_PRE_FACTOR",
    "PRE_SAFETY",
    "PULSE_SAMPLES",
    "PULSE_WIDTH",
    "READ_CONTENT_ROWS",
    "CapturedDecay",
    "ContentWelch",
    "DecayPass",
    "DecayScan",
    "Decimated",
    "LocatedDecay",
    "StreamingDecimation",
    "captured_decays",
    "chunk_maxima",
    "decay_pass",
    "hann_window",
    "head_content",
    "locate_impact",
    "locate_impacts",
    "located_decay",
    "located_decays",
    "power_density",
    "pre_factor",
    "prepared_decays",
    "prepared_from",
    "record_power",
    "second_factor",
    "spectra_content",
]

Array = NDArray[np.float64]
Blocks = Iterable[Array]
Spectrum = tuple[Array, Array]

READ_CONTENT_ROWS = 1 << 18
"""Rows of free decay the reader's content spectrum covers (2^18; the estimation's own spectrum of a
whole record covers 2^16): the second stage's factor comes from it, and a longer span resolves
the modes' leakage better at high rates (8 x 10^7 rows at 500 kHz: content to 1709 Hz against
1831 Hz, a second stage of 3 against 2, 18 MB held against 27 MB)."""

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

AFTER_ROWS = 1 << 16
"""Raw rows held after the estimate's decay start (at least): where the largest channel energy is sought."""

_THRESHOLD = 0.01  # find_impact's defaults, as the estimation uses them
_CHUNK = 128  # rows per maximum kept outside the window (the energy bound's resolution)


class ContentWelch:
    """``content_spectrum`` of the decay ``record[start : start + READ_CONTENT_ROWS]`` fed block by block.

    The segments (4096 samples, half overlap, Hann window, mean removed) are
    transformed as soon as they are complete; each channel's sum is divided by
    the variance of its whole part at the end, as
    :func:`~rigidid.core.timedomain.preprocess.content_spectrum` does.

    Parameters
    ----------
    start : int
        Raw row (from 0) where the free decay starts.
    dt : float
        Sample interval (s).
    channels : int
        Columns of every block.
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
            self.power += segment_power(self.buffer, np.asarray(starts), self.window).T
            self.segments += len(starts)
        drop = self.next - self.buffer_at
        self.buffer = self.buffer[drop:].copy()
        self.buffer_at = self.next

    def complete(self, rows: int) -> bool:
        """Whether the spectrum is final once `rows` raw rows have been fed."""
        return rows >= self.start + self.SPAN

    def spectrum(self) -> Spectrum | None:
        """Frequencies and the summed normalised spectrum (None: decay shorter than a segment)."""
        if self.segments == 0 or self.count < self.SEG:
            return None
        var = self.squares / self.count - (self.sums / self.count) ** 2
        keep = var > 0.0
        total = (self.power[keep] / self.segments / var[keep, None]).sum(axis=0)
        freqs: Array = np.asarray(np.fft.rfftfreq(self.SEG, self.dt), dtype=float)
        return freqs, total


def head_content(head: Array, time: Array) -> tuple[float, Spectrum, int] | None:
    """Sample interval, content spectrum of the decay in the head and the decay's start (None: none found).

    Parameters
    ----------
    head : ndarray, shape (n, channels)
        The first rows of the record.
    time : ndarray, shape (n,)
        Their sample times (s).
    """
    found = _head_impact(head, time)
    return None if found is None else (found[0], found[1], found[2].start)


def _head_impact(head: Array, time: Array) -> tuple[float, Spectrum, Impact] | None:
    """:func:`head_content` with the whole impact the head holds."""
    dt = float(time[-1] - time[0]) / (time.shape[0] - 1)
    if not dt > 0.0:
        return None
    try:
        impact = find_impact(head, dt)
    except InputError:  # an all-zero head: the checks after reading will say what is wrong
        return None
    freqs, total = content_spectrum([head[impact.start :]], dt)
    return (dt, (freqs, total), impact) if total.size else None


def pre_factor(dt: float, spectrum: Spectrum, f_limit: float | None) -> int:
    """The pre-decimation factor from the content of the head (see the module documentation).

    Parameters
    ----------
    dt : float
        The raw sample interval (s).
    spectrum : (ndarray, ndarray)
        :func:`head_content`'s spectrum.
    f_limit : float, optional
        Upper edge of the user's band (Hz).
    """
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
        The raw sample interval (s).
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
    if f_limit is not None:
        f_high = min(f_high, f_limit)
    return decimation_for(f_high, dt * factor, margin=estimate.DECIMATION_MARGIN)


def spectra_content(spectra: Sequence[Spectrum | None], dt: float) -> tuple[float, float] | None:
    """The content range from the spectra measured on the raw records (None: let the estimation measure it).

    Parameters
    ----------
    spectra : sequence of (ndarray, ndarray) or None
        Each record's :meth:`ContentWelch.spectrum`.
    dt : float
        The raw sample interval (s).
    """
    if any(s is None for s in spectra) or len({s[1].shape for s in spectra if s is not None}) != 1:
        return None
    total = np.sum([s[1] for s in spectra if s is not None], axis=0)
    return content_from_spectrum(spectra[0][0], total, 0.5 / dt) if spectra[0] is not None else None


class _Rows:
    """Output rows appended in place; the buffer grows by a quarter when a row count was underestimated."""

    def __init__(self, capacity: int, channels: int) -> None:
        self.out = np.empty((capacity, channels))
        self.capacity, self.filled = capacity, 0

    def add(self, done: Array) -> None:
        if self.filled + done.shape[0] > self.capacity:  # the row count of a CSV was estimated from its size
            self.capacity = max(self.filled + done.shape[0], int(self.capacity * 1.25))
            grown = np.empty((self.capacity, self.out.shape[1]))
            grown[: self.filled] = self.out[: self.filled]
            self.out = grown
        self.out[self.filled : self.filled + done.shape[0]] = done
        self.filled += done.shape[0]

    def view(self) -> Array:
        return self.out[: self.filled]


@dataclass(frozen=True)
class Decimated:
    """A record after :class:`StreamingDecimation`.

    Attributes
    ----------
    data : ndarray, shape (m, channels)
        The record decimated by `factor`.
    factor : int
        Total decimation factor (1: the record as fed).
    offset : int
        Raw row (from 0) of ``data[0]``; row ``k`` of `data` is raw row ``offset + k factor``.
    stages : (int, int)
        The pre-factor and the second stage's factor; `factor` is their product.
    energy : ndarray, shape (m,)
        ``channel_energy(data)``.
    spectrum : (ndarray, ndarray) or None
        The content spectrum of the first :data:`READ_CONTENT_ROWS` raw rows of
        decay (:class:`ContentWelch`); None for a record of at most
        :data:`HEAD_ROWS` rows.
    """

    data: Array
    factor: int
    offset: int
    stages: tuple[int, int]
    energy: Array
    spectrum: Spectrum | None
    captured: CapturedDecay | None = None


@dataclass(frozen=True)
class CapturedDecay:
    """The refit's reading of a record, done during :class:`StreamingDecimation`'s (its ``capture`` option).

    Attributes
    ----------
    impact : Impact
        As :func:`locate_impact` finds it on the raw record.
    decay : DecayPass
        ``decay_pass(record, ..., impact.start, impact.onset - 2, factor, cap)``.
    factor : int
        The fit's decimation factor the decay was taken at.
    """

    impact: Impact
    decay: DecayPass
    factor: int


class StreamingDecimation:
    """A record decimated as its blocks arrive, in one or two stages (module documentation).

    Parameters
    ----------
    rows : int
        The record's rows as known before reading (a CSV's estimated from its
        size): sizes the output buffer and bounds the factors.
    channels : int
        Columns of every block.
    factor : int, optional
        Pre-decimation factor; default: chosen from the first :data:`HEAD_ROWS`
        rows (:func:`pre_factor`).
    f_limit : float, optional
        Upper edge of the user's band (Hz): caps the content the factors keep.
    cascade : bool
        Start a second stage (:func:`second_factor`) once the content spectrum
        is complete, when the record is long enough (at least twice the rows
        the estimation requires) and `factor` is not given.
    second : int, optional
        A second-stage factor fixed by the caller, applied from the first row.
    keep_rows : int, optional
        An automatic pre-factor leaves at least this many of `rows`.
    capture : sequence of int, optional
        Read the refit's data on the way (:class:`CapturedDecay`, in ``finish().captured``): the
        rows of the test's other records as known before reading. The impact the head holds
        (:func:`find_impact`) is the guess of :class:`DecayScan`, which proves it at the end on
        the raw rows from a few pulse widths before its onset to :data:`AFTER_ROWS` after its
        decay start. The fit's factor is :func:`~rigidid.core.timedomain.refine.fit_factor` of
        these rows and `rows` (the same for every record of the test, so they share it), up to
        the total factor once the second stage is chosen (the decay's rows are held until then, at
        most :data:`READ_CONTENT_ROWS`). Memory: those rows, whatever the record's length.

    Notes
    -----
    :meth:`run` feeds the blocks, :meth:`finish` ends the record: the output is
    ``decimate(record, q0)`` (and ``decimate(., q2)`` of it), the same
    polyphase sums as :func:`~rigidid.core.timedomain.preprocess.decimate` on
    the whole record.
    """

    def __init__(
        self,
        rows: int,
        channels: int,
        *,
        factor: int | None = None,
        f_limit: float | None = None,
        cascade: bool = False,
        second: int | None = None,
        keep_rows: int | None = None,
        capture: Sequence[int] | None = None,
    ) -> None:
        self.hint, self.channels, self.factor, self.f_limit = rows, channels, factor, f_limit
        self.cascade, self.second, self.keep_rows = cascade, second, keep_rows
        self.capture = None if capture is None else list(capture)
        self.scan: DecayScan | None = None
        self.rows = 0  # raw rows fed
        self.welch: ContentWelch | None = None
        self.stage2: Decimator | None = None
        self.auto = False
        self.total = 1

    def run(self, blocks: Iterable[tuple[Array, Array]], check: Callable[[Array, Array], None] | None = None) -> None:
        """Feed every block ``(time, values)``; `check` sees each before it is used."""
        blocks = iter(blocks)
        pending: list[tuple[Array, Array]] = []
        held = 0  # hold the head raw: its content chooses the factor and is the estimation's
        for t, values in blocks:
            pending.append((t, values))
            held += t.shape[0]
            if held > HEAD_ROWS:
                break
        self._start(pending, held)
        for t, values in pending:
            self._feed(t, values, check)
        pending.clear()
        for t, values in blocks:
            self._feed(t, values, check)

    def _start(self, pending: list[tuple[Array, Array]], held: int) -> None:
        """Choose the pre-factor from the head (longer records only) and set up the stages."""
        if held > HEAD_ROWS:  # longer than the head (a shorter record is fed whole, not pre-decimated)
            head = np.concatenate([v for _, v in pending])[:HEAD_ROWS]
            found = _head_impact(head, np.concatenate([t for t, _ in pending])[:HEAD_ROWS])
            del head
            if found is not None:
                self.welch = ContentWelch(found[2].start, found[0], self.channels)
                self._capture(found[0], found[2])
                if self.factor is None:
                    self.factor = pre_factor(found[0], found[1], self.f_limit)
                    if self.keep_rows is not None:
                        self.factor = max(1, min(self.factor, self.hint // max(1, self.keep_rows)))
        factor = self.factor = 1 if self.factor is None else self.factor
        self.auto = self.cascade and self.second is None and factor > 1
        self.stream = Decimator(factor, self.channels)
        if self.second is not None and self.second > 1 and factor > 1:
            self.stage2 = Decimator(self.second, self.channels)
        self.total = factor * (self.stage2.factor if self.stage2 is not None else 1)
        self.out = _Rows(self.hint // self.total + 2 * FIR_HALF_LENGTH + 16, self.channels)

    def _feed(self, t: Array, values: Array, check: Callable[[Array, Array], None] | None) -> None:
        if check is not None:
            check(t, values)
        if self.welch is not None:
            self.welch.add(values, self.rows)
        self.rows += t.shape[0]
        done = self.stream.push(values)
        self.out.add(done if self.stage2 is None else self.stage2.push(done))
        if self.auto and self.welch is not None and self.welch.complete(self.rows):
            self.auto = False  # the content is known: start the second stage on what is held
            self._second_stage(self.welch)
        if self.scan is not None:  # after the second stage is chosen: the fit's factor may be asked
            self.scan.push(values)

    def _capture(self, dt: float, impact: Impact) -> None:
        """Start the refit's reading (the `capture` option) around the impact the head holds."""
        if self.capture is None:
            return
        pulse = max(2, round(PULSE_WIDTH / dt))
        lo = max(0, impact.onset - 4 * pulse - 2 * FIR_HALF_LENGTH)
        lengths = [self.hint, *self.capture]  # every record of the test the same: one factor for all
        cap = MAX_ROWS // self.channels + 1  # no decay keeps more (cut_decays)

        def factor(final: bool) -> int | None:  # once the second stage is chosen (or will not be)
            return None if self.auto and not final else fit_factor(lengths, self.channels, max(1, self.total))

        self.scan = DecayScan(self.channels, dt, lo, impact.start + AFTER_ROWS, cap, factor, guess=impact)

    def _second_stage(self, welch: ContentWelch) -> None:
        spectrum = welch.spectrum()
        if spectrum is None:
            return
        factor = int(self.factor or 1)
        q2 = second_factor(content_from_spectrum(*spectrum, 0.5 / welch.dt)[1], welch.dt, factor, self.f_limit)
        if q2 > 1 and (self.hint - welch.start) // factor >= 2 * q2 * estimate.MIN_DECIMATED_SAMPLES:
            self.stage2 = Decimator(q2, self.channels)
            held = self.stage2.push(self.out.view())
            self.total = factor * q2
            self.out = _Rows(max(self.hint // self.total + 2 * FIR_HALF_LENGTH + 16, held.shape[0]), self.channels)
            self.out.add(held)

    def finish(self, dt: float | None = None) -> Decimated:
        """End of the record: the decimated rows and where they sit (`dt`: the record's checked interval).

        Raises
        ------
        InputError
            A record too short for a stage's filter.
        """
        self.stream.finish()
        if self.stage2 is not None:
            self.stage2.finish()
        factor = int(self.factor or 1)
        data = self.out.view()
        offset = FIR_HALF_LENGTH * factor if factor > 1 else 0
        if self.stage2 is not None:
            offset += FIR_HALF_LENGTH * self.total
        spectrum = self.welch.spectrum() if self.welch is not None else None
        stages = (factor, self.total // factor)
        located = None if self.scan is None else self.scan.finish(dt)
        captured = None
        if located is not None and located.decay is not None:
            captured = CapturedDecay(located.impact, located.decay, self.scan.factor)  # type: ignore[union-attr]
        return Decimated(data, self.total, offset, stages, channel_energy(data), spectrum, captured)


def locate_impact(blocks: Blocks, channels: int, dt: float, lo: int, hi: int) -> Impact | None:
    """:func:`find_impact` on a raw record, from its rows ``lo:hi`` and every block's maxima; None if unsure.

    Parameters
    ----------
    blocks : iterable of ndarray, shape (rows, channels)
        The raw record, in order.
    channels : int
        Columns of every block.
    dt : float
        Sample interval (s).
    lo, hi : int
        The raw rows held (where the impact and the largest energy must lie).

    Returns
    -------
    Impact or None
        In the record's rows; None when the rows held cannot prove it (a
        larger energy, or one above the onset threshold, outside them).
    """
    scan = _WindowScan(channels, lo, hi)
    for values in blocks:
        scan.add(values)
    return _proved(np.concatenate(scan.held), scan.peaks, scan.before, scan.after, dt, lo) if scan.held else None


class _WindowScan:
    """A record's blocks seen once around the rows ``lo:hi``: the channels' peaks so far, the rows
    held, and each block part's chunk maxima before and after them (what :func:`_proved` needs)."""

    def __init__(self, channels: int, lo: int, hi: int) -> None:
        self.lo, self.hi, self.row = lo, hi, 0
        self.peaks = np.zeros(channels)
        self.held: list[Array] = []
        self.before: list[Array] = []  # max |x| per channel of each block part before the window
        self.after: list[Array] = []  # ... and after it

    def add(self, values: Array) -> int:
        """Take the next block; return the row it starts at."""
        row, stop, lo, hi = self.row, self.row + values.shape[0], self.lo, self.hi
        if row < lo:
            self.before.append(chunk_maxima(values[: min(stop, lo) - row]))
            self.peaks = np.maximum(self.peaks, self.before[-1].max(axis=0, initial=0.0))
        if stop > lo and row < hi:
            self.held.append(np.array(values[max(0, lo - row) : min(stop, hi) - row], dtype=float))
            self.peaks = np.maximum(self.peaks, np.abs(self.held[-1]).max(axis=0, initial=0.0))
        if stop > hi:
            self.after.append(chunk_maxima(values[max(0, hi - row) :]))
            self.peaks = np.maximum(self.peaks, self.after[-1].max(axis=0, initial=0.0))
        self.row = stop
        return row


def chunk_maxima(x: Array) -> Array:
    """``max |x|`` per channel of every 128 rows of `x` (shape (n, p)), shape (chunks, p): from each chunk's
    largest and smallest value, no ``|x|`` made (the capture's pass over every row of a record, issue 23)."""
    n, p = x.shape
    whole = n // _CHUNK * _CHUNK
    parts = []
    if whole:
        chunks = x[:whole].reshape(-1, _CHUNK, p)
        parts.append(np.maximum(chunks.max(axis=1), -chunks.min(axis=1)))
    if whole < n:
        parts.append(np.maximum(x[whole:].max(axis=0), -x[whole:].min(axis=0))[None, :])
    return np.concatenate(parts) if parts else np.zeros((0, p))


def _in_window(window: Array, peaks: Array, dt: float, lo: int) -> tuple[Impact, float] | None:
    """:func:`find_impact` on the rows held from row `lo`, the energy weighted by `peaks`, and the energy's top."""
    energy = channel_energy(window, peaks)
    top = float(energy.max()) if energy.size else 0.0
    if top <= 0.0:
        return None
    found = find_impact(window, dt, threshold=_THRESHOLD, pulse_width=PULSE_WIDTH, energy=energy)
    pulse = max(2, round(PULSE_WIDTH / dt))
    if found.onset + pulse > window.shape[0] or found.start >= window.shape[0] - 1:
        return None  # the pulse window or the decay start run past the rows held
    return Impact(lo + found.onset, lo + found.peak, lo + found.start, found.hits), top


def _proved(window: Array, peaks: Array, before: list[Array], after: list[Array], dt: float, lo: int) -> Impact | None:
    """The impact in `window` when the chunk maxima `before` and `after` it prove it (:func:`locate_impact`)."""
    found = _in_window(window, peaks, dt, lo)
    if found is None:
        return None

    def bound(parts: list[Array]) -> float:  # no row of these chunks has a larger energy
        return float(max(energy_bound(m, peaks).max() for m in parts)) if parts else 0.0

    # the largest energy lies in the window, no row before it reaches the threshold
    if bound(after) > found[1] or bound(before) > _THRESHOLD * found[1]:
        return None
    return found[0]


def locate_impacts(
    records: Callable[[int], Blocks], channels: int, dt: float, near: Sequence[Impact], reach: int
) -> list[Impact] | None:
    """The impacts :func:`find_impact` finds on raw records, each read once in blocks.

    Parameters
    ----------
    records : callable
        ``records(i)``: the blocks of record ``i`` (read when called).
    channels : int
        Columns of every block.
    dt : float
        The raw sample interval (s).
    near : sequence of Impact
        Where the decimated records put each impact (in raw rows).
    reach : int
        Raw rows the true onset may lie before ``near.onset`` and the true
        decay start after ``near.start`` (the decimation filters' reach).

    Returns
    -------
    list of Impact or None
        None when the rows held cannot prove one of them (:func:`locate_impact`).

    Notes
    -----
    Per record, the raw rows ``near.onset - reach ... near.start + max(reach,
    AFTER_ROWS)`` are held (the largest energy can come a cycle of the slowest
    mode after the impact) and, outside them, ``max |x|`` per channel of every
    128 rows. The energy weights (``1 / max |x|`` per channel,
    :func:`channel_energy`) come from the whole record; the rows outside the
    window are bounded by their blocks' maxima, as
    :func:`~rigidid.core.timedomain.preprocess.impact_from_blocks` does.
    """
    found = []
    for i, impact in enumerate(near):
        lo, hi = max(0, impact.onset - reach), impact.start + max(reach, AFTER_ROWS)
        one = locate_impact(records(i), channels, dt, lo, hi)
        if one is None:
            return None
        found.append(one)
    return found


@dataclass(frozen=True)
class DecayPass:
    """What one pass over a record gives the refit (:func:`decay_pass`).

    Attributes
    ----------
    rows : int
        Rows counted.
    pre_count : int
        Pre-trigger rows.
    pre_m2 : ndarray, shape (p,)
        Their squared deviations from their mean, per channel.
    decay : ndarray, shape (m, p)
        ``decimate(record[start:], factor)``, at most `cap` rows of it.
    pre_held : ndarray, shape (k, p), or None
        The pre-trigger's first rows, at most
        :data:`~rigidid.core.timedomain.pretrigger.PRE_HELD` (its noise in the fit's band).
    """

    rows: int
    pre_count: int
    pre_m2: Array
    decay: Array
    pre_held: Array | None = None


def decay_pass(blocks: Blocks, channels: int, start: int, pre_end: int, factor: int, cap: int) -> DecayPass:
    """The pre-trigger statistics of rows ``:pre_end`` and the decimated decay from row `start` of a record.

    The pre-trigger count and squared deviations from the mean are merged
    block by block (Chan, Golub and LeVeque's pairwise update, so no
    cancellation); the decay is decimated by a streaming
    :class:`~rigidid.core.timedomain.preprocess.Decimator` fed from row
    `start` (the same polyphase sums as on the whole record).
    """
    pre = _Moments(channels)
    feed = _DecayFeed(factor, channels, cap)
    row = 0
    for values in blocks:
        stop = row + values.shape[0]
        if row < pre_end:  # pre-trigger statistics, merged block by block
            pre.add(values[: min(stop, pre_end) - row])
        if stop > start:
            feed.push(values[max(0, start - row) :])
        row = stop
    return DecayPass(row, pre.count, pre.m2, feed.finish(), pre.held())


class _Moments:
    """Count and squared deviations from the mean per channel, merged block by block (Chan, Golub and LeVeque),
    and the first :data:`~rigidid.core.timedomain.pretrigger.PRE_HELD` rows."""

    def __init__(self, channels: int) -> None:
        self.count, self.mean, self.m2 = 0, np.zeros(channels), np.zeros(channels)
        self.rows: list[Array] = []

    def held(self) -> Array:
        """The rows held, in order."""
        return np.concatenate(self.rows) if self.rows else np.zeros((0, self.mean.shape[0]))

    def add(self, x: Array) -> None:
        n_b = x.shape[0]
        if n_b == 0:
            return
        if self.count < PRE_HELD:
            self.rows.append(np.array(x[: PRE_HELD - self.count], dtype=float))
        mean_b = x.mean(axis=0)
        m2_b = ((x - mean_b) ** 2).sum(axis=0)
        total = self.count + n_b
        delta = mean_b - self.mean
        self.m2 = self.m2 + m2_b + delta**2 * (self.count * n_b / total)
        self.mean = self.mean + delta * (n_b / total)
        self.count = total


class _DecayFeed:
    """A decay's rows decimated as they arrive (:class:`Decimator`), at most `cap` rows of it kept."""

    def __init__(self, factor: int, channels: int, cap: int) -> None:
        self.stream, self.channels, self.cap = Decimator(factor, channels), channels, cap
        self.parts: list[Array] = []
        self.held = 0

    def push(self, values: Array) -> None:
        if self.held >= self.cap:
            return
        out = self.stream.push(values)
        if out.shape[0]:
            out = out[: self.cap - self.held]
            self.parts.append(np.array(out, dtype=float))
            self.held += out.shape[0]

    def finish(self) -> Array:
        if self.held < self.cap:
            self.stream.finish()
        return np.concatenate(self.parts) if self.parts else np.zeros((0, self.channels))


def prepared_decays(
    records: Callable[[int], Blocks],
    rows: Sequence[int],
    channels: int,
    dt: float,
    *,
    starts: Sequence[int],
    onsets: Sequence[int],
    factor: int,
) -> PreparedDecays:
    """:func:`~rigidid.core.timedomain.refine.prepare_decays` of records read in blocks.

    Parameters
    ----------
    records : callable
        ``records(i)``: the blocks of record ``i`` (read when called; a record
        may be read twice).
    rows : sequence of int
        Each record's rows as known before reading (a CSV's from its size).
    channels : int
        Columns of every block.
    dt : float
        The raw sample interval (s).
    starts, onsets : sequence of int
        Per record, the impact's free-decay start and onset (raw rows from 0).
    factor : int
        The modal estimate's total decimation factor.

    Returns
    -------
    PreparedDecays
        The same as ``prepare_decays(records, dt, starts, onsets, factor)`` on
        the whole records.

    Notes
    -----
    The fit's factor (:func:`~rigidid.core.timedomain.refine.fit_factor`)
    depends on the records' lengths: it is taken from `rows` and checked
    against the rows counted; when they ask another factor the records are
    read once more. At most :data:`~rigidid.core.timedomain.refine.MAX_ROWS`
    values of the decays are held.
    """
    cap = MAX_ROWS // channels + 1  # no decay keeps more (cut_decays)
    known = list(rows)
    for _ in range(2):
        q = fit_factor([n - s for n, s in zip(known, starts, strict=True)], channels, max(1, factor))
        read = [
            decay_pass(records(i), channels, s, max(0, o - 2), q, cap)
            for i, (s, o) in enumerate(zip(starts, onsets, strict=True))
        ]
        counted = [r.rows for r in read]
        if fit_factor([n - s for n, s in zip(counted, starts, strict=True)], channels, max(1, factor)) == q:
            break
        known = counted
    return prepared_from(read, channels, dt, q)


def prepared_from(read: Sequence[DecayPass], channels: int, dt: float, q: int) -> PreparedDecays:
    """The refit's data from each record's :class:`DecayPass` at the fit's factor `q`.

    Raises
    ------
    InputError
        Records too short for the refinement (:func:`~rigidid.core.timedomain.refine.cut_decays`).
    """
    decays = cut_decays([r.decay for r in read], channels)
    sigma, noise_from = pretrigger_sigma([r.pre_count for r in read], [r.pre_m2 for r in read], len(read), q)
    held = [r.pre_held for r in read if r.pre_held is not None]
    return PreparedDecays(decays, sigma, dt * q, noise_from, pre_counts=tuple(r.pre_count for r in read),
                          pre_m2=np.array([r.pre_m2 for r in read]),
                          pre_held=tuple(held) if len(held) == len(read) else None)  # fmt: skip


@dataclass(frozen=True)
class LocatedDecay:
    """What :func:`located_decay` gives: the impact and, when read on the way, the refit's pass.

    Attributes
    ----------
    impact : Impact
        As :func:`locate_impact` finds it.
    decay : DecayPass or None
        ``decay_pass(record, ..., impact.start, impact.onset - 2, factor, cap)``; None when
        the impact found before the record's end was not the one proved at its end (or
        its pre-trigger ends before the rows held): the decay must be read again.
    """

    impact: Impact
    decay: DecayPass | None


def located_decay(
    blocks: Blocks, channels: int, dt: float, lo: int, hi: int, factor: int, cap: int
) -> LocatedDecay | None:
    """:func:`locate_impact` and :func:`decay_pass` in one read of a record (None as :func:`locate_impact`).

    Once rows ``lo:hi`` are held, the impact is found in them with the channels' peaks seen so
    far (the impact's own, usually the record's) and its decay is decimated from there as the
    rest arrives; at the end the impact is proved as :func:`locate_impact` proves it, and the
    decay kept when it started where the proved impact starts. The pre-trigger statistics merge
    the rows before `lo` as they arrive and the held ones before the onset at the end
    (:class:`DecayScan`).
    """
    scan = DecayScan(channels, dt, lo, hi, cap, lambda final: factor)
    for values in blocks:
        scan.push(values)
    return scan.finish()


class DecayScan:
    """:func:`located_decay` fed block by block; the fit's factor asked for as the decay arrives.

    Parameters
    ----------
    channels : int
        Columns of every block.
    dt : float
        Sample interval (s).
    lo, hi : int
        The raw rows held (where the impact and the largest energy must lie).
    cap : int
        Decimated decay rows kept at most.
    factor : callable
        ``factor(final)``: the fit's decimation factor, or None while it is not known yet (the
        decay's rows are then held until it is; with ``final`` true it must answer). A first read
        decides it while reading (:class:`StreamingDecimation`'s capture).
    guess : Impact, optional
        Where the impact is expected (the head's, found on the same raw rows): its decay is read
        from the first block on, and kept when the impact proved at the end is this one.
        Default: found in rows ``lo:hi`` once they are held (:func:`located_decay`).
    """

    def __init__(self, channels: int, dt: float, lo: int, hi: int, cap: int,
                 factor: Callable[[bool], int | None], guess: Impact | None = None) -> None:  # fmt: skip
        self.scan = _WindowScan(channels, lo, hi)
        self.pre = _Moments(channels)
        self.dt, self.lo, self.hi, self.cap, self.ask = dt, lo, hi, cap, factor
        self.feed: _DecayFeed | None = None
        self.guess = guess
        self.pending: list[Array] = []  # decay rows held until the factor is known
        self.factor = 0  # the factor the decay is read at (0: not yet)

    def push(self, values: Array) -> None:
        """Take the next block of raw rows (in order)."""
        scan, lo, hi = self.scan, self.lo, self.hi
        row = scan.add(values)
        if row < lo:
            self.pre.add(values[: min(scan.row, lo) - row])
        if self.guess is not None:
            self._decay(values, row)
        elif scan.row >= hi and scan.held:
            self._guess(np.concatenate(scan.held))
            self._decay(values[hi - row :], hi)

    def _guess(self, window: Array) -> None:
        """The impact found in the rows held, its decay among them read."""
        found = _in_window(window, self.scan.peaks, self.dt, self.lo)
        self.guess = Impact(-1, -1, -1) if found is None else found[0]  # none: nothing is read
        if found is not None:
            self._decay(window, self.lo)

    def _decay(self, values: Array, first: int) -> None:
        """Rows ``first ...`` of the record: those of the guessed decay read (held until the factor is known)."""
        assert self.guess is not None
        if self.guess.start < 0:
            return
        part = values[max(0, self.guess.start - first) :]
        if part.shape[0] == 0 or (self.feed is not None and self.feed.held >= self.cap):
            return
        if self.feed is None:
            q = self.ask(False)
            if q is None:
                self.pending.append(np.array(part, dtype=float))
                return
            self._start(q)
        assert self.feed is not None
        self.feed.push(part)

    def _start(self, q: int) -> None:
        self.factor, self.feed = q, _DecayFeed(q, self.scan.peaks.shape[0], self.cap)
        for part in self.pending:
            self.feed.push(part)
        self.pending.clear()

    def finish(self, dt: float | None = None) -> LocatedDecay | None:
        """The end of the record: :func:`located_decay`'s answer (`dt`: the interval to prove the impact with)."""
        scan, lo = self.scan, self.lo
        if not scan.held:
            return None
        window = np.concatenate(scan.held)
        if self.guess is None:  # the record ended inside the window
            self._guess(window)
        if self.feed is None and self.guess is not None and self.guess.start >= 0:
            self._start(int(self.ask(True) or 1))
        impact = _proved(window, scan.peaks, scan.before, scan.after, self.dt if dt is None else dt, lo)
        if impact is None:
            return None
        if self.feed is None or self.guess != impact or impact.onset - 2 < lo:
            return LocatedDecay(impact, None)
        self.pre.add(window[: impact.onset - 2 - lo])
        pre = self.pre
        return LocatedDecay(impact, DecayPass(scan.row, pre.count, pre.m2, self.feed.finish(), pre.held()))


def located_decays(
    records: Callable[[int], Blocks],
    rows: Sequence[int],
    channels: int,
    dt: float,
    near: Sequence[Impact],
    reach: int,
    factor: int,
) -> tuple[list[Impact], list[DecayPass] | None, int] | None:
    """:func:`locate_impacts` and :func:`prepared_decays`'s reading in one read of each record.

    Parameters
    ----------
    records, channels, dt, near, reach
        As for :func:`locate_impacts`.
    rows, factor
        As for :func:`prepared_decays`.

    Returns
    -------
    (list of Impact, list of DecayPass or None, int) or None
        None when :func:`locate_impacts` would give None. Otherwise the impacts,
        each record's :class:`DecayPass` at the fit's factor and that factor
        (:func:`prepared_from` makes them :func:`prepared_decays`'s answer, the
        factor chosen from `rows`); the passes are None when a record's decay could
        not be read on the way (:func:`located_decay`) or the rows counted ask a
        factor more than :data:`_FACTOR_SLACK` away: the caller reads them again
        (:func:`prepared_decays`).
    """
    cap = MAX_ROWS // channels + 1
    q = fit_factor([n - i.start for n, i in zip(rows, near, strict=True)], channels, max(1, factor))
    found: list[Impact] = []
    passes: list[DecayPass] = []
    for i, impact in enumerate(near):
        lo, hi = max(0, impact.onset - reach), impact.start + max(reach, AFTER_ROWS)
        one = located_decay(records(i), channels, dt, lo, hi, q, cap)
        if one is None:
            return None
        found.append(one.impact)
        if one.decay is not None:
            passes.append(one.decay)
    if len(passes) < len(near):
        return found, None, q
    counted = fit_factor([p.rows - f.start for p, f in zip(passes, found, strict=True)], channels, max(1, factor))
    return found, (passes if abs(counted - q) <= _FACTOR_SLACK * counted else None), q


def captured_decays(
    captured: Sequence[CapturedDecay], channels: int, factor: int, near: Sequence[Impact], reach: int
) -> tuple[list[Impact], list[DecayPass], int] | None:
    """:func:`located_decays`'s answer from the decays a first read captured (None: read the records again).

    Parameters
    ----------
    captured : sequence of CapturedDecay
        Each record's, from :class:`StreamingDecimation` (its `capture` option).
    channels : int
        Columns of every record.
    factor : int
        The modal estimate's total decimation factor.
    near : sequence of Impact
        Where the modal estimate put each impact (raw rows).
    reach : int
        Raw rows the captured impact may lie from `near`'s (:func:`locate_impacts`).

    Returns
    -------
    (list of Impact, list of DecayPass, int) or None
        The impacts, the passes and their common factor, as :func:`located_decays` gives them; None
        when the records' factors differ, an impact lies farther than `reach` from the estimate's
        (the head held another hit), the factor read exceeds `factor` (it would cut into the band),
        or it exceeds the one the rows counted ask by more than :data:`_FACTOR_SLACK` (a CSV's rows
        overestimated from its size: the decays would be shorter than the row budget).

    Notes
    -----
    The factor read may be smaller than the rows counted ask: the first read chose it before
    the estimation decimated beyond the reader's own factor (:class:`StreamingDecimation`'s
    `capture`). The decays are then cut at the row budget
    (:func:`~rigidid.core.timedomain.refine.cut_decays`), as a whole read cuts them when its
    factor is capped by the estimate's: the same rows budget, at a finer rate over a shorter
    span of the decay (its end, which holds the least signal).
    """
    if len(captured) != len(near) or not captured:
        return None
    q = captured[0].factor
    if any(c.factor != q for c in captured):
        return None
    if any(abs(c.impact.start - n.start) > reach or abs(c.impact.onset - n.onset) > reach
           for c, n in zip(captured, near, strict=True)):  # fmt: skip
        return None
    counted = fit_factor([c.decay.rows - c.impact.start for c in captured], channels, max(1, factor))
    if q > max(1, factor) or q - counted > _FACTOR_SLACK * counted:
        return None
    return [c.impact for c in captured], [c.decay for c in captured], q


_FACTOR_SLACK = 0.1
"""A one-pass read keeps the fit's factor chosen from the rows as known before reading (a CSV's
estimated from its size) when the rows counted ask one at most this fraction away: the decays are
then at most a tenth longer (their end cut, :func:`~rigidid.core.timedomain.refine.cut_decays`) or
shorter than the budget. Re-reading a 530 MB CSV for a factor of 53 instead of 52 doubled the refit's
reading."""


def hann_window(n: int) -> Array:
    """The periodic Hann window of `n` samples (``scipy.signal.get_window("hann", n)``): Welch's segments'."""
    k = np.arange(n)
    return np.asarray(0.5 - 0.5 * np.cos(2.0 * np.pi * k / n))


def record_power(blocks: Blocks, channels: int, window: Array) -> Array:
    """Sum over channels of the mean of ``|rfft((x_s - mean) w)|^2`` over every Welch segment of one record.

    Parameters
    ----------
    blocks : iterable of ndarray, shape (rows, channels)
        The record, in order.
    channels : int
        Columns of every block.
    window : ndarray, shape (n,)
        The segment's window (its length is the segment's); segments overlap by half.

    Raises
    ------
    ValueError
        A record shorter than one segment.
    """
    n = window.shape[0]
    step = n - n // 2
    power = np.zeros((n // 2 + 1, channels))
    count = 0
    buffer = np.empty((0, channels))
    base = 0  # row of buffer[0]
    following = 0  # row of the next segment's start
    for values in blocks:
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
        raise ValueError(f"shorter than one segment of {n} rows")
    return np.asarray(power.sum(axis=1) / count)


def power_density(total: Array, window: Array, dt: float) -> tuple[Array, Array]:
    """Frequencies and the one-sided density from the summed :func:`record_power` of the records.

    Returns
    -------
    frequency_hz : ndarray, shape (n // 2 + 1,)
    power : ndarray, shape (n // 2 + 1,)
        Summed one-sided power spectral density (channel unit squared per Hz),
        as :func:`rigidid.core.spectrum.summed_spectrum`.
    """
    n = window.shape[0]
    density = total / ((1.0 / dt) * float(np.sum(window * window)))
    density[1 : (n + 1) // 2] *= 2.0  # one-sided: DC (and Nyquist for even n) once
    return np.asarray(np.fft.rfftfreq(n, dt), dtype=float), density
