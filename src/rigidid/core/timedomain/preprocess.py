"""From a raw impact record to the free decay the estimators fit.

Steps, each usable on its own: find the impact (:func:`find_impact`), keep the
free decay after it (:func:`free_decay`), choose a decimation factor from the
spectrum (:func:`auto_decimation`) and decimate with a zero-phase anti-alias
filter (:func:`decimate`), and optionally band-limit (:func:`band_limit`).

Records are 2-D arrays, samples by channels. Functions work channel by channel
where an operation would otherwise copy the whole record, so a long record
needs little more memory than itself.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from rigidid.errors import InputError

__all__ = [
    "FIR_HALF_LENGTH",
    "Decimator",
    "Impact",
    "auto_decimation",
    "band_limit",
    "channel_energy",
    "column_peaks",
    "content_from_spectrum",
    "content_range",
    "content_spectrum",
    "decimate",
    "decimation_for",
    "find_impact",
    "fir_taps",
    "free_decay",
    "last_hit",
    "segment_power",
]

Array = NDArray[np.float64]

FIR_HALF_LENGTH = 10
"""Half length of the anti-alias FIR filter, in output samples (scipy's default)."""


@dataclass(frozen=True)
class Impact:
    """Where the impact and the free decay are in a record.

    Attributes
    ----------
    onset : int
        First sample whose energy exceeds the detection threshold.
    peak : int
        Sample of largest energy within the pulse window after `onset`.
    start : int
        First sample of the free decay (a little after `peak`, or after the last
        hit's peak when the record holds several: :func:`last_hit`).
    hits : int
        Hits found (1: a clean impact; more: a double hit, the decay taken after the last).
    """

    onset: int
    peak: int
    start: int
    hits: int = 1


_ENERGY_BLOCK = 1 << 16

CONTENT_ROWS = 1 << 16
"""Rows of each free decay the content spectrum is estimated from, at most (``2^16``)."""
"""Values per row block of :func:`channel_energy` (512 kB of float64)."""


def channel_energy(record: Array, peaks: Array | None = None) -> Array:
    """Sum over channels of the squared samples, each channel scaled by its peak.

    Parameters
    ----------
    record : ndarray, shape (n, p)
        Samples by channels.
    peaks : ndarray, shape (p,), optional
        ``column_peaks(record)`` when the caller has them.

    Returns
    -------
    ndarray, shape (n,)
        ``sum_i (x_i[t] / max |x_i|)^2`` (channels that are all zero add 0), so
        that a channel in large units does not drown the others.

    Notes
    -----
    Two passes (:func:`column_peaks`, then the squares of each row block
    times the weights), with no temporary the size of the record: the one
    channel-energy routine of rigidid (impact location and the reader's
    decay check both use it).
    """
    n, p = record.shape
    energy = np.zeros(n)
    if n == 0 or p == 0:
        return energy
    peak = column_peaks(record) if peaks is None or peaks.shape != (p,) else peaks
    # row blocks that stay in cache: squares, then one matrix-vector product with the weights
    # (twice as fast as one einsum pass over narrow rows)
    # each channel scaled by its peak before squaring: records near 1e300 or 1e-300 neither overflow nor underflow
    scale = np.divide(1.0, peak, out=np.zeros(p), where=peak > 0.0)
    ones = np.ones(p)
    step = max(1, _ENERGY_BLOCK // max(p, 1))
    scratch = np.empty((min(step, n), p))
    for lo in range(0, n, step):
        block = record[lo : lo + step]
        squares = scratch[: block.shape[0]]
        np.multiply(block, scale, out=squares)
        np.multiply(squares, squares, out=squares)
        np.dot(squares, ones, out=energy[lo : lo + block.shape[0]])
    return energy


def energy_bound(maxima: Array, peaks: Array) -> Array:
    """The largest :func:`channel_energy` any row can have, from its rows' ``max |x|`` per channel.

    Parameters
    ----------
    maxima : ndarray, shape (m, p)
        ``max |x|`` per channel of each of m groups of rows.
    peaks : ndarray, shape (p,)
        ``max |x|`` per channel of the whole record (the energy's weights).

    Returns
    -------
    ndarray, shape (m,)
        ``sum_i (maxima[b, i] / peaks[i])^2``: no row of group ``b`` has a larger energy.
    """
    scaled = maxima * np.divide(1.0, peaks, out=np.zeros(peaks.shape[0]), where=peaks > 0.0)
    bound: Array = np.sum(scaled * scaled, axis=1)
    return bound


def column_peaks(record: Array) -> Array:
    """``max |x|`` of every column, shape (p,), without a temporary the size of the record.

    Blocks of rows (about 65536 values) take their absolute values into one
    scratch array, viewed ``k`` rows at a time as one long row (``k p``
    values), so the reduction runs along long contiguous rows (a reduction
    over axis 0 of a narrow C-ordered array is several times slower). NaN
    and infinities reach the result.
    """
    return block_peaks(record)[0]


def block_peaks(record: Array) -> tuple[Array, Array, int]:
    """:func:`column_peaks`, and the same maxima per block of rows (one pass).

    Parameters
    ----------
    record : ndarray, shape (n, p)
        Samples by channels.

    Returns
    -------
    peaks : ndarray, shape (p,)
        ``max |x|`` of every column.
    maxima : ndarray, shape (ceil(n / rows), p)
        ``max |x|`` of every column over rows ``b rows ... (b + 1) rows - 1``.
    rows : int
        Rows per block (about 65536 values per block).
    """
    n, p = record.shape
    if n == 0:
        return np.zeros(p), np.zeros((0, p)), 1
    k = max(1, min(n, 4096 // max(p, 1)))
    step = max(k, (_ENERGY_BLOCK // max(p, 1)) // k * k)
    whole = n // k * k
    maxima = np.zeros((-(-n // step), p))
    scratch = np.empty((min(step, whole), p))
    for b, start in enumerate(range(0, whole, step)):
        block = record[start : min(start + step, whole)]
        values = scratch[: block.shape[0]]
        np.abs(block, out=values)
        maxima[b] = values.reshape(-1, k * p).max(axis=0).reshape(k, p).max(axis=0)
    if whole < n:  # the last rows (fewer than k) belong to the last block
        maxima[-1] = np.maximum(maxima[-1], np.abs(record[whole:]).max(axis=0))
    peaks: Array = maxima.max(axis=0)
    return peaks, maxima, step


def impact_from_blocks(
    record: Array,
    dt: float,
    peaks: Array,
    maxima: Array,
    rows: int,
    *,
    threshold: float = 0.01,
    pulse_width: float = 0.005,
) -> Impact:
    """:func:`find_impact` from :func:`block_peaks`, computing the energy of few rows.

    Parameters
    ----------
    record : ndarray, shape (n, p)
        Samples by channels.
    dt : float
        Sample interval (s).
    peaks, maxima, rows
        From :func:`block_peaks`.
    threshold, pulse_width : float
        As for :func:`find_impact`.

    Returns
    -------
    Impact
        The impact :func:`find_impact` finds.

    Raises
    ------
    InputError
        If the record is empty or all zero.

    Notes
    -----
    No row of block ``b`` has an energy (:func:`channel_energy`) above
    ``U_b = sum_i (maxima[b, i] / peaks[i])^2``. The largest energy is sought
    only in the blocks whose bound exceeds the largest energy found so far
    (blocks by descending bound), the onset only in the blocks whose bound
    exceeds ``threshold`` times it, in order, and the peak in the pulse
    window after the onset: on an impact record a small part of the rows,
    where :func:`find_impact` needs the energy of every row.
    """
    n = record.shape[0]
    bound = energy_bound(maxima, peaks)

    def energy(lo: int, hi: int) -> Array:
        return channel_energy(record[lo:hi], peaks)

    top = 0.0
    for b in np.argsort(-bound, kind="stable").tolist():
        if bound[b] <= top:
            break
        top = max(top, float(energy(b * rows, min(n, (b + 1) * rows)).max()))
    if n == 0 or top <= 0.0:
        raise InputError("the record is empty or all zero")
    onset = -1
    for b in np.flatnonzero(bound > threshold * top).tolist():
        hits = np.flatnonzero(energy(b * rows, min(n, (b + 1) * rows)) > threshold * top)
        if hits.size:
            onset = b * rows + int(hits[0])
            break
    return _after_onset(onset, lambda window: energy(onset, onset + window), dt, pulse_width, n,
                        lambda lo, hi: record[lo:hi])  # fmt: skip


def _after_onset(
    onset: int, pulse: Callable[[int], Array], dt: float, pulse_width: float, n: int, rows: Callable[[int, int], Array]
) -> Impact:
    """The impact whose onset is `onset`: the energy peak in the pulse window after it (``pulse(window)``
    gives the energy of those rows), the decay half a window after the peak (:func:`find_impact`'s rule),
    or half a window after the last hit's peak when :func:`last_hit` finds more (``rows(lo, hi)``: the
    record's rows)."""
    window = max(2, round(pulse_width / dt))
    peak = onset + int(np.argmax(pulse(window)))
    base = max(0, onset - _HIT_BEFORE)  # the predictor of last_hit needs rows before the first hit
    span = rows(base, min(n, onset + window + min(round(HIT_SPAN / dt), _HIT_ROWS)))
    later = last_hit(span, peak - base, window)
    if later is None:
        return Impact(onset, peak, min(peak + max(1, window // 2), n - 1))
    hits, last = later
    return Impact(onset, peak, min(base + last + max(1, window // 2), n - 1), hits)


HIT_SPAN = 1.0
"""Time after an impact searched for further hits (s): a hammer's bounce comes within it."""

_HIT_BEFORE = 16  # rows before the onset given to last_hit
_HIT_ROWS = 1 << 16  # at most these rows searched (memory: their second difference)
_HIT_LEVEL = 0.01  # a later hit's innovation energy is at least this fraction of the first's
_HIT_NOISE = 30.0  # ... and this many times the median innovation energy of the decay (about p / 2)


def _innovations(rows: Array, start: int) -> Array:
    """Per row, the energy of the one-step prediction error of a free decay fitted to ``rows[start:]``.

    Each channel is predicted from the previous ``L`` rows of every channel and a constant (a
    free decay of eq. (19) of [1]: 12 states seen through p channels, ``L p >= 12``), by least
    squares on the rows from `start`; the errors are scaled by each channel's median absolute
    error over those rows, squared and summed.
    """
    n, p = rows.shape
    lags = max(2, -(-13 // max(p, 1)))
    if n - start < 4 * (lags * p + 1) or start < lags:
        return np.zeros(0)
    top = float(np.max(np.abs(rows)))
    if top > 0.0:  # by a power of two, exactly: squares of records of 1e300 or 1e-300 stay finite
        rows = np.ldexp(rows, -int(np.frexp(top)[1]))
    design = np.hstack([rows[lags - k - 1 : n - k - 1] for k in range(lags)] + [np.ones((n - lags, 1))])
    target = rows[lags:]
    fit = slice(start - lags, None)
    scale = np.sqrt(np.sum(design[fit] ** 2, axis=0))
    scale = np.where(scale > 0.0, scale, 1.0)
    coef = np.linalg.lstsq(design[fit] / scale, target[fit], rcond=None)[0] / scale[:, None]
    err = target - design @ coef
    mad = np.median(np.abs(err[fit]), axis=0)
    floor = 1e-12 * np.max(np.abs(rows), axis=0)
    err = err / np.maximum(mad, np.where(floor > 0.0, floor, 1.0))
    out = np.zeros(n)
    out[lags:] = np.einsum("ij,ij->i", err, err)
    return out


def last_hit(rows: Array, peak: int, window: int) -> tuple[int, int] | None:
    """Hits after the first in the rows of an impact: their number and the last one's peak.

    Parameters
    ----------
    rows : ndarray, shape (m, p)
        The record from a little before the first hit's onset on (over :data:`HIT_SPAN`).
    peak : int
        The first hit's energy peak (row of `rows`).
    window : int
        The pulse window (samples).

    Returns
    -------
    (int, int) or None
        The number of hits and the row of `rows` where the last one peaks; None for one hit.

    Notes
    -----
    Between hits a record is a free decay of the rigid-body modes (eq. (19) of [1]): each
    sample follows linearly from the previous few. A hit is a force the decay does not
    predict, so it stands out in the one-step prediction error of a linear predictor
    fitted to the decay after the first hit (:func:`_innovations`; the few rows of a later
    hit hardly move the least-squares fit). A later hit is a row whose prediction-error
    energy exceeds :data:`_HIT_LEVEL` times the first hit's and :data:`_HIT_NOISE` times the
    decay's median (the noise: about p / 2 there); one pulse window after each hit found,
    the search goes on.
    """
    start = min(peak + window, rows.shape[0])
    e = _innovations(rows, start)
    if e.size == 0:
        return None
    first = float(e[:start].max())
    level = max(_HIT_LEVEL * first, _HIT_NOISE * float(np.median(e[start:])))
    found = np.flatnonzero(e[start:] > level)
    if not found.size:
        return None
    hits, last, pos = 1, start, start
    for row in (start + found).tolist():
        if row < pos:
            continue
        top = row + int(np.argmax(e[row : row + window]))
        hits, last, pos = hits + 1, top, top + window
    return hits, last


def find_impact(
    record: Array,
    dt: float,
    *,
    threshold: float = 0.01,
    pulse_width: float = 0.005,
    energy: Array | None = None,
) -> Impact:
    """Locate the impact in a record and the start of the free decay after it.

    Parameters
    ----------
    record : ndarray, shape (n, p)
        Samples by channels; pre-trigger samples before the impact may be present.
    dt : float
        Sample interval (s).
    threshold : float
        The impact is the first sample whose energy (see :func:`channel_energy`)
        exceeds `threshold` times the largest energy in the record: with the
        default, an amplitude of about 10 % of the peak.
    pulse_width : float
        Longest expected duration of the impact force (s). The energy peak is
        sought within this window after the onset, and the free decay starts
        half a window after that peak (at least one sample).
    energy : ndarray, shape (n,), optional
        ``channel_energy(record)`` when the caller has it already (the record
        reader computes it for its decay check), so it is computed once.

    Returns
    -------
    Impact

    Raises
    ------
    InputError
        If the record is empty or all zero.

    Notes
    -----
    On a record that already starts at the free decay the onset is at or near
    sample 0 and only the first half pulse window is dropped, which costs
    little: a free decay can start anywhere after the force has ended.
    """
    if energy is None or energy.shape != (record.shape[0],):
        energy = channel_energy(record)
    if energy.size == 0 or not np.any(energy > 0.0):
        raise InputError("the record is empty or all zero")
    top = float(energy.max())
    onset = int(np.argmax(energy > threshold * top))
    return _after_onset(onset, lambda window: energy[onset : onset + window], dt, pulse_width, record.shape[0],
                        lambda lo, hi: record[lo:hi])  # fmt: skip


def free_decay(record: Array, dt: float, *, pulse_width: float = 0.005) -> tuple[Array, Impact]:
    """The free-decay part of an impact record (a view, not a copy).

    Parameters
    ----------
    record : ndarray, shape (n, p)
        Samples by channels.
    dt : float
        Sample interval (s).
    pulse_width : float
        See :func:`find_impact`.

    Returns
    -------
    decay : ndarray, shape (n - start, p)
        ``record[start:]``.
    impact : Impact
        Where the impact was found.
    """
    impact = find_impact(record, dt, pulse_width=pulse_width)
    return record[impact.start :], impact


def content_range(records: Sequence[Array], dt: float, *, floor_factor: float = 3.0) -> tuple[float, float]:
    """Lowest and highest frequency at which the records stand out of their noise floor.

    Parameters
    ----------
    records : sequence of ndarray, shape (n_k, p)
        Free decays.
    dt : float
        Sample interval (s).
    floor_factor : float
        Content is significant where the summed, normalised power spectrum,
        smoothed over 5 bins, exceeds `floor_factor` times its median over
        frequency (the noise floor when the sample rate is well above the
        modes).

    Returns
    -------
    f_low, f_high : float
        First and last significant frequency (Hz), ignoring the two lowest
        bins (offsets and drift); ``(0, nyquist)`` if nothing stands out.

    Notes
    -----
    The spectrum is a Welch estimate (Hann window, segments of 4096 samples
    or the shortest record, overlapping by half, each channel scaled to unit
    variance) of at most the first :data:`CONTENT_ROWS` (2^16) samples of
    each record, so the cost does not grow with record length. The median is a fair noise floor only
    when most of the band holds no mode; otherwise `f_high` comes out high,
    which is the safe side for decimation.
    """
    freqs, total = content_spectrum(records, dt)
    return content_from_spectrum(freqs, total, 0.5 / dt, floor_factor=floor_factor)


def content_spectrum(records: Sequence[Array], dt: float) -> tuple[Array, Array]:
    """The summed, normalised Welch spectrum :func:`content_range` judges.

    Parameters
    ----------
    records : sequence of ndarray, shape (n_k, p)
        Free decays.
    dt : float
        Sample interval (s).

    Returns
    -------
    freqs, total : ndarray, shape (m,)
        Frequencies (Hz) and the spectrum summed over records and channels
        (empty when no record has 64 samples). Spectra of records read apart
        with the same segment length add up: the record reader computes one
        per record as it reads and the estimation adds them.
    """
    parts = [rec[:CONTENT_ROWS] for rec in records if rec.shape[0] >= 64]
    if not parts:
        return np.zeros(0), np.zeros(0)
    seg = min(4096, *(part.shape[0] for part in parts))
    window = np.hanning(seg + 2)[1:-1]
    total = np.zeros(seg // 2 + 1)
    freqs: Array = np.asarray(np.fft.rfftfreq(seg, dt), dtype=float)
    for part in parts:
        starts = np.arange(0, part.shape[0] - seg + 1, seg // 2)
        var = _row_blocked_variance(part)
        keep = np.flatnonzero(var > 0.0)
        if keep.size == 0:
            continue
        power = segment_power(part if keep.size == part.shape[1] else part[:, keep], starts, window)
        total += (power / starts.size / var[keep]).sum(axis=1)
    return freqs, total


def segment_power(part: Array, starts: NDArray[np.intp], window: Array) -> Array:
    """Summed power spectra of windowed, mean-removed segments of every column.

    Parameters
    ----------
    part : ndarray, shape (n, p)
        Samples by channels.
    starts : ndarray of int
        First row of each segment (each ``start + len(window) <= n``).
    window : ndarray, shape (seg,)
        The window (Hann in :func:`content_spectrum`).

    Returns
    -------
    ndarray, shape (seg // 2 + 1, p)
        ``sum_s |rfft((x_s - mean(x_s)) window)|^2`` per channel.

    Notes
    -----
    All channels at once, a few segments at a time (about 4 MB of
    temporaries per batch, rows read contiguously).
    """
    seg = window.shape[0]
    power = np.zeros((seg // 2 + 1, part.shape[1]))
    batch = max(1, (1 << 19) // (seg * max(part.shape[1], 1)))
    for lo in range(0, starts.size, batch):
        segments = part[starts[lo : lo + batch, None] + np.arange(seg)]  # (segments, seg, channels)
        segments -= segments.mean(axis=1, keepdims=True)
        segments *= window[:, None]
        spectra = np.fft.rfft(segments, axis=1)
        power += np.sum(spectra.real**2 + spectra.imag**2, axis=0)
    return power


def _row_blocked_variance(part: Array) -> Array:
    """Per-column variance (two passes: mean, then squared deviations) over blocks of rows."""
    n, p = part.shape
    step = max(1, _ENERGY_BLOCK // max(p, 1))
    total = np.zeros(p)
    for start in range(0, n, step):
        total += part[start : start + step].sum(axis=0)
    mean = total / n
    squares = np.zeros(p)
    for start in range(0, n, step):
        centred = part[start : start + step] - mean
        squares += np.einsum("ij,ij->j", centred, centred)
    result: Array = squares / n
    return result


def content_from_spectrum(
    freqs: Array, total: Array, nyquist: float, *, floor_factor: float = 3.0
) -> tuple[float, float]:
    """:func:`content_range` from a :func:`content_spectrum` (``(0, nyquist)`` if it is empty)."""
    if total.size == 0:
        return 0.0, nyquist
    smooth = np.convolve(total, np.ones(5) / 5.0, mode="same")
    floor = float(np.median(smooth))
    significant = np.flatnonzero(smooth[2:] > floor_factor * floor) + 2
    if significant.size == 0 or floor <= 0.0:
        return 0.0, nyquist
    return float(freqs[significant[0]]), float(freqs[significant[-1]])


def auto_decimation(records: Sequence[Array], dt: float, *, margin: float = 4.0) -> int:
    """A decimation factor that keeps every mode well below the new Nyquist frequency.

    Parameters
    ----------
    records : sequence of ndarray, shape (n_k, p)
        Free decays.
    dt : float
        Sample interval (s).
    margin : float
        The new Nyquist frequency is at least `margin` times the highest
        significant frequency of :func:`content_range`.

    Returns
    -------
    int
        Factor ``q >= 1``; 1 when the content reaches near the Nyquist frequency.
    """
    f_high = content_range(records, dt)[1]
    return decimation_for(f_high, dt, margin=margin)


def decimation_for(f_high: float, dt: float, *, margin: float = 4.0) -> int:
    """Largest factor ``q`` with the new Nyquist frequency ``1 / (2 q dt) >= margin * f_high``.

    Parameters
    ----------
    f_high : float
        Highest frequency to keep (Hz).
    dt : float
        Sample interval (s).
    margin : float
        Ratio of the new Nyquist frequency to `f_high`.

    Returns
    -------
    int
        At least 1.
    """
    if f_high <= 0.0:
        return 1
    return max(1, int(0.5 / (dt * margin * f_high)))


def fir_taps(factor: int) -> Array:
    """Anti-alias FIR filter of :func:`decimate`.

    Parameters
    ----------
    factor : int
        Decimation factor ``q >= 2``.

    Returns
    -------
    ndarray, shape (20 q + 1,)
        Hamming-windowed sinc, cut-off at the new Nyquist frequency, unit gain
        at 0 Hz: the filter ``scipy.signal.decimate(..., ftype="fir")`` designs
        (``firwin(20 q + 1, 1 / q, window="hamming")``).
    """
    half = FIR_HALF_LENGTH * factor
    t = np.arange(-half, half + 1) / factor
    taps = np.sinc(t) * np.hamming(2 * half + 1)
    result: Array = taps / taps.sum()
    return result


def decimate(record: Array, factor: int) -> Array:
    """Low-pass filter and keep every `factor`-th sample, zero phase.

    Parameters
    ----------
    record : ndarray, shape (n, p)
        Samples by channels.
    factor : int
        Decimation factor ``q >= 1`` (1 returns the record unchanged).

    Returns
    -------
    ndarray, shape (n // q - 2 * FIR_HALF_LENGTH - 1, p)
        Samples ``k q`` of the filtered record for the ``k`` where the filter
        lies wholly inside the record (:data:`FIR_HALF_LENGTH` output samples
        are lost at each end).

    Raises
    ------
    InputError
        If the record is too short for the filter.

    Notes
    -----
    The filter is :func:`fir_taps`, the linear-phase FIR filter of
    ``scipy.signal.decimate(x, q, ftype="fir", zero_phase=True)``, centred on
    each kept sample (so zero phase) and evaluated only at the kept samples
    (polyphase: cost ``21 n p`` multiply-adds whatever `q`, no copy of the
    record). Unlike an IIR anti-alias filter it adds no poles of its own that
    could pass as lightly damped modes. Every channel gets the same filter,
    so mode shapes are unchanged; content above about 0.8 of the new Nyquist
    frequency is attenuated, content above it folds back attenuated by 40 dB
    or more. Implemented with numpy to spare the import of ``scipy.signal``.
    """
    if factor <= 1:
        return record
    return _filter_and_keep(record, fir_taps(factor), FIR_HALF_LENGTH, factor)


def _filter_and_keep(record: Array, kernel: Array, half: int, factor: int) -> Array:
    """Samples ``(k + half) factor`` of `record` filtered by the odd-length `kernel` centred on them.

    The kernel lies in ``2 half + 1`` phases of `factor` taps (centre at
    ``half factor``); outputs are kept where the phases lie wholly inside the
    record (``half`` blocks lost at the start, ``half + 1`` at the end).
    """
    blocks = record.shape[0] // factor
    stop = blocks - half - 1
    if stop <= half:
        raise InputError(f"the record is too short to decimate by {factor} ({record.shape[0]} samples)")
    taps = np.zeros((2 * half + 1) * factor)
    lead = half * factor - (kernel.size - 1) // 2
    taps[lead : lead + kernel.size] = kernel
    cube = record[: blocks * factor].reshape(blocks, factor, record.shape[1])
    out = np.zeros((stop - half, record.shape[1]))
    _polyphase(taps.reshape(2 * half + 1, factor), cube, half, out)
    return out


PRESUM_ORDER = 3
"""Boxcars in the first stage of :func:`decimate_in_stages` (a third-order CIC filter)."""

_MIN_SECOND_STAGE = 4  # the FIR stage of decimate_in_stages decimates by at least this
_MIN_STAGED = 12  # factors below this are decimated in one stage


def stage_factors(factor: int, *, exact: bool = False) -> tuple[int, int]:
    """Split a decimation factor into a cheap first stage and an FIR second stage.

    Parameters
    ----------
    factor : int
        Decimation factor wanted, ``q >= 1``.
    exact : bool
        Keep `factor` itself (a factor the user chose): split it only into an
        odd divisor ``q1 >= 3`` and ``q2 = q / q1 >= 4``, the largest such
        ``q1``. Otherwise the first stage takes the largest odd
        ``q1 <= q / 4`` and the second ``q2 = floor(q / q1)``: the product may
        come out below `factor` (by a fifth at most), which is the safe side
        for an automatic factor, and the first stage does the most of the
        work at the least cost.

    Returns
    -------
    (q1, q2) : tuple of int
        ``q1`` odd (``1``: one stage, ``q2 = factor``), ``q2 >= 4``,
        ``q1 q2 <= factor``. One stage below 12.

    Examples
    --------
    >>> stage_factors(42), stage_factors(156), stage_factors(11), stage_factors(42, exact=True)
    ((9, 4), (39, 4), (1, 11), (7, 6))
    """
    q = int(factor)
    if q < _MIN_STAGED:
        return 1, max(q, 1)
    if not exact:
        q1 = q // _MIN_SECOND_STAGE
        q1 -= 1 - q1 % 2
        return q1, q // q1
    for q1 in range(q // _MIN_SECOND_STAGE, 2, -1):
        if q1 % 2 == 1 and q % q1 == 0:
            return q1, q // q1
    return 1, q


def presum(record: Array, factor: int) -> Array:
    """Decimate by a third-order CIC filter: three boxcars of `factor` samples, zero phase.

    Parameters
    ----------
    record : ndarray, shape (n, p)
        Samples by channels.
    factor : int
        Odd decimation factor ``q1 >= 3``.

    Returns
    -------
    ndarray, shape (n // q1 - 5, p)
        Samples ``(k + 2) q1`` of the record filtered by the normalised
        quadratic B-spline of ``3 q1 - 2`` taps centred on them.

    Notes
    -----
    The first stage of :func:`decimate_in_stages`: 5 multiply-adds per
    sample and channel (the FIR filter of :func:`decimate` takes 21). Its
    response ``(sin(pi f q1 / fs) / (q1 sin(pi f / fs)))^3`` is zero at every
    multiple of the new sample rate, so what folds onto the band the second
    stage keeps (a quarter of the first stage's Nyquist frequency or less)
    comes from near those zeros: attenuated by 47 dB or more at that band's
    edge (51 dB for large ``q1``), 84 dB or more at a quarter of it, where
    :func:`decimation_for`'s margin puts the highest content. The passband
    droops (0.5 % at a quarter of the band's edge, 7.5 % at the edge): the
    same gain on every channel, which changes neither poles nor mode
    shapes.
    """
    q1 = int(factor)
    if q1 < 3 or q1 % 2 == 0:
        raise ValueError(f"the first-stage factor must be odd and at least 3, got {factor}")
    box = np.ones(q1)
    kernel = np.convolve(np.convolve(box, box), box)
    # phases a = -2..2 span 5 q1 >= 3 q1 - 2 taps around the centre 2 q1
    return _filter_and_keep(record, kernel / kernel.sum(), 2, q1)


def decimate_in_stages(record: Array, first: int, second: int) -> Array:
    """:func:`presum` by `first`, then :func:`decimate` by `second` (`first` 1: one stage).

    Parameters
    ----------
    record : ndarray, shape (n, p)
        Samples by channels.
    first, second : int
        The factors of :func:`stage_factors`.

    Returns
    -------
    ndarray, shape (m, p)
        The record at ``first * second`` times the sample interval: sample
        ``k`` is the filtered record at sample ``(H second + 2) first + k
        first second`` (``H`` = :data:`FIR_HALF_LENGTH`).

    Notes
    -----
    About 5 + 21 / `first` multiply-adds per sample and channel instead of
    :func:`decimate`'s 21 (at 42 = 7 x 6: 2.6 times fewer). The second stage
    is :func:`decimate`'s FIR filter, which sets the band's edge and the
    attenuation of what would fold onto it.

    Examples
    --------
    >>> t = np.arange(200_000) * 1e-4  # 10 kHz
    >>> x = np.stack([np.sin(2 * np.pi * 12.0 * t), np.cos(2 * np.pi * 30.0 * t)], axis=1)
    >>> q1, q2 = stage_factors(42)
    >>> y = decimate_in_stages(x, q1, q2)
    >>> rows = (FIR_HALF_LENGTH * q2 + 2) * q1 + q1 * q2 * np.arange(y.shape[0])
    >>> bool(np.max(np.abs(y - x[rows])) < 0.005)  # the signal at those samples, within the filters' ripple
    True
    """
    if first <= 1:
        return decimate(record, second)
    return decimate(presum(record, first), second)


_POLYPHASE_BLOCK = 1 << 18
"""Input values per row block of :func:`_polyphase` (2 MB: the block stays in cache for the 21 phases)."""


def _polyphase(phases: Array, cube: Array, first: int, out: Array) -> None:
    """``out[k] += sum_a phases[a + H] @ cube[first + k + a]``, in row blocks that stay in cache.

    ``phases`` has ``2 H + 1`` rows (``H`` = :data:`FIR_HALF_LENGTH` for
    :func:`decimate`, 2 for :func:`presum`). Each block of input rows is
    multiplied by all phases at once (one stacked matrix product,
    ``(2 H + 1, q) @ (q, p)`` per input block), then the phases' products are
    added in the order of ``a`` along the shifted rows; the block is finished
    while its input is in cache. :func:`decimate` and :class:`Decimator` both
    run through here, so they compute the same sums in the same order.
    """
    na = phases.shape[0]
    half = (na - 1) // 2
    n, q, p = out.shape[0], cube.shape[1], cube.shape[2]
    # at least 8 output rows per phase: the 2 H rows of the block's edges are multiplied twice
    step = max(8 * na, _POLYPHASE_BLOCK // max(1, q * p))
    scratch = np.empty((min(step, n) + 2 * half, na, p))
    for lo in range(0, n, step):
        hi = min(n, lo + step)
        products = scratch[: hi - lo + 2 * half]
        np.matmul(phases, cube[first + lo - half : first + hi + half], out=products)
        rows = out[lo:hi]
        for a in range(na):
            rows += products[a : a + hi - lo, a]


class Decimator:
    """:func:`decimate` fed chunk by chunk: the same output, memory bounded by the output.

    Parameters
    ----------
    factor : int
        Decimation factor ``q >= 1``.
    channels : int
        Columns of every chunk.

    Notes
    -----
    The raw rows a later output sample still needs (at most ``(2 H + 2) q``
    with ``H`` = :data:`FIR_HALF_LENGTH`) are carried from one chunk to the
    next, so :meth:`push` returns, and :meth:`finish` completes, exactly the
    samples ``decimate(record, factor)`` computes on the whole record: output
    ``k`` is produced as soon as raw block ``k + H + 1`` is complete, which is
    also the condition under which the whole-record filter keeps it. Chunk
    boundaries only change the order of floating-point sums (differences of
    order 1e-16 relative). With ``factor == 1`` chunks are passed through.

    Examples
    --------
    >>> x = np.random.default_rng(0).standard_normal((5000, 2))
    >>> d = Decimator(4, 2)
    >>> y = np.concatenate([d.push(x[:1234]), d.push(x[1234:]), d.finish()])
    >>> bool(np.allclose(y, decimate(x, 4), rtol=0.0, atol=1e-12))
    True
    """

    def __init__(self, factor: int, channels: int) -> None:
        self.factor = int(factor)
        self.channels = int(channels)
        taps = np.zeros((2 * FIR_HALF_LENGTH + 1) * max(self.factor, 1))
        if self.factor > 1:
            taps[: 2 * FIR_HALF_LENGTH * self.factor + 1] = fir_taps(self.factor)
        self._phases = taps.reshape(2 * FIR_HALF_LENGTH + 1, max(self.factor, 1))
        self._buffer = np.empty((0, self.channels))
        self._base = 0  # block index of the buffer's first row
        self._next = FIR_HALF_LENGTH  # next output sample
        self.rows_in = 0

    def push(self, chunk: Array) -> Array:
        """Feed the next raw rows; return the output samples they complete, shape (k, channels)."""
        self.rows_in += chunk.shape[0]
        if self.factor <= 1:
            return chunk
        q, half = self.factor, FIR_HALF_LENGTH
        buffer = np.concatenate([self._buffer, chunk]) if self._buffer.shape[0] else chunk
        blocks = buffer.shape[0] // q
        last = self._base + blocks - 2 - half  # last output whose blocks (up to k + H + 1) are complete
        out = np.zeros((max(0, last + 1 - self._next), self.channels))
        if out.shape[0]:
            cube = buffer[: blocks * q].reshape(blocks, q, self.channels)
            _polyphase(self._phases, cube, self._next - self._base, out)
            self._next += out.shape[0]
        keep = self._next - half - self._base  # first block still needed
        self._buffer = buffer[keep * q :].copy()
        self._base += keep
        return out

    def finish(self) -> Array:
        """End of the record: no further output (as :func:`decimate`, the last blocks are lost).

        Raises
        ------
        InputError
            If the record was too short for the filter.
        """
        if self.factor > 1 and self.rows_in // self.factor - FIR_HALF_LENGTH - 1 <= FIR_HALF_LENGTH:
            raise InputError(f"the record is too short to decimate by {self.factor} ({self.rows_in} samples)")
        return np.zeros((0, self.channels))


def band_limit(record: Array, dt: float, band: tuple[float, float], *, order: int = 4) -> Array:
    """Zero-phase Butterworth band-pass (or low/high-pass) filter, channel by channel.

    Parameters
    ----------
    record : ndarray, shape (n, p)
        Samples by channels.
    dt : float
        Sample interval (s).
    band : (float, float)
        Lower and upper edge (Hz). A lower edge of 0 gives a low-pass filter;
        an upper edge at or above the Nyquist frequency a high-pass one.
    order : int
        Butterworth order (applied forwards and backwards, so twice).

    Returns
    -------
    ndarray, shape (n, p)
        The filtered record (a new array).

    Notes
    -----
    Butterworth poles have damping ratios of 38 % and more (order 4), so the
    filter's own transients are not taken for lightly damped modes.
    """
    from scipy.signal import butter, sosfiltfilt

    nyquist = 0.5 / dt
    low, high = band
    has_low = low > 0.0
    has_high = high < 0.999 * nyquist
    if not has_low and not has_high:
        return record.copy()
    if has_low and has_high:
        sos = butter(order, [low, high], btype="bandpass", fs=1.0 / dt, output="sos")
    elif has_low:
        sos = butter(order, low, btype="highpass", fs=1.0 / dt, output="sos")
    else:
        sos = butter(order, high, btype="lowpass", fs=1.0 / dt, output="sos")
    out = np.empty_like(record)
    for i in range(record.shape[1]):
        out[:, i] = sosfiltfilt(sos, record[:, i])
    return out
