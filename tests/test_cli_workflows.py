"""Whole workflows through the command line: records, uncertainty, plan, report, UFF."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from .cli_runner import run
from .conftest import PAPER, SAMPLES

ENGINE = SAMPLES / "engine-on-mounts"


@pytest.fixture(scope="module")
def engine_records(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    folder = tmp_path_factory.mktemp("records")
    out = run(
        "simulate", ENGINE / "body.json", ENGINE / "layout.json", "-o", folder / "exact.csv",
        "--write-records", folder, "--add-record-noise", "0.01", "--seed", "7",
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    return sorted(folder.glob("record-*.csv"))


def test_simulate_writes_two_records(engine_records: list[Path]) -> None:
    assert [p.name for p in engine_records] == ["record-1.csv", "record-2.csv"]
    header = engine_records[0].read_text().splitlines()[0].split(",")
    assert header[0] == "time" and len(header) == 13


def test_modes_from_records_match_the_exact_modes(engine_records: list[Path], tmp_path: Path) -> None:
    target = tmp_path / "modes.csv"
    out = run("modes", ENGINE / "layout.json", *engine_records, "-o", target, "--json", tmp_path / "est.json")
    assert out.returncode == 0, out.stderr
    exact = np.loadtxt(engine_records[0].parent / "exact.csv", delimiter=",", skiprows=1, usecols=(0, 1, 2))
    found = np.loadtxt(target, delimiter=",", skiprows=1, usecols=(0, 1, 2))
    np.testing.assert_allclose(found[:, 1], exact[:, 1], rtol=1e-3)
    np.testing.assert_allclose(found[:, 2], exact[:, 2], rtol=0.1)
    estimation = json.loads((tmp_path / "est.json").read_text())
    assert len(estimation["modes"]) == 6 and estimation["stabilisation"]


def test_identify_from_records_recovers_the_body(engine_records: list[Path]) -> None:
    out = run("identify", ENGINE / "layout.json", "--records", *engine_records, "--json", "-")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    body = json.loads((ENGINE / "body.json").read_text())
    layout = json.loads((ENGINE / "layout.json").read_text())
    positions = np.array([s["position"] for s in layout["sensors"]])
    span = max(np.linalg.norm(a - b) for a in positions for b in positions)
    assert np.linalg.norm(np.subtract(data["center_of_gravity"], body["center_of_gravity"])) < 0.01 * span
    np.testing.assert_allclose(np.diag(data["inertia_tensor"]), np.diag(body["inertia_tensor"]), rtol=0.05)
    assert data["modal_estimation"]["method"] == "era"


def test_records_need_the_flag(engine_records: list[Path]) -> None:
    out = run("identify", ENGINE / "layout.json", *engine_records)
    assert out.returncode == 2
    assert "pass --records" in out.stderr


def test_uncertainty_in_json_and_tables() -> None:
    out = run("identify", PAPER / "layout.json", PAPER / "modes.csv", "--uncertainty", "300", "--json", "-")
    assert out.returncode == 0, out.stderr
    unc = json.loads(out.stdout)["uncertainty"]
    assert unc["draws"] == 300
    cg = unc["center_of_gravity"]
    for (lo, hi), est, std in zip(cg["ci95"], cg["estimate"], cg["std"], strict=True):
        assert lo < est < hi and std > 0
    tables = run("identify", PAPER / "layout.json", PAPER / "modes.csv", "--uncertainty", "300", "--angle-noise", "1")
    assert "Uncertainty (300 Monte Carlo draws" in tables.stdout
    assert "direction 1 deg" in tables.stdout


def test_bad_noise_option() -> None:
    out = run("identify", PAPER / "layout.json", PAPER / "modes.csv", "--uncertainty", "10", "--angle-noise", "-1")
    assert out.returncode == 2
    assert "--angle-noise: must be zero or positive" in out.stderr


def _collinear_layout(path: Path) -> Path:
    sensors = [
        {"id": str(i), "position": [10.0 * i, 0.01 * i * i, 0.0], "direction": d}
        for i, d in enumerate(["+x", "+y", "+z", "+y", "+z", "+x", "+z"])
    ]
    path.write_text(json.dumps({"units": {"length": "mm", "mass": "kg"}, "sensors": sensors}))
    return path


def test_plan_prefers_a_good_layout_and_says_why(tmp_path: Path) -> None:
    good = run("plan", ENGINE / "layout.json", "--json", "-")
    poor = run("plan", _collinear_layout(tmp_path / "line.json"), "--json", "-")
    assert good.returncode == 0, good.stderr
    good_data, poor_data = json.loads(good.stdout), json.loads(poor.stdout)
    assert good_data["layout"]["ok"]
    worse = (
        poor_data["layout"]["condition"] is None or poor_data["layout"]["condition"] > good_data["layout"]["condition"]
    )
    assert worse
    text = " ".join(f["message"] for f in poor_data["layout"]["findings"])
    assert "line" in text


def test_plan_with_body_predicts_and_suggests(tmp_path: Path) -> None:
    out = run(
        "plan", ENGINE / "layout.json", "--body", ENGINE / "body.json", "--add", "1", "--draws", "100", "--json", "-",
        "--records", "--sample-rate", "256", "--duration", "2",
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert len(data["prediction"]["center_of_gravity_std"]) == 3
    step = data["suggestions"]["steps"][0]
    assert step["figures"]["score"] <= data["suggestions"]["baseline"]["score"]
    # the budget: the noise's part (the prediction's draws) beside each sensor tolerance's, in quadrature
    budget = data["sensor_budget"]
    assert list(budget) == ["noise", "sensitivity", "orientation", "transverse", "position", "combined"]
    assert budget["noise"]["center_of_gravity"] == data["prediction"]["center_of_gravity_std"]
    for key in ("center_of_gravity", "inertia_tensor", "stiffness_diagonal"):
        parts = [np.asarray(budget[s][key]) for s in budget if s != "combined"]
        np.testing.assert_allclose(budget["combined"][key], np.sqrt(sum(p**2 for p in parts)), rtol=1e-12)
    assert data["tolerances"]["orientation_deg"] > 0
    # a records test planned: the refit's own budget per source, and the four sources in quadrature
    records = data["records_sensor_budget"]
    sources = ["sensitivity", "orientation", "transverse", "position"]
    assert list(records) == ["noise", *sources, "sensors", "combined"]
    for key in ("center_of_gravity", "inertia_tensor", "stiffness_diagonal"):
        sensors = np.sqrt(sum(np.asarray(records[s][key]) ** 2 for s in sources))
        np.testing.assert_allclose(records["sensors"][key], sensors, rtol=1e-12)
        np.testing.assert_allclose(records["combined"][key], np.hypot(records["noise"][key], sensors), rtol=1e-12)
    test = data["records_test"]
    assert (test["sample_rate_hz"], test["duration_s"], test["noise"], len(test["impacts"])) == (256.0, 2.0, 0.01, 2)
    assert 0 < test["rows_used"] <= test["fit_rows"] <= 512


def test_report_is_one_offline_html_file(tmp_path: Path) -> None:
    target = tmp_path / "report.html"
    out = run("report", PAPER / "layout.json", PAPER / "modes.csv", "-o", target, "--png", tmp_path / "png")
    assert out.returncode == 0, out.stderr
    html = target.read_text()
    assert html.lstrip().lower().startswith("<!doctype html")
    assert html.count("data:image/png;base64,") >= 3
    assert "http://" not in html and "https://" not in html
    assert len(list((tmp_path / "png").glob("*.png"))) >= 3


def test_identify_writes_uff_modes(tmp_path: Path) -> None:
    uff = tmp_path / "result.uff"
    out = run("identify", ENGINE / "layout.json", ENGINE / "modes.csv", "--uff", uff, "--json", "-")
    assert out.returncode == 0, out.stderr
    from rigidid.io.uff import read_uff

    contents = read_uff(uff)
    assert {row[0] for row in contents.mode_rows} == {1, 2, 3, 4, 5, 6}


PAPER_BODY = {
    "units": {"length": "in", "mass": "lb"},
    "mass": 136.0,
    "center_of_gravity": [0.0, 0.0, -1.4],
    "inertia_tensor": [[2652.0, 40.0, -25.0], [40.0, 3087.0, 15.0], [-25.0, 15.0, 5440.0]],
    "mounts": [
        {"position": [x, y, -2.5], "stiffness": [45000.0, 45000.0, 70000.0], "damping": [60.0, 60.0, 35.0]}
        for x, y in ((7.0, 3.0), (-6.0, 4.5), (-2.0, -6.0))
    ],
}


def test_uff_test_set_identifies_like_csv(tmp_path: Path) -> None:
    """Nodes, signed-direction time records and lb/in units through pyuff give the CSV result."""
    from rigidid import api
    from rigidid.io.uff import write_uff_test

    body = tmp_path / "body.json"
    body.write_text(json.dumps(PAPER_BODY))
    layout = json.loads((PAPER / "layout.json").read_text())
    paths = api.simulate_records(body, PAPER / "layout.json", tmp_path, sample_rate=256.0, duration=6.0, seed=3)
    ids = [s["id"] for s in layout["sensors"]]
    records = []
    for path in paths:
        table = np.loadtxt(path, delimiter=",", skiprows=1)
        records.append((table[:, 0], table[:, 1:], ids))
    exact = api.simulate(body, PAPER / "layout.json")
    mode_rows = [
        (label, float(exact.frequency_hz[k]), float(exact.damping_ratio[k]), sid, v.real, v.imag)
        for k, label in enumerate(exact.labels)
        for sid, v in zip(exact.sensor_ids, exact.shapes[:, k], strict=True)
    ]
    uff = tmp_path / "test.uff"
    write_uff_test(uff, layout, records, mode_rows=mode_rows)

    from_modes = run("identify", uff, "--mass", "136", "--json", "-")  # dataset 55
    assert from_modes.returncode == 0, from_modes.stderr
    np.testing.assert_allclose(
        json.loads(from_modes.stdout)["center_of_gravity"], PAPER_BODY["center_of_gravity"], atol=1e-3
    )
    planned = run("plan", uff, "--json", "-")
    assert planned.returncode == 0, planned.stderr
    assert json.loads(planned.stdout)["layout"]["sensors"] == 6

    from_csv = run("identify", PAPER / "layout.json", "--records", *paths, "--mass", "136", "--json", "-")
    from_uff = run("identify", uff, "--records", "--mass", "136", "--json", "-")
    assert from_csv.returncode == 0, from_csv.stderr
    assert from_uff.returncode == 0, from_uff.stderr
    a, b = json.loads(from_csv.stdout), json.loads(from_uff.stdout)
    np.testing.assert_allclose(b["center_of_gravity"], a["center_of_gravity"], atol=1e-3)
    np.testing.assert_allclose(b["inertia_tensor"], a["inertia_tensor"], rtol=1e-3, atol=1.0)
    np.testing.assert_allclose(a["center_of_gravity"], PAPER_BODY["center_of_gravity"], atol=0.05)

    converted = tmp_path / "converted"
    out = run("convert", uff, "-o", converted)
    assert out.returncode == 0, out.stderr
    assert sorted(p.name for p in converted.iterdir()) == ["layout.json", "modes.csv", "record-1.csv", "record-2.csv"]
    again = run("identify", converted / "layout.json", "--records", *sorted(converted.glob("record-*.csv")),
                "--mass", "136", "--json", "-")  # fmt: skip
    assert again.returncode == 0, again.stderr
    np.testing.assert_allclose(json.loads(again.stdout)["center_of_gravity"], b["center_of_gravity"], atol=1e-6)


def test_record_spread_through_the_cli(engine_records: list[Path]) -> None:
    out = run("identify", ENGINE / "layout.json", "--records", *engine_records, "--resample", "4", "--json", "-")
    assert out.returncode == 0, out.stderr
    spread = json.loads(out.stdout)["uncertainty_records"]
    assert spread["segments"] == 4 and spread["used"] == 4
    assert all(lo < hi for lo, hi in spread["center_of_gravity"]["ci95"])


def test_resample_needs_records() -> None:
    out = run("identify", PAPER / "layout.json", PAPER / "modes.csv", "--resample", "4")
    assert out.returncode == 2
    assert "--resample: data-driven intervals need impact records" in out.stderr
