"""UFF 58 FRF writing (simulate --frf OUT.uff): round trips through rigidid's reader, units, refusals,
and a real FRF export (pyuff's public data) read or refused in one line."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from rigidid.api import frf as api_frf
from rigidid.errors import InputError
from rigidid.io import files
from rigidid.io.frf import frf_format_from, frf_uff_bytes, load_frf_uff, load_references, reference_arrays

from .conftest import DATA, SAMPLES
from .tolerances import FRF_UFF_ASCII_REL, UFF_E13_REL

FOUR = SAMPLES / "four-mounts"
REAL = DATA / "frf" / "pyuff" / "h1_no_nodes_non_ascii_header.uff"
SI = {"length": "m", "mass": "kg"}


def run(*args: str | Path) -> SimpleNamespace:
    """The command line, in this process (a subprocess costs a second of start-up per call)."""
    from typer.testing import CliRunner

    from rigidid.cli import app

    result = CliRunner().invoke(app, [str(a) for a in args])
    return SimpleNamespace(returncode=result.exit_code, stdout=result.stdout, stderr=result.stderr)


@pytest.fixture
def test_files(tmp_path: Path) -> tuple[Path, Path]:
    """four-mounts' layout with every sensor along an axis (ids 1..8), and references with UFF ids."""
    layout = json.loads((FOUR / "layout.json").read_text())
    for sensor in layout["sensors"]:
        if sensor["id"] == "8":
            sensor["direction"] = "+y"
    refs = {
        "units": SI,
        "references": [
            {"id": "101+x", "position": [0.3, 0.2, 0.15], "direction": "+x"},
            {"id": "102", "position": [-0.3, 0.2, -0.15], "direction": "+y"},
            {"id": "103-z", "position": [0.3, -0.2, -0.15], "direction": "-z"},
        ],
    }
    (tmp_path / "layout.json").write_text(json.dumps(layout))
    (tmp_path / "refs.json").write_text(json.dumps(refs))
    return tmp_path / "layout.json", tmp_path / "refs.json"


def _simulated(
    layout: Path, refs: Path, lines: np.ndarray | None = None
) -> tuple[api_frf.FrfData, np.ndarray, np.ndarray]:
    lay = files.load_layout(layout, require_rank=False)
    ref = load_references(refs)
    grid = 0.25 * np.arange(1, 301) if lines is None else lines
    data = api_frf.simulate_frf(FOUR / "body.json", lay, ref, frequencies=grid, noise=0.01, seed=3)
    return data, files.layout_arrays(lay)[2], reference_arrays(ref)[2]


@pytest.mark.parametrize("binary", [True, False])
def test_uff_58_round_trips_through_the_reader(tmp_path: Path, test_files: tuple[Path, Path], binary: bool) -> None:
    data, dirs, rdirs = _simulated(*test_files)
    path = tmp_path / "frf.uff"
    path.write_bytes(frf_uff_bytes(data.frequencies, data.frf, data.sensor_ids, dirs, data.reference_ids, rdirs,
                                   SI, binary=binary))  # fmt: skip
    # read against another reference order: the array follows the ids asked for
    freqs, h = load_frf_uff(path, data.sensor_ids, data.reference_ids[::-1], units=SI)
    np.testing.assert_allclose(freqs, data.frequencies, rtol=1e-12, atol=0.0)
    np.testing.assert_allclose(h, data.frf[:, ::-1], rtol=FRF_UFF_ASCII_REL, atol=0.0)
    if binary:  # double precision, abscissa per line: exact
        np.testing.assert_array_equal(h, data.frf[:, ::-1])


def test_an_uneven_grid_in_ascii_keeps_six_digits_of_frequency(tmp_path: Path, test_files: tuple[Path, Path]) -> None:
    lines = np.geomspace(1.0, 300.0, 50)
    data, dirs, rdirs = _simulated(*test_files, lines)
    path = tmp_path / "frf.uff"
    path.write_bytes(frf_uff_bytes(data.frequencies, data.frf, data.sensor_ids, dirs, data.reference_ids, rdirs,
                                   SI, binary=False))  # fmt: skip
    freqs, h = load_frf_uff(path, data.sensor_ids, data.reference_ids, units=SI)
    np.testing.assert_allclose(freqs, lines, rtol=UFF_E13_REL)
    assert np.max(np.abs(freqs / lines - 1.0)) > 1e-12  # the abscissa is E13.5 there
    np.testing.assert_allclose(h, data.frf, rtol=FRF_UFF_ASCII_REL, atol=0.0)


