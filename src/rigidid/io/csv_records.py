"""Streamed reading of CSV impact records with the pandas C parser, chunk by chunk.

The layout (``docs/FORMATS.md``): a header ``time,<sensor id>,...`` and one
row per sample. Accepted as spreadsheets and recorders write it (see
:mod:`rigidid.io.dialect`): ``,`` ``;`` or tab separators, a decimal comma
with ``;``/tab, a time header with a unit (``Time (s)``, ``time [s]``,
case-insensitive; another unit than seconds is an error), and columns that
are not sensors but excitation or trigger channels (``force``, ``hammer``,
``trigger``, ``excitation``, ``tacho``... with or without a unit) left out
with a :class:`~rigidid.errors.NonSensorColumnWarning`.

Why pandas: on 32 channels x 200 000 rows (86 MB) here pandas' C engine
parsed in 0.19 s against 0.40 s for :func:`numpy.loadtxt` (pyarrow and
polars are not installed in the project's environment; ``benchmarks/
modes_speed.py`` measures the reader end to end).

Each chunk (:data:`CHUNK_ROWS` rows) is checked as it arrives (numbers,
finite) and copied into one preallocated array sized from the file size and
the line length sampled at five places, so memory is the record (plus a few
per cent) plus one chunk. Errors are one line naming the file,
the row (line number, header = 1, blank lines counted) and the column; the
row of a bad value is found by re-reading the file only on that error path.

Limits: only regular files are read (``/dev/zero``, pipes and terminals are
refused), the header must end within :data:`MAX_HEADER_BYTES`, and a file
that grows while it is read stops with an error at its size when opened.
"""

from __future__ import annotations

import itertools
import math
import os
import re
import stat
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rigidid.errors import InputError, NonSensorColumnWarning
from rigidid.io.columns import NON_SENSOR_PREFIXES, match_columns
from rigidid.io.columns import column as _column
from rigidid.io.columns import row as _where
from rigidid.io.dialect import Dialect, column_key, decimal_point, sniff_dialect
from rigidid.progress import ProgressCallback

__all__ = [
    "CHUNK_ROWS",
    "MAX_HEADER_BYTES",
    "NON_SENSOR_PREFIXES",
    "CsvHead",
    "RawCsv",
    "csv_blocks",
    "read_csv_columns",
]

Array = NDArray[np.float64]

CHUNK_ROWS = 1 << 14
"""Rows parsed per chunk (16384: as fast as larger chunks here, a few MB of temporaries)."""

MAX_HEADER_BYTES = 1 << 20
"""The header line must end within this many bytes (1 MiB)."""

_SNIFF_BYTES = 1 << 16
_TAIL_BYTES = 1 << 16
_TIME_KEYS = {"time", "time_s", "t_s", "zeit_s"}


class _Bounded:
    """A binary file that refuses to give more than `limit` bytes (a file growing while read)."""

    def __init__(self, fh: Any, limit: int, src: str):
        self._fh, self._left, self._src = fh, limit, src

    def read(self, n: int = -1) -> bytes:
        data: bytes = self._fh.read(n if n is not None and n >= 0 else -1)
        self._left -= len(data)
        if self._left < 0:
            raise InputError("the file grew while it was read (an endless or live file?)", source=self._src)
        return data

    def __iter__(self) -> Any:
        return self

    def __next__(self) -> bytes:
        line: bytes = self._fh.readline()
        if not line:
            raise StopIteration
        self._left -= len(line)
        if self._left < 0:
            raise InputError("the file grew while it was read (an endless or live file?)", source=self._src)
        return line


class RawCsv:
    """The columns of a CSV record before the checks shared with the binary formats.

    Attributes
    ----------
    data : ndarray, shape (n, len(wanted)), layout order
    time : ndarray, shape (n,)
    line_of : callable
        ``line_of(k)`` is the line number (header = 1) of data row ``k``
        (negative ``k`` from the end).
    time_tokens : callable
        The time cells of the last rows as written (for their resolution).
    """

    def __init__(
        self, data: Array, time: Array, line_of: Callable[[int], int], time_tokens: Callable[[], list[str]]
    ) -> None:
        self.data, self.time, self.line_of, self.time_tokens = data, time, line_of, time_tokens


def _split(text: str, dialect: Dialect) -> list[str]:
    return [cell.strip().strip('"').strip("'").strip() for cell in text.rstrip("\r\n").split(dialect.delimiter)]


def _data_lines(path: Path, dialect: Dialect, encoding: str = "utf-8-sig") -> Any:
    """(line number, text) of the non-blank data lines, lazily (error paths only)."""
    fh = path.open("r", encoding=encoding, errors="replace", newline="")
    fh.readline()
    return fh, ((k, text) for k, text in enumerate(fh, start=2) if text.strip())


def _line_map(path: Path, dialect: Dialect, n_rows: int) -> Callable[[int], int]:
    cache: list[int] = []

    def line_of(k: int) -> int:
        index = k if k >= 0 else n_rows + k
        if index >= len(cache):
            fh, lines = _data_lines(path, dialect)
            with fh:
                cache[:] = [number for number, _ in itertools.islice(lines, index + 1)]
        return cache[min(index, len(cache) - 1)] if cache else index + 2

    return line_of


