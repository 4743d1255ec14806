"""Tables an engineer can sign: units kept whole, one unit throughout, units on every column, the data sheet
beside the test, and options that do not apply refused rather than ignored."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

from . import cli_runner

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "samples" / "engine-test"
UNIT_OPENED = re.compile(r"\((kg|g|t|lb|slug|N|kN|lbf|mm|cm|m|in|ft)\b[^)]*$")


def run(*args: object, columns: int = 80, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    """``rigidid ARGS`` (in this process: see :mod:`tests.cli_runner`), `columns` wide, without colour."""
    return cli_runner.run(*map(str, args), cwd=cwd, env={"COLUMNS": str(columns), "NO_COLOR": "1"})


@pytest.fixture(scope="module")
def identified() -> str:
    out = run("identify", SAMPLE / "layout.json", SAMPLE / "modes.csv", "--mounts", SAMPLE / "mounts.json")
    assert out.returncode == 0, out.stderr
    return out.stdout


def test_no_title_or_label_breaks_inside_its_unit(identified: str) -> None:
    """'(kg' on one line and 'mm^2)' on the next was printed at 80 columns."""
    broken = [line for line in identified.splitlines() if UNIT_OPENED.search(line.rstrip(" │┃"))]
    assert broken == []
    assert "(kg·mm^2)" in identified and "(N/mm, N·mm/rad)" in identified


def test_rotational_stiffness_in_one_unit_throughout(identified: str) -> None:
    rows = [line for line in identified.splitlines() if re.match(r"^\W*r[xyz]\s", line) and "/rad" in line]
    assert rows and all("N·mm/rad" in line for line in rows)  # the diagonal table, as the matrix above it
    assert "N·m/rad" not in identified and "N m/rad" not in identified


def test_the_data_sheet_beside_the_identified_mount_rates(identified: str) -> None:
    """mounts.json's rates (the JSON's nominal_stiffness) printed under each mount's identified rates."""
    lines = identified.splitlines()
    for mount, rates in (("front", "180.00 │ 160.00 │ 420.00"), ("rear-left", "150.00 │ 170.00 │ 380.00")):
        k = next(i for i, line in enumerate(lines) if line.startswith(f"│ {mount} "))
        assert "data sheet" in lines[k + 1] and rates in lines[k + 1]


def test_plan_add_columns_have_units(tmp_path: Path) -> None:
    args = ("plan", SAMPLE / "layout.json", "--body", SAMPLE / "cad-estimate.json", "--add", "1", "--uncertainty", "20",
            "--duration", "2")  # fmt: skip
    out = run(*args, columns=160)
    assert out.returncode == 0, out.stderr
    header = next(line for line in out.stdout.splitlines() if "step" in line and "position" in line)
    for column in ("position (mm)", "direction (unit)", "CG std (mm)", "score (-)"):
        assert column in header
    # --duration plans a records test: the refit's predicted budget, per source and the four in quadrature
    lines = out.stdout.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("Predicted sensor budget, records route"))
    names = ("noise", "sensitivity", "orientation", "transverse", "position", "sensors", "combined")
    assert all(name in lines[start + 2] for name in names)
    assert lines[start + 4].startswith("│ CG x (mm)") and "2 impacts, 512 Hz, 2 s" in out.stdout


@pytest.mark.parametrize(
    ("option", "needs"),
    [
        (["--impact", "0,0,0:0,0,1"], "--write-records"),
        (["--sample-rate", "100"], "--write-records"),
        (["--add-record-noise", "0.01"], "--write-records"),
        (["--references", str(SAMPLE / "refs.json")], "--write-frf"),
        (["--add-frf-noise", "0.01"], "--write-frf"),
    ],
)
def test_simulate_refuses_options_of_outputs_not_asked_for(tmp_path: Path, option: list[str], needs: str) -> None:
    out = run("simulate", SAMPLE / "body.json", SAMPLE / "layout.json", "-o", "m.csv", *option, cwd=tmp_path)
    assert out.returncode == 2
    assert out.stderr.strip().splitlines() == [f"rigidid: error: {option[0]}: applies only with {needs} " +
                                               ("DIR (the impulse-response records)" if needs == "--write-records"
                                                else "FILE (the FRFs)")]  # fmt: skip
    assert list(tmp_path.iterdir()) == []  # nothing written
