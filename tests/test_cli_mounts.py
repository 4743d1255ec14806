"""``--mounts`` on simulate, plan, identify --method mounts and report, run as a user runs them."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from rigidid.models import ResultFile

from .cli_runner import run
from .conftest import SAMPLES
from .tolerances import MOUNT_RATES_CSV_REL

CASE = SAMPLES / "four-mounts"
RATES = [3.0e4, 2.0e4, 1.2e5]


def _identical_mounts(folder: Path, *, group: bool = True, stiffness: bool = True) -> Path:
    """The four-mounts sample's positions, one mount type (rates `RATES` along x, y, z) in one group."""
    sample = json.loads((CASE / "mounts.json").read_text())
    for m in sample["mounts"]:
        if stiffness:
            m["stiffness"], m["damping"] = RATES, [20.0, 20.0, 60.0]
        if group:
            m["group"] = "rubber-A"
    path = folder / "mounts.json"
    path.write_text(json.dumps(sample))
    return path


def test_simulate_with_mounts_then_the_grouped_mount_model_returns_their_rates(tmp_path: Path) -> None:
    mounts = _identical_mounts(tmp_path)
    modes = tmp_path / "modes.csv"
    out = run("simulate", CASE / "body.json", CASE / "layout.json", "--mounts", mounts, "-o", modes)
    assert out.returncode == 0, out.stderr
    out = run("identify", CASE / "layout.json", modes, "--method", "mounts", "--mounts", mounts, "--json", "-")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    ResultFile.model_validate(data)
    rates = np.array([m["stiffness"] for m in data["mounts"]["mounts"]])
    np.testing.assert_allclose(rates, np.tile(RATES, (4, 1)), rtol=MOUNT_RATES_CSV_REL)  # not the body's own
    assert {m["group"] for m in data["mounts"]["mounts"]} == {"rubber-A"} and data["mounts"]["unknowns"] == 3
    model = data["mount_model"]
    assert model["groups"] == 1 and model["parameters"] == 15 and model["f_dof"] == [72 - 15, 2 * 6 * (8 - 6)]
    assert model["f_test_adequate"] is True and model["p_value"] > model["significance"]
    # `adequate` keeps its first meaning, the AIC comparison (FORMATS.md)
    assert model["free_aic"] is not None and model["adequate"] is (model["aic"] <= model["free_aic"])


def test_simulate_refuses_a_mount_without_stiffness(tmp_path: Path) -> None:
    mounts = _identical_mounts(tmp_path, stiffness=False)
    out = run("simulate", CASE / "body.json", CASE / "layout.json", "--mounts", mounts)
    assert out.returncode == 2 and out.stdout == ""
    assert str(mounts) in out.stderr and "mounts.0" in out.stderr and len(out.stderr.splitlines()) == 1


def test_plan_says_whether_the_mount_layout_determines_every_rate(tmp_path: Path) -> None:
    out = run("plan", CASE / "layout.json", "--mounts", CASE / "mounts.json", "--json", "-")
    assert out.returncode == 0, out.stderr
    split = json.loads(out.stdout)["mount_split"]
    assert split["unique"] and split["unknowns"] == split["rank"] == 12
    many = {"units": {"length": "m", "mass": "kg"},
            "mounts": [{"position": [x, y, -0.1]} for x in (-0.3, 0.0, 0.3) for y in (-0.2, 0.2)]
            + [{"position": [0.0, 0.0, -0.2]}, {"position": [0.1, 0.0, 0.3]}]}  # fmt: skip
    (tmp_path / "many.json").write_text(json.dumps(many))
    out = run("plan", CASE / "layout.json", "--mounts", tmp_path / "many.json")
    assert out.returncode == 0, out.stderr
    assert "not unique: 24 rates" in " ".join(out.stdout.split())
    from rigidid import api

    for m in many["mounts"]:
        m["group"] = "same"
    (tmp_path / "many.json").write_text(json.dumps(many))
    assert api.plan(CASE / "layout.json", mounts=tmp_path / "many.json").mount_split == (
        3,
        3,
        "unique: 3 rates, all determined by the 21 independent entries of the 6x6 matrix",
    )


def test_report_draws_identified_mounts_and_the_torque_roll_axis(tmp_path: Path) -> None:
    html = tmp_path / "report.html"
    out = run("report", CASE / "layout.json", CASE / "modes.csv", "--mounts", CASE / "mounts.json",
              "--torque-axis", "x", "-o", html)  # fmt: skip
    assert out.returncode == 0, out.stderr
    text = html.read_text()
    assert "Mounts (identified)" in text and "Torque roll axis" in text
    for name in ("front-left", "rear-left", "rear-right", "front-right"):
        assert name in text
    assert "29\u2009000 / 5\u2009000 / 73\u2009100" in text  # the sample's front-left rates, identified (N/m)


def test_plan_predicts_the_mount_model_with_a_body_estimate() -> None:
    """With --body and --mounts: the mount model's precision to first order, finer than the free route's."""
    from rigidid import api

    plan = api.plan(CASE / "layout.json", body=CASE / "body.json", mounts=CASE / "mounts.json", draws=6, seed=3)
    assert plan.prediction is not None and plan.mount_prediction is not None
    assert plan.mount_prediction.draws == 0
    mounts_cg = np.linalg.norm(plan.mount_prediction.center_of_gravity_std)
    assert 0.0 < mounts_cg < np.linalg.norm(plan.prediction.center_of_gravity_std)