@pytest.mark.parametrize(("units", "factor"), [({"length": "in", "mass": "lb"}, 386.08858), (SI, 1.0)])
def test_values_are_per_the_164_force_unit_and_come_back_in_layout_units(
    tmp_path: Path, test_files: tuple[Path, Path], units: dict[str, str], factor: float
) -> None:
    import pyuff

    data, dirs, rdirs = _simulated(*test_files, 0.5 * np.arange(1, 21))
    path = tmp_path / "frf.uff"
    path.write_bytes(frf_uff_bytes(data.frequencies, data.frf, data.sensor_ids, dirs, data.reference_ids, rdirs,
                                   units))  # fmt: skip
    raw = pyuff.UFF(str(path)).read_sets()
    assert raw[0]["type"] == 164 and raw[0]["units_code"] == (7 if units["length"] == "in" else 1)
    first = raw[1]  # sensor 1, reference 101+x: lbf in the file for in/lb (gravitational)
    assert (first["func_type"], first["rsp_node"], first["rsp_dir"], first["ref_node"], first["ref_dir"]) == (
        4, 1, 3, 101, 1,
    )  # fmt: skip
    assert first["ordinate_spec_data_type"] == 12 and first["orddenom_spec_data_type"] == 13
    np.testing.assert_allclose(first["data"], data.frf[0, 0] * factor, rtol=1e-6)
    last = raw[-1]
    assert (last["rsp_node"], last["ref_node"], last["ref_dir"]) == (8, 103, -3)
    _, h = load_frf_uff(path, data.sensor_ids, data.reference_ids, units=units)
    np.testing.assert_allclose(h, data.frf, rtol=1e-12, atol=0.0)
    other = {"length": "mm", "mass": "kg"}
    with pytest.raises(InputError, match=r"units .* differ from the layout's units \(mm, kg\)") as info:
        load_frf_uff(path, data.sensor_ids, data.reference_ids, units=other)
    assert info.value.location == "dataset 164"


@pytest.mark.parametrize(
    ("sensor_id", "direction", "message"),
    [
        ("s1", [0.0, 0.0, 1.0], "sensor id 's1' is not a UFF node"),
        ("1", [0.6, 0.8, 0.0], r"sensor 1: direction \(0.6, 0.8, 0\) is not along an axis"),
        ("1+x", [0.0, 0.0, 1.0], "sensor id '1\\+x' names the axis \\+x but its direction is \\+z"),
    ],
)
def test_what_uff_58_cannot_state_is_refused(sensor_id: str, direction: list[float], message: str) -> None:
    h = np.ones((1, 1, 2), dtype=complex)
    with pytest.raises(InputError, match=message):
        frf_uff_bytes(np.array([1.0, 2.0]), h, [sensor_id], np.array([direction]), ["7"], np.array([[1.0, 0, 0]]), SI)


def test_the_format_comes_from_the_option_or_the_suffix() -> None:
    assert frf_format_from("a.UFF", None) == "uff"
    assert frf_format_from("a.csv", None) == "csv"
    assert frf_format_from("a.unv", "uff-ascii") == "uff-ascii"
    with pytest.raises(InputError, match="one of csv, uff, uff-ascii"):
        frf_format_from("a.uff", "xls")
    with pytest.raises(InputError, match=r"name it \.csv"):
        frf_format_from("a.uff", "csv")
    with pytest.raises(InputError, match=r"name it \.uff or \.unv"):
        frf_format_from("a.txt", "uff")


def test_simulate_frf_uff_then_identify_massline(tmp_path: Path, test_files: tuple[Path, Path]) -> None:
    layout, refs = test_files
    frf = tmp_path / "frf.unv"
    done = run("simulate", FOUR / "body.json", layout, "-o", tmp_path / "m.csv", "--write-frf", frf,
               "--references", refs, "--frf-format", "uff-ascii")  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert b"    58 " in frf.read_bytes()[:400] and b"58b" not in frf.read_bytes()
    done = run("identify", layout, "--frf", frf, "--references", refs, "--method", "massline", "--json", "-")
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout)
    body = json.loads((FOUR / "body.json").read_text())
    assert abs(out["mass_measured"] / body["mass"] - 1.0) < 1e-3
    np.testing.assert_allclose(out["center_of_gravity"], body["center_of_gravity"], atol=2e-3)


