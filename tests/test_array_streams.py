"""Named binary records (.npz, .mat v5 and v7.3, .h5) read in row blocks: equal to the file, bad files named."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from scipy.io import loadmat, savemat

from rigidid.errors import InputError
from rigidid.io.records.binary import named_blocks, read_binary, write_binary
from rigidid.io.records.streamed import read_record_streamed

IDS = ["a", "b c", "d"]
N = 1003
BLOCK = 100


def _record() -> tuple[np.ndarray, np.ndarray]:
    x = np.random.default_rng(7).standard_normal((N, len(IDS)))
    return np.arange(N) * 1e-3, x


def write_mat73(path: Path, fields: dict[str, np.ndarray | list[str]]) -> None:
    """A MATLAB v7.3 file as MATLAB lays it out: 512-byte user block, transposed arrays, cells of uint16 chars."""
    h5py = pytest.importorskip("h5py")
    with h5py.File(path, "w", userblock_size=512) as fh:
        refs = fh.create_group("#refs#")
        for name, value in fields.items():
            if isinstance(value, list):  # cell array (1 x k) of char row vectors
                cells = []
                for i, text in enumerate(value):
                    chars = refs.create_dataset(
                        f"{name}{i}", data=np.array([ord(c) for c in text], "u2").reshape(-1, 1)
                    )
                    chars.attrs["MATLAB_class"] = np.bytes_("char")
                    cells.append(chars.ref)
                ds = fh.create_dataset(name, data=np.array(cells, dtype=h5py.ref_dtype).reshape(-1, 1))
                ds.attrs["MATLAB_class"] = np.bytes_("cell")
            else:
                arr = np.atleast_2d(value) if np.ndim(value) < 2 else value
                if np.ndim(value) == 1:
                    arr = arr.T  # MATLAB saves a vector as a column
                ds = fh.create_dataset(name, data=np.ascontiguousarray(arr.T))
                ds.attrs["MATLAB_class"] = np.bytes_("double")


def _mat(compress: bool) -> Callable[[Path, dict], None]:
    return lambda path, fields: savemat(path, fields, do_compression=compress)


def _npz(path: Path, fields: dict) -> None:
    np.savez(path, **fields)


def _npz_deflated(path: Path, fields: dict) -> None:
    np.savez_compressed(path, **fields)


def _h5(path: Path, fields: dict) -> None:
    h5py = pytest.importorskip("h5py")
    with h5py.File(path, "w") as fh:
        for name, value in fields.items():
            fh.create_dataset(name, data=value if value.dtype.kind != "U" else np.char.encode(value, "utf-8"))


WRITERS = {
    "mat5": (".mat", _mat(False)),
    "mat5-zlib": (".mat", _mat(True)),
    "mat73": (".mat", write_mat73),
    "npz": (".npz", _npz),
    "npz-deflated": (".npz", _npz_deflated),
    "h5": (".h5", _h5),
}


def _layouts(t: np.ndarray, x: np.ndarray, kind: str) -> dict[str, dict]:
    cells: object = list(IDS) if kind == "mat73" else np.array(IDS, dtype=object)
    names = cells if kind.startswith("mat") else np.array(IDS)
    layouts = {
        "data-time": {"time": t, "data": x, "channels": names},
        "channels-x-samples": {"sample_rate": np.float64(1000.0), "data": np.ascontiguousarray(x.T), "channels": names},
        "per-sensor": {"dt": np.float64(1e-3), "b c": x[:, 1], "d": x[:, 2], "a": x[:, 0]},
    }
    if kind.startswith("npz"):
        layouts["fortran"] = {"time": t, "data": np.asfortranarray(x), "channels": names}
        layouts["int16-big-endian"] = {"time": t, "data": (x * 1000).astype(">i2"), "channels": names}
    if kind.startswith("mat5"):
        layouts["char-matrix"] = {"time": t, "data": x, "channels": np.array(["a  ", "b c", "d  "])}
        layouts["single"] = {"time": t, "data": x.astype(np.float32), "channels": names}
        layouts["per-sensor"] = {"dt": 1e-3, "d": x[:, 2], "a": x[:, 0], "e": x[:, 1]}  # MATLAB names: no space
    if kind == "h5":
        layouts["per-sensor"]["a"] = x[:, 0]
    return layouts


CASES = [(kind, name) for kind in WRITERS for name in _layouts(*_record(), kind)]


@pytest.mark.parametrize(("kind", "layout"), CASES, ids=[f"{k}-{n}" for k, n in CASES])
def test_blocks_equal_the_written_record_and_the_whole_read(tmp_path: Path, kind: str, layout: str) -> None:
    t, x = _record()
    suffix, write = WRITERS[kind]
    fields = _layouts(t, x, kind)[layout]
    path = tmp_path / f"rec{suffix}"
    write(path, fields)
    want = np.asarray(fields["data"], dtype=float) if "data" in fields else None
    if want is not None and want.shape[0] != N:
        want = want.T
    ids = IDS if "e" not in fields else ["a", "e", "d"]
    if want is None:
        want = np.column_stack([fields[s] for s in ids]).astype(float)
    blocks = named_blocks(path, BLOCK)
    assert blocks is not None, "not read in row blocks"
    assert blocks.rows == N and sorted(blocks.names or []) == sorted(ids)
    parts = list(blocks.blocks)
    assert max(v.shape[0] for _, v in parts) == BLOCK and len(parts) == -(-N // BLOCK)
    got = np.concatenate([v for _, v in parts])[:, [blocks.names.index(s) for s in ids]]  # type: ignore[union-attr]
    np.testing.assert_array_equal(got, want)
    if "time" in fields:
        np.testing.assert_array_equal(np.concatenate([tt for tt, _ in parts]), t)
    else:
        assert blocks.dt == pytest.approx(1e-3, rel=1e-15)
    whole = read_binary(path)
    np.testing.assert_array_equal(whole.data[:, [whole.names.index(s) for s in ids]], want)  # type: ignore[union-attr]


def test_real_matlab_files_stream_to_what_loadmat_reads() -> None:
    """MATLAB-written v5/v7 files shipped with scipy's tests (big-endian, compressed): the same values."""
    import scipy.io.matlab

    from rigidid.io.records.arrays import _mat5_arrays, _stream_reader, is_mat73, scan_mat5

    folder = Path(scipy.io.matlab.__file__).parent / "tests" / "data"
    files = sorted(folder.glob("test*_7.*_GLNX86.mat")) + sorted(folder.glob("big_endian.mat"))
    if not files:
        pytest.skip("scipy's MATLAB test files are not installed")
    compared = 0
    for path in files:
        scanned = scan_mat5(path)
        if is_mat73(path):
            continue
        assert scanned is not None, path.name
        reference = loadmat(path)
        for name, arr in _mat5_arrays(path, scanned[0]).items():
            if name not in reference or arr.shape[0] == 0 or len(arr.shape) != 2:
                continue
            closers: list = []
            got = _stream_reader(arr, 0, closers)(arr.shape[0])
            for item in closers:
                item.close()
            np.testing.assert_array_equal(got, np.asarray(reference[name], dtype=float), err_msg=path.name)
            compared += 1
    assert compared >= 5


