"""Named arrays of ``.npz``, ``.mat`` (v5 and v7.3) and ``.h5`` files read in row blocks.

The record layouts are those of :mod:`rigidid.io.records.binary`: ``data``
plus ``channels``, or one 1-D array per sensor id; ``time`` or a scalar
``dt``/``sample_rate``. This module finds where each array's values sit and
reads them a block of samples at a time, so the memory held is one block,
whatever the file's size:

- ``.npz`` members are read from their zip stream (stored or deflated); a
  member whose channels are contiguous (Fortran order ``(n, k)``, or C order
  ``(k, n)``) is read through one stream per channel (deflated: decompressed
  once to a temporary file, then read a block per channel).
- MATLAB v5 ``.mat`` variables are found by walking the file's data-element
  tags (MATLAB 5.0 MAT-file format: 128-byte header, then ``miMATRIX`` or
  ``miCOMPRESSED`` elements). Uncompressed numeric variables are read from
  their offset in the file, one channel at a time (MATLAB matrices are
  column-major: a channel of ``data`` (samples x channels) is contiguous);
  compressed ones (zlib) through :func:`zlib.decompressobj`, a ``data``
  matrix decompressed once to a temporary file, then read a block per
  channel. Small variables (``channels``, ``dt``, ``sample_rate``) are read
  by :func:`scipy.io.loadmat` restricted to them.
- MATLAB v7.3 ``.mat`` files are HDF5: MATLAB writes an ``m x n`` matrix as
  the dataset of shape ``(n, m)``; cell arrays of names as object references
  to ``uint16`` character arrays, char matrices as ``uint16`` datasets.

:func:`open_blocks` returns None when a file does not fit (not numeric,
sparse or complex arrays, inconsistent shapes, v4 files...); the caller then
loads it whole, which names the fault.
"""

from __future__ import annotations

import io
import math
import struct
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from rigidid.errors import InputError
from rigidid.io.records.columns import RESERVED_FIELDS, channel_names

__all__ = ["MatVar", "is_mat73", "mat73_fields", "npz_headers", "open_blocks", "scan_mat5"]

Array = NDArray[np.float64]
Reader = Callable[[int], Array]  # next `count` samples, (count, m)

_CHUNK = 1 << 16
_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


class _Raw:
    """A sequential byte source: a file region, a zlib stream in a file, or a zip member."""

    def __init__(self, fh: Any, src: str, name: str, inflate: bool = False) -> None:
        self.fh, self.src, self.name = fh, src, name
        self.dec = zlib.decompressobj() if inflate else None
        self.tail = b""

    def read(self, size: int) -> bytes:
        if self.dec is None:
            out = self.fh.read(size)
        else:
            buf = bytearray()
            while len(buf) < size and not self.dec.eof:
                feed = self.tail or self.fh.read(_CHUNK)
                if not feed:
                    break
                try:
                    buf += self.dec.decompress(feed, size - len(buf))
                except zlib.error as exc:
                    raise InputError(
                        f"its compressed values are damaged ({exc})", source=self.src, location=f"field {self.name!r}"
                    ) from None
                self.tail = self.dec.unconsumed_tail
            out = bytes(buf)
        if len(out) != size:
            raise InputError(
                "the file is shorter than its header says", source=self.src, location=f"field {self.name!r}"
            )
        return bytes(out)

    def skip(self, size: int) -> None:
        if self.dec is None and isinstance(self.fh, io.BufferedReader):
            self.fh.seek(size, 1)
            return
        while size > 0:
            step = min(size, 1 << 20)
            self.read(step)
            size -= step

    def close(self) -> None:
        self.fh.close()


@dataclass(frozen=True)
class _Array:
    """A numeric array: logical shape (as numpy / MATLAB shows it), storage order, element type, opener."""

    shape: tuple[int, ...]
    fortran: bool
    dtype: np.dtype[Any]
    open: Callable[[], _Raw]  # a byte source positioned at the first value
    compressed: bool = False  # read only from the start (a zlib stream)


