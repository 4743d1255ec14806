"""Every reader under seeded mutations (benchmarks/fuzz.py's mutators) and the hostile files of issue 24.

A reader either returns or raises one :class:`InputError` whose single line names
the file; any other exception (a library's ``BadZipFile``, ``KeyError``,
``IndexError``...) fails the test. Fast: small files, a few cases per reader.
"""

from __future__ import annotations

import io
import json
import random
import struct
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rigidid.errors import InputError
from rigidid.io.files import load_mounts
from rigidid.io.frf import frf_csv_text, frf_uff_bytes, load_frf_csv, load_frf_uff, load_references
from rigidid.io.records import read_record
from rigidid.io.records.binary import write_binary
from rigidid.io.records.streamed import read_record_streamed
from rigidid.io.uff import read_uff, write_uff_test

from .conftest import SAMPLES
from .test_fuzz import _fuzzer

IDS = ["1", "2", "3"]
DIRS = ["+x", "+y", "+z"]
REFS = ["101", "102"]
CASES_PER_READER = 8


def _decay() -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(600) / 200.0
    x = np.column_stack([np.exp(-1.5 * t) * np.sin(2 * np.pi * f * t + k) for k, f in enumerate((11.0, 17.0, 23.0))])
    return t, x


def _files(folder: Path) -> dict[str, bytes]:
    """One small file per reader (records in every format, FRFs, references, mounts, UFF)."""
    t, x = _decay()
    out: dict[str, bytes] = {}
    for suffix in ("npz", "mat", "h5", "wav"):
        write_binary(folder / f"r.{suffix}", t, x, IDS)
        out[f"r.{suffix}"] = (folder / f"r.{suffix}").read_bytes()
    buf = io.BytesIO()
    np.save(buf, np.column_stack([t, x]))
    out["r.npy"] = buf.getvalue()
    from nptdms import ChannelObject, TdmsWriter

    with TdmsWriter(folder / "r.tdms") as writer:
        writer.write_segment([ChannelObject("impact", s, x[:, i], properties={"wf_increment": 0.005})
                              for i, s in enumerate(IDS)])  # fmt: skip
    out["r.tdms"] = (folder / "r.tdms").read_bytes()
    rows = ["time," + ",".join(IDS)]
    rows += [",".join(repr(float(v)) for v in (tt, *xx)) for tt, xx in zip(t, x, strict=True)]
    out["r.csv"] = ("\n".join(rows) + "\n").encode()
    out["r.semicolon.csv"] = out["r.csv"].decode().replace(",", ";").replace(".", ",").encode()
    sensors = [{"id": s, "position": [0.1 * k, 0.2, 0.3 - 0.1 * k], "direction": d}
               for k, (s, d) in enumerate(zip(IDS, DIRS, strict=True))]  # fmt: skip
    layout = {"units": {"length": "m", "mass": "kg"}, "sensors": sensors}
    write_uff_test(folder / "r.uff", layout, [(t, x, IDS)], binary=False)
    out["r.uff"] = (folder / "r.uff").read_bytes()
    freqs = np.linspace(1.0, 50.0, 40)
    frf = (np.arange(6).reshape(3, 2, 1) + 1.0) * (1.0 + 0.1j * freqs)
    out["f.csv"] = frf_csv_text(freqs, frf, IDS, REFS).encode()
    eye = np.eye(3)
    for name, binary in (("f.uff", False), ("fb.uff", True)):
        out[name] = frf_uff_bytes(freqs, frf, IDS, eye, REFS, eye[:2], {"length": "m", "mass": "kg"}, binary=binary)
    out["refs.json"] = json.dumps({"references": [{"id": r, "position": [0.1, 0.2, 0.3], "direction": "+x"}
                                                  for r in REFS]}).encode()  # fmt: skip
    out["mounts.json"] = (SAMPLES / "engine-on-mounts/mounts.json").read_bytes()
    out["local.unv"] = (SAMPLES / "uff-local-systems/test.unv").read_bytes()
    return out


def _read(name: str) -> Callable[[Path], Any]:
    if name.startswith("r.") and name != "r.uff":
        return lambda p: (read_record(p, IDS), read_record_streamed(p, IDS))
    if name.endswith(".uff") and name.startswith("f"):
        return lambda p: load_frf_uff(p, IDS, REFS)
    return {
        "r.uff": read_uff, "local.unv": read_uff, "f.csv": lambda p: load_frf_csv(p, IDS, REFS),
        "refs.json": load_references, "mounts.json": load_mounts,
    }[name]  # fmt: skip


def _contract(reader: Callable[[Path], Any], path: Path) -> str | None:
    """None when the reader kept the contract (read it, or one line naming the file); else what went wrong."""
    try:
        reader(path)
    except InputError as exc:
        text = str(exc)
        if "\n" in text or path.name not in text:
            return f"not one line naming the file: {text!r}"
    except Exception as exc:  # any other exception breaks the contract
        return f"{type(exc).__name__}: {exc}"
    return None


