"""Binary datasets 58 (``58b``) of a universal file, located and read without pyuff.

pyuff reads a whole file into memory, finds every ``    -1`` delimiter in it
(binary data included) and decodes binary values with :mod:`struct`: on a
32-channel record of 10^6 samples per channel (256 MB of 58b) ``rigidid
modes`` took 5.1 s and 1.09 GB. This module walks the file dataset by
dataset instead: an ASCII dataset is read line by line up to its closing
delimiter; a 58b dataset's ID line gives the number of ASCII header lines
and of data bytes, so its data are skipped over, then read with
:func:`numpy.fromfile` (a private copy per channel, in the byte order the ID
line gives), with the closing delimiter checked where the byte count says it
is.

Only the 58b datasets are decoded here, into the dictionaries pyuff gives
(the same keys, the same values); every other dataset is left to pyuff
(:func:`rigidid.io.uff.read_all` passes it those datasets alone). When the
file departs from that layout (a byte count that does not end on a
delimiter, an ID line that cannot be read), :func:`scan` returns None and
pyuff reads the whole file as before.

Layout of a 58b dataset (the UFF specification, as pyuff writes and reads
it)::

        -1
        58b     2     2          11        4096     0     0           0           0
    <11 ASCII header records: ID lines 1-5, records 6-11>
    <n_bytes of binary values>
        -1

The ID line's fields (``I6,A1,I6,I6,I12,I12,I6,I6,I12,I12``) are the type, the
``b``, the byte ordering (1 little-endian, 2 big-endian), the floating-point
format, the number of ASCII header lines and the number of bytes.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["BOM", "Block", "read_58b", "scan"]

_DELIMITER = b"    -1"
_MAX_HEADER_LINES = 64  # the specification has 11

# records 6-11 of dataset 58 (pyuff's field names, widths and types: 1 text, 2 integer, 3 real)
_RECORDS: tuple[tuple[tuple[str, int, int], ...], ...] = (
    (
        ("func_type", 5, 2), ("func_id", 10, 2), ("ver_num", 5, 2), ("load_case_id", 10, 2),
        ("rsp_ent_name", 11, 1), ("rsp_node", 10, 2), ("rsp_dir", 4, 2), ("ref_ent_name", 11, 1),
        ("ref_node", 10, 2), ("ref_dir", 4, 2),
    ),
    (
        ("ord_data_type", 10, 2), ("num_pts", 10, 2), ("abscissa_spacing", 10, 2), ("abscissa_min", 13, 3),
        ("abscissa_inc", 13, 3), ("z_axis_value", 13, 3),
    ),
    *(
        (
            (f"{axis}_spec_data_type", 10, 2), (f"{axis}_len_unit_exp", 5, 2), (f"{axis}_force_unit_exp", 5, 2),
            (f"{axis}_temp_unit_exp", 5, 2), (f"{axis}_axis_lab", 21, 1), (f"{axis}_axis_units_lab", 21, 1),
        )
        for axis in ("abscissa", "ordinate", "orddenom", "z_axis")
    ),
)  # fmt: skip


@dataclass(frozen=True)
class Block:
    """One dataset of a universal file.

    Attributes
    ----------
    kind : int
        The dataset type (15, 58, 2411...).
    start, end : int
        Byte offsets of its opening delimiter line and just past its closing one.
    header : tuple of bytes
        58b only: the ID line and the ASCII header records.
    data : (int, int)
        58b only: offset and length (bytes) of its binary values; ``(0, 0)`` otherwise.
    """

    kind: int
    start: int
    end: int
    header: tuple[bytes, ...] = ()
    data: tuple[int, int] = (0, 0)

    @property
    def binary58(self) -> bool:
        """Whether this is a binary dataset 58 (read by :func:`read_58b`)."""
        return bool(self.header)


def _is_delimiter(line: bytes) -> bool:
    """``    -1`` followed by the end of the line or by blanks (pyuff's rule)."""
    return line.startswith(_DELIMITER) and not line[len(_DELIMITER) :].strip()


BOM = b"\xef\xbb\xbf"
"""The UTF-8 byte-order mark, skipped at the start of a file."""


def scan(path: str | os.PathLike[str]) -> list[Block] | None:
    """The datasets of a universal file, in order (None when its layout is not followed).

    Parameters
    ----------
    path : path-like
        A universal file.

    Returns
    -------
    list of Block or None
        None when a delimiter is missing where the layout puts one (a 58b
        byte count that does not end on a delimiter, a file that ends inside
        a dataset), an ID line is not a number, or a binary dataset is not a
        58: pyuff is then left to read the file as it can.
    """
    blocks: list[Block] = []
    with open(path, "rb") as fh:
        size = os.fstat(fh.fileno()).st_size
        if fh.read(3) != BOM:  # a byte-order mark some editors put first: not part of the first line
            fh.seek(0)
        while True:
            start = fh.tell()
            line = fh.readline()
            if not line:
                return blocks
            if not line.strip():
                continue
            if not _is_delimiter(line):
                return None
            id_line = fh.readline()
            try:
                kind = int(id_line[:6])
            except ValueError:
                return None
            if id_line[6:7] in (b"b", b"B"):
                if kind != 58:
                    return None
                try:
                    n_lines, n_bytes = int(id_line[19:31]), int(id_line[31:43])
                except ValueError:
                    return None
                if not 8 <= n_lines <= _MAX_HEADER_LINES or n_bytes < 0:
                    return None
                header = [id_line] + [fh.readline() for _ in range(n_lines)]
                offset = fh.tell()
                if offset + n_bytes > size:
                    return None
                fh.seek(offset + n_bytes)
                closing = fh.readline()
                if not closing.strip():  # a line end written after the values
                    closing = fh.readline()
                if not _is_delimiter(closing):
                    return None
                blocks.append(Block(kind, start, fh.tell(), tuple(header), (offset, n_bytes)))
                continue
            for line in fh:
                if _is_delimiter(line):
                    break
            else:
                return None
            blocks.append(Block(kind, start, fh.tell()))


def _fields(line: bytes, fields: tuple[tuple[str, int, int], ...]) -> dict[str, Any]:
    """Fixed-width fields of a header record (text stripped; a blank or unreadable number: 0)."""
    text = line.decode("utf-8", errors="replace").rstrip("\r\n").ljust(80)
    out: dict[str, Any] = {}
    at = 0
    for name, width, kind in fields:
        value = text[at : at + width].strip()
        at += width
        if kind == 1:
            out[name] = value
            continue
        try:
            number = float(value.replace("D", "E").replace("d", "e")) if value else 0.0
        except ValueError:
            number = 0.0
        out[name] = int(number) if kind == 2 else number
    return out


def read_58b(path: str | os.PathLike[str], block: Block) -> dict[str, Any]:
    """The dataset pyuff would return for a binary 58: header fields, ``x`` and ``data``.

    Parameters
    ----------
    path : path-like
        The file `block` was scanned from.
    block : Block
        A binary 58 (:attr:`Block.binary58`).

    Returns
    -------
    dict
        pyuff's keys: ``type``, ``binary``, ``byte_ordering``, ``fp_format``,
        ``n_ascii_lines``, ``n_bytes``, ``id1``...``id5``, the fields of
        records 6-11, and ``x`` and ``data`` (float64, or complex for
        ordinate types 5 and 6; for an uneven abscissa, the values' own
        abscissa). A time record (function type 1, real, even abscissa) has
        ``x`` None (``abscissa_min``, ``abscissa_inc`` and ``num_pts`` give
        it) and ``data`` a read-only :class:`numpy.memmap` of the file.

    """
    id_line, *records = block.header
    dset: dict[str, Any] = {"type": 58, "binary": 1}
    dset.update(
        _fields(id_line[6:], (("", 1, 1), ("byte_ordering", 6, 2), ("fp_format", 6, 2),
                              ("n_ascii_lines", 12, 2), ("n_bytes", 12, 2)))
    )  # fmt: skip
    dset.pop("", None)
    for k in range(5):
        dset[f"id{k + 1}"] = records[k].decode("utf-8", errors="replace").rstrip("\r\n").strip()
    for record, fields in zip(records[5:], _RECORDS, strict=False):
        dset.update(_fields(record, fields))
    order = "<" if dset.get("byte_ordering") == 1 else ">"
    kind = int(dset.get("ord_data_type", 4))
    width = 4 if kind in (2, 5) else 8
    offset, n_bytes = block.data
    complex_values = kind in (5, 6)
    even = int(dset.get("abscissa_spacing", 1)) != 0
    per_point = (2 if complex_values else 1) + (0 if even else 1)
    points = n_bytes // width // per_point  # as pyuff: what the bytes hold (the reader checks num_pts)
    if int(dset.get("func_type", 0)) == 1 and even and not complex_values and points > 0:
        # a time record: its values mapped from the file, not read (the reader copies them where
        # they go, then drops the mapping); the time axis is in the header
        dset["x"] = None
        dset["data"] = np.memmap(path, dtype=f"{order}f{width}", mode="r", offset=offset, shape=(points,))
        return dset
    with open(path, "rb") as fh:
        fh.seek(offset)
        values = np.fromfile(fh, dtype=f"{order}f{width}", count=points * per_point).astype(float)
    values = values.reshape(points, per_point)
    if per_point in (2, 3) and not (per_point == 2 and complex_values):  # uneven abscissa: x first
        dset["x"], values = values[:, 0].copy(), values[:, 1:]
    else:
        dset["x"] = float(dset.get("abscissa_min", 0.0)) + np.arange(points) * float(dset.get("abscissa_inc", 0.0))
    dset["data"] = values[:, 0] + 1j * values[:, 1] if complex_values else values[:, 0].copy()
    return dset


def blocks_text(path: str | os.PathLike[str], blocks: list[Block]) -> bytes:
    """The bytes of `blocks`, in order (the datasets pyuff is given)."""
    parts = []
    with open(Path(path), "rb") as fh:
        for block in blocks:
            fh.seek(block.start)
            parts.append(fh.read(block.end - block.start))
    return b"".join(parts)