def _stream_reader(arr: _Array, samples_axis: int, closers: list[Any]) -> Reader:
    """Sequential reader of `arr`'s samples (along `samples_axis`) as float64 (count, channels)."""
    shape = arr.shape if len(arr.shape) == 2 else (arr.shape[0], 1)
    n = shape[samples_axis]
    k = shape[1 - samples_axis]
    size = arr.dtype.itemsize
    # interleaved: the values of one sample are adjacent
    interleaved = k == 1 or (samples_axis == 0) != arr.fortran
    if interleaved:
        raw = arr.open()
        closers.append(raw)

        def take(count: int) -> Array:
            values = np.frombuffer(raw.read(count * k * size), dtype=arr.dtype)
            return np.asarray(values, dtype=np.float64).reshape(count, k)

        return take
    if arr.compressed:
        return _spooled_columns(arr, n, k, closers)
    raws = []
    for j in range(k):
        raw = arr.open()
        closers.append(raw)
        raw.skip(j * n * size)
        raws.append(raw)

    def take_columns(count: int) -> Array:
        out = np.empty((count, k))
        for j, raw in enumerate(raws):
            out[:, j] = np.frombuffer(raw.read(count * size), dtype=arr.dtype)
        return out

    return take_columns


def _spooled_columns(arr: _Array, n: int, k: int, closers: list[Any]) -> Reader:
    """Channels stored one after another in a compressed stream: decompressed once to a temporary file, then read.

    Reading each channel through its own decompressor would decompress the
    stream up to k times over; the temporary file (the array's size on disk,
    in the system's temporary folder) costs one pass and bounded memory.
    """
    import tempfile

    size = arr.dtype.itemsize
    spool = tempfile.TemporaryFile()  # noqa: SIM115 (closed with the record's other files)
    closers.append(spool)
    where = [j * n * size for j in range(k)]
    state = {"filled": False}

    def fill() -> None:
        raw = arr.open()
        try:
            left = n * k * size
            while left:
                chunk = raw.read(min(left, 1 << 22))
                spool.write(chunk)
                left -= len(chunk)
        finally:
            raw.close()
        spool.flush()
        state["filled"] = True

    def take_columns(count: int) -> Array:
        if not state["filled"]:
            fill()
        out = np.empty((count, k))
        for j in range(k):
            spool.seek(where[j])
            out[:, j] = np.frombuffer(spool.read(count * size), dtype=arr.dtype)
            where[j] += count * size
        return out

    return take_columns


def _vector_length(shape: tuple[int, ...]) -> int | None:
    """Samples of a 1-D array or a row/column vector; None otherwise."""
    if len(shape) == 1:
        return shape[0]
    if len(shape) == 2 and min(shape) == 1:
        return max(shape)
    return None


def _positive(value: Any) -> float | None:
    try:
        arr = np.ravel(np.asarray(value, dtype=np.float64))
    except (TypeError, ValueError):
        return None
    if arr.size != 1 or not (math.isfinite(float(arr[0])) and float(arr[0]) > 0.0):
        return None
    return float(arr[0])


@dataclass
class _Plan:
    names: list[str]
    rows: int
    dt: float | None
    field: str
    time: tuple[str, int] | None  # (array name, samples axis)
    parts: list[tuple[str, int]]  # arrays read side by side, with their samples axis


