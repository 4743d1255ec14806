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

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.errors import InputError
from rigidid.io.atomic import atomic_path
from rigidid.io.records.checks import MIN_ROWS, check_record, layout_ids
from rigidid.io.records.columns import column_order
from rigidid.io.records.columns import row as _where
from rigidid.io.records.sources import is_binary_record

__all__ = ["read_record", "write_record"]

Array = NDArray[np.float64]


def _read_binary_record(path: Path, wanted: list[str], src: str) -> tuple[Array, float]:
    """A binary record (layouts in :mod:`rigidid.io.records.binary`), checked like a CSV one.

    Row numbers in messages count samples from 1.
    """
    from rigidid.io.records.binary import read_binary

    raw = read_binary(path)
    order = column_order(raw.names, raw.data.shape[1], wanted, src, raw.field)
    data = raw.data if order == list(range(len(order))) else np.ascontiguousarray(raw.data[:, order])
    n = data.shape[0]
    if n < MIN_ROWS:
        raise InputError(f"{n} samples; a record needs at least {MIN_ROWS}", source=src, location=raw.field)
    time: Array = raw.time if raw.time is not None else np.arange(n, dtype=float) * float(raw.dt or 0.0)
    data, dt = check_record(data, time, lambda k: (k if k >= 0 else n + k) + 1, list, src, wanted)
    return data, (float(raw.dt) if raw.time is None and raw.dt is not None else dt)


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
    ``.hdf5`` are binary records (:mod:`rigidid.io.records.binary`, row
    numbers then count samples from 1); anything else is CSV, parsed in
    chunks by pandas' C engine into one preallocated array
    (:mod:`rigidid.io.records.csv`: ``;``/tab separators, decimal comma,
    ``Time (s)`` headers, force/trigger columns left out with a
    :class:`~rigidid.errors.NonSensorColumnWarning`), so memory is the result
    plus one chunk. Blank lines are skipped (but counted in row numbers).
    """
    src = str(path)
    wanted = layout_ids(sensor_ids, src)
    p = Path(path)
    if is_binary_record(p, src):
        return _read_binary_record(p, wanted, src)
    from rigidid.io.records.csv import read_csv_columns

    raw = read_csv_columns(p, wanted)
    n = raw.time.shape[0]
    if n < MIN_ROWS:
        last = raw.line_of(n - 1) if n else 1
        raise InputError(f"{n} data rows; a record needs at least {MIN_ROWS}", source=src, location=_where(last))
    return check_record(raw.data, raw.time, raw.line_of, raw.time_tokens, src, wanted)


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