def test_convert_writer_mat_round_trips(tmp_path: Path) -> None:
    t, x = _record()
    path = tmp_path / "rec.mat"
    write_binary(path, t, x, IDS)
    blocks = named_blocks(path, BLOCK)
    assert blocks is not None and blocks.names == IDS
    np.testing.assert_array_equal(np.concatenate([v for _, v in blocks.blocks]), x)
    whole = read_binary(path)
    assert whole.names == IDS
    np.testing.assert_array_equal(whole.data, x)
    np.testing.assert_array_equal(whole.time, t)


def _truncate(path: Path, keep: int) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: len(data) - keep])


@pytest.mark.parametrize(
    ("name", "fault", "message"),
    [
        ("truncated.mat", "truncated", "shorter than its header says"),
        ("damaged-zlib.mat", "damaged", "not a MATLAB file"),
        ("wrong-lengths.mat", "lengths", "field 'b'"),
        ("no-channel-names.mat", "names", "field 'channels'"),
        ("names-for-other-columns.mat", "count", "2 names for 3 columns"),
        ("no-sampling.mat", "sampling", "no sampling"),
        ("truncated-v73.mat", "truncated73", "not a MATLAB file"),
    ],
)
def test_bad_mat_is_one_line_naming_file_and_field(tmp_path: Path, name: str, fault: str, message: str) -> None:
    t, x = _record()
    path = tmp_path / name
    ids = ["a", "b"]
    if fault == "truncated":
        # data last: the names and time are read, the values stop short
        savemat(path, {"channels": np.array(ids, dtype=object), "time": t, "data": x[:, :2]})
        _truncate(path, 4000)
    elif fault == "damaged":
        savemat(path, {"time": t, "data": x[:, :2], "channels": np.array(ids, dtype=object)}, do_compression=True)
        raw = bytearray(path.read_bytes())
        raw[400:440] = bytes(40)
        path.write_bytes(bytes(raw))
    elif fault == "lengths":
        savemat(path, {"dt": 1e-3, "a": x[:, 0], "b": x[:-5, 1]})
    elif fault == "names":
        savemat(path, {"time": t, "data": x[:, :2]})
    elif fault == "count":
        savemat(path, {"time": t, "data": x, "channels": np.array(ids, dtype=object)})
    elif fault == "sampling":
        savemat(path, {"a": x[:, 0], "b": x[:, 1]})
    else:
        write_mat73(path, {"time": t, "data": x[:, :2], "channels": ids})
        _truncate(path, 6000)
    with pytest.raises(InputError) as info:
        read_record_streamed(path, ids).data.sum()
    text = str(info.value)
    assert "\n" not in text and str(path) in text and message in text, text


def test_bad_mat_record_exits_2_with_one_line(tmp_path: Path) -> None:
    from rigidid import api

    from .cli_runner import run
    from .test_record_formats import ENGINE

    ids = [s.id for s in api.load_layout(ENGINE / "layout.json").sensors]
    t = np.arange(4000) * 1e-3
    x = np.exp(-t)[:, None] * np.random.default_rng(1).standard_normal((t.size, len(ids)))
    path = tmp_path / "truncated.mat"
    savemat(path, {"channels": np.array(ids, dtype=object), "time": t, "data": x})
    _truncate(path, 4000)
    out = run("modes", ENGINE / "layout.json", path, "-o", tmp_path / "modes.csv")
    assert out.returncode == 2 and len(out.stderr.strip().splitlines()) == 1 and str(path) in out.stderr
    assert "field 'data'" in out.stderr and "shorter than its header says" in out.stderr
    assert not (tmp_path / "modes.csv").exists()