def _plan(
    shapes: dict[str, tuple[int, ...]],
    small: Callable[[str], Any],
    names_of: Callable[[Any], list[str]],
    extra_dt: dict[str, Any],
) -> _Plan | None:
    """Decide how to read a record from its arrays' shapes (None: load it whole instead)."""
    time_part = None
    n_time = None
    dt = None
    if "time" in shapes:
        n_time = _vector_length(shapes["time"])
        if n_time is None:
            return None
        time_part = ("time", 0 if len(shapes["time"]) == 1 or shapes["time"][1] == 1 else 1)
    else:
        for key in ("dt", "sample_rate"):
            if dt is None and (key in shapes or key in extra_dt):
                value = _positive(small(key) if key in shapes else extra_dt[key])
                if value is None:
                    return None
                dt = value if key == "dt" else 1.0 / value
        if dt is None:
            return None
    if "data" in shapes:
        shape = shapes["data"]
        if "channels" not in shapes or len(shape) != 2:
            return None
        try:
            names = names_of(small("channels"))
        except (TypeError, ValueError, KeyError):
            return None
        if len(names) == shape[1]:
            axis = 0
        elif len(names) == shape[0]:
            axis = 1
        else:
            return None
        n = shape[axis]
        plan = _Plan(names, n, dt, "field 'data'", time_part, [("data", axis)])
    else:
        names = [k for k in shapes if k not in RESERVED_FIELDS and not k.startswith("__")]
        if not names:
            return None
        lengths = {_vector_length(shapes[k]) for k in names}
        if len(lengths) != 1 or None in lengths:
            return None
        n = int(lengths.pop() or 0)
        parts = [(k, 0 if len(shapes[k]) == 1 or shapes[k][1] == 1 else 1) for k in names]
        plan = _Plan([k.strip() for k in names], n, dt, "the channel arrays", time_part, parts)
    if n_time is not None and n_time != plan.rows:
        return None
    return plan


def _blocks(plan: _Plan, readers: list[Reader], time: Reader | None, rows: int, closers: list[Any]) -> Iterator[Any]:
    try:
        for start in range(0, plan.rows, rows):
            count = min(rows, plan.rows - start)
            t = time(count).reshape(-1) if time is not None else None
            parts = [read(count) for read in readers]
            yield t, (parts[0] if len(parts) == 1 else np.concatenate(parts, axis=1))
    finally:
        for item in closers:
            item.close()


def _numeric(dtype: np.dtype[Any]) -> bool:
    return dtype.kind in "fiu"


# ---------------------------------------------------------------- .npz


def npz_headers(zf: Any, src: str) -> dict[str, tuple[tuple[int, ...], bool, np.dtype[Any], int]]:
    """Each ``.npy`` member's (shape, Fortran order, dtype, header bytes), checked against its zip entry.

    Raises
    ------
    InputError
        A member whose array header does not fit its zip entry's size (a
        header claiming a huge array, a size field that lies), or is no
        ``.npy`` header.
    """
    import zipfile

    out = {}
    for info in zf.infolist():
        member = info.filename
        if not member.endswith(".npy"):
            continue
        with zf.open(member) as fh:
            version = np.lib.format.read_magic(fh)
            if version == (1, 0):
                shape, fortran, dtype = np.lib.format.read_array_header_1_0(fh)
            else:
                shape, fortran, dtype = np.lib.format.read_array_header_2_0(fh)
            skip = fh.tell()
        dtype = np.dtype(dtype)
        if not dtype.hasobject:
            expected = skip + math.prod(int(d) for d in shape) * dtype.itemsize
            stored = info.compress_type == zipfile.ZIP_STORED
            if info.file_size != expected or (stored and info.compress_size != info.file_size):
                raise InputError(
                    f"its zip entry holds {info.file_size} bytes, its array header {tuple(shape)} needs {expected}",
                    source=src, location=f"field {member[:-4]!r}",
                )  # fmt: skip
        out[member] = (tuple(int(d) for d in shape), bool(fortran), dtype, skip)
    return out


def _npz_arrays(path: Path) -> tuple[Any, dict[str, _Array]] | None:
    import zipfile

    try:
        zf = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError):
        return None
    try:
        headers = npz_headers(zf, str(path))
    except Exception:  # a damaged header raises many types (TokenError too): read_binary names it
        zf.close()
        return None
    arrays: dict[str, _Array] = {}
    for member, (shape, fortran, dtype, skip) in headers.items():

        def opener(member: str = member, skip: int = skip) -> _Raw:
            raw = _Raw(zf.open(member), str(path), member[:-4])
            raw.read(skip)
            return raw

        deflated = zf.getinfo(member).compress_type != zipfile.ZIP_STORED
        arrays[member[:-4]] = _Array(shape, fortran, dtype, opener, deflated)
    return zf, arrays


# ---------------------------------------------------------------- MATLAB v5

_MI = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 9: "f8", 12: "i8", 13: "u8"}
_MI_MATRIX, _MI_COMPRESSED = 14, 15
_NUMERIC_CLASSES = set(range(6, 16))


