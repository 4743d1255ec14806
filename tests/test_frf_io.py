"""FRF files: references.json, the FRF CSV (round trip, faults named), and the command line."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from rigidid.api import frf as api_frf
from rigidid.errors import InputError
from rigidid.io.frf import frf_csv_text, load_frf_csv, load_frf_uff, load_references, reference_arrays

from .cli_runner import run as run_here
from .conftest import DATA, SAMPLES

FOUR = SAMPLES / "four-mounts"
REFS = DATA / "frf" / "references.json"


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


@pytest.fixture(scope="module")
def noisy(tmp_path_factory: pytest.TempPathFactory) -> SimpleNamespace:
    """The four-mounts body's FRFs with 1 % complex noise (400 lines to 20x its highest mode), and its modes.

    400 lines, not simulate's 2000: the errors asserted below are still 10-30x inside their bounds
    (observed over seeds 1-4: mass <= 0.09 %, CG <= 0.3 mm, inertia <= 0.2 %, k_xx <= 0.4 %).
    """
    from rigidid import api
    from rigidid.io.files import modes_csv_text

    folder = tmp_path_factory.mktemp("noisy")
    table = api.simulate(FOUR / "body.json", FOUR / "layout.json")
    top = 20.0 * float(np.max(table.frequency_hz))
    lines = np.linspace(top / 400.0, top, 400)
    data = api_frf.simulate_frf(FOUR / "body.json", FOUR / "layout.json", REFS, noise=0.01, seed=3, frequencies=lines)
    frf, modes = folder / "frf.csv", folder / "modes.csv"
    frf.write_text(frf_csv_text(data.frequencies, data.frf, data.sensor_ids, data.reference_ids))
    modes.write_text(modes_csv_text(table))
    return SimpleNamespace(frf=frf, modes=modes)


def test_simulate_frf_then_identify_massline_from_the_command_line(tmp_path: Path, noisy: SimpleNamespace) -> None:
    """``simulate --write-frf`` writes the FRFs identify reads; the mass line's JSON measures the body (the
    identification through the API on shorter FRFs: ``identify --frf`` on the command line is run in
    test_frf_lab_file and test_frf_uff_write)."""
    from rigidid.jsonout import massline_to_dict

    frf = tmp_path / "frf.csv"
    done = run_here("simulate", FOUR / "body.json", FOUR / "layout.json", "-o", tmp_path / "m.csv", "--write-frf",
                    frf, "--references", REFS, "--add-frf-noise", "0.01", "--seed", "1")  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "FRFs (2000 lines)" in done.stderr
    ids = [s["id"] for s in json.loads((FOUR / "layout.json").read_text())["sensors"]]
    assert load_frf_csv(frf, ids, ["h1", "h2", "h3"])[1].shape == (len(ids), 3, 2000)
    out = massline_to_dict(api_frf.identify_massline(FOUR / "layout.json", noisy.frf, REFS, method="massline"))
    body = json.loads((FOUR / "body.json").read_text())
    assert out["route"] == "massline" and out["band_source"] == "automatic"
    assert out["supports"] in ("exact", "first_order") and out["supports_reason"] in out["route_reason"]
    assert abs(out["mass_measured"] / body["mass"] - 1.0) < 0.01
    assert out["mass_given"] == body["mass"]  # the layout's mass
    assert out["mass_difference"] == pytest.approx(out["mass_measured"] - body["mass"])
    np.testing.assert_allclose(out["center_of_gravity"], body["center_of_gravity"], atol=0.006)
    np.testing.assert_allclose(np.diag(out["inertia_tensor"]), np.diag(body["inertia_tensor"]), rtol=0.03)


def test_massline_without_references_is_an_input_error(tmp_path: Path) -> None:
    done = run_here("identify", FOUR / "layout.json", "--frf", tmp_path / "x.csv", "--method", "massline")
    assert done.returncode == 2
    assert "--references" in done.stderr and len(done.stderr.strip().splitlines()) == 1


def _write_uff58(path: Path, data: api_frf.FrfData, directions: dict[str, int], ref_dirs: dict[str, int]) -> None:
    import pyuff

    sets = []
    for i, s in enumerate(data.sensor_ids):
        for j, r in enumerate(data.reference_ids):
            w = 2 * np.pi * data.frequencies
            mobility = i == 0 and j == 0  # one pair as mobility: converted back to accelerance
            values = data.frf[i, j] / (1j * w) if mobility else data.frf[i, j]
            sets.append(
                pyuff.prepare_58(
                    func_type=4, rsp_node=int(s), rsp_dir=directions[s], ref_node=int(r), ref_dir=ref_dirs[r],
                    ord_data_type=6, num_pts=data.frequencies.size, abscissa_spacing=0, abscissa_spec_data_type=18,
                    ordinate_spec_data_type=11 if mobility else 12, orddenom_spec_data_type=13,
                    data=values, x=data.frequencies, id1="rigidid test", rsp_ent_name="b", ref_ent_name="b",
                    abscissa_min=float(data.frequencies[0]), abscissa_inc=0.0,
                )
            )  # fmt: skip
    uff = pyuff.UFF(str(path))
    uff.write_sets(sets, mode="overwrite")


def test_uff58_frfs_read_as_accelerance(tmp_path: Path) -> None:
    refs = tmp_path / "refs.json"
    refs.write_text(
        json.dumps(
            {"references": [{"id": "101", "position": [0.3, 0.2, 0.15], "direction": "+x"},
                            {"id": "102", "position": [-0.3, 0.2, -0.15], "direction": "+y"},
                            {"id": "103", "position": [0.3, -0.2, -0.15], "direction": "+z"}]}
        )
    )  # fmt: skip
    lines = np.arange(1.0, 400.0, 4.0)  # exact in the 58's abscissa format
    data = api_frf.simulate_frf(FOUR / "body.json", FOUR / "layout.json", refs, frequencies=lines)
    codes = {"1": 3, "2": 1, "3": 2, "4": 3, "5": 1, "6": 2, "7": 3, "8": 1}
    path = tmp_path / "frf.uff"
    _write_uff58(path, data, codes, {"101": 1, "102": 2, "103": 3})
    freqs, h = load_frf_uff(path, data.sensor_ids, data.reference_ids)
    np.testing.assert_allclose(freqs, data.frequencies, rtol=1e-12)
    np.testing.assert_allclose(h, data.frf, rtol=1e-9, atol=1e-15)


def test_a_real_h1_export_without_nodes_is_refused_saying_why(tmp_path: Path) -> None:
    path = tmp_path / "h1.uff"
    path.write_bytes((DATA / "uff" / "non_ascii_header_frf.uff").read_bytes())
    with pytest.raises(InputError, match=r"dataset 58 #1.*names no response or reference node.*no geometry"):
        load_frf_uff(path, ["1"], ["h1"])


def test_identify_residues_takes_the_poles_from_the_modes_file(noisy: SimpleNamespace) -> None:
    from rigidid.jsonout import massline_to_dict

    result = api_frf.identify_massline(
        FOUR / "layout.json", noisy.frf, REFS, method="residues", modes=noisy.modes, mass=41.0
    )
    out = massline_to_dict(result)
    assert out["route"] == "residues" and "poles" in out["route_reason"]
    assert abs(out["mass_measured"] / 40.0 - 1.0) < 0.01  # the truth is 40 kg
    assert out["mass_given"] == 41.0
    assert out["mass_difference_relative"] == pytest.approx(out["mass_measured"] / 41.0 - 1.0)
    out = massline_to_dict(api_frf.identify_massline(FOUR / "layout.json", noisy.frf, REFS, method="residues"))
    assert "found in the FRFs" in out["route_reason"]  # without modes.csv the poles are fitted to the FRFs
    assert abs(out["mass_measured"] / 40.0 - 1.0) < 0.01
    scaled = out["scaled_modes"]  # absolute stiffness from the scaled modes: k_xx is the mounts' sum
    assert abs(scaled["mass"] / 40.0 - 1.0) < 0.01
    assert abs(scaled["stiffness_matrix"][0][0] / (29000.0 + 5800.0 + 6900.0 + 250700.0) - 1.0) < 0.02