def test_simulate_refuses_a_reference_uff_cannot_name(tmp_path: Path, test_files: tuple[Path, Path]) -> None:
    layout, _ = test_files
    refs = DATA / "frf" / "references.json"  # ids h1, h2, h3
    frf = tmp_path / "frf.uff"
    done = run(
        "simulate", FOUR / "body.json", layout, "-o", tmp_path / "m.csv", "--write-frf", frf, "--references", refs
    )
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "error:" in done.stderr
    assert str(refs) in done.stderr and "reference id 'h1' is not a UFF node" in done.stderr
    assert not frf.exists() and not (tmp_path / "m.csv").exists()


def test_a_real_h1_export_without_nodes_is_refused_saying_why() -> None:
    with pytest.raises(InputError, match=r"names no response or reference node .* carries no geometry") as info:
        load_frf_uff(REAL, ["1"], ["2"])
    assert info.value.location == "dataset 58 #1" and str(REAL) in str(info.value)


def test_the_real_h1_export_reads_once_its_nodes_are_named(tmp_path: Path) -> None:
    """Record 6 of the real file patched to name nodes 1 (+z) and 2 (+z): the values are the file's."""
    lines = REAL.read_bytes().split(b"\n")
    record6 = 7
    assert lines[record6].startswith(b"    4 ")
    lines[record6] = b"%5d%10d%5d%10d %-10s%10d%4d %-10s%10d%4d" % (4, 0, 0, 0, b"NONE", 1, 3, b"NONE", 2, 3)
    path = tmp_path / "named.uff"
    path.write_bytes(b"\n".join(lines))
    freqs, h = load_frf_uff(path, ["1+z"], ["2"])
    # the file: 6 complex lines from 0 Hz in steps of 0.195313 Hz; the 0 Hz line is dropped
    np.testing.assert_allclose(freqs, 0.195313 * np.arange(1, 6), rtol=1e-12)
    expected = np.array([-5.99924e-02 - 5.53260e-02j, 2.58750e-02 - 2.30085e-04j, -2.99003e-01 + 3.17213e-01j,
                         -1.80250e00 + 1.55302e00j, 3.75037e00 + 2.93363e00j])  # fmt: skip
    np.testing.assert_allclose(h[0, 0], expected, rtol=1e-12)


@pytest.mark.parametrize(
    ("func", "message"),
    [
        (1, r"function type 1 \(time response\) is not an FRF \(function type 4\): time records are read with"),
        (9, r"function type 9 \(power spectral density \(PSD\)\) is not an FRF"),
        (3, r"function type 3 is a cross spectrum, not an FRF"),
    ],
)
def test_other_function_types_are_refused_by_name(tmp_path: Path, func: int, message: str) -> None:
    h = np.ones((1, 1, 3), dtype=complex)
    text = frf_uff_bytes(np.array([1.0, 2.0, 3.0]), h, ["1"], np.array([[0, 0, 1.0]]), ["2"], np.array([[1.0, 0, 0]]),
                         SI, binary=False)  # fmt: skip
    lines = text.split(b"\n")
    record6 = next(k for k, line in enumerate(lines) if line.startswith(b"    4 "))
    lines[record6] = b"%5d" % func + lines[record6][5:]
    path = tmp_path / "other.uff"
    path.write_bytes(b"\n".join(lines))
    with pytest.raises(InputError, match=message) as info:
        load_frf_uff(path, ["1"], ["2"])
    assert info.value.location == "dataset 58 #1"


def test_the_api_writes_simulated_frfs_as_the_command_does(tmp_path: Path, test_files: tuple[Path, Path]) -> None:
    """``api.write_simulated_frf`` (what ``simulate --write-frf`` does) writes a UFF whose lines are
    a grid its 6-digit step states exactly, and the same FRFs as the CSV on that grid."""
    from rigidid import api

    layout, refs = test_files
    data = api.write_simulated_frf(FOUR / "body.json", layout, refs, tmp_path / "frf.uff")
    step = data.frequencies[0]
    assert float(f"{step:.5e}") == step
    np.testing.assert_allclose(np.diff(data.frequencies), step, rtol=1e-12)
    freqs, h = load_frf_uff(tmp_path / "frf.uff", data.sensor_ids, data.reference_ids, units=SI)
    np.testing.assert_array_equal(freqs, data.frequencies)
    np.testing.assert_array_equal(h, data.frf)
    again = api_frf.simulate_frf(FOUR / "body.json", layout, refs, frequencies=data.frequencies)
    np.testing.assert_allclose(again.frf, data.frf, rtol=1e-12)
    with pytest.raises(InputError, match="hammer points") as err:
        api.write_simulated_frf(FOUR / "body.json", layout, None, tmp_path / "x.csv")
    assert err.value.source == "references"
    assert not (tmp_path / "x.csv").exists()