@dataclass(frozen=True)
class MatVar:
    """Where a numeric MATLAB v5 variable's real values start.

    Attributes
    ----------
    name : str
    dims : tuple of int
        MATLAB dimensions (column-major).
    dtype : numpy dtype
        The stored element type (MATLAB may store doubles as smaller integers).
    offset : int
        File offset of the values (uncompressed) or of the zlib stream (compressed).
    skip : int
        Bytes of the decompressed stream before the values (0 when uncompressed).
    compressed : bool
    """

    name: str
    dims: tuple[int, ...]
    dtype: np.dtype[Any]
    offset: int
    skip: int
    compressed: bool


def _tag(buf: bytes, pos: int, order: Literal["<", ">"]) -> tuple[int, int, int]:
    """(type, bytes, position of the data) of the data element tag at `pos` (small element format too)."""
    first, second = struct.unpack_from(order + "II", buf, pos)
    if first >> 16:
        return first & 0xFFFF, first >> 16, pos + 4
    return first, second, pos + 8


def _matrix_header(head: bytes, order: Literal["<", ">"]) -> tuple[str, tuple[int, ...], np.dtype[Any], int] | None:
    """Name, dims, stored dtype and data position of an ``miMATRIX`` element's bytes (None: not plain numeric)."""
    try:
        kind, _, pos = _tag(head, 0, order)
        if kind != _MI_MATRIX:
            return None
        kind, nbytes, at = _tag(head, pos, order)  # array flags
        flags = struct.unpack_from(order + "I", head, at)[0]
        pos = at + ((nbytes + 7) // 8) * 8
        if (flags & 0xFF) not in _NUMERIC_CLASSES or flags & 0x0800:  # complex
            return None
        kind, nbytes, at = _tag(head, pos, order)  # dimensions
        dims = struct.unpack_from(order + f"{nbytes // 4}i", head, at)
        pos = at + ((nbytes + 7) // 8) * 8 if at == pos + 8 else pos + 8
        kind, nbytes, at = _tag(head, pos, order)  # name
        name = head[at : at + nbytes].decode("ascii", errors="replace")
        pos = at + ((nbytes + 7) // 8) * 8 if at == pos + 8 else pos + 8
        kind, nbytes, at = _tag(head, pos, order)  # real part
        if kind not in _MI or at != pos + 8:
            return None
        dtype = np.dtype(_MI[kind]).newbyteorder(order)
        if nbytes != dtype.itemsize * int(np.prod(dims)):
            return None
        return name, tuple(int(d) for d in dims), dtype, at
    except struct.error:
        return None


def scan_mat5(path: Path) -> tuple[dict[str, MatVar], set[str]] | None:
    """The numeric variables of a MATLAB v5 file and the names of all its variables (None: not v5).

    Walks the top-level data elements without reading their values (a
    compressed element's first 4 kB are decompressed for its header).
    """
    found: dict[str, MatVar] = {}
    every: set[str] = set()
    size = path.stat().st_size
    with path.open("rb") as fh:
        header = fh.read(128)
        if len(header) < 128 or header[126:128] not in (b"IM", b"MI"):
            return None
        order: Literal["<", ">"] = "<" if header[126:128] == b"IM" else ">"
        pos = 128
        while pos + 8 <= size:
            fh.seek(pos)
            kind, nbytes = struct.unpack(order + "II", fh.read(8))
            start = pos + 8
            pos = start + nbytes
            if kind == _MI_MATRIX:
                pos = start + ((nbytes + 7) // 8) * 8
                fh.seek(start - 8)
                head = fh.read(min(nbytes + 8, 4096))
                parsed = _matrix_header(head, order)
                compressed = False
            elif kind == _MI_COMPRESSED:
                fh.seek(start)
                dec = zlib.decompressobj()
                head = b""
                while len(head) < 4096 and not dec.eof:
                    chunk = fh.read(min(_CHUNK, max(0, pos - fh.tell())))
                    if not chunk:
                        break
                    try:
                        head += dec.decompress(chunk, 4096 - len(head))
                    except zlib.error:
                        return None  # loadmat names the fault
                    if dec.unconsumed_tail:
                        break
                parsed = _matrix_header(head, order)
                compressed = True
            else:
                continue
            name = _element_name(head, order)
            if name:
                every.add(name)
            if parsed is None:
                continue
            name, dims, dtype, at = parsed
            if compressed:
                found[name] = MatVar(name, dims, dtype, start, at, True)
            else:
                found[name] = MatVar(name, dims, dtype, start - 8 + at, 0, False)
    return found, every


def _element_name(head: bytes, order: Literal["<", ">"]) -> str | None:
    try:
        _, _, pos = _tag(head, 0, order)
        for _ in range(2):  # flags, dims
            _, nbytes, at = _tag(head, pos, order)
            pos = at + ((nbytes + 7) // 8) * 8 if at == pos + 8 else pos + 8
        _, nbytes, at = _tag(head, pos, order)
        return head[at : at + nbytes].decode("ascii", errors="replace")
    except struct.error:
        return None


def _mat5_arrays(path: Path, variables: dict[str, MatVar]) -> dict[str, _Array]:
    arrays = {}
    for name, var in variables.items():

        def opener(var: MatVar = var) -> _Raw:
            fh = path.open("rb")
            fh.seek(var.offset)
            raw = _Raw(fh, str(path), var.name, inflate=var.compressed)
            if var.skip:
                raw.read(var.skip)
            return raw

        arrays[name] = _Array(var.dims, True, var.dtype, opener, var.compressed)
    return arrays


# ---------------------------------------------------------------- MATLAB v7.3 (HDF5)


def is_mat73(path: Path) -> bool:
    """Whether a ``.mat`` file is HDF5 (MATLAB v7.3: 512-byte user block, then the HDF5 signature)."""
    try:
        with path.open("rb") as fh:
            fh.seek(512)
            return fh.read(8) == _HDF5_SIGNATURE
    except OSError:
        return False


def _mat73_value(fh: Any, item: Any) -> Any:
    """A small v7.3 variable as loadmat would give it: char → str, cell of char → list of str, numeric transposed."""
    import h5py

    cls = item.attrs.get("MATLAB_class", b"")
    cls = cls.decode() if isinstance(cls, bytes) else str(cls)
    value = item[()]
    if cls == "char":
        chars = np.asarray(value).T  # rows of the MATLAB char matrix
        rows = chars.reshape(1, -1) if chars.ndim == 1 else chars
        return ["".join(chr(int(c)) for c in row).strip() for row in rows]
    if cls == "cell" or (isinstance(value, np.ndarray) and value.dtype == h5py.ref_dtype):
        out = []
        for ref in np.ravel(np.asarray(value).T):
            target = fh[ref]
            element = _mat73_value(fh, target)
            out.append(element[0] if isinstance(element, list) and len(element) == 1 else str(element))
        return out
    return np.asarray(value).T if isinstance(value, np.ndarray) else value


def mat73_fields(path: Path, src: str) -> dict[str, Any]:
    """Every variable of a MATLAB v7.3 file, as loadmat would give a v5 file's (the whole-file fallback)."""
    import h5py

    try:
        fh = h5py.File(path, "r")
    except OSError as exc:
        raise InputError(f"not a MATLAB file ({exc})", source=src) from None
    with fh:
        return {k: _mat73_value(fh, v) for k, v in fh.items() if isinstance(v, h5py.Dataset) and not k.startswith("#")}


def _h5_reader(dataset: Any, samples_axis: int) -> Reader:
    """Sequential reader of an HDF5 dataset's samples as float64 (count, channels)."""
    state = {"start": 0}
    vector = dataset.ndim == 1

    def take(count: int) -> Array:
        start = state["start"]
        state["start"] = start + count
        if vector:
            part = dataset[start : start + count].reshape(-1, 1)
        elif samples_axis == 0:
            part = dataset[start : start + count, :]
        else:
            part = dataset[:, start : start + count].T
        return np.ascontiguousarray(part, dtype=np.float64)

    return take


def _h5_record(path: Path, rows: int, mat73: bool) -> tuple[_Plan, Iterator[Any]] | None:
    try:
        import h5py
    except ImportError:
        return None
    try:
        fh = h5py.File(path, "r")
    except OSError:
        return None
    datasets = {k: v for k, v in fh.items() if isinstance(v, h5py.Dataset) and not k.startswith("#")}
    # MATLAB stores an m x n matrix as an (n, m) dataset: the logical shape is the reverse
    shapes = {k: (tuple(reversed(v.shape)) if mat73 else tuple(v.shape)) for k, v in datasets.items()}
    ok = all(_numeric(v.dtype) for k, v in datasets.items() if k not in ("channels",))
    extra: dict[str, Any] = {}
    if not mat73:
        extra = {k: v for k, v in fh.attrs.items() if k in ("dt", "sample_rate")}
        if "data" in datasets:
            extra.update({k: v for k, v in datasets["data"].attrs.items() if k in ("dt", "sample_rate")})

    def small(key: str) -> Any:
        return _mat73_value(fh, datasets[key]) if mat73 else datasets[key][()]

    plan = _plan(shapes, small, channel_names, extra) if ok else None
    if plan is None:
        fh.close()
        return None

    def reader(name: str, axis: int) -> Reader:
        # the dataset's axes are the logical ones reversed for MATLAB files
        return _h5_reader(datasets[name], 1 - axis if mat73 and datasets[name].ndim == 2 else axis)

    readers = [reader(name, axis) for name, axis in plan.parts]
    time = reader(*plan.time) if plan.time is not None else None
    return plan, _blocks(plan, readers, time, rows, [fh])


# ---------------------------------------------------------------- entry point


def open_blocks(path: Path, rows: int) -> tuple[_Plan, Iterator[Any]] | None:
    """A record of named arrays read `rows` samples at a time (None: load it whole instead).

    Returns
    -------
    (plan, blocks) or None
        ``plan.names`` (channel names), ``plan.rows``, ``plan.dt`` (None when
        the file has ``time``), ``plan.field``; `blocks` yields
        ``(time[start:stop] or None, data[start:stop])`` as float64 and closes
        the file when it ends or is closed.
    """
    suffix = path.suffix.lower()
    if suffix in (".h5", ".hdf5"):
        return _h5_record(path, rows, mat73=False)
    if suffix == ".mat" and is_mat73(path):
        return _h5_record(path, rows, mat73=True)
    closers: list[Any] = []
    if suffix == ".npz":
        opened = _npz_arrays(path)
        if opened is None:
            return None
        zf, arrays = opened
        closers.append(zf)

        def small(key: str) -> Any:
            with np.load(path, allow_pickle=False) as npz:
                return npz[key]

    elif suffix == ".mat":
        scanned = scan_mat5(path)
        if scanned is None:
            return None
        variables, every = scanned
        arrays = _mat5_arrays(path, variables)
        shapes_small = {k: (1,) for k in every if k not in arrays}

        def small(key: str) -> Any:
            from scipy.io import loadmat

            return loadmat(path, variable_names=[key], squeeze_me=True, chars_as_strings=True)[key]

    else:
        return None
    shapes = {k: a.shape for k, a in arrays.items()}
    if suffix == ".mat":
        shapes = {**shapes_small, **shapes}
        if any(k not in arrays for k in shapes if k not in ("channels", "dt", "sample_rate")):
            return None  # a non-numeric array: load it whole (its message)
    elif any(not _numeric(a.dtype) for k, a in arrays.items() if k != "channels"):
        for item in closers:
            item.close()
        return None
    try:
        plan = _plan(shapes, small, channel_names, {})
    except (ValueError, OSError, NotImplementedError, KeyError):
        plan = None
    if plan is None or any(name not in arrays for name, _ in plan.parts):
        for item in closers:
            item.close()
        return None
    readers = [_stream_reader(arrays[name], axis, closers) for name, axis in plan.parts]
    time = _stream_reader(arrays["time"], plan.time[1], closers) if plan.time is not None else None
    return plan, _blocks(plan, readers, time, rows, closers)