def _tail_tokens(path: Path, dialect: Dialect) -> Callable[[], list[str]]:
    def tokens() -> list[str]:
        with path.open("rb") as fh:
            size = fh.seek(0, os.SEEK_END)
            fh.seek(max(0, size - _TAIL_BYTES))
            text = fh.read().decode("utf-8", errors="replace")
        rows = [line for line in text.splitlines()[1:] if line.strip()]
        return [decimal_point(line.split(dialect.delimiter, 1)[0].strip(), dialect) for line in rows[-200:]]

    return tokens


def _diagnose(path: Path, dialect: Dialect, header: list[str], line: int, src: str) -> InputError:
    """The precise error for data line `line`: field count, empty cell, text, NaN/inf."""
    fh, lines = _data_lines(path, dialect)
    with fh:
        text = next((t for k, t in lines if k == line), "")
    cells = text.rstrip("\r\n").split(dialect.delimiter)
    if len(cells) != len(header):
        return InputError(f"{len(cells)} fields, the header has {len(header)}", source=src, location=_where(line))
    for name, cell in zip(header, cells, strict=True):
        value = cell.strip().strip('"')
        where = f"{_where(line)}, {_column(name)}"
        if not value:
            return InputError("empty cell", source=src, location=where)
        try:
            number = float(decimal_point(value, dialect))
        except ValueError:
            return InputError(f"{value!r} is not a number", source=src, location=where)
        if not math.isfinite(number):
            return InputError("a value is NaN or infinite", source=src, location=where)
    return InputError("cannot read the data row", source=src, location=_where(line))


def _first_bad_line(path: Path, dialect: Dialect, n_fields: int, start: int) -> int:
    """The first data line at or after `start` whose field count is not `n_fields`."""
    fh, lines = _data_lines(path, dialect)
    with fh:
        for k, text in lines:
            if k >= start and len(text.rstrip("\r\n").split(dialect.delimiter)) != n_fields:
                return int(k)
    return start


def _check_time_header(name: str, header: list[str], src: str) -> None:
    key = column_key(name)
    if key in _TIME_KEYS:
        return
    if re.match(r"^(time|t)_", key):
        raise InputError(
            f"time must be in seconds, the header says {name!r}", source=src, location=f"{_where(1)}, {_column(name)}"
        )
    where = _column(name) if "time" not in [column_key(h) for h in header] else _column("time")
    raise InputError(
        "the first column must be 'time' (header: time,<sensor id>,<sensor id>,...)",
        source=src,
        location=f"{_where(1)}, {where}",
    )


def _estimate_rows(fh: Any, size: int, head: bytes, header_size: int) -> int:
    """Rows to preallocate: the shortest mean line length of five samples of the file, plus 2 %."""
    samples = [head[header_size:]]
    for fraction in (0.25, 0.5, 0.75, 1.0):
        fh.seek(max(header_size, int(size * fraction) - _SNIFF_BYTES))
        samples.append(fh.read(_SNIFF_BYTES))
    shortest = min(
        (len(block) / block.count(b"\n") for block in samples if block.count(b"\n") >= 4), default=float(size or 1)
    )
    return max(16, int((size - header_size) / max(shortest, 1.0) * 1.02) + 16)


class CsvHead:
    """What the header of a CSV record says, yielded first by :func:`csv_blocks`.

    Attributes
    ----------
    rows : int
        Rows to preallocate (an estimate from the file size, a few per cent high).
    line_of : callable
        ``line_of(n_rows)`` gives the row-to-line map of a record of `n_rows` data rows.
    time_tokens : callable
        The time cells of the last rows as written.
    """

    def __init__(self, rows: int, line_of: Callable[[int], Callable[[int], int]], time_tokens: Callable[[], list[str]]):
        self.rows, self.line_of, self.time_tokens = rows, line_of, time_tokens


def read_csv_columns(path: str | os.PathLike[str], wanted: list[str]) -> RawCsv:
    """Parse a CSV record in chunks, its sensor columns in the order of `wanted`.

    Raises
    ------
    InputError
        One line naming the file and row/column (see the module documentation).
    """
    blocks = csv_blocks(path, wanted)
    head = next(blocks)
    assert isinstance(head, CsvHead)
    capacity = head.rows
    data = np.empty((capacity, len(wanted)))
    time = np.empty(capacity)
    filled = 0
    for item in blocks:
        assert not isinstance(item, CsvHead)
        t, values = item
        rows = t.shape[0]
        if filled + rows > capacity:
            capacity = max(filled + rows, int(capacity * 1.25))
            data = np.resize(data, (capacity, len(wanted)))
            time = np.resize(time, capacity)
        data[filled : filled + rows] = values
        time[filled : filled + rows] = t
        filled += rows
    return RawCsv(data[:filled], time[:filled], head.line_of(filled), head.time_tokens)


