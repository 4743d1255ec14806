"""Binary record formats (.npy, .npz, .mat, .h5, .wav) read to the same modes as the CSV they came from."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rigidid import api
from rigidid.errors import InputError
from rigidid.io.records import read_record
from rigidid.io.records.binary import write_binary

ROOT = Path(__file__).resolve().parents[1]
ENGINE = ROOT / "samples" / "engine-on-mounts"


@pytest.fixture(scope="module")
def engine_csv(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[str], list[Path]]:
    folder = tmp_path_factory.mktemp("formats")
    paths = api.simulate_records(ENGINE / "body.json", ENGINE / "layout.json", folder, duration=2.0, seed=1)
    ids = [s.id for s in api.load_layout(ENGINE / "layout.json").sensors]
    return folder, ids, paths


def _modes(paths: list[Path]) -> np.ndarray:
    _, est = api.estimate_modes(ENGINE / "layout.json", paths)
    shapes = np.asarray(est.shapes)
    return np.concatenate(
        [np.asarray(est.frequency_hz), np.asarray(est.damping_ratio), shapes.real.ravel(), shapes.imag.ravel()]
    )


def test_binary_formats_give_the_csv_modes(engine_csv: tuple[Path, list[str], list[Path]]) -> None:
    pytest.importorskip("h5py")
    folder, ids, paths = engine_csv
    reference = _modes(paths)
    for suffix in (".npz", ".mat", ".h5", ".npy", ".wav", "-v73.mat", "-fortran.npz"):
        converted = []
        for k, path in enumerate(paths):
            data, dt = read_record(path, ids)
            time = np.arange(data.shape[0]) * dt
            target = folder / f"{path.stem}{suffix}"
            if suffix == ".npy":
                np.save(target, np.column_stack([time, data]))
            elif suffix == ".mat":
                from scipy.io import savemat

                # one array per channel, reversed order, and the sample rate instead of time
                fields = {sid: data[:, i] for i, sid in reversed(list(enumerate(ids)))} if k == 0 else {}
                if k == 0:
                    savemat(target, {**fields, "sample_rate": 1.0 / dt})
                else:
                    savemat(target, {"data": data, "channels": np.array(ids, dtype=object), "time": time})
            elif suffix == "-v73.mat":  # MATLAB v7.3 (HDF5, transposed), then v5 compressed, one array per sensor
                from scipy.io import savemat

                from .test_array_streams import write_mat73

                if k == 0:
                    write_mat73(target, {"time": time, "data": data, "channels": list(ids)})
                else:
                    savemat(target, {"dt": dt, **{s: data[:, i] for i, s in enumerate(ids)}}, do_compression=True)
            elif suffix == "-fortran.npz":
                np.savez_compressed(target, time=time, data=np.asfortranarray(data), channels=np.array(ids))
            else:
                write_binary(target, time, data, ids)
            converted.append(target)
        np.testing.assert_allclose(_modes(converted), reference, rtol=1e-9, atol=0, err_msg=suffix)


def test_npz_channel_arrays_are_matched_by_name(tmp_path: Path) -> None:
    t = np.arange(400) / 100.0
    a = np.exp(-t) * np.sin(20 * t + 0.1)
    b = np.exp(-t) * np.cos(20 * t)
    np.savez(tmp_path / "r.npz", b=b, a=a, dt=0.01)
    data, dt = read_record(tmp_path / "r.npz", ["a", "b"])
    np.testing.assert_array_equal(data, np.column_stack([a, b]))
    assert dt == 0.01


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"data": np.ones((40, 2)), "dt": 0.1}, "field 'channels'"),
        ({"a": np.ones(40), "b": np.ones(40)}, "no sampling"),
        ({"a": np.ones(40), "b": np.ones(30), "dt": 0.1}, "field 'b'"),
        ({"a": np.ones(40), "c": np.ones(40), "dt": 0.1}, "column 'c' is not a sensor"),
        ({"a": np.ones(40), "dt": 0.1}, "sensor 'b' of the layout has no column"),
        ({"a": np.ones(40), "b": np.ones(40), "dt": -1.0}, "field 'dt'"),
        ({"data": np.ones((40, 2)), "channels": np.array(["a", "b", "c"]), "dt": 0.1}, "3 names for 2 columns"),
    ],
)
def test_bad_npz_is_one_line_naming_file_and_field(tmp_path: Path, fields: dict, message: str) -> None:
    path = tmp_path / "bad.npz"
    np.savez(path, **fields)
    with pytest.raises(InputError) as info:
        read_record(path, ["a", "b"])
    text = str(info.value)
    assert "\n" not in text and str(path) in text and message in text


def test_not_a_binary_file(tmp_path: Path) -> None:
    for suffix in (".npy", ".npz", ".mat", ".h5", ".wav", ".tdms"):
        path = tmp_path / f"junk{suffix}"
        path.write_text("time,a,b\n")
        with pytest.raises(InputError, match=str(path).replace(".", r"\.")):
            read_record(path, ["a", "b"])


def test_convert_writes_npz_and_wav_records_that_modes_reads(tmp_path: Path) -> None:
    import json

    from rigidid.io.uff import write_uff_test

    from .cli_runner import run
    from .test_cli_workflows import PAPER, PAPER_BODY

    body = tmp_path / "body.json"
    body.write_text(json.dumps(PAPER_BODY))
    layout = json.loads((PAPER / "layout.json").read_text())
    ids = [s["id"] for s in layout["sensors"]]
    paths = api.simulate_records(body, PAPER / "layout.json", tmp_path, sample_rate=256.0, duration=6.0, seed=3)
    records = []
    for path in paths:
        data, dt = read_record(path, ids)
        records.append((np.arange(data.shape[0]) * dt, data, ids))
    uff = tmp_path / "test.uff"
    write_uff_test(uff, layout, records)
    out = {}
    for fmt in ("csv", "npz", "wav", "mat"):
        target = tmp_path / fmt
        converted = run("convert", uff, "-o", target, "--records-format", fmt)
        assert converted.returncode == 0, converted.stderr
        files = sorted(target.glob(f"record-*.{fmt}"))
        assert len(files) == 2
        modes = run("modes", target / "layout.json", *files, "-o", tmp_path / f"{fmt}.csv")
        assert modes.returncode == 0, modes.stderr
        out[fmt] = np.loadtxt(tmp_path / f"{fmt}.csv", delimiter=",", skiprows=1, usecols=(1, 2))
    np.testing.assert_allclose(out["npz"], out["csv"], rtol=1e-6)
    np.testing.assert_array_equal(out["wav"], out["npz"])  # 64-bit float WAV: the same values
    np.testing.assert_array_equal(out["mat"], out["npz"])  # MATLAB v5 doubles: the same values
    bad = run("convert", uff, "-o", tmp_path / "x", "--records-format", "tdms")
    assert bad.returncode == 2 and "tdms" in bad.stderr and len(bad.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "x").exists()


def test_channel_energy_row_blocked_equals_the_column_sum() -> None:
    from rigidid.core.timedomain import preprocess

    rng = np.random.default_rng(4)
    record = rng.normal(size=(70_001, 5)) * np.array([1.0, 1e3, 1e-3, 0.0, 2.0])
    expected = sum((record[:, i] / np.max(np.abs(record[:, i]))) ** 2 for i in (0, 1, 2, 4))
    np.testing.assert_allclose(preprocess.channel_energy(record), expected, rtol=1e-12)
    assert preprocess.channel_energy(np.empty((0, 3))).shape == (0,)


def test_spreadsheet_csv_gives_the_plain_csv_modes(engine_csv: tuple[Path, list[str], list[Path]]) -> None:
    """';' separators, decimal commas, a 'Time (s)' header and a force column: the same modes."""
    from rigidid.errors import NonSensorColumnWarning

    folder, _, paths = engine_csv
    converted = []
    for path in paths:
        lines = path.read_text().splitlines()
        header = lines[0].split(",")
        rows = [line.split(",") for line in lines[1:]]
        out = [";".join(["Time (s)", "Force [N]", *header[1:], "trigger"])]
        for k, cells in enumerate(rows):
            out.append(";".join([cells[0], f"{0.5 * (k < 3):g}", *cells[1:], "1"]).replace(".", ","))
        target = folder / f"{path.stem}-excel.csv"
        target.write_text("\n".join(out) + "\n")
        converted.append(target)
    with pytest.warns(NonSensorColumnWarning, match="'Force \\[N\\]', 'trigger'"):
        modes = _modes(converted)
    np.testing.assert_allclose(modes, _modes(paths), rtol=1e-9, atol=0)


@pytest.mark.parametrize(
    ("text", "location", "message"),
    [
        ("time,a,b\n0,1,2\n0.1,,2\n", "row 3, column 'a'", "empty cell"),
        ("time;a;b\n0;1;2\n\n0,1;1;nan\n", "row 4, column 'b'", "NaN or infinite"),
        ("time,a,b\n0,1,2\n0.1,1,2,3\n", "row 3", "4 fields, the header has 3"),
        ("time,a,b\n0,1,2\n0.1,1\n", "row 3", "2 fields, the header has 3"),
        ("time,a,b\n0,1,2\n0.1,1,x2\n", "row 3, column 'b'", "'x2' is not a number"),
        ("Time (ms),a,b\n0,1,2\n", "column 'Time (ms)'", "time must be in seconds"),
        ("time,a,b,Force (N)\n0,1,2,3\n", "", "16"),
    ],
)
def test_bad_csv_cell_names_row_and_column(tmp_path: Path, text: str, location: str, message: str) -> None:
    import warnings

    path = tmp_path / "bad.csv"
    path.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(InputError) as info:
            read_record(path, ["a", "b"])
    err = info.value
    assert location in (err.location or "") and message in err.message and "\n" not in str(err)


def test_endless_inputs_end_with_one_line(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="not a regular file"):
        read_record("/dev/zero", ["a", "b"])
    path = tmp_path / "zeros.csv"
    with path.open("wb") as fh:
        fh.truncate(3 << 20)  # 3 MiB of NUL bytes, no line break
    with pytest.raises(InputError, match="no line break") as info:
        read_record(path, ["a", "b"])
    assert "\n" not in str(info.value)


def test_a_file_growing_while_read_stops_with_one_line(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import os
    from types import SimpleNamespace

    from rigidid.io.records import csv as csv_records

    t = np.arange(2000) / 100.0
    path = tmp_path / "live.csv"
    path.write_text("time,a,b\n" + "".join(f"{x:.2f},{np.exp(-x):.6f},{np.sin(x):.6f}\n" for x in t))
    real = os.fstat

    def smaller(fd: int) -> SimpleNamespace:  # the size when opened: a quarter of what is there when read
        info = real(fd)
        return SimpleNamespace(st_mode=info.st_mode, st_size=info.st_size // 4)

    monkeypatch.setattr(csv_records.os, "fstat", smaller)
    with pytest.raises(InputError, match="grew while it was read") as info:
        read_record(path, ["a", "b"])
    assert "\n" not in str(info.value) and str(path) in str(info.value)


@pytest.mark.parametrize("dtype", ["int16", "int32", "uint8", "float32", "float64"])
def test_wav_samples_are_read_as_stored_in_layout_order(tmp_path: Path, dtype: str) -> None:
    from scipy.io import wavfile

    from rigidid.io.records.streamed import read_record_streamed

    rng = np.random.default_rng(6)
    n = 70_000  # longer than the streamed reader's head: read in row blocks
    decay = np.exp(-np.arange(n) / 8000.0)[:, None] * np.sin(0.01 * np.arange(n))[:, None]
    values = decay * rng.uniform(0.3, 1.0, 3)
    scale = {"int16": 2**14, "int32": 2**30, "uint8": 100, "float32": 1.0, "float64": 1.0}[dtype]
    stored = np.round(values * scale) + (128 if dtype == "uint8" else 0) if dtype[0] in "iu" else values * scale
    stored = stored.astype(dtype)
    path = tmp_path / f"hit-{dtype}.wav"
    wavfile.write(path, 8000, stored)
    expected = stored.astype(np.float64) - (128.0 if dtype == "uint8" else 0.0)
    data, dt = read_record(path, ["a", "b", "c"])
    assert dt == pytest.approx(1.0 / 8000.0, rel=1e-12)
    np.testing.assert_array_equal(data, expected)
    streamed = read_record_streamed(path, ["a", "b", "c"], factor=1)
    np.testing.assert_array_equal(streamed.data, expected)
    with pytest.raises(InputError, match="3 sensor columns after time, the layout has 2 sensors"):
        read_record(path, ["a", "b"])


def test_wav_records_written_by_convert_round_trip(tmp_path: Path) -> None:
    t = np.arange(5000) / 2048.0
    x = np.random.default_rng(7).standard_normal((5000, 2)) * np.exp(-3.0 * t)[:, None]  # a decay
    write_binary(tmp_path / "r.wav", t, x, ["p", "q"])
    data, dt = read_record(tmp_path / "r.wav", ["p", "q"])
    np.testing.assert_array_equal(data, x)  # 64-bit floats: exact
    assert dt == 1.0 / 2048.0
    with pytest.raises(InputError, match="whole number of Hz"):
        write_binary(tmp_path / "s.wav", np.arange(10) / 1000.5, np.zeros((10, 1)), ["p"])


def test_convert_writes_a_uff_step_kept_to_six_digits_as_a_whole_rate(tmp_path: Path) -> None:
    from scipy.io import wavfile

    from rigidid.io.uff import write_uff_test

    layout = {"units": {"length": "m", "mass": "kg"},
              "sensors": [{"id": "p", "position": [0, 0, 0], "direction": "+x"}]}  # fmt: skip
    t = np.arange(64) / 512.0  # the UFF keeps 1.95312e-3 s: 512.0013 Hz
    x = np.exp(-t)[:, None]
    write_uff_test(tmp_path / "t.uff", layout, [(t, x, ["p"])])
    written = api.convert(tmp_path / "t.uff", tmp_path / "out", records_format="wav")
    rate, data = wavfile.read(written[-1])
    assert rate == 512
    np.testing.assert_array_equal(data, x[:, 0])
    with pytest.raises(InputError, match=r"1000\.5 Hz \(its step 0\.0009995 s kept to 6 digits\)"):
        write_binary(tmp_path / "s.wav", np.arange(10) / 1000.5, np.zeros((10, 1)), ["p"], step_digits=6)
