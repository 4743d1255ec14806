"""Reading and writing impact records, ``records.csv``: one file per impact.

Format: a header ``time,<sensor id>,<sensor id>,...`` and one row per sample;
``time`` in seconds, uniformly sampled; every other column is a sensor id of
the layout, holding the acceleration that sensor reads along its own
direction. A record holds the free decay after one impact, possibly preceded
by pre-trigger samples.

:func:`read_record` validates once, here, and raises
:class:`~rigidid.errors.InputError` naming the file and the row (line number,
header = row 1) or column. :func:`write_record` is atomic: the file appears
whole or not at all.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.errors import InputError
from rigidid.io.atomic import atomic_path
from rigidid.io.binary_records import BINARY_SUFFIXES
from rigidid.io.columns import column as _column
from rigidid.io.columns import column_order
from rigidid.io.columns import row as _where

__all__ = [
    "DECAY_RATIO",
    "MIN_ROWS",
    "TIME_TOLERANCE",
    "read_record",
    "write_record",
]

Array = NDArray[np.float64]

TIME_TOLERANCE = 0.01
"""Largest relative deviation of a time step from the mean sample interval.

The mean interval is ``(t_last - t_first) / (n - 1)``. When the time column is
written with few digits, the rounding (half a unit of the last digit of the
last row's time, twice) is allowed on top."""

DECAY_RATIO = 0.5
"""A record decays when, after its energy peak, the RMS of the last 10 % of the
samples is below this fraction of the RMS of the first 10 % (channels scaled
by their peak value, then summed)."""

MIN_ROWS = 16
"""Fewest data rows a record may have."""


def _resolution(token: str) -> float:
    """Unit of the last digit of a number as written (``"0.125"`` -> 0.001, ``"1.5e-3"`` -> 1e-4)."""
    text = token.strip().lower()
    exponent = 0
    if "e" in text:
        text, _, exp = text.partition("e")
        try:
            exponent = int(exp)
        except ValueError:
            return 0.0
    decimals = len(text.partition(".")[2]) if "." in text else 0
    return float(10.0 ** (exponent - decimals))


def _check_time(time: Array, line_of: Callable[[int], int], time_tokens: Callable[[], list[str]], src: str) -> float:
    n = time.shape[0]
    dt: float = float(time[-1] - time[0]) / (n - 1)
    if not dt > 0.0:
        raise InputError("time does not increase from the first to the last row", source=src, location=_column("time"))
    steps = np.diff(time)
    typical = float(np.median(steps))
    deviation = np.abs(steps - typical)
    tolerance = TIME_TOLERANCE * typical
    bad = np.flatnonzero(deviation > tolerance)
    if bad.size:
        # allow the rounding of the digits written (two roundings of half a unit each)
        resolution = min((_resolution(token) for token in time_tokens()), default=0.0)
        if resolution > 0.5 * typical:
            raise InputError(
                f"time is written with too few digits (to {resolution:g} s) for the sample interval {typical:.6g} s",
                source=src,
                location=_column("time"),
            )
        allowed = max(tolerance, resolution) * (1.0 + 1e-6)
        bad = np.flatnonzero((deviation > allowed) & (np.abs(steps - dt) > allowed))
    if bad.size:
        k = int(bad[0])
        raise InputError(
            f"time step {steps[k]:.6g} s differs from the sample interval {typical:.6g} s by more than "
            f"{100 * TIME_TOLERANCE:g} % (time must be uniformly sampled and increasing)",
            source=src,
            location=_where(line_of(k + 1)),
        )
    return dt


def _check_decay(data: Array, line_of: Callable[[int], int], src: str, energy: Array | None = None) -> Array:
    """Raise unless the record decays after its energy peak; return its ``channel_energy``."""
    from rigidid.core.timedomain.preprocess import channel_energy

    if energy is None:
        energy = channel_energy(data)
    peak = int(np.argmax(energy))
    after = energy[peak:]
    k = after.shape[0] // 10
    if k < 2:
        raise InputError(
            f"the largest sample is at the end of the record ({after.shape[0]} samples follow it): no free decay",
            source=src,
            location=_where(line_of(peak)),
        )
    head = math.sqrt(float(np.mean(after[:k])))
    tail = math.sqrt(float(np.mean(after[-k:])))
    if not tail < DECAY_RATIO * head:
        first, last = line_of(data.shape[0] - k), line_of(data.shape[0] - 1)
        raise InputError(
            f"the signal does not decay: after the peak (row {line_of(peak)}) the RMS of the last 10 % of the "
            f"samples is {100 * tail / head:.0f} % of that of the first 10 % (must be below {100 * DECAY_RATIO:g} %)",
            source=src,
            location=f"rows {first}-{last}",
        )
    return energy


def _read_binary_record(path: Path, wanted: list[str], src: str) -> tuple[Array, float]:
    """A binary record (layouts in :mod:`rigidid.io.binary_records`), checked like a CSV one.

    Row numbers in messages count samples from 1.
    """
    from rigidid.io.binary_records import read_binary

    raw = read_binary(path)
    order = column_order(raw.names, raw.data.shape[1], wanted, src, raw.field)
    data = raw.data if order == list(range(len(order))) else np.ascontiguousarray(raw.data[:, order])
    n = data.shape[0]
    if n < MIN_ROWS:
        raise InputError(f"{n} samples; a record needs at least {MIN_ROWS}", source=src, location=raw.field)
    time: Array = raw.time if raw.time is not None else np.arange(n, dtype=float) * float(raw.dt or 0.0)
    data, dt = _validate(data, time, lambda k: (k if k >= 0 else n + k) + 1, list, src, wanted)
    return data, (float(raw.dt) if raw.time is None and raw.dt is not None else dt)


def is_binary_record(path: Path, src: str) -> bool:
    """Whether the suffix names a binary record (:mod:`rigidid.io.binary_records`) rather than CSV.

    Raises
    ------
    InputError
        A universal file (``.uff``/``.unv``): its records are read with its own geometry,
        as the test's first argument, not beside a layout.json.
    """
    suffix = path.suffix.lower()
    if suffix in (".uff", ".unv"):
        raise InputError(
            "a universal file is not a record beside a layout: give it as the test itself, in place of "
            "layout.json (its dataset 58 records and geometry are read together)",
            source=src,
        )
    return suffix in BINARY_SUFFIXES


def layout_ids(sensor_ids: Sequence[str], src: str) -> list[str]:
    """The layout's sensor ids as strings, the column names a record must have; refused when one repeats."""
    wanted = [str(s) for s in sensor_ids]
    if len(set(wanted)) != len(wanted):
        raise InputError("the layout has a sensor id twice", source=src)
    return wanted


def read_record(path: str | os.PathLike[str], sensor_ids: Sequence[str]) -> tuple[Array, float]:
    """Read one impact record, its columns ordered like the layout's sensors.

    Parameters
    ----------
    path : str or path-like
        The record of one impact: ``records.csv`` or a binary file.
    sensor_ids : sequence of str
        The layout's sensor ids: every one must have a column, and every
        column but ``time`` must be one of them.

    Returns
    -------
    data : ndarray, shape (n, len(sensor_ids))
        Accelerations, column ``i`` for ``sensor_ids[i]``, one row per sample.
    dt : float
        Sample interval (s): ``(t_last - t_first) / (n - 1)``.

    Raises
    ------
    InputError
        Naming the file and the row (line number, header = 1) or column, for:
        a missing or empty file; a header not starting with ``time``; a column
        not in `sensor_ids`, a sensor of `sensor_ids` without a column, a
        column twice; a row with the wrong number of fields; a value that is
        not a number, or is NaN or infinite; fewer than :data:`MIN_ROWS` rows;
        time not uniformly sampled (a step off the mean interval by more than
        :data:`TIME_TOLERANCE`, plus the rounding of the digits written); a
        channel that is zero in every row; a signal that does not decay (see
        :data:`DECAY_RATIO`).

    Notes
    -----
    The suffix chooses the reader: ``.npy``, ``.npz``, ``.mat``, ``.h5`` and
    ``.hdf5`` are binary records (:mod:`rigidid.io.binary_records`, row
    numbers then count samples from 1); anything else is CSV, parsed in
    chunks by pandas' C engine into one preallocated array
    (:mod:`rigidid.io.csv_records`: ``;``/tab separators, decimal comma,
    ``Time (s)`` headers, force/trigger columns left out with a
    :class:`~rigidid.errors.NonSensorColumnWarning`), so memory is the result
    plus one chunk. Blank lines are skipped (but counted in row numbers).
    """
    src = str(path)
    wanted = layout_ids(sensor_ids, src)
    p = Path(path)
    if is_binary_record(p, src):
        return _read_binary_record(p, wanted, src)
    from rigidid.io.csv_records import read_csv_columns

    raw = read_csv_columns(p, wanted)
    n = raw.time.shape[0]
    if n < MIN_ROWS:
        last = raw.line_of(n - 1) if n else 1
        raise InputError(f"{n} data rows; a record needs at least {MIN_ROWS}", source=src, location=_where(last))
    return _validate(raw.data, raw.time, raw.line_of, raw.time_tokens, src, wanted)


def _validate(
    data: Array,
    time: Array,
    line_of: Callable[[int], int],
    time_tokens: Callable[[], list[str]],
    src: str,
    wanted: list[str],
) -> tuple[Array, float]:
    """The checks every record passes whatever its format: finite, uniform time, no dead channel, decay."""
    if not np.isfinite(time).all() or not np.isfinite(data).all():
        finite = np.isfinite(data)
        bad_rows = np.flatnonzero(~np.isfinite(time) | ~finite.all(axis=1))
        k = int(bad_rows[0])
        name = "time" if not np.isfinite(time[k]) else wanted[int(np.argmin(finite[k]))]
        raise InputError("a value is NaN or infinite", source=src, location=f"{_where(line_of(k))}, {_column(name)}")
    dt = _check_time(time, line_of, time_tokens, src)
    peaks = np.zeros(data.shape[1])
    step = max(1, (1 << 16) // max(1, data.shape[1]))
    for start in range(0, data.shape[0], step):
        np.maximum(peaks, np.max(np.abs(data[start : start + step]), axis=0), out=peaks)
    for i, name in enumerate(wanted):
        if not peaks[i] > 0.0:
            raise InputError(f"sensor {name!r} reads zero in every row", source=src, location=_column(name))
    _check_decay(data, line_of, src)
    return data, dt


def write_record(
    path: str | os.PathLike[str],
    time: ArrayLike,
    data: ArrayLike,
    sensor_ids: Sequence[str],
    *,
    digits: int = 10,
) -> None:
    """Write one impact record atomically (temporary file in the same folder, then rename).

    Parameters
    ----------
    path : str or path-like
        The file to write (replaced if it exists).
    time : array_like, shape (n,)
        Sample times (s), written with 15 significant digits.
    data : array_like, shape (n, len(sensor_ids))
        Accelerations, column ``i`` for ``sensor_ids[i]``.
    sensor_ids : sequence of str
        Column names after ``time``.
    digits : int
        Significant digits of the data values.

    Raises
    ------
    InputError
        For mismatched shapes, a sensor id that is empty, repeated, ``time``
        or contains a comma, quote or line break, or a folder that does not
        exist or is not writable.
    """
    t = np.asarray(time, dtype=float).ravel()
    x = np.asarray(data, dtype=float)
    ids = [str(s) for s in sensor_ids]
    if x.ndim != 2 or x.shape != (t.shape[0], len(ids)):
        raise InputError(f"data must be (samples, sensors) = ({t.shape[0]}, {len(ids)}), got {x.shape}")
    if len(set(ids)) != len(ids):
        raise InputError("a sensor id appears twice")
    for sid in ids:
        if not sid or sid.lower() == "time" or any(c in sid for c in ",\"'\r\n") or sid != sid.strip():
            raise InputError(f"sensor id {sid!r} cannot be a column name")
    row_format = ",".join(["%.15g"] + [f"%.{digits}g"] * len(ids)) + "\n"
    with atomic_path(path) as tmp, tmp.open("w", encoding="utf-8", newline="") as fh:
        fh.write(",".join(["time", *ids]) + "\n")
        step = 4096
        for start in range(0, t.shape[0], step):
            block = np.column_stack([t[start : start + step], x[start : start + step]])
            fh.write((row_format * block.shape[0]) % tuple(block.ravel().tolist()))
