"""The refit's data read from record files in row blocks (the second pass of ``identify --records``).

The modal estimate (the first pass, :mod:`rigidid.io.records.streamed`) gives each
impact's onset and free-decay start in the files' rows and its decimation factor.
This pass reads every record file again, a block of rows at a time, and builds what
:func:`rigidid.core.timedomain.refine.prepare_decays` builds from whole records:

- the pre-trigger statistics (rows before ``onset - 2``): count and the sum of
  squared deviations from the record's own mean, per channel, merged block by
  block (Chan, Golub and LeVeque's pairwise update, so no cancellation);
- the decay ``decimate(record[start:], q)`` by a streaming
  :class:`~rigidid.core.timedomain.preprocess.Decimator` fed from row `start`
  (the same polyphase sums, so the same numbers up to the order of
  floating-point sums), at most :data:`~rigidid.core.timedomain.refine.MAX_ROWS`
  values of it held.

The fit's factor ``q`` (:func:`~rigidid.core.timedomain.refine.fit_factor`) depends
on the records' lengths: it is taken from the rows the file's header or size tells
and checked against the rows counted; when they ask another factor (a CSV whose
size misled) the files are read once more. Memory: one block of rows plus the
decays held, whatever the records' length. The records were checked by the first
pass; this one does not check them again.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from rigidid.core.timedomain.preprocess import Impact
from rigidid.io.records.streamed import open_source
from rigidid.progress import ProgressCallback

if TYPE_CHECKING:
    from rigidid.core.timedomain.refine import PreparedDecays

__all__ = ["locate_impacts", "read_prepared_decays"]

Array = NDArray[np.float64]

_THRESHOLD = 0.01  # find_impact's defaults, as the estimation uses them
_PULSE_WIDTH = 0.005
_CHUNK = 128  # rows per maximum kept outside the window (the energy bound's resolution)
AFTER_ROWS = 1 << 16
"""Raw rows held after the estimate's decay start (at least): where the largest channel energy is sought."""


def _chunk_maxima(mags: Array) -> Array:
    """``max |x|`` per channel of every :data:`_CHUNK` rows of `mags`, shape (chunks, p)."""
    n = mags.shape[0]
    whole = n // _CHUNK * _CHUNK
    parts = [mags[:whole].reshape(-1, _CHUNK, mags.shape[1]).max(axis=1)] if whole else []
    if whole < n:
        parts.append(mags[whole:].max(axis=0, keepdims=True))
    return np.concatenate(parts) if parts else np.zeros((0, mags.shape[1]))


def _locate_one(
    path: Path, wanted: list[str], dt: float, lo: int, hi: int, progress: ProgressCallback | None
) -> Impact | None:
    """:func:`find_impact` on the raw record, from its rows ``lo:hi`` and every block's maxima; None if unsure."""
    from rigidid.core.timedomain.preprocess import Impact, channel_energy, energy_bound, find_impact

    p = len(wanted)
    source = open_source(path, wanted, progress)
    peaks = np.zeros(p)
    held: list[Array] = []
    before: list[Array] = []  # max |x| per channel of each block part before the window
    after: list[Array] = []  # ... and after it
    row = 0
    for _, values in source.blocks:
        stop = row + values.shape[0]
        mags = np.abs(values)
        peaks = np.maximum(peaks, mags.max(axis=0))
        if row < lo:
            before.append(_chunk_maxima(mags[: min(stop, lo) - row]))
        if stop > lo and row < hi:
            held.append(np.array(values[max(0, lo - row) : min(stop, hi) - row], dtype=float))
        if stop > hi:
            after.append(_chunk_maxima(mags[max(0, hi - row) :]))
        row = stop
    if not held:
        return None
    window = np.concatenate(held)
    energy = channel_energy(window, peaks)
    top = float(energy.max()) if energy.size else 0.0
    if top <= 0.0:
        return None

    def bound(parts: list[Array]) -> float:  # no row of these chunks has a larger energy
        return float(max(energy_bound(m, peaks).max() for m in parts)) if parts else 0.0

    # the largest energy lies in the window, no row before it reaches the threshold
    if bound(after) > top or bound(before) > _THRESHOLD * top:
        return None
    found = find_impact(window, dt, threshold=_THRESHOLD, pulse_width=_PULSE_WIDTH, energy=energy)
    pulse = max(2, round(_PULSE_WIDTH / dt))
    if found.onset + pulse > window.shape[0] or found.start >= window.shape[0] - 1:
        return None  # the pulse window or the decay start run past the rows held
    return Impact(lo + found.onset, lo + found.peak, lo + found.start)


