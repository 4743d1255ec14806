"""Binary datasets 58 read without pyuff (rigidid.io.uff_scan): the same datasets pyuff reads."""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rigidid.errors import InputError
from rigidid.io import uff_scan
from rigidid.io.uff import read_uff, write_uff_test
from rigidid.io.uff_scan import Block, read_58b, scan

from .test_uff import mixed_layout, simulated_records

pyuff = pytest.importorskip("pyuff")

DATA = Path(__file__).resolve().parent / "data" / "uff"
REAL_58B = ["binary8byte.uff", "sample_58b_float32.uff"]  # pyuff's data/ (see data/uff/README.md)


def _x(dset: dict[str, Any]) -> np.ndarray:
    if dset["x"] is not None:
        return np.asarray(dset["x"])
    return float(dset["abscissa_min"]) + np.arange(int(dset["num_pts"])) * float(dset["abscissa_inc"])


@pytest.mark.parametrize("name", [*REAL_58B, "testlab_161_164_18_15_82.uff", "nx_2411_2414_excerpt.unv"])
def test_datasets_found_are_pyuffs(name: str) -> None:
    blocks = scan(DATA / name)
    assert blocks is not None
    assert [b.kind for b in blocks] == [int(t) for t in pyuff.UFF(str(DATA / name)).get_set_types()]


@pytest.mark.parametrize("name", REAL_58B)
def test_binary_58_of_real_exports_reads_as_pyuff_reads_it(name: str) -> None:
    path = DATA / name
    reference = pyuff.UFF(str(path))
    blocks = scan(path)
    assert blocks is not None and any(b.binary58 for b in blocks)
    for i, block in enumerate(blocks):
        if not block.binary58:
            continue
        mine, theirs = read_58b(path, block), reference.read_sets(i)
        for key, value in theirs.items():
            if key == "x":
                np.testing.assert_array_equal(_x(mine), value)
            elif key == "data":
                np.testing.assert_array_equal(np.asarray(mine["data"]), value)
            else:
                assert mine[key] == value, key


def _test_file(folder: Path) -> tuple[Path, list[tuple[np.ndarray, np.ndarray, list[str]]]]:
    layout = mixed_layout()
    records = simulated_records([s["id"] for s in layout["sensors"]])
    path = folder / "test.uff"
    write_uff_test(path, layout, records, binary=True)
    return path, records


def _read_by_pyuff(monkeypatch: pytest.MonkeyPatch, path: Path) -> Any:
    with monkeypatch.context() as m:
        m.setattr(uff_scan, "scan", lambda _path: None)  # the reader falls back to pyuff for the whole file
        return read_uff(path)


def _assert_same_contents(a: Any, b: Any) -> None:
    assert a.layout == b.layout and a.record_labels == b.record_labels and a.nodes == b.nodes
    assert len(a.records) == len(b.records)
    for x, y in zip(a.records, b.records, strict=True):
        assert x.sensor_ids == y.sensor_ids
        np.testing.assert_array_equal(x.time, y.time)
        np.testing.assert_array_equal(x.data, y.data)


def test_a_test_file_reads_the_same_without_pyuff_for_its_records(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path, records = _test_file(tmp_path)
    fast, slow = read_uff(path), _read_by_pyuff(monkeypatch, path)
    _assert_same_contents(fast, slow)
    np.testing.assert_array_equal(fast.records[0].data, records[0][1])  # binary 58: exact


def _rewrite_58b(path: Path, out: Path, *, order: str, width: int, crlf: bool = False) -> None:
    """`path` with every binary 58's values re-encoded (byte order, float width), headers to match."""
    blocks = scan(path)
    assert blocks is not None
    raw = path.read_bytes()
    parts = []
    for block in blocks:
        if not block.binary58:
            parts.append(raw[block.start : block.end])
            continue
        values = np.asarray(read_58b(path, block)["data"], dtype=float)
        payload = values.astype(f"{'<' if order == 'little' else '>'}f{width}").tobytes()
        id_line, *records = block.header
        id_line = id_line[:7] + b"%6i%6i%12i%12i" % (1 if order == "little" else 2, 2, len(records), len(payload))
        id_line += b"%6i%6i%12i%12i\n" % (0, 0, 0, 0)
        fields = records[6].decode()
        records[6] = (f"{2 if width == 4 else 4:10d}" + fields[10:]).encode()
        head = b"    -1\n" + id_line + b"".join(records)
        end = b"\n    -1\n"
        if crlf:
            head, end = head.replace(b"\n", b"\r\n"), end.replace(b"\n", b"\r\n")
        parts.append(head + payload + end)
    out.write_bytes(b"".join(parts))


@pytest.mark.parametrize(("order", "width", "crlf"), [("big", 4, False), ("big", 8, True), ("little", 4, True)])
def test_byte_orders_widths_and_line_ends_read_as_pyuff_reads_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, order: str, width: int, crlf: bool
) -> None:
    path, records = _test_file(tmp_path)
    variant = tmp_path / "variant.uff"
    _rewrite_58b(path, variant, order=order, width=width, crlf=crlf)
    fast = read_uff(variant)
    _assert_same_contents(fast, _read_by_pyuff(monkeypatch, variant))
    expected = records[0][1].astype(np.float32) if width == 4 else records[0][1]
    np.testing.assert_array_equal(fast.records[0].data, expected)


