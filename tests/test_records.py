"""Reading and writing impact records (rigidid.io.records)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rigidid.errors import InputError
from rigidid.io.records import csv as csv_records
from rigidid.io.records import read_record, write_record

from .conftest import DATA

BAD = DATA / "records"
IDS = ["1", "2", "9"]


def _decay(n: int = 400, dt: float = 0.001, channels: int = 3) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(n) * dt
    phase = np.linspace(0.2, 2.0, channels)
    x = np.exp(-8.0 * t)[:, None] * np.sin(2 * np.pi * 40.0 * t[:, None] + phase) * np.linspace(1.0, 3.0, channels)
    return t, x


def test_good_sample_is_read() -> None:
    data, dt = read_record(BAD / "good.csv", IDS)
    assert data.shape == (40, 3)
    assert dt == pytest.approx(0.001, rel=1e-9)
    first = np.array([1.0 * np.sin(0.3), 0.6 * np.sin(1.1), -0.8 * np.sin(2.0)])
    np.testing.assert_allclose(data[0], first, rtol=1e-5)


@pytest.mark.parametrize(
    ("name", "location", "message"),
    [
        ("ragged_rows.csv", "row 12", "3 fields, the header has 4"),
        ("non_uniform_time.csv", "row 20", "time step"),
        ("unknown_sensor.csv", "column '7'", "not a sensor of the layout"),
        ("missing_sensor.csv", "row 1", "sensor '9' of the layout has no column"),
        ("duplicate_column.csv", "column '2'", "appears twice"),
        ("header_without_time.csv", "column 't'", "first column must be 'time'"),
        ("all_zero_channel.csv", "column '2'", "reads zero in every row"),
        ("nan_value.csv", "row 15, column '9'", "NaN or infinite"),
        ("inf_value.csv", "row 22, column '2'", "NaN or infinite"),
        ("non_numeric.csv", "row 8, column '1'", "'abc' is not a number"),
        ("no_decay.csv", "rows 39-41", "does not decay"),
        ("empty.csv", "row 1", "empty"),
        ("too_few_rows.csv", "row 6", "5 data rows"),
    ],
)
def test_bad_record_names_file_and_place(name: str, location: str, message: str) -> None:
    path = BAD / name
    with pytest.raises(InputError) as info:
        read_record(path, IDS)
    err = info.value
    assert err.source == str(path)
    assert err.location is not None and location in err.location
    assert message in err.message
    assert str(err).startswith(f"{path}: ")


def test_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "nope.csv"
    with pytest.raises(InputError, match="file not found") as info:
        read_record(path, IDS)
    assert info.value.source == str(path)


def test_layout_with_a_repeated_id_is_refused() -> None:
    with pytest.raises(InputError, match="twice"):
        read_record(BAD / "good.csv", ["1", "1", "9"])


def test_round_trip_orders_columns_like_the_layout(tmp_path: Path) -> None:
    t, x = _decay()
    path = tmp_path / "hit.csv"
    write_record(path, t - 0.05, x, ["a", "b", "c"])
    data, dt = read_record(path, ["c", "a", "b"])
    np.testing.assert_allclose(data, x[:, [2, 0, 1]], rtol=1e-9, atol=1e-12)
    assert dt == pytest.approx(0.001, rel=1e-12)
    assert path.read_text().splitlines()[0] == "time,a,b,c"


def test_write_is_atomic_and_leaves_no_temporary_file(tmp_path: Path) -> None:
    t, x = _decay()
    path = tmp_path / "hit.csv"
    path.write_text("old")
    with pytest.raises(InputError, match="data must be"):
        write_record(path, t, x[:, :2], IDS)
    assert path.read_text() == "old"
    write_record(path, t, x, IDS)
    assert [p.name for p in tmp_path.iterdir()] == ["hit.csv"]
    with pytest.raises(InputError, match="cannot write"):
        write_record(tmp_path / "missing" / "hit.csv", t, x, IDS)


@pytest.mark.parametrize("bad_id", ["time", "a,b", "", " x"])
def test_write_refuses_ids_that_cannot_be_columns(tmp_path: Path, bad_id: str) -> None:
    t, x = _decay()
    with pytest.raises(InputError, match="cannot be a column name"):
        write_record(tmp_path / "hit.csv", t, x, ["1", "2", bad_id])


def test_crlf_bom_and_blank_lines_are_accepted(tmp_path: Path) -> None:
    t, x = _decay(100)
    lines = ["time,1,2,9"] + [f"{ti:.6f}," + ",".join(f"{v:.8g}" for v in xi) for ti, xi in zip(t, x, strict=True)]
    path = tmp_path / "windows.csv"
    path.write_bytes(("\ufeff" + "\r\n".join(lines) + "\r\n\r\n").encode("utf-8"))
    data, dt = read_record(path, IDS)
    assert data.shape == (100, 3)
    assert dt == pytest.approx(0.001)


def test_row_numbers_count_blank_lines_and_chunks(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(csv_records, "CHUNK_ROWS", 7)
    monkeypatch.setattr(csv_records, "CHUNK_BYTES", 300)  # a few lines per chunk, cut anywhere
    t, x = _decay(100)
    lines = ["time,1,2,9"] + [f"{ti:.6f}," + ",".join(f"{v:.8g}" for v in xi) for ti, xi in zip(t, x, strict=True)]
    lines.insert(5, "")  # line 6 is blank
    lines[60] = lines[60].replace(",", ",x", 1)  # line 61
    path = tmp_path / "hit.csv"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError) as info:
        read_record(path, IDS)
    assert info.value.location == "row 61, column '1'"
    lines[60] = lines[59]
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match="time step") as info:
        read_record(path, IDS)
    assert info.value.location == "row 61"


def test_time_rounding_is_tolerated_but_not_too_few_digits(tmp_path: Path) -> None:
    fs = 51200.0
    t, x = _decay(2000, dt=1.0 / fs)
    x = x * np.exp(-300.0 * t)[:, None]
    body = [",".join(f"{v:.8g}" for v in xi) for xi in x]
    path = tmp_path / "rounded.csv"
    path.write_text("\n".join(["time,1,2,9"] + [f"{ti:.6f},{b}" for ti, b in zip(t, body, strict=True)]) + "\n")
    _, dt = read_record(path, IDS)
    assert dt == pytest.approx(1.0 / fs, rel=1e-4)
    path.write_text("\n".join(["time,1,2,9"] + [f"{ti:.4f},{b}" for ti, b in zip(t, body, strict=True)]) + "\n")
    with pytest.raises(InputError, match="too few digits") as info:
        read_record(path, IDS)
    assert info.value.location == "column 'time'"


def test_large_record_is_read_in_chunks(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(csv_records, "CHUNK_ROWS", 1000)
    monkeypatch.setattr(csv_records, "CHUNK_BYTES", 10_000)
    t, x = _decay(5003, dt=1e-4)
    path = tmp_path / "long.csv"
    write_record(path, t, x, IDS)
    data, dt = read_record(path, IDS)
    np.testing.assert_allclose(data, x, rtol=1e-9, atol=1e-12)
    assert dt == pytest.approx(1e-4, rel=1e-12)


def _repr_csv(path: Path, t: np.ndarray, x: np.ndarray) -> None:
    rows = [f"{float(ti)!r}," + ",".join(repr(float(v)) for v in xi) for ti, xi in zip(t, x, strict=True)]
    path.write_text("\n".join(["time,1,2,9", *rows]) + "\n")


def test_values_written_with_repr_come_back_exactly(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(csv_records, "CHUNK_BYTES", 4096)
    rng = np.random.default_rng(4)
    t = 1e-3 * np.arange(3000)
    x = rng.standard_normal((3000, 3)) * np.exp(-3.0 * t)[:, None] * 10.0 ** rng.integers(-8, 8, size=3)
    path = tmp_path / "exact.csv"
    _repr_csv(path, t, x)
    data, _ = read_record(path, IDS)
    np.testing.assert_array_equal(data, x)  # the fast parser rounds correctly: the binary record's values


def test_chunks_the_fast_parser_declines_are_read_by_pandas(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(csv_records, "CHUNK_BYTES", 2048)
    rng = np.random.default_rng(5)
    t = 1e-3 * np.arange(2000)
    x = rng.standard_normal((2000, 3)) * np.exp(-3.0 * t)[:, None]
    path = tmp_path / "odd.csv"
    _repr_csv(path, t, x)
    lines = path.read_text().splitlines()
    lines[700] = " , ".join(lines[700].split(","))  # spaces around the numbers of one line
    lines.insert(1500, "")  # and a blank line further on
    path.write_text("\n".join(lines) + "\n")
    data, _ = read_record(path, IDS)
    np.testing.assert_allclose(data, x, rtol=1e-15, atol=0.0)


def test_pandas_alone_reads_what_polars_reads(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    t, x = _decay(3000, dt=1e-4)
    path = tmp_path / "hit.csv"
    write_record(path, t, x, IDS)
    fast, _ = read_record(path, IDS)
    monkeypatch.setattr(csv_records._Parser, "_polars", lambda self, chunk: None)
    slow, _ = read_record(path, IDS)
    np.testing.assert_allclose(fast, slow, rtol=1e-15, atol=0.0)


def test_the_command_line_imports_no_csv_parser_until_records_are_read() -> None:
    import subprocess
    import sys

    code = "import sys, rigidid.cli; print(sorted({m.split('.')[0] for m in sys.modules} & {'polars', 'pandas'}))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
