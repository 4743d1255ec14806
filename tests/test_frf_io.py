"""FRF files: references.json, the FRF CSV (round trip, faults named), and the command line."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rigidid import api_frf
from rigidid.errors import InputError
from rigidid.io.frf import frf_csv_text, load_frf_csv, load_references, reference_arrays

from .conftest import DATA, SAMPLES

FOUR = SAMPLES / "four-mounts"
REFS = DATA / "frf" / "references.json"


def run(*args: str | Path) -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-m", "rigidid", *map(str, args)]
    return subprocess.run(cmd, capture_output=True, text=True, check=False)


def test_frf_csv_round_trip_is_exact(tmp_path: Path) -> None:
    data = api_frf.simulate_frf(FOUR / "body.json", FOUR / "layout.json", REFS, noise=0.01, seed=2)
    path = tmp_path / "frf.csv"
    path.write_text(frf_csv_text(data.frequencies, data.frf, data.sensor_ids, data.reference_ids))
    # read against a different reference order: the array follows the ids asked for
    freqs, h = load_frf_csv(path, data.sensor_ids, data.reference_ids[::-1])
    np.testing.assert_array_equal(freqs, data.frequencies)
    np.testing.assert_array_equal(h, data.frf[:, ::-1])
    ids, _pos, dirs = reference_arrays(load_references(REFS))
    assert ids == ("h1", "h2", "h3")
    np.testing.assert_array_equal(dirs, np.eye(3))


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("frequency_hz,response,reference,real\n1,1,h1,0\n", "missing column 'imag'"),
        ("frequency_hz,response,reference,real,imag\n1,99,h1,0,0\n", "response '99' is not a sensor"),
        ("frequency_hz,response,reference,real,imag\n1,1,h9,0,0\n", "reference 'h9' is not in"),
        ("frequency_hz,response,reference,real,imag\n1,1,h1,x,0\n", "real: not a number"),
        ("frequency_hz,response,reference,real,imag\n1,1,h1,0,0\n1,1,h1,0,0\n", "duplicate line"),
        ("frequency_hz,response,reference,real,imag\n1,1,h1,0,0\n", "no FRF for response '1' and reference 'h2'"),
    ],
)
def test_bad_frf_csv_names_its_fault(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "frf.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=message) as info:
        load_frf_csv(path, ["1", "2"], ["h1", "h2"])
    assert str(path) in str(info.value)


def test_simulate_frf_then_identify_massline_from_the_command_line(tmp_path: Path) -> None:
    frf = tmp_path / "frf.csv"
    done = run("simulate", FOUR / "body.json", FOUR / "layout.json", "-o", tmp_path / "m.csv", "--frf", frf,
               "--references", REFS, "--frf-noise", "0.01", "--seed", "1")  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "FRFs (2000 lines)" in done.stderr
    done = run("identify", FOUR / "layout.json", "--frf", frf, "--references", REFS, "--method", "massline",
               "--json", "-")  # fmt: skip
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout)
    body = json.loads((FOUR / "body.json").read_text())
    assert out["route"] == "massline" and out["band_source"] == "automatic"
    assert abs(out["mass_measured"] / body["mass"] - 1.0) < 0.01
    assert out["mass_given"] == body["mass"]  # the layout's mass
    assert out["mass_difference"] == pytest.approx(out["mass_measured"] - body["mass"])
    np.testing.assert_allclose(out["center_of_gravity"], body["center_of_gravity"], atol=0.006)
    np.testing.assert_allclose(np.diag(out["inertia_tensor"]), np.diag(body["inertia_tensor"]), rtol=0.03)


def test_massline_without_references_is_an_input_error(tmp_path: Path) -> None:
    done = run("identify", FOUR / "layout.json", "--frf", tmp_path / "x.csv", "--method", "massline")
    assert done.returncode == 2
    assert "--references" in done.stderr and len(done.stderr.strip().splitlines()) == 1
