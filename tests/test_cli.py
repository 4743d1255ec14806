"""The command line, run as a user runs it (``python -m rigidid``)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rigidid.models import ResultFile

from .cli_runner import run
from .conftest import DATA, PAPER, SAMPLES
from .tolerances import CSV_DIGITS_REL, MOUNT_RATES_CSV_REL

ENGINE = SAMPLES / "engine-on-mounts"


def test_identify_prints_tables() -> None:
    out = run("identify", PAPER / "layout.json", PAPER / "modes.csv")
    assert out.returncode == 0, out.stderr
    for title in ("Centre of gravity", "Inertia tensor", "Principal moments", "Stiffness", "Damping", "Diagnostics"):
        assert title in out.stdout
    assert "-1.628" in out.stdout  # z of the CG
    assert "rigidid: warning:" in out.stderr  # the paper's damping matrix is not positive semi-definite
    assert "rigidid: warning:" not in out.stdout


def test_json_to_stdout_is_only_json() -> None:
    out = run("identify", PAPER / "layout.json", PAPER / "modes.csv", "--json", "-")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    ResultFile.model_validate(data)
    assert data["units"] == {"length": "in", "mass": "lb", "time": "s"}
    assert data["mass"] == 136.0
    assert data["modes_used"] == [1, 2, 3, 4, 5, 6]


def test_json_file_and_tables(tmp_path: Path) -> None:
    target = tmp_path / "result.json"
    out = run("identify", PAPER / "layout.json", PAPER / "modes.csv", "--json", target)
    assert out.returncode == 0, out.stderr
    assert "Centre of gravity" in out.stdout
    assert json.loads(target.read_text())["method"] == "structured"
    assert [p.name for p in tmp_path.iterdir()] == ["result.json"]  # no temporary file left


def test_failure_writes_nothing_and_prints_one_line(tmp_path: Path) -> None:
    target = tmp_path / "result.json"
    out = run("identify", PAPER / "layout.json", DATA / "bad" / "modes_nan.csv", "--json", target)
    assert out.returncode == 2
    assert out.stdout == ""
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rigidid: error: ")
    assert "modes_nan.csv: row 5: real" in lines[0]
    assert "Traceback" not in out.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("--mass", "-3"), "--mass: must be positive"),
        (("--mass", "1e-320"), "--mass: must be at least 1e-100"),
        (("--method", "guess"), "--method: unknown method 'guess'"),
        (("--modes", "1,2,x"), "--modes: expected mode labels"),
        (("--modes", "1,2,3,4,5,7"), "--modes: mode 7 is not in the modes file"),
        (("--estimate-delays",), "--estimate-delays: needs impact records and the refit"),
        (("--estimate-highpass",), "--estimate-highpass: needs impact records and the refit"),
        (("--no-estimate-highpass",), "--no-estimate-highpass: needs impact records and the refit"),
    ],
)
def test_bad_options(args: tuple[str, ...], message: str) -> None:
    out = run("identify", PAPER / "layout.json", PAPER / "modes.csv", *args)
    assert out.returncode == 2
    assert message in out.stderr
    assert "Traceback" not in out.stderr


def test_missing_file_is_one_line() -> None:
    out = run("identify", "nowhere.json", PAPER / "modes.csv")
    assert out.returncode == 2
    assert out.stderr.strip() == "rigidid: error: nowhere.json: file not found"


def test_mass_option_overrides_layout() -> None:
    a = json.loads(run("identify", PAPER / "layout.json", PAPER / "modes.csv", "--json", "-").stdout)
    b = json.loads(run("identify", PAPER / "layout.json", PAPER / "modes.csv", "--json", "-", "--mass", "272").stdout)
    assert b["mass"] == 272.0
    np.testing.assert_allclose(np.array(b["inertia_tensor"]), 2 * np.array(a["inertia_tensor"]))
    np.testing.assert_allclose(b["inertia_per_mass"], a["inertia_per_mass"])


def test_paper_method_option() -> None:
    data = json.loads(
        run("identify", PAPER / "layout.json", PAPER / "modes.csv", "--method", "paper", "--json", "-").stdout
    )
    assert data["method"] == "paper"
    np.testing.assert_allclose(data["center_of_gravity"], [-0.39, -0.19, -1.63], atol=0.01)


def test_automatic_and_given_mode_choice() -> None:
    auto = json.loads(run("identify", ENGINE / "layout.json", ENGINE / "modes.csv", "--json", "-").stdout)
    assert auto["modes_selected"] == "automatic" and auto["modes_used"] == [1, 2, 3, 4, 5, 6]
    assert len(auto["diagnostics"]["candidate_modes"]) == 8
    given = json.loads(
        run("identify", ENGINE / "layout.json", ENGINE / "modes.csv", "--modes", "1,2,3,4,5,6", "--json", "-").stdout
    )
    assert given["modes_selected"] == "given"
    np.testing.assert_allclose(given["center_of_gravity"], auto["center_of_gravity"])


def test_simulate_then_identify_round_trip(tmp_path: Path) -> None:
    body = json.loads((ENGINE / "body.json").read_text())
    modes = tmp_path / "modes.csv"
    out = run("simulate", ENGINE / "body.json", ENGINE / "layout.json", "-o", modes)
    assert out.returncode == 0, out.stderr
    data = json.loads(run("identify", ENGINE / "layout.json", modes, "--json", "-").stdout)
    np.testing.assert_allclose(data["center_of_gravity"], body["center_of_gravity"], rtol=CSV_DIGITS_REL)
    inertia = np.asarray(body["inertia_tensor"])
    np.testing.assert_allclose(data["inertia_tensor"], inertia, rtol=0, atol=CSV_DIGITS_REL * np.abs(inertia).max())


def test_simulate_noise_is_seeded() -> None:
    args = ("simulate", ENGINE / "body.json", ENGINE / "layout.json", "--add-shape-noise", "0.01", "--seed", "3")
    a, b = run(*args), run(*args)
    exact = run("simulate", ENGINE / "body.json", ENGINE / "layout.json")
    assert a.returncode == 0 and a.stdout == b.stdout and a.stdout != exact.stdout


def test_simulate_rejects_unit_mismatch(tmp_path: Path) -> None:
    layout = json.loads((ENGINE / "layout.json").read_text())
    layout["units"]["length"] = "m"
    (tmp_path / "layout.json").write_text(json.dumps(layout))
    out = run("simulate", ENGINE / "body.json", tmp_path / "layout.json")
    assert out.returncode == 2
    assert "body.json: units: units (mm, kg) differ from the layout's units (m, kg)" in out.stderr


def test_help_and_version() -> None:
    out = run("--help")
    assert out.returncode == 0 and "identify" in out.stdout and "simulate" in out.stdout
    version = run("--version")
    assert version.returncode == 0 and version.stdout.startswith("rigidid ")


def test_errors_name_the_option_where_the_api_names_its_parameter(tmp_path: Path) -> None:
    """The API says `modes_used`; the command line says --modes (one mapping, in cli.options.FLAGS)."""
    text = (PAPER / "modes.csv").read_text()
    extra = [line.replace("1,", "7,", 1) for line in text.splitlines()[1:7]]
    seven = tmp_path / "seven.csv"
    seven.write_text(text + "\n".join(extra) + "\n")
    out = run("identify", PAPER / "layout.json", seven)
    assert out.returncode == 2
    assert "--modes" in out.stderr and "modes_used" not in out.stderr
    few = run("identify", PAPER / "layout.json", PAPER / "modes.csv", "--uncertainty", "1")
    assert few.returncode == 2
    assert few.stderr.startswith("rigidid: error: --uncertainty: need at least 2 draws")


def test_warnings_come_before_the_error_they_led_to(tmp_path: Path) -> None:
    """A warning raised before an identification error is printed, and first (it was lost before)."""
    from rigidid.core.simulate import body_modes
    from rigidid.io.atomic import write_text_atomic
    from rigidid.io.files import ModeTable, modes_csv_text

    from .bodies import flat_layout_on_symmetric_mounts

    body, pos, dirs = flat_layout_on_symmetric_mounts()
    modes = body_modes(body, pos, dirs)
    f, z = np.abs(modes.poles) / (2 * np.pi), -modes.poles.real / np.abs(modes.poles)
    ids = [str(i + 1) for i in range(len(pos))]
    write_text_atomic(tmp_path / "m.csv", modes_csv_text(ModeTable.numbered(f, z, ids, modes.shapes), digits=17))
    rows = zip(ids, pos, dirs, strict=True)
    sensors = [{"id": i, "position": p.tolist(), "direction": d.tolist()} for i, p, d in rows]
    layout = {"units": {"length": "m", "mass": "kg"}, "sensors": sensors}
    (tmp_path / "layout.json").write_text(json.dumps(layout))
    out = run("identify", tmp_path / "layout.json", tmp_path / "m.csv")
    assert out.returncode == 1
    lines = out.stderr.splitlines()
    assert lines[0].startswith("rigidid: warning: sensor layout is ill-conditioned"), out.stderr
    assert lines[-1].startswith("rigidid: error: ") and "the inertia is not observable" in lines[-1], out.stderr


def test_mounts_and_torque_roll_axis_from_the_command_line() -> None:
    """The four-mount sample's rates come back from its modes (written with 10 digits)."""
    case = SAMPLES / "four-mounts"
    out = run("identify", case / "layout.json", case / "modes.csv", "--mounts", case / "mounts.json",
              "--torque-axis", "1,0,0", "--json", "-")  # fmt: skip
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    ResultFile.model_validate(data)
    body = json.loads((case / "body.json").read_text())
    rates = np.array([m["stiffness"] for m in data["mounts"]["mounts"]])
    np.testing.assert_allclose(rates, [m["stiffness"] for m in body["mounts"]], rtol=MOUNT_RATES_CSV_REL)
    assert data["mounts"]["unique"] and data["mounts"]["mounts"][0]["id"] == "front-left"
    assert data["torque_roll_axis"]["angle_to_torque_deg"] > 0.0
    bad = run("identify", case / "layout.json", case / "modes.csv", "--torque-axis", "0,0,0")
    assert bad.returncode == 2 and "--torque-axis" in bad.stderr
