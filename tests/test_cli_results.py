"""Issue 9 (results half): force units, findings on wrong data, the command line's manners."""

from __future__ import annotations

import csv
import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

from rigidid import __version__, api
from rigidid.io.files import modes_csv_text

from . import cli_runner
from .conftest import PAPER, SAMPLES

ENGINE = SAMPLES / "engine-on-mounts"


def run(*args: str | Path, columns: int | None = None) -> subprocess.CompletedProcess[str]:
    """``rigidid ARGS`` (in this process: see :mod:`tests.cli_runner`), `columns` wide."""
    return cli_runner.run(*args, env=None if columns is None else {"COLUMNS": str(columns)})


def test_paper_vertical_stiffness_in_lbf_per_inch_fits_80_columns(tmp_path: Path) -> None:
    out = run("identify", PAPER / "layout.json", PAPER / "modes.csv", "--json", tmp_path / "r.json", columns=80)
    assert out.returncode == 0, out.stderr
    assert "lbf/in" in out.stdout and "580.65" in out.stdout
    assert max(len(line) for line in out.stdout.splitlines()) <= 80
    assert "…" not in out.stdout  # no cell cut short
    data = json.loads((tmp_path / "r.json").read_text())
    assert data["stiffness_force"][2][2] == pytest.approx(580.65, abs=0.01)
    assert data["force_units"]["stiffness"]["translation"] == "lbf/in"
    assert data["stiffness_matrix"][2][2] == pytest.approx(224184, rel=1e-5)  # the old key keeps its meaning
    assert data["quantity_units"]["center_of_gravity"] == "in"


def test_engine_tables_fit_80_columns_without_cutting_cells() -> None:
    out = run("identify", ENGINE / "layout.json", ENGINE / "modes.csv", columns=80)
    assert out.returncode == 0, out.stderr
    assert max(len(line) for line in out.stdout.splitlines()) <= 80
    assert "…" not in out.stdout
    # one unit throughout: the diagonal terms in the matrices' units (N m/rad beside N mm/rad was printed)
    assert "N/mm" in out.stdout and "N·mm/rad" in out.stdout and "N·m/rad" not in out.stdout


def test_slug_layout_gives_the_same_lbf_per_inch() -> None:
    from rigidid.jsonout import result_to_dict
    from rigidid.models import LayoutFile
    from rigidid.units import KG_PER_MASS, LB

    data = json.loads((PAPER / "layout.json").read_text())
    data["units"]["mass"] = "slug"
    data["mass"] = 136.0 * LB / KG_PER_MASS["slug"]
    layout = LayoutFile.model_validate(data)
    with pytest.warns(UserWarning, match="damping matrix"):
        out = result_to_dict(api.identify(layout, api.load_modes(PAPER / "modes.csv", layout)))
    assert out["force_units"]["stiffness"]["translation"] == "lbf/in"
    assert out["stiffness_force"][2][2] == pytest.approx(580.65, abs=0.01)


def test_force_unit_option_and_csv(tmp_path: Path) -> None:
    out = run("identify", PAPER / "layout.json", PAPER / "modes.csv", "--force-unit", "N", "--csv", tmp_path / "c")
    assert out.returncode == 0, out.stderr
    rows = list(csv.reader((tmp_path / "c" / "stiffness.csv").read_text().splitlines()))
    assert rows[0][0] == "(N/in; N/rad; N in/rad)" and rows[0][1:] == ["x", "y", "z", "rx", "ry", "rz"]
    assert float(rows[3][3]) == pytest.approx(580.65 * 4.4482216152605, rel=1e-4)
    assert {p.name for p in (tmp_path / "c").iterdir()} >= {"inertia.csv", "damping.csv", "center_of_gravity.csv"}
    bad = run("identify", PAPER / "layout.json", PAPER / "modes.csv", "--force-unit", "kgf")
    assert bad.returncode == 2 and "--force-unit" in bad.stderr


def _misplaced_test(tmp_path: Path) -> tuple[Path, Path]:
    """Engine modes simulated with the true layout; the layout file has sensor B+y 120 mm off in x."""
    modes = api.simulate(ENGINE / "body.json", ENGINE / "layout.json")
    (tmp_path / "modes.csv").write_text(modes_csv_text(modes))
    layout = json.loads((ENGINE / "layout.json").read_text())
    sensor = next(s for s in layout["sensors"] if s["id"] == "B+y")
    sensor["position"][0] += 120.0
    (tmp_path / "layout.json").write_text(json.dumps(layout))
    return tmp_path / "layout.json", tmp_path / "modes.csv"


def test_misplaced_sensor_warns_and_names_it(tmp_path: Path) -> None:
    layout, modes = _misplaced_test(tmp_path)
    out = run("identify", layout, modes, "--json", tmp_path / "r.json")
    assert out.returncode == 0, out.stderr
    assert "rigidid: warning: sensor 'B+y' does not move with the others" in out.stderr
    data = json.loads((tmp_path / "r.json").read_text())
    assert any("'B+y'" in w for w in data["diagnostics"]["warnings"])
    # the harm it names is real: the CG is off by centimetres
    assert np.linalg.norm(np.subtract(data["center_of_gravity"], [35.0, -12.0, 180.0])) > 10.0