def test_a_byte_count_that_does_not_end_on_a_delimiter_leaves_the_file_to_pyuff(tmp_path: Path) -> None:
    path, records = _test_file(tmp_path)
    raw = bytearray(path.read_bytes())
    at = raw.index(b"    58b")
    field = slice(at + 31, at + 43)
    raw[field] = b"%12i" % (int(raw[field]) - 8)  # 8 bytes fewer than the values hold (a writer's slip)
    broken = tmp_path / "broken.uff"
    broken.write_bytes(bytes(raw))
    assert scan(broken) is None
    back = read_uff(broken)  # pyuff finds its datasets by their delimiters: the values are all there
    np.testing.assert_array_equal(back.records[0].data, records[0][1])


def test_non_finite_values_are_refused_naming_dataset_and_node(tmp_path: Path) -> None:
    layout = mixed_layout()
    records = simulated_records([s["id"] for s in layout["sensors"]])
    path = tmp_path / "nan.uff"
    write_uff_test(path, layout, records, binary=True)
    raw = bytearray(path.read_bytes())
    blocks = scan(path)
    assert blocks is not None
    third = [b for b in blocks if b.binary58][2]
    raw[third.data[0] + 8 * 10 : third.data[0] + 8 * 11] = np.array([np.nan]).tobytes()
    path.write_bytes(bytes(raw))
    with pytest.raises(InputError, match="NaN or infinite") as info:
        read_uff(path)
    assert info.value.location is not None and "dataset 58 #3" in info.value.location


def test_a_sample_count_other_than_the_header_says_is_refused(tmp_path: Path) -> None:
    path, _ = _test_file(tmp_path)
    raw = bytearray(path.read_bytes())
    blocks = scan(path)
    assert blocks is not None
    first = next(b for b in blocks if b.binary58)
    record7 = first.header[7]
    at = raw.index(record7, first.start)
    raw[at + 10 : at + 20] = b"%10i" % 1499  # the header announces one sample fewer than the bytes hold
    path.write_bytes(bytes(raw))
    with pytest.raises(InputError, match="1500 samples where the header says 1499"):
        read_uff(path)


def test_block_offsets_frame_each_dataset(tmp_path: Path) -> None:
    path, _ = _test_file(tmp_path)
    blocks = scan(path)
    assert blocks is not None
    raw = path.read_bytes()
    assert blocks[0].start == 0 and blocks[-1].end == len(raw)
    for before, after in itertools.pairwise(blocks):
        assert before.end <= after.start
    for block in blocks:
        assert isinstance(block, Block)
        assert raw[block.start : block.end].strip().endswith(b"-1")
        if block.binary58:
            offset, size = block.data
            assert block.start < offset and offset + size < block.end


def test_damaged_files_end_in_one_input_error_or_a_reading(tmp_path: Path) -> None:
    """Bytes of a binary test file overwritten at random: never a traceback, never a hang."""
    from rigidid.errors import RigididError

    path, _ = _test_file(tmp_path)
    raw = path.read_bytes()
    rng = np.random.default_rng(11)
    damaged = tmp_path / "damaged.uff"
    for trial in range(60):
        data = bytearray(raw)
        for at in rng.integers(0, len(data), size=int(rng.integers(1, 6))):
            data[at] = int(rng.integers(0, 256)) if trial % 2 else ord(rng.choice(list("-0123456789 b\n")))
        damaged.write_bytes(bytes(data))
        blocks = scan(damaged)
        assert blocks is None or all(isinstance(b, Block) for b in blocks)
        message = ""
        try:
            read_uff(damaged)
        except RigididError as exc:  # InputError or the package's other one-line errors
            message = str(exc)
        assert "\n" not in message


def test_a_dataset_pyuff_cannot_read_is_numbered_among_all_of_its_kind(tmp_path: Path) -> None:
    path, records = _test_file(tmp_path)
    n58 = sum(r[1].shape[1] for r in records)  # binary 58 datasets written: one per sensor and impact
    path.write_bytes(path.read_bytes() + b"    -1\n    58\n garbage\n    -1\n")  # an ASCII 58 after them
    with pytest.raises(InputError, match="pyuff cannot read it") as info:
        read_uff(path)
    assert info.value.location == f"dataset 58 #{n58 + 1}"