READERS = ["r.npy", "r.npz", "r.mat", "r.h5", "r.wav", "r.tdms", "r.csv", "r.semicolon.csv", "r.uff", "f.csv",
           "f.uff", "fb.uff", "refs.json", "mounts.json", "local.unv"]  # fmt: skip


@pytest.fixture(scope="module")
def base(tmp_path_factory: pytest.TempPathFactory) -> dict[str, bytes]:
    return _files(tmp_path_factory.mktemp("base"))


@pytest.mark.parametrize("name", READERS)
def test_every_reader_keeps_the_contract_on_mutated_files(
    base: dict[str, bytes], tmp_path: Path, name: str, capfd: pytest.CaptureFixture[str]
) -> None:
    fuzz = _fuzzer()
    reader = _read(name)
    assert _contract(reader, _write(tmp_path / name, base[name])) is None  # the unmutated file reads
    bad = []
    for i in range(CASES_PER_READER):
        data, what = fuzz.mutate(base[name], random.Random(20261126 + 7919 * i), name)
        path = _write(tmp_path / f"m{i}-{name}", data)
        fault = _contract(reader, path)
        if fault:
            bad.append(f"{name} [{what}]: {fault}")
    assert bad == []
    assert capfd.readouterr().err == ""  # no library's own lines (npTDMS's logged warnings) on stderr


def _write(path: Path, data: bytes) -> Path:
    path.write_bytes(data)
    return path


def _lying_npz(data: bytes) -> bytes:
    zz = bytearray(data)
    at = zz.rfind(b"PK\x01\x02")  # the last member's central directory entry: its uncompressed size
    struct.pack_into("<I", zz, at + 24, struct.unpack_from("<I", zz, at + 24)[0] + 800)
    return bytes(zz)


def _huge_npz() -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        head = io.BytesIO()
        np.lib.format.write_array_header_1_0(head, {"descr": "<f8", "fortran_order": False, "shape": (10**11, 3)})
        z.writestr("data.npy", head.getvalue() + bytes(800))
        for key, value in (("dt", np.array(0.005)), ("channels", np.array(IDS))):
            item = io.BytesIO()
            np.save(item, value)
            z.writestr(f"{key}.npy", item.getvalue())
    return buf.getvalue()


def _h5_link(kind: str) -> Callable[[Path], None]:
    def make(path: Path) -> None:
        import h5py

        t, _ = _decay()
        with h5py.File(path, "w") as fh:
            fh["time"] = t
            fh["channels"] = [s.encode() for s in IDS]
            fh["data"] = h5py.SoftLink("/nowhere") if kind == "soft" else h5py.ExternalLink("missing.h5", "/data")

    return make


def _uff_direction(data: bytes, code: int) -> bytes:
    lines = data.decode().split("\n")
    k = next(i for i, line in enumerate(lines) if line.strip() == "58") + 6  # record 6: nodes and directions
    lines[k] = lines[k][:51] + f"{code:4d}" + lines[k][55:]
    return "\n".join(lines).encode()


