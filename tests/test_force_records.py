"""identify --records with a force channel measures the mass (issue 23, item 5); --frf-out writes H1 FRFs.

The records come from the forward model of ``tests/core/test_force.py`` (shares no code with rigidid).
The refit is left out (``--no-refine``) to keep the tests fast: the mass is fitted to the body per
unit mass whichever route gave it.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from .cli_runner import run
from .core.test_force import AXES, CG, DRIVE, DRIVE_DIR, INERTIA, MASS, RATE, SENSORS, _records


def _write(folder: Path, force_block: bool = True, noise: float = 0.0) -> list[Path]:
    layout: dict[str, object] = {
        "units": {"length": "m", "mass": "kg"},
        "mass": 140.0,
        "sensors": [
            {"id": f"s{i + 1}", "position": SENSORS[i].tolist(), "direction": AXES[i].tolist()}
            for i in range(len(AXES))
        ],
        "tolerances": {"sensitivity": 0.0, "orientation_deg": 0.0, "transverse": 0.0, "position": 0.0},
    }
    if force_block:
        layout["force"] = {"column": "force", "position": DRIVE.tolist(), "direction": DRIVE_DIR.tolist()}
    (folder / "layout.json").write_text(json.dumps(layout))
    rng = np.random.default_rng(0)
    header = "time," + ",".join(f"s{i + 1}" for i in range(len(AXES))) + ",force"
    paths = []
    for k, (y, f) in enumerate(zip(*_records(), strict=True)):
        y = y + noise * np.sqrt(np.mean(y**2, axis=0)) * rng.standard_normal(y.shape)
        t = np.arange(y.shape[0]) / RATE
        path = folder / f"hit{k + 1}.csv"
        np.savetxt(path, np.column_stack([t, y, f]), delimiter=",", header=header, comments="", fmt="%.12g")
        paths.append(path)
    return paths


@pytest.fixture(scope="module")
def case(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[Path]]:
    folder = tmp_path_factory.mktemp("force")
    return folder, _write(folder)


@pytest.fixture(scope="module")
def ran(case: tuple[Path, list[Path]]) -> tuple[Path, str]:
    """identify --records with the layout's force block, the result JSON and the H1 FRFs written."""
    folder, paths = case
    out = run(
        "identify", folder / "layout.json", "--records", *paths, "--no-refine", "--json", folder / "r.json",
        "--frf-out", folder / "frf.csv",
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    return folder, out.stderr


def test_the_force_measures_the_mass(ran: tuple[Path, str]) -> None:
    """Noise-free records: the mass to 1e-3 (observed 5e-5), used for the inertia; the layout's mass reported beside."""
    folder, stderr = ran
    assert "not sensors" not in stderr  # the force column is used, not left out
    data = json.loads((folder / "r.json").read_text())
    assert data["mass_source"] == "force"
    assert data["mass"] == pytest.approx(MASS, rel=1e-3)
    assert data["mass_measured"] == data["mass"]
    assert data["mass_given"] == 140.0
    assert data["force_mass"]["estimator"] == "errors-in-variables"  # the automatic band: up to the tip's limit
    budget = data["force_mass"]["budget"]
    assert budget["body"] > 0  # the per-mass body's standard errors reach the mass's
    assert data["force_mass"]["std"] == pytest.approx(np.sqrt(sum(v**2 for v in budget.values())))
    assert np.allclose(data["center_of_gravity"], CG, atol=1e-6)
    assert np.allclose(data["inertia_tensor"], INERTIA, rtol=2e-3, atol=2e-3)
    assert np.allclose(data["inertia_tensor"], data["mass"] * np.asarray(data["inertia_per_mass"]))
    header = (folder / "frf.csv").read_text().splitlines()[0]
    assert header == "frequency_hz,response,reference,real,imag,coherence"
    refs = json.loads((folder / "frf.references.json").read_text())
    assert refs["references"][0]["id"] == "force"


def test_frf_out_reads_back_in_the_frf_route(ran: tuple[Path, str], tmp_path: Path) -> None:
    """modes --frf on the written H1 FRFs finds the records' modes; identify on them, the CG within its intervals."""
    folder, _ = ran
    out = run("modes", folder / "layout.json", "--frf", folder / "frf.csv", "--references",
              folder / "frf.references.json", "-o", tmp_path / "m.csv")  # fmt: skip
    assert out.returncode == 0, out.stderr
    out = run("identify", folder / "layout.json", tmp_path / "m.csv", "--json", tmp_path / "f.json")
    assert out.returncode == 0, out.stderr
    records, frf = (json.loads(p.read_text()) for p in (folder / "r.json", tmp_path / "f.json"))
    f_records = [m["frequency_hz"] for m in records["diagnostics"]["modes"]]
    f_frf = [m["frequency_hz"] for m in frf["diagnostics"]["modes"]]
    assert np.allclose(sorted(f_frf), sorted(f_records), rtol=2e-3)
    std = np.asarray(frf["standard_errors"]["center_of_gravity"])
    assert np.all(np.abs(np.asarray(frf["center_of_gravity"]) - records["center_of_gravity"]) < 3 * std)


def test_force_option_needs_the_drive_point(tmp_path: Path) -> None:
    """--force without a 'force' block in the layout: one line naming the option, exit 2, nothing written."""
    paths = _write(tmp_path, force_block=False)
    out = run("identify", tmp_path / "layout.json", "--records", *paths, "--no-refine", "--force", "force",
              "--json", tmp_path / "r.json")  # fmt: skip
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "--force" in lines[0] and "drive point" in lines[0]
    assert not (tmp_path / "r.json").exists()


def test_force_column_missing(case: tuple[Path, list[Path]], tmp_path: Path) -> None:
    """--force naming a column the records lack: one line naming the file and the column, exit 2."""
    folder, paths = case
    out = run("identify", folder / "layout.json", "--records", *paths, "--no-refine", "--force", "hammer")
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "hammer" in lines[0] and "hit1.csv" in lines[0]
