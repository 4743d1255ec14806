"""One block-source interface for every record format: rows, sample interval, blocks of rows.

:func:`open_source` opens a record file (the suffix chooses the format: CSV, or
one of :mod:`rigidid.io.records.binary`'s) and returns a :class:`BlockSource`:
the rows its header or size tells, its sample interval when the file states
one, and an iterator of ``(time, values)`` blocks in row order, the sensor
columns in layout order, each block checked for finite values as it is read.
Only files and checks here; what is done with the blocks (decimation, spectra,
impacts) is :mod:`rigidid.core.timedomain.streaming`'s.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rigidid.errors import InputError
from rigidid.io.records.binary import BINARY_SUFFIXES
from rigidid.io.records.columns import column as _column
from rigidid.io.records.columns import column_order
from rigidid.io.records.columns import row as _where
from rigidid.progress import ProgressCallback

__all__ = ["BLOCK_ROWS", "SAFE_PEAK", "BlockSource", "in_range", "is_binary_record", "open_source", "values_of"]

Array = NDArray[np.float64]

BLOCK_ROWS = 1 << 14
"""Rows per block of a binary record."""


@dataclass(frozen=True)
class BlockSource:
    """A record file as blocks of rows.

    Attributes
    ----------
    blocks : iterator of (ndarray, ndarray)
        ``(time (k,), values (k, sensors))`` in row order, sensors in layout
        order; a NaN or infinite value raises :class:`~rigidid.errors.InputError`
        when its block is read.
    rows : int
        Data rows as the header tells (a CSV's: estimated from its size).
    line_of : callable
        ``line_of(rows)(k)``: the file's line (or sample number) of data row
        `k` (negative: from the end), once `rows` rows have been read.
    time_tokens : callable
        The time column as written (a CSV's; empty for binary files).
    dt : float or None
        The sample interval when the file states it rather than a time column.
    """

    blocks: Iterator[tuple[Array, Array]]
    rows: int
    line_of: Callable[[int], Callable[[int], int]]
    time_tokens: Callable[[], list[str]]
    dt: float | None = None


SAFE_PEAK = 2.0**200
"""Values read are scaled by a power of two when the first nonzero block's peak is above this or below its
inverse (:func:`in_range`)."""


def in_range(blocks: Iterator[tuple[Array, Array]], exponent: int | None) -> tuple[Iterator[tuple[Array, Array]], int]:
    """`blocks` ``(time, values)`` with the values times ``2**exponent``; `exponent` None: chosen so that the
    first block with a nonzero value peaks in ``[0.5, 1)`` when it peaks outside ``[2^-200, 2^200]``, else 0
    (the blocks read to choose it are held and given first)."""
    held: list[tuple[Array, Array]] = []
    if exponent is None:
        exponent = 0
        for t, values in blocks:
            held.append((t, values))
            top = float(np.max(np.abs(values))) if values.size else 0.0
            if top > 0.0:
                if not 1.0 / SAFE_PEAK <= top <= SAFE_PEAK:
                    exponent = -math.frexp(top)[1]
                break
    chained = itertools.chain(held, blocks)
    if exponent == 0:
        return chained, 0
    scale = exponent
    return ((t, np.ldexp(values, scale)) for t, values in chained), exponent


def values_of(source: BlockSource) -> Iterator[Array]:
    """The blocks of `source` without their time column."""
    for _, values in source.blocks:
        yield values


def _sample_lines(n: int) -> Callable[[int], int]:
    """Row `k` of a binary record of `n` rows is its sample ``k + 1`` (negative `k`: from the end)."""
    return lambda k: (k if k >= 0 else n + k) + 1


def is_binary_record(path: Path, src: str) -> bool:
    """Whether the suffix names a binary record (:mod:`~rigidid.io.records.binary`) rather than CSV.

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


def open_source(path: Path, wanted: list[str], progress: ProgressCallback | None) -> BlockSource:
    """A record file's row blocks (CSV or binary, by its suffix), its sensor columns in the order of `wanted`."""
    src = str(path)
    if is_binary_record(path, src):
        return _binary_source(path, wanted, src, progress)
    return _csv_source(path, wanted, progress)


def _csv_source(path: Path, wanted: list[str], progress: ProgressCallback | None) -> BlockSource:
    from rigidid.io.records.csv import CsvHead, csv_blocks

    gen = csv_blocks(path, wanted, progress)
    head = next(gen)
    assert isinstance(head, CsvHead)

    def blocks() -> Iterator[tuple[Array, Array]]:
        for item in gen:
            assert not isinstance(item, CsvHead)
            yield item

    return BlockSource(blocks(), head.rows, head.line_of, head.time_tokens)


def _binary_source(path: Path, wanted: list[str], src: str, progress: ProgressCallback | None) -> BlockSource:
    from rigidid.io.records.binary import named_blocks, npy_blocks, read_binary

    if path.suffix.lower() == ".npy" and path.is_file():
        found = npy_blocks(path, BLOCK_ROWS)
        if found is not None:
            return _npy_source(path, wanted, src, progress, *found)
    named = named_blocks(path, BLOCK_ROWS)  # .npz and .h5 of the data/channels layout: row blocks
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
            for start in range(0, n, BLOCK_ROWS):
                stop = start + BLOCK_ROWS
                yield (None if raw.time is None else raw.time[start:stop]), raw.data[start:stop]

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

    return BlockSource(blocks(), n, _sample_lines, list, step)


def _npy_source(
    path: Path, wanted: list[str], src: str, progress: ProgressCallback | None, n: int, columns: int, raw: Any
) -> BlockSource:
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

    return BlockSource(blocks(), n, _sample_lines, list)