def csv_blocks(
    path: str | os.PathLike[str], wanted: list[str], progress: ProgressCallback | None = None
) -> Iterator[CsvHead | tuple[Array, Array]]:
    """Parse a CSV record chunk by chunk: first a :class:`CsvHead`, then ``(time, data)`` blocks.

    Each block has at most :data:`CHUNK_ROWS` rows, its sensor columns in the
    order of `wanted`, checked (field count, numbers, finite) before it is
    yielded. `progress` is called with ``("reading <file name>", bytes,
    file size)`` after each chunk.

    Raises
    ------
    InputError
        One line naming the file and row/column (see the module documentation).
    """
    import pandas as pd

    src = str(path)
    p = Path(path)
    try:
        fh = p.open("rb")
    except FileNotFoundError:
        raise InputError("file not found", source=src) from None
    except IsADirectoryError:
        raise InputError("is a folder, not a file", source=src) from None
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror}", source=src) from None
    with fh:
        info = os.fstat(fh.fileno())
        if stat.S_ISDIR(info.st_mode):
            raise InputError("is a folder, not a file", source=src)
        if not stat.S_ISREG(info.st_mode):
            raise InputError("not a regular file (devices, pipes and terminals are not read)", source=src)
        size = info.st_size
        head = fh.read(min(size, max(_SNIFF_BYTES, 0)) or _SNIFF_BYTES)
        newline = head.find(b"\n")
        if newline < 0 and len(head) < size:
            head += fh.read(MAX_HEADER_BYTES - len(head))
            newline = head.find(b"\n")
            if newline < 0 and len(head) >= MAX_HEADER_BYTES:
                raise InputError(
                    f"no line break in the first {MAX_HEADER_BYTES >> 20} MiB: not a CSV record",
                    source=src,
                    location=_where(1),
                )
        header_bytes = head if newline < 0 else head[: newline + 1]
        try:
            header_text = header_bytes.decode("utf-8-sig")
            sample = head.decode("utf-8-sig", errors="ignore")
        except UnicodeDecodeError:
            raise InputError("not a text file (UTF-8)", source=src, location=_where(1)) from None
        if not header_text.strip():
            raise InputError("the file is empty (no header)", source=src, location=_where(1))
        dialect = sniff_dialect(sample)
        header = _split(header_text, dialect)
        _check_time_header(header[0], header, src)
        order, skipped = match_columns(header[1:], wanted, src, _where(1), skip_non_sensors=True)
        order = [k + 1 for k in order]
        if skipped:
            warnings.warn(
                f"{src}: columns {', '.join(repr(s) for s in skipped)} are not sensors (force, trigger...): left out",
                NonSensorColumnWarning,
                stacklevel=4,
            )
        n_fields = len(header)
        capacity = _estimate_rows(fh, size, head, len(header_bytes))
        yield CsvHead(capacity, lambda n: _line_map(p, dialect, n), _tail_tokens(p, dialect))
        fh.seek(len(header_bytes))
        reader = pd.read_csv(
            _Bounded(fh, size - len(header_bytes), src),
            sep=dialect.delimiter,
            decimal=dialect.decimal,
            header=None,
            index_col=False,
            engine="c",
            chunksize=CHUNK_ROWS,
            encoding="utf-8",
            skip_blank_lines=True,
            dtype=None,
        )
        filled = 0
        task = f"reading {p.name}"
        columns = [0, *order]
        try:
            for chunk in reader:
                if chunk.shape[1] != n_fields:
                    start = _line_map(p, dialect, filled + chunk.shape[0])(filled)
                    raise _diagnose(p, dialect, header, _first_bad_line(p, dialect, n_fields, start), src)
                try:  # all columns numeric (the usual case): one array, no copy of a column subset
                    values = chunk.to_numpy(dtype=np.float64)
                    time_column, sensor_columns = 0, order
                except (ValueError, TypeError):  # text somewhere: coerce the columns used, find it below
                    values = np.column_stack(
                        [pd.to_numeric(chunk.iloc[:, j], errors="coerce").to_numpy(dtype=np.float64) for j in columns]
                    )
                    time_column, sensor_columns = 0, list(range(1, len(columns)))
                del chunk
                rows = values.shape[0]
                time_block = values[:, time_column].copy()
                block = np.take(values, sensor_columns, axis=1)
                del values
                finite = np.isfinite(block).all(axis=1) & np.isfinite(time_block)
                if not finite.all():
                    k = int(np.flatnonzero(~finite)[0])
                    line = _line_map(p, dialect, filled + rows)(filled + k)
                    raise _diagnose(p, dialect, header, line, src)
                filled += rows
                if progress is not None:
                    progress(task, float(fh.tell()), float(size))
                yield time_block, block
        except pd.errors.ParserError:
            start = _line_map(p, dialect, filled + 1)(filled) if filled else 2
            raise _diagnose(p, dialect, header, _first_bad_line(p, dialect, n_fields, start), src) from None
        except pd.errors.EmptyDataError:
            return
        except UnicodeDecodeError:
            raise InputError("not a text file (UTF-8)", source=src) from None