def locate_impacts(
    paths: Sequence[str | os.PathLike[str]],
    sensor_ids: Sequence[str],
    dt: float,
    near: Sequence[Impact],
    reach: int,
    *,
    progress: ProgressCallback | None = None,
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

    Returns
    -------
    list of Impact or None
        The raw records' impacts; None when the rows held cannot prove it
        (a larger energy, or one above the onset threshold, outside them):
        the caller then reads the records whole.

    Notes
    -----
    Per file, one pass holds the raw rows ``near.onset - reach ... near.start
    + max(reach, AFTER_ROWS)`` (the largest energy can come a cycle of the
    slowest mode after the impact) and, outside them, ``max |x|`` per channel
    of every 128 rows. The energy weights
    (``1 / max |x|`` per channel, :func:`channel_energy`) come from the whole
    record; the rows outside the window are bounded by their blocks' maxima, as
    :func:`~rigidid.core.timedomain.preprocess.impact_from_blocks` does.
    """
    from rigidid.io.records.read import layout_ids

    found = []
    for path, impact in zip(paths, near, strict=True):
        lo, hi = max(0, impact.onset - reach), impact.start + max(reach, AFTER_ROWS)
        one = _locate_one(Path(path), layout_ids(sensor_ids, str(path)), dt, lo, hi, progress)
        if one is None:
            return None
        found.append(one)
    return found


def _read_one(
    path: Path, wanted: list[str], start: int, pre_end: int, factor: int, cap: int, progress: ProgressCallback | None
) -> tuple[int, int, Array, Array]:
    """Rows counted, pre-trigger count, its squared deviations (p,), the decimated decay (at most `cap` rows)."""
    from rigidid.core.timedomain.preprocess import Decimator

    p = len(wanted)
    source = open_source(path, wanted, progress)
    stream = Decimator(factor, p)
    n_pre, mean, m2 = 0, np.zeros(p), np.zeros(p)
    parts: list[Array] = []
    held = 0
    row = 0
    for _, values in source.blocks:
        stop = row + values.shape[0]
        if row < pre_end:  # pre-trigger statistics, merged block by block
            x = values[: min(stop, pre_end) - row]
            n_b = x.shape[0]
            mean_b = x.mean(axis=0)
            m2_b = ((x - mean_b) ** 2).sum(axis=0)
            total = n_pre + n_b
            delta = mean_b - mean
            m2 = m2 + m2_b + delta**2 * (n_pre * n_b / total)
            mean = mean + delta * (n_b / total)
            n_pre = total
        if stop > start and held < cap:
            out = stream.push(values[max(0, start - row) :])
            if out.shape[0]:
                out = out[: cap - held]
                parts.append(np.array(out, dtype=float))
                held += out.shape[0]
        row = stop
    if held < cap:
        stream.finish()
    decay = np.concatenate(parts) if parts else np.zeros((0, p))
    return row, n_pre, m2, decay


def read_prepared_decays(
    paths: Sequence[str | os.PathLike[str]],
    sensor_ids: Sequence[str],
    dt: float,
    *,
    starts: Sequence[int],
    onsets: Sequence[int],
    factor: int,
    progress: ProgressCallback | None = None,
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

    Returns
    -------
    PreparedDecays
        The same as ``prepare_decays(records, dt, starts, onsets, factor)`` on
        the whole records.

    Raises
    ------
    InputError
        Records too short for the refinement (or for the fit's filter).
    """
    from rigidid.core.timedomain.refine import MAX_ROWS, PreparedDecays, cut_decays, fit_factor, pretrigger_sigma
    from rigidid.io.records.read import layout_ids

    files = [Path(p) for p in paths]
    p = len(sensor_ids)
    guess = []
    for path in files:
        wanted = layout_ids(sensor_ids, str(path))
        guess.append(open_source(path, wanted, None).rows)  # the header's rows (a CSV's: from its size)
    rows: list[int] = guess
    cap = MAX_ROWS // p + 1  # no decay keeps more (cut_decays)
    for _ in range(2):
        q = fit_factor([n - s for n, s in zip(rows, starts, strict=True)], p, max(1, factor))
        read = [
            _read_one(path, layout_ids(sensor_ids, str(path)), s, max(0, o - 2), q, cap, progress)
            for path, s, o in zip(files, starts, onsets, strict=True)
        ]
        counted = [r[0] for r in read]
        if fit_factor([n - s for n, s in zip(counted, starts, strict=True)], p, max(1, factor)) == q:
            break
        rows = counted
    decays = cut_decays([r[3] for r in read], p)
    sigma, noise_from = pretrigger_sigma([r[1] for r in read], [r[2] for r in read], len(files), q)
    return PreparedDecays(decays, sigma, dt * q, noise_from)
