"""Impact records in binary files: NumPy ``.npy``/``.npz``, MATLAB ``.mat``, HDF5 ``.h5``, WAV and TDMS.

The layouts (also in ``docs/FORMATS.md``):

``.npy``
    One 2-D float array, samples x (1 + sensors): column 0 is time (s), the
    other columns are the layout's sensors **in layout order** (a ``.npy``
    file has no room for names).
``.wav``
    A WAV file (PCM 8, 16, 24 or 32-bit integers, or 32/64-bit floats), its
    channels the layout's sensors **in layout order**, sampled at its rate
    (time starts at 0). Values as stored: integers are counts (8-bit samples
    centred on 0), so the channels must share one scale, or be calibrated
    floats; mode shapes compare channels.
``.tdms``
    One group of channels named by sensor id, plus optionally ``time``;
    else the channels' ``wf_increment`` (:mod:`rigidid.io.records.tdms`).
``.npz``, ``.mat``, ``.h5``/``.hdf5``
    Named arrays (``.h5``: datasets at the root of the file), either

    - ``data`` (samples x channels) and ``channels`` (the channel names, one
      per column: an array of strings, a MATLAB cell array or char matrix), or
    - one 1-D array per channel, named by its sensor id;

    and the sampling, one of

    - ``time`` (1-D, s, uniformly sampled; checked like the CSV time column),
    - ``dt`` (scalar, s) or ``sample_rate`` (scalar, Hz): time starts at 0.

    In ``.h5`` files ``dt`` and ``sample_rate`` may also be attributes of the
    root or of the ``data`` dataset. Names are matched exactly (surrounding
    spaces removed), as the CSV reader matches its header.

This module only opens the file and returns the named columns; the checks
shared with the CSV reader (sensor ids, finite values, uniform time, decay)
are in :mod:`rigidid.io.records`. ``h5py`` is an optional dependency (the
``hdf5`` extra), imported only when an HDF5 file is read.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.errors import InputError
from rigidid.io.guard import guarded, reading
from rigidid.io.records.columns import RESERVED_FIELDS, channel_names

__all__ = ["BINARY_SUFFIXES", "BlockRecord", "RawRecord", "named_blocks", "npy_blocks", "read_binary", "write_binary"]

Array = NDArray[np.float64]

BINARY_SUFFIXES = (".npy", ".npz", ".mat", ".h5", ".hdf5", ".wav", ".tdms")


@dataclass(frozen=True)
class RawRecord:
    """The columns of a binary record before they are checked against the layout.

    Attributes
    ----------
    names : list of str or None
        Channel names, one per column of `data`; None for ``.npy`` (layout order).
    data : ndarray, shape (n, k)
    time : ndarray, shape (n,), or None
    dt : float or None
        From ``dt`` or ``1 / sample_rate`` when there is no `time`.
    field : str
        Where the channels came from, for messages (``"field 'data'"``).
    """

    names: list[str] | None
    data: Array
    time: Array | None
    dt: float | None
    field: str


def _field(name: str) -> str:
    return f"field {name!r}"


def _floats(value: Any, src: str, name: str) -> Array:
    if np.iscomplexobj(value):
        raise InputError("has complex values: records are real", source=src, location=_field(name))
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError("is not numeric", source=src, location=_field(name)) from None


def _scalar(value: Any, src: str, name: str) -> float:
    arr = _floats(value, src, name)
    if arr.size != 1:
        raise InputError(f"must be one number, has {arr.size} values", source=src, location=_field(name))
    number = float(arr.reshape(-1)[0])
    if not (math.isfinite(number) and number > 0.0):
        raise InputError(f"must be a positive number, is {number:g}", source=src, location=_field(name))
    return number


def _from_mapping(fields: dict[str, Any], attrs: dict[str, Any], src: str) -> RawRecord:
    """A record from named arrays (npz, mat, h5 root)."""
    time: Array | None = None
    dt: float | None = None
    if "time" in fields:
        time = _floats(fields["time"], src, "time").reshape(-1) if np.ndim(fields["time"]) else None
        if time is None:
            raise InputError("must be a 1-D array of sample times", source=src, location=_field("time"))
    for key in ("dt", "sample_rate"):
        for where in (fields, attrs):
            if key in where and time is None and dt is None:
                value = _scalar(where[key], src, key)
                dt = value if key == "dt" else 1.0 / value
    if time is None and dt is None:
        raise InputError("no sampling: give an array 'time', or a scalar 'dt' or 'sample_rate'", source=src)
    if "data" in fields:
        data = _floats(fields["data"], src, "data")
        if data.ndim == 1:
            data = data.reshape(-1, 1)
        if data.ndim != 2:
            raise InputError(f"must be 2-D (samples x channels), is {data.ndim}-D", source=src, location=_field("data"))
        if "channels" not in fields:
            raise InputError(
                "'data' needs 'channels', the names of its columns", source=src, location=_field("channels")
            )
        names = channel_names(fields["channels"])
        if len(names) != data.shape[1]:
            if len(names) == data.shape[0] and data.shape[1] != len(names):
                data = data.T  # channels x samples, as MATLAB users often store it
            else:
                raise InputError(
                    f"{len(names)} names for {data.shape[1]} columns of 'data'", source=src, location=_field("channels")
                )
        field = _field("data")
    else:
        names = [k for k in fields if k not in RESERVED_FIELDS and not k.startswith("__")]
        if not names:
            raise InputError("no channels: give 'data' and 'channels', or one array per sensor id", source=src)
        columns = []
        n = None
        for name in names:
            col = _floats(fields[name], src, name).reshape(-1)
            if n is not None and col.shape[0] != n:
                raise InputError(f"has {col.shape[0]} samples, others {n}", source=src, location=_field(name))
            n = col.shape[0]
            columns.append(col)
        data = np.column_stack(columns)
        names = [n.strip() for n in names]
        field = "the channel arrays"
    if time is not None and time.shape[0] != data.shape[0]:
        raise InputError(
            f"has {time.shape[0]} samples, the channels {data.shape[0]}", source=src, location=_field("time")
        )
    return RawRecord(names, np.ascontiguousarray(data), time, dt, field)


def _read_h5(path: Path, src: str) -> RawRecord:
    try:
        import h5py
    except ImportError:
        raise InputError("reading HDF5 needs h5py: pip install 'rigidid[hdf5]'", source=src) from None
    try:
        fh = h5py.File(path, "r")
    except OSError as exc:
        raise InputError(f"not an HDF5 file ({exc})", source=src) from None
    with fh:
        fields: dict[str, Any] = {}
        for key, item in fh.items():
            if isinstance(item, h5py.Dataset):
                fields[key] = item[()]
        attrs: dict[str, Any] = dict(fh.attrs)
        if "data" in fh and isinstance(fh["data"], h5py.Dataset):
            attrs.update({k: v for k, v in fh["data"].attrs.items() if k in ("dt", "sample_rate")})
    return _from_mapping(fields, attrs, src)


def npy_blocks(path: str | os.PathLike[str], rows: int) -> tuple[int, int, Any] | None:
    """A plain ``.npy`` record read `rows` rows at a time, without holding it whole.

    Returns
    -------
    (n, columns, blocks) or None
        Rows, columns and an iterator of float64 arrays ``(<= rows, columns)``
        (time in column 0); None when the file is not a C-ordered 2-D
        little-endian float64 array (then :func:`read_binary` loads it whole)
        or not a ``.npy`` file.
    """
    with Path(path).open("rb") as fh:
        try:
            version = np.lib.format.read_magic(fh)
            if version == (1, 0):
                shape, fortran, dtype = np.lib.format.read_array_header_1_0(fh)
            elif version == (2, 0):
                shape, fortran, dtype = np.lib.format.read_array_header_2_0(fh)
            else:
                return None
        except Exception:  # a damaged header (numpy's tokenizer raises TokenError too): read_binary names it
            return None
        offset = fh.tell()
    if fortran or dtype != np.dtype("<f8") or len(shape) != 2 or shape[1] < 2:
        return None
    n, columns = int(shape[0]), int(shape[1])

    def blocks() -> Any:
        with Path(path).open("rb") as data:
            data.seek(offset)
            for start in range(0, n, rows):
                count = min(rows, n - start) * columns
                block = np.fromfile(data, dtype="<f8", count=count)
                if block.size != count:
                    raise InputError("the file is shorter than its header says", source=str(path))
                yield block.reshape(-1, columns)

    return n, columns, guarded(blocks(), str(path), ".npy")


@dataclass(frozen=True)
class BlockRecord:
    """A ``.npz`` or ``.h5`` record (``data``, ``channels``, ``time`` or ``dt``) read in row blocks.

    Attributes
    ----------
    names : list of str or None
        Channel names, one per column of ``data`` (None: the layout's sensors
        in layout order, ``.wav``).
    rows : int
        Samples.
    dt : float or None
        The sample interval when the file has no ``time``.
    blocks : iterator of (ndarray or None, ndarray)
        ``(time[start:stop] or None, data[start:stop])`` in order; the file
        is closed when it ends (or is closed).
    field : str
        ``"field 'data'"``, for messages.
    """

    names: list[str] | None
    rows: int
    dt: float | None
    blocks: Any
    field: str
    columns: int = 0

    @property
    def count(self) -> int:
        """Columns of ``data``."""
        return len(self.names) if self.names is not None else self.columns


def _wav(path: Path, src: str, mmap: bool) -> tuple[float, Any]:
    """Sample rate and the samples (n, channels) of a WAV file (scipy's reader)."""
    import warnings

    from scipy.io import wavfile

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", wavfile.WavFileWarning)  # chunks it skips (metadata)
            rate, data = wavfile.read(path, mmap=mmap)
    except ZeroDivisionError:
        raise InputError(
            "its channel count, block size and bit depth disagree (0 bytes per sample)", source=src, location="header"
        ) from None
    except (ValueError, TypeError, UnboundLocalError) as exc:  # a format field scipy maps to no type; no data chunk
        if mmap:
            raise ValueError(str(exc)) from None
        reason = "no data chunk" if isinstance(exc, UnboundLocalError) else str(exc).splitlines()[0]
        raise InputError(f"not a WAV file scipy reads ({reason})", source=src) from None
    except OSError as exc:
        raise InputError(f"cannot read it as WAV ({exc})", source=src) from None
    if not float(rate) > 0.0:
        raise InputError(f"its sample rate is {rate}", source=src, location="header")
    if data.ndim == 2 and data.shape[1] == 0:
        raise InputError("its header gives 0 channels", source=src, location="header")
    values = data.reshape(-1, 1) if data.ndim == 1 else data
    return float(rate), values


def _wav_floats(block: Any) -> Array:
    """WAV samples as float64: values as stored, 8-bit (unsigned) samples centred on 0."""
    values = np.asarray(block, dtype=np.float64)
    if block.dtype == np.uint8:
        values -= 128.0
    return values


def _wav_blocks(path: Path, rows: int) -> BlockRecord | None:
    try:
        rate, data = _wav(path, str(path), mmap=True)
    except (ValueError, InputError):  # a bit depth scipy cannot map (24-bit): read whole instead
        return None
    if not isinstance(data, np.memmap) or data.filename is None:
        return None
    n, columns, dtype, offset = int(data.shape[0]), int(data.shape[1]), data.dtype, int(data.offset)
    del data  # read from the file, not the mapping: its pages would count as the process's memory

    def blocks() -> Any:
        with path.open("rb") as fh:
            fh.seek(offset)
            for start in range(0, n, rows):
                count = min(rows, n - start)
                block = np.fromfile(fh, dtype=dtype, count=count * columns)
                if block.size != count * columns:
                    raise InputError("the file is shorter than its header says", source=str(path))
                yield None, _wav_floats(block.reshape(count, columns))

    return BlockRecord(None, n, 1.0 / rate, blocks(), "channels", columns=columns)


def named_blocks(path: str | os.PathLike[str], rows: int) -> BlockRecord | None:
    """A ``.npz`` or ``.h5`` record read `rows` rows at a time, without holding it whole.

    Returns
    -------
    BlockRecord or None
        None when the file is not of the ``data``/``channels`` layout with
        ``time`` (same length) or a positive ``dt``/``sample_rate`` (``.npz``:
        float64 members in C order, stored or compressed); :func:`read_binary`
        then loads it whole and names what is wrong.
    """
    p = Path(path)
    if not p.is_file():
        return None
    try:
        with reading(str(p), p.suffix.lower()):
            found = _named_blocks(p, rows)
    except InputError:
        return None  # read_binary names the fault
    if found is None:
        return None
    return BlockRecord(found.names, found.rows, found.dt, guarded(found.blocks, str(p), p.suffix.lower()), found.field,
                       found.columns)  # fmt: skip


def _named_blocks(p: Path, rows: int) -> BlockRecord | None:
    suffix = p.suffix.lower()
    if suffix in (".npz", ".h5", ".hdf5", ".mat"):
        from rigidid.io.records.arrays import open_blocks

        opened = open_blocks(p, rows)
        if opened is None:
            return None
        plan, parts = opened
        return BlockRecord(plan.names, plan.rows, plan.dt, parts, plan.field)
    if suffix == ".wav":
        return _wav_blocks(p, rows)
    if suffix == ".tdms":
        from rigidid.io.records.tdms import open_tdms

        try:
            names, n, dt, parts = open_tdms(p, rows)
        except InputError:
            return None  # read_binary names the fault
        return BlockRecord(names, n, dt, parts, "channels")
    return None


def read_binary(path: str | os.PathLike[str]) -> RawRecord:
    """Open a binary record and return its named columns (layouts in the module documentation).

    This loads the file whole (``.mat`` v4 to v7.2 by :func:`scipy.io.loadmat`,
    v7.3 by h5py): it serves the readers that need every sample, and names
    the fault of a file :func:`named_blocks` declines. Streamed reading goes
    through :func:`named_blocks` / :func:`npy_blocks` first; a file they
    cannot stream (complex, sparse, struct or cell data, v4 ``.mat``, 24-bit
    WAV) is read here and then cut into blocks.

    Raises
    ------
    InputError
        One line naming the file and the field: missing file, not a file of
        its suffix's format, missing or misshapen fields, h5py not installed.
    """
    src = str(path)
    p = Path(path)
    if not p.exists():
        raise InputError("file not found", source=src)
    if p.is_dir():
        raise InputError("is a folder, not a file", source=src)
    with reading(src, p.suffix.lower()):
        return _read_binary(p, src)


def _read_binary(p: Path, src: str) -> RawRecord:
    suffix = p.suffix.lower()
    if suffix in (".h5", ".hdf5"):
        return _read_h5(p, src)
    if suffix == ".npy":
        try:
            arr = np.load(p, allow_pickle=False)
        except (ValueError, OSError, EOFError) as exc:
            raise InputError(f"not a .npy file ({exc})", source=src) from None
        arr = _floats(arr, src, "array")
        if arr.ndim != 2 or arr.shape[1] < 2:
            raise InputError(
                f"must be 2-D, samples x (time + sensors), is {arr.shape}", source=src, location=_field("array")
            )
        return RawRecord(None, np.ascontiguousarray(arr[:, 1:]), np.ascontiguousarray(arr[:, 0]), None, "columns")
    if suffix == ".npz":
        import zipfile

        if not zipfile.is_zipfile(p):
            raise InputError("not a .npz file (not a zip archive, or truncated)", source=src)
        from rigidid.io.records.arrays import npz_headers

        with zipfile.ZipFile(p) as zf:
            npz_headers(zf, src)
        try:
            with np.load(p, allow_pickle=False) as npz:
                fields = {key: npz[key] for key in npz.files}
        except (ValueError, OSError, EOFError) as exc:
            raise InputError(f"not a .npz file ({exc})", source=src) from None
        return _from_mapping(fields, {}, src)
    if suffix == ".wav":
        rate, data = _wav(p, src, mmap=False)
        return RawRecord(None, _wav_floats(data), None, 1.0 / rate, "channels")
    if suffix == ".tdms":
        from rigidid.io.records.tdms import open_tdms

        names, _, dt, parts = open_tdms(p, 1 << 16)
        pieces = list(parts)
        time = None if dt is not None else np.concatenate([t for t, _ in pieces]) if pieces else np.empty(0)
        data = np.concatenate([v for _, v in pieces]) if pieces else np.empty((0, len(names)))
        return RawRecord(names, data, time, dt, "channels")
    if suffix == ".mat":
        from scipy.io import loadmat

        from rigidid.io.records.arrays import is_mat73, mat73_fields

        if is_mat73(p):  # MATLAB v7.3 is HDF5
            try:
                import h5py  # noqa: F401
            except ImportError:
                raise InputError(
                    "reading MATLAB v7.3 files needs h5py: pip install 'rigidid[hdf5]'", source=src
                ) from None
            return _from_mapping(mat73_fields(p, src), {}, src)
        try:
            mat = loadmat(p, squeeze_me=True, chars_as_strings=True)
        except Exception as exc:  # scipy raises several unrelated types on a bad file
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise InputError(f"not a MATLAB file ({reason})", source=src) from None
        return _from_mapping({k: v for k, v in mat.items() if not k.startswith("__")}, {}, src)
    raise InputError(f"unknown record suffix {suffix!r} (one of .csv {' '.join(BINARY_SUFFIXES)})", source=src)


def _rate_resolution(step: float, digits: int | None) -> float:
    """How far a rate of time step `step` (s) can be from the true one: 1e-6 of it, or a step kept to `digits`
    significant digits: one unit of its last digit, ``unit / step^2`` (Hz)."""
    rate = 1.0 / step
    if digits is None:
        return 1e-6 * rate
    unit = 10.0 ** (math.floor(math.log10(step)) - (digits - 1))
    return max(1e-6 * rate, unit * rate * rate)


def write_binary(
    path: str | os.PathLike[str],
    time: ArrayLike,
    data: ArrayLike,
    sensor_ids: Sequence[str],
    *,
    step_digits: int | None = None,
) -> None:
    """Write a record as ``.npz`` or ``.h5`` (``time``, ``data``, ``channels``) or ``.wav``, atomically.

    A ``.wav`` file holds the channels in the order given as 64-bit floats
    (exact), at the record's rate, which must be a whole number of Hz; it
    keeps no names (its channels are read in layout order). With
    `step_digits` (the significant digits the time step was written with: 6
    in a UFF 58), the rate is a whole number when it is one to that
    resolution (a UFF's ``1.95312E-03`` s is 512 Hz, not 512.0013 Hz).

    Raises
    ------
    InputError
        For another suffix, ``.h5`` without h5py, or a WAV of a rate that is
        not a whole number of Hz.
    """
    from rigidid.io.atomic import atomic_path

    p = Path(path)
    suffix = p.suffix.lower()
    t = np.asarray(time, dtype=float)
    x = np.asarray(data, dtype=float)
    names = np.array([str(s) for s in sensor_ids])
    if suffix == ".npz":
        with atomic_path(p) as tmp, tmp.open("wb") as fh:
            np.savez(fh, time=t, data=x, channels=names)
    elif suffix in (".h5", ".hdf5"):
        try:
            import h5py
        except ImportError:
            raise InputError("writing HDF5 needs h5py: pip install 'rigidid[hdf5]'", source=str(p)) from None
        with atomic_path(p) as tmp, h5py.File(tmp, "w") as fh:
            fh.create_dataset("time", data=t)
            fh.create_dataset("data", data=x)
            fh.create_dataset("channels", data=[s.encode("utf-8") for s in names])
    elif suffix == ".mat":
        from scipy.io import savemat

        with atomic_path(p) as tmp, tmp.open("wb") as fh:  # MATLAB v5, uncompressed: read back in row blocks
            savemat(fh, {"time": t, "data": x, "channels": np.array(list(names), dtype=object)}, oned_as="column")
    elif suffix == ".wav":
        from scipy.io import wavfile

        step = np.diff(t)
        if t.size < 2 or not np.all(step > 0) or np.ptp(step) > 1e-9 * float(np.mean(step)):
            raise InputError("a WAV file holds uniformly sampled records only", source=str(p))
        mean_step = float(np.mean(step))
        rate = 1.0 / mean_step
        written = ""
        if step_digits is not None:
            written = f" (its step {mean_step:.{step_digits}g} s kept to {step_digits} digits)"
        if abs(rate - round(rate)) > _rate_resolution(mean_step, step_digits):
            raise InputError(
                f"a WAV file's sample rate is a whole number of Hz, this one is {rate:.9g} Hz{written}", source=str(p)
            )
        with atomic_path(p) as tmp:
            wavfile.write(tmp, round(rate), np.ascontiguousarray(x, dtype=np.float64))  # 64-bit float: exact
    else:
        raise InputError(f"records are written as .csv, .npz, .mat, .h5 or .wav, not {suffix!r}", source=str(p))