HOSTILE: list[tuple[str, str, Callable[[bytes], bytes], str]] = [
    ("npy header unclosed", "r.npy", lambda d: d.replace(b"}", b" ", 1), "r.npy: not a"),  # numpy's TokenError
    ("npz truncated", "r.npz", lambda d: d[: len(d) * 7 // 10], "not a .npz file"),
    ("npz bad CRC", "r.npz", lambda d: d[:400] + bytes([d[400] ^ 0xFF]) + d[401:], "r.npz"),
    ("npz lying size", "r.npz", _lying_npz, "its zip entry holds"),
    ("npz huge header", "r.npz", lambda d: _huge_npz(), "its zip entry holds"),
    ("wav format field", "r.wav", lambda d: d[:34] + bytes([48]) + d[35:], "not a WAV file"),
    ("wav no data chunk", "r.wav", lambda d: d.replace(b"data", b"dxta", 1), "not a WAV file scipy reads (no data"),
    ("wav zero channels", "r.wav", lambda d: d[:22] + bytes(2) + d[24:], "r.wav: header"),
    ("csv 1_0", "r.csv", lambda d: d.replace(b"\n0.5,", b"\n1_0,", 1), "'1_0' is not a number"),
    ("frf csv arabic digit", "f.csv", lambda d: d.replace(b"\n1.0,", "\n\u0661,".encode(), 1), "not a number"),
    ("frf csv huge cell", "f.csv", lambda d: d + b"9" * 200_000, "not valid CSV: field larger than field limit"),
    ("frf uff rotation", "f.uff", lambda d: _uff_direction(d, 4), "is a rotation about x"),
    ("frf uff direction 0", "f.uff", lambda d: _uff_direction(d, 0), "is not a UFF direction code"),
]  # fmt: skip


@pytest.mark.parametrize(("what", "name", "damage", "message"), HOSTILE, ids=[h[0] for h in HOSTILE])
def test_hostile_files_are_one_line_naming_the_file(
    base: dict[str, bytes], tmp_path: Path, what: str, name: str, damage: Callable[[bytes], bytes], message: str
) -> None:
    path = _write(tmp_path / name, damage(base[name]))
    with pytest.raises(InputError) as caught:
        _read(name)(path)
    assert message in str(caught.value) and "\n" not in str(caught.value)


@pytest.mark.parametrize("kind", ["soft", "external"])
def test_an_hdf5_link_to_nowhere_is_one_line(tmp_path: Path, kind: str) -> None:
    path = tmp_path / "r.h5"
    _h5_link(kind)(path)
    with pytest.raises(InputError, match=r"r\.h5: not a readable \.h5 file"):
        read_record_streamed(path, IDS)


@pytest.mark.parametrize("suffix", ["npy", "npz", "mat"])
def test_complex_records_are_refused(tmp_path: Path, suffix: str) -> None:
    t, x = _decay()
    z = x + 1j * x
    path = tmp_path / f"r.{suffix}"
    if suffix == "npy":
        np.save(path, np.column_stack([t, z]))
    elif suffix == "npz":
        np.savez(path, time=t, data=z, channels=np.array(IDS))
    else:
        from scipy.io import savemat

        savemat(path, {"time": t, "data": z, "channels": np.array(IDS, dtype=object)})
    with pytest.raises(InputError, match="has complex values"):
        read_record_streamed(path, IDS)


def test_a_byte_order_mark_does_not_lose_the_first_dataset(base: dict[str, bytes], tmp_path: Path) -> None:
    plain = read_uff(_write(tmp_path / "a.unv", base["local.unv"]))
    marked = read_uff(_write(tmp_path / "b.unv", b"\xef\xbb\xbf" + base["local.unv"]))
    assert marked.layout == plain.layout


def test_mounts_axes_are_normalised_after_scaling_and_must_be_orthogonal(tmp_path: Path) -> None:
    spec = json.loads((SAMPLES / "four-mounts/mounts.json").read_text())
    spec["mounts"][0]["axes"] = [[0, 0, 1e-200], [2e-200, 0, 0], [0, 3e-200, 0]]
    mounts = load_mounts(_write(tmp_path / "tiny.json", json.dumps(spec).encode()))
    assert mounts.mounts[0].axes == ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    spec["mounts"][0]["axes"] = [[0, 0, 1], [1, 0, 0.5], [0, 1, 0]]
    with pytest.raises(InputError, match=r"mounts\.0\.axes: axes 1 and 2 are not orthogonal"):
        load_mounts(_write(tmp_path / "skew.json", json.dumps(spec).encode()))
    spec["mounts"][0]["axes"] = [[0, 0, 1], [1, 0, 0], [0, 1, 0]]
    spec["mounts"][1]["id"] = spec["mounts"][0]["id"]
    with pytest.raises(InputError, match=r"mounts\.1\.id: duplicate mount id"):
        load_mounts(_write(tmp_path / "dup.json", json.dumps(spec).encode()))


def test_a_truncated_tdms_is_one_error_and_no_nptdms_lines(base: dict[str, bytes], tmp_path: Path) -> None:
    # in a process of its own: npTDMS's log handler holds the stderr of the moment it was imported
    import subprocess
    import sys

    path = _write(tmp_path / "r.tdms", base["r.tdms"][: len(base["r.tdms"]) * 2 // 3])
    code = (
        "import sys\nfrom rigidid.errors import InputError\nfrom rigidid.io.records import read_record\n"
        f"try:\n    read_record({str(path)!r}, {IDS!r})\nexcept InputError as exc:\n    print(exc)\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True)
    assert "r.tdms" in proc.stdout
    assert proc.stderr == ""  # npTDMS logs "Last segment of file has less data than expected"


def test_a_dataset_55_missing_a_values_line_is_one_line(base: dict[str, bytes], tmp_path: Path) -> None:
    lines = base["local.unv"].decode().split("\n")
    start = next(i for i, line in enumerate(lines) if line.strip() == "55" and lines[i - 1].strip() == "-1")
    end = next(i for i in range(start, len(lines)) if lines[i].strip() == "-1")
    path = _write(tmp_path / "cut.unv", "\n".join(lines[: end - 1] + lines[end:]).encode())  # the last values line
    with pytest.raises(InputError, match=r"cut\.unv: dataset 55 #1: 8 nodes but 7, 7, 7 values per direction"):
        read_uff(path)


def test_an_unclosed_npy_header_is_one_line_when_streamed(base: dict[str, bytes], tmp_path: Path) -> None:
    path = _write(tmp_path / "r.npy", base["r.npy"].replace(b"}", b" ", 1))  # numpy's tokenizer: TokenError
    with pytest.raises(InputError, match=r"r\.npy: not a"):
        read_record_streamed(path, IDS)