def test_damping_in_percent_warns(tmp_path: Path) -> None:
    text = (PAPER / "modes.csv").read_text().splitlines()
    header, rows = text[0], [r.split(",") for r in text[1:]]
    for r in rows:
        r[2] = f"{100 * float(r[2]):.4f}"  # 0.3914 meant as 0.3914 %
    (tmp_path / "modes.csv").write_text("\n".join([header, *(",".join(r) for r in rows)]) + "\n")
    out = run("identify", PAPER / "layout.json", tmp_path / "modes.csv")
    assert out.returncode == 0, out.stderr
    assert "were they given in percent?" in out.stderr


def test_nonrigid_modes_exit_1_with_labels_in_identify_and_report(tmp_path: Path) -> None:
    args = (ENGINE / "layout.json", ENGINE / "modes.csv", "--modes", "1,2,3,5,6,7")
    ident = run("identify", *args)
    rep = run("report", *args, "-o", tmp_path / "r.html")
    assert ident.returncode == rep.returncode == 1
    error = [line for line in ident.stderr.splitlines() if line.startswith("rigidid: error:")]
    assert error == [line for line in rep.stderr.splitlines() if line.startswith("rigidid: error:")]
    assert "mode 7 is not a rigid-body mode" in error[0] and "0.63" in error[0]
    assert "mode 4" not in ident.stderr and "mode 5" not in ident.stderr
    assert not (tmp_path / "r.html").exists()


def test_help_shows_defaults_version_and_one_modal_method_name() -> None:
    out = run("identify", "--help", columns=120)
    assert "[default: 0.001]" in out.stdout and "[default: from the spectrum]" in out.stdout
    assert "--force-unit" in out.stdout and "--csv" in out.stdout
    modes = run("modes", "--help", columns=120)
    assert "--modal-method" in modes.stdout and "--method" not in modes.stdout.replace("--modal-method", "")
    assert run("-V").stdout.strip() == f"rigidid {__version__}"


def test_simulate_records_reports_progress(tmp_path: Path) -> None:
    seen: list[tuple[str, float, float | None]] = []
    written = api.simulate_records(
        ENGINE / "body.json", ENGINE / "layout.json", tmp_path, duration=1.0, progress=lambda *a: seen.append(a)
    )
    assert len(written) == 2
    simulated = [(done, total) for task, done, total in seen if task == "simulating impulse responses"]
    assert simulated[-1] == (1024.0, 1024.0)  # two impacts of 512 samples
    assert [done for task, done, _ in seen if task == "writing records"] == [0, 1, 2]


def test_inertia_not_positive_definite_exits_1_naming_the_modes(tmp_path: Path) -> None:
    # six sensors: the elastic mode 7 fits "rigid motion" exactly, and the inertia comes out impossible
    keep = ("A+x", "A+y", "A+z", "B+x", "B+y", "C+x")
    layout = json.loads((ENGINE / "layout.json").read_text())
    layout["sensors"] = [s for s in layout["sensors"] if s["id"] in keep]
    (tmp_path / "layout.json").write_text(json.dumps(layout))
    lines = (ENGINE / "modes.csv").read_text().splitlines()
    (tmp_path / "modes.csv").write_text("\n".join([lines[0], *(r for r in lines[1:] if r.split(",")[3] in keep)]))
    args = (tmp_path / "layout.json", tmp_path / "modes.csv", "--modes", "1,2,3,5,6,7")
    ident, rep = run("identify", *args), run("report", *args, "-o", tmp_path / "r.html")
    assert ident.returncode == rep.returncode == 1
    error = next(line for line in ident.stderr.splitlines() if line.startswith("rigidid: error:"))
    assert "modes 1, 2, 3, 5, 6, 7 determine no rigid body" in error and "not positive definite" in error
    assert error in rep.stderr


def test_modes_method_is_a_deprecated_alias_of_modal_method(tmp_path: Path) -> None:
    api.simulate_records(ENGINE / "body.json", ENGINE / "layout.json", tmp_path, duration=1.0)
    out = run("modes", ENGINE / "layout.json", tmp_path / "record-1.csv", "--method", "bogus")
    assert out.returncode == 2
    assert "--method is deprecated; use --modal-method" in out.stderr
    assert "--method: unknown method 'bogus'" in out.stderr  # the error names the option the user typed


def test_numerical_zeros_print_as_zero_in_matrix_tables() -> None:
    """An entry at the rounding of its diagonals' scale is a zero, a small true coupling is a figure (issue 25)."""
    from rich.console import Console

    from rigidid.render import ROUNDING_ZERO, _matrix_table

    # mixed units as K at the CG: translations ~1e3, rotations ~1e7, so coupling entries scale as ~1e5
    a = np.diag([540.0, 470.0, 1160.0, 4.2e7, 6.0e7, 4.0e7])
    a[0, 2] = a[2, 0] = 0.3 * ROUNDING_ZERO * np.sqrt(540.0 * 1160.0)  # rounding: prints 0
    a[0, 1] = a[1, 0] = 0.05  # a true coupling 1e-4 of the diagonals: kept
    a[0, 3] = a[3, 0] = 1e-3  # 6.5e-9 of sqrt(540 * 4.2e7): kept, it is above the rounding
    console = Console(width=200, record=True)
    console.print(_matrix_table("K", a, ["x", "y", "z", "rx", "ry", "rz"]))
    rows = [line.split() for line in console.export_text().splitlines()]
    cells = next(row for row in rows if row[:1] == ["x"] and row[1:2] != ["y"])  # the row, not the header
    assert cells[1:5] == ["540.00", "0.050000", "0", "1.0000e-3"], cells
