"""Streamed reading of CSV impact records, chunk by chunk: pandas, or polars (optional) and pandas where it declines.

The layout (``docs/FORMATS.md``): a header ``time,<sensor id>,...`` and one
row per sample. Accepted as spreadsheets and recorders write it (see
:mod:`rigidid.io.dialect`): ``,`` ``;`` or tab separators, a decimal comma
with ``;``/tab, a time header with a unit (``Time (s)``, ``time [s]``,
case-insensitive; another unit than seconds is an error), and columns that
are not sensors but excitation or trigger channels (``force``, ``hammer``,
``trigger``, ``excitation``, ``tacho``... with or without a unit) left out
with a :class:`~rigidid.errors.NonSensorColumnWarning`.

The file after its header is read in chunks of :data:`CHUNK_BYTES` that end
at line ends. polars parses a chunk on every core (correctly rounded, so a
CSV written with Python's shortest repr gives the very values of the binary
record); a chunk polars declines or reads with non-finite values (blank
lines, text, NaN, ragged lines, spaces around numbers) is parsed again by
pandas' C engine, which skips blank lines, and its errors are diagnosed
line by line. Parsing alone, measured by ``benchmarks/csv_parsers.py``
(fresh processes, imports included, medians of 3) on 32 channels x 10^6
rows (485 MB): pandas' C engine in chunks 2.28 s (whole: 1.42 s, 1075 MB),
pyarrow's streaming reader 2.26 s, polars in 8 MiB chunks 1.37 s and 116
MB (its streaming engine: 0.95 s, but 360 MB); on 8 x 10^7 rows (1.27 GB):
4.67 s, 4.78 s and 3.54 s (polars' streaming engine 1.64 s, 355 MB). polars is optional (the
``fast-csv`` extra; it takes 181 MB installed, pandas 84 MB): rigidid's reader (parsing and checks)
on 32 channels x 3 x 10^5 rows (155 MB, 2 busy cores) takes 2.92 s with it and 4.36 s with pandas
alone, the same 210 MB peak.

Each block is checked as it arrives (numbers, finite) and handed on (to the
streamed decimation, or copied into one preallocated array sized from the
file size and the line length sampled at five places), so memory is the
record (or the decimated record) plus one chunk. Errors are one line naming
the file, the row (line number, header = 1, blank lines counted) and the
column; the row of a bad value is found by re-reading the file only on
that error path.

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
from rigidid.io.dialect import Dialect, column_key, decimal_point, plain_number, sniff_dialect
from rigidid.io.records.columns import NON_SENSOR_PREFIXES, match_columns
from rigidid.io.records.columns import column as _column
from rigidid.io.records.columns import row as _where
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
"""Rows pandas parses at a time (16384: as fast as larger chunks here, a few MB of temporaries)."""

CHUNK_BYTES = 1 << 23
"""Bytes of data lines read and parsed at a time (8 MiB; 4 and 16 MiB took as long within the noise here,
16 MiB held 45 MB more)."""

MAX_HEADER_BYTES = 1 << 20
"""The header line must end within this many bytes (1 MiB)."""

_SNIFF_BYTES = 1 << 16
_TAIL_BYTES = 1 << 16
_TIME_KEYS = {"time", "time_s", "t_s", "zeit_s"}


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
            if not plain_number(value):
                raise ValueError(value)
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
        capacity = _estimate_rows(fh, size, head, len(header_bytes))
        yield CsvHead(capacity, lambda n: _line_map(p, dialect, n), _tail_tokens(p, dialect))
        fh.seek(len(header_bytes))
        task = f"reading {p.name}"
        parse = _Parser(p, src, dialect, header, order)
        for chunk in _byte_chunks(fh, size - len(header_bytes), src):
            for time_block, block in parse(chunk):
                if progress is not None:
                    progress(task, float(fh.tell()), float(size))
                yield time_block, block


def _byte_chunks(fh: Any, size: int, src: str) -> Iterator[bytes]:
    """The file after its header in chunks of about :data:`CHUNK_BYTES` that end at line ends.

    At most `size` bytes (the size when opened) are read; a byte more means
    the file grew while it was read, an error.
    """
    left, rest = size, b""
    while left > 0:
        data = fh.read(min(CHUNK_BYTES, left))
        if not data:
            break
        left -= len(data)
        if left == 0 and fh.read(1):  # before the last lines: they may be cut where the size was taken
            raise InputError("the file grew while it was read (an endless or live file?)", source=src)
        data = rest + data
        cut = data.rfind(b"\n") + 1 if left > 0 else len(data)
        rest = data[cut:]
        if cut:
            yield data[:cut]
    if rest:
        yield rest


def _strict_numeric(column: Any) -> Array:
    """A parsed column as floats: text NaN, and so is a number Python reads but the contract does not (``1_0``)."""
    import pandas as pd

    out: Array = pd.to_numeric(column, errors="coerce").to_numpy(dtype=np.float64, copy=True)
    if not pd.api.types.is_numeric_dtype(column.dtype):  # text cells (object or pandas' string dtype)
        odd = column.astype(str).str.contains(r"[^\x00-\x7f]|_", regex=True).to_numpy(dtype=bool)
        out[odd] = np.nan
    return out


class _Parser:
    """Chunks of data lines to checked ``(time, sensors)`` blocks: polars first, pandas where it declines.

    polars parses a chunk of plain numeric lines (every field a number, the
    header's field count) on all cores, about twice as fast as pandas' C
    parser. Anything else in a chunk (blank lines, NaN, text, ragged lines,
    spaces around numbers) makes polars decline or gives non-finite values;
    the chunk is then parsed again by pandas, whose reading skips blank lines
    and whose errors are diagnosed line by line as before. Both give the
    same rows: the data lines that are not blank.
    """

    def __init__(self, path: Path, src: str, dialect: Dialect, header: list[str], order: list[int]) -> None:
        self.path, self.src, self.dialect, self.header, self.order = path, src, dialect, header, order
        self.filled = 0  # data rows before the chunk being parsed
        try:
            import polars as pl
        except ImportError:  # pandas alone: polars is the optional fast-csv extra
            self.polars: Any = None
        else:
            self.polars = pl
            self.schema = {f"c{k}": pl.Float64 for k in range(len(header))}

    def __call__(self, chunk: bytes) -> Iterator[tuple[Array, Array]]:
        values = self._polars(chunk)
        if values is None:
            yield from self._pandas(chunk)
            return
        yield self._checked(values, 0, self.order)

    def _polars(self, chunk: bytes) -> Array | None:
        if self.polars is None:
            return None
        import io

        try:
            frame = self.polars.read_csv(
                io.BytesIO(chunk),
                has_header=False,
                schema=self.schema,
                separator=self.dialect.delimiter,
                decimal_comma=self.dialect.decimal == ",",
                quote_char='"',
            )
        except Exception:  # polars declines: pandas parses the chunk and says what is wrong
            return None
        values: Array = frame.to_numpy()
        if values.dtype != np.float64 or not np.isfinite(values).all():  # blank lines read as NaN rows...
            return None
        return values

    def _pandas(self, chunk: bytes) -> Iterator[tuple[Array, Array]]:
        import io

        import pandas as pd

        p, dialect, header, src = self.path, self.dialect, self.header, self.src
        n_fields = len(header)
        reader = pd.read_csv(
            io.BytesIO(chunk),
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
        columns = [0, *self.order]
        try:
            for frame in reader:
                if frame.shape[1] != n_fields:
                    start = _line_map(p, dialect, self.filled + frame.shape[0])(self.filled)
                    raise _diagnose(p, dialect, header, _first_bad_line(p, dialect, n_fields, start), src)
                numeric = all(pd.api.types.is_numeric_dtype(t) for t in frame.dtypes)
                if numeric:  # the usual case: one array, no copy of a column subset
                    yield self._checked(frame.to_numpy(dtype=np.float64), 0, self.order)
                else:  # text somewhere (numpy would read '1_0' as 10): coerce the columns used, find it below
                    values = np.column_stack([_strict_numeric(frame.iloc[:, j]) for j in columns])
                    yield self._checked(values, 0, list(range(1, len(columns))))
        except pd.errors.ParserError:
            start = _line_map(p, dialect, self.filled + 1)(self.filled) if self.filled else 2
            raise _diagnose(p, dialect, header, _first_bad_line(p, dialect, n_fields, start), src) from None
        except pd.errors.EmptyDataError:
            return
        except UnicodeDecodeError:
            raise InputError("not a text file (UTF-8)", source=src) from None

    def _checked(self, values: Array, time_column: int, sensor_columns: list[int]) -> tuple[Array, Array]:
        """The time and sensor columns of parsed rows, every value finite (else the line's precise error)."""
        rows = values.shape[0]
        time_block = values[:, time_column].copy()
        block = np.take(values, sensor_columns, axis=1)
        finite = np.isfinite(block).all(axis=1) & np.isfinite(time_block)
        if not finite.all():
            k = int(np.flatnonzero(~finite)[0])
            line = _line_map(self.path, self.dialect, self.filled + rows)(self.filled + k)
            raise _diagnose(self.path, self.dialect, self.header, line, self.src)
        self.filled += rows
        return time_block, block
