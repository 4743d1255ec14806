"""Test planning: layout findings, predicted uncertainty, greedy sensor suggestions."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rigidid.core.noise import NoiseLevels
from rigidid.core.plan import (
    SHORTLIST,
    Finding,
    candidate_grid,
    check_layout,
    predict_uncertainty,
    suggest_sensors,
)
from rigidid.core.simulate import Body, Mount
from rigidid.errors import IdentificationError, InputError
from rigidid.jsonout import layout_report_to_dict, prediction_to_dict, sensor_plan_to_dict

from ..tolerances import ZERO_SPREAD_REL

NOISE = NoiseLevels(frequency=0.001, damping=0.05, shape=0.01)
Z = np.array([0.0, 0.0, 1.0])


def body() -> Body:
    """A 136 lb body (inches) like the paper's, on three identical mounts at one height."""
    inertia = np.array([[2652.0, 40.0, -25.0], [40.0, 3087.0, 15.0], [-25.0, 15.0, 5440.0]])
    mounts = tuple(
        Mount.from_values([x, y, -2.5], [45000.0, 45000.0, 70000.0], [60.0, 60.0, 35.0])
        for x, y in ((7.0, 3.0), (-6.0, 4.5), (-2.0, -6.0))
    )
    return Body(136.0, np.array([0.0, 0.0, -1.4]), inertia, mounts)


def good_layout() -> tuple[np.ndarray, np.ndarray]:
    """Twelve sensors spread over the body, four along each axis."""
    positions = np.array(
        [
            [6.75, 1.5, 0.0], [2.0, 5.7, -0.8], [7.25, 2.0, 0.75], [-8.4, 0.75, -3.25],
            [4.5, -4.0, 0.0], [-9.0, -0.7, -2.5], [-6.0, 4.0, 0.0], [0.0, -4.5, -1.0],
            [8.5, -2.0, -1.5], [-3.0, -4.5, 0.0], [-7.5, 3.0, -1.0], [3.0, 4.5, -2.0],
        ]
    )  # fmt: skip
    axes = np.eye(3)
    directions = np.array([axes[k] for k in (2, 0, 1, 1, 2, 2, 2, 1, 0, 2, 0, 1)])
    return positions, directions


def collinear_layout() -> tuple[np.ndarray, np.ndarray]:
    """Twelve sensors along one bar (the x axis), a few tenths of an inch off it."""
    rng = np.random.default_rng(3)
    x = np.linspace(-9.0, 9.0, 12)
    positions = np.column_stack([x, 0.3 * rng.standard_normal(12), -1.0 + 0.3 * rng.standard_normal(12)])
    directions = np.eye(3)[np.arange(12) % 3]
    return positions, directions


def codes(findings: tuple[Finding, ...], severity: str | None = None) -> list[str]:
    return [f.code for f in findings if severity is None or f.severity == severity]


def test_collinear_layout_ranks_worse_and_is_named() -> None:
    good = check_layout(*good_layout(), unit="in")
    poor = check_layout(*collinear_layout(), unit="in")
    assert good.ok and poor.ok  # both have rank 6
    assert good.worst == "info"
    assert poor.condition > 10.0 * good.condition
    assert poor.severity_key > good.severity_key
    assert sorted([poor, good], key=lambda r: r.severity_key)[0] is good
    line = [f for f in poor.findings if f.code == "collinear"]
    assert line and line[0].severity == "warning"
    assert "lie almost on one line" in line[0].message and "about that line" in line[0].message
    assert "in" in line[0].message
    assert "rotation about the axis along (1, " in poor.weakest_motion or "(-1, " in poor.weakest_motion
    assert "collinear" not in codes(good.findings)


def test_partial_line_warns_when_the_rest_cannot_see_the_rotation() -> None:
    # six sensors on the x axis, two off it that cannot see rotation about x well
    positions = np.vstack([np.column_stack([np.linspace(-9, 9, 6), np.zeros(6), np.zeros(6)]),
                           [[0.0, 1.2, 0.0], [2.0, -1.2, 0.3]]])  # fmt: skip
    directions = np.vstack([np.eye(3)[np.arange(6) % 3], [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]])
    report = check_layout(positions, directions)
    line = [f for f in report.findings if f.code == "collinear"]
    assert line and line[0].severity == "warning"
    assert line[0].sensors == (1, 2, 3, 4, 5, 6)
    assert "move one of them off the line" in line[0].message


def test_predicted_uncertainty_is_worse_for_the_collinear_layout() -> None:
    good = predict_uncertainty(body(), *good_layout(), noise=NOISE, draws=300)
    poor = predict_uncertainty(body(), *collinear_layout(), noise=NOISE, draws=300)
    assert poor.score > 3.0 * good.score
    assert np.all(poor.center_of_gravity_std > good.center_of_gravity_std)
    assert good.figures.failed == 0
    # the figures are those of the full Monte Carlo result
    np.testing.assert_array_equal(good.center_of_gravity_std, good.uncertainty.center_of_gravity.std)
    np.testing.assert_allclose(good.uncertainty.center_of_gravity.estimate, body().center_of_gravity, atol=1e-7)


def test_prediction_without_noise_is_zero_and_seeded() -> None:
    zero = predict_uncertainty(body(), *good_layout(), noise=NoiseLevels(), draws=20)
    assert np.all(zero.center_of_gravity_std <= ZERO_SPREAD_REL * 10.0)
    assert zero.score <= ZERO_SPREAD_REL * 10.0
    a = predict_uncertainty(body(), *good_layout(), noise=NOISE, draws=50, seed=4)
    b = predict_uncertainty(body(), *good_layout(), noise=NOISE, draws=50, seed=4)
    np.testing.assert_array_equal(a.inertia_std, b.inertia_std)
    doc = prediction_to_dict(a)
    json.dumps(doc, allow_nan=False)
    assert np.array(doc["inertia_std"]).shape == (3, 3) and "uncertainty" in doc


def test_rank_and_count_errors() -> None:
    positions, _ = good_layout()
    all_z = check_layout(positions, np.tile(Z, (12, 1)))
    assert not all_z.ok and all_z.rank == 3
    assert "rank" in codes(all_z.findings, "error")
    assert codes(all_z.findings, "error").count("axis-missing") == 2
    rank_msg = next(f.message for f in all_z.findings if f.code == "rank")
    assert "3 independent motions" in rank_msg and "translation" in rank_msg
    few = check_layout(positions[:4], good_layout()[1][:4])
    assert not few.ok and "too-few-sensors" in codes(few.findings, "error")
    with pytest.raises(IdentificationError):
        predict_uncertainty(body(), positions[:5], good_layout()[1][:5], draws=10)


def test_axis_counts_and_oblique_sensors() -> None:
    positions, directions = good_layout()
    report = check_layout(positions[:6], directions[:6])
    assert report.axis_counts == (1, 2, 3, 0)
    assert "minimum-sensors" in codes(report.findings, "info")
    tilted = directions.copy()
    tilted[[1, 8, 10]] = [[0.8, 0.6, 0.0], [0.7, 0.0, 0.714], [0.75, -0.66, 0.0]]  # every x sensor oblique
    report = check_layout(positions, tilted)
    assert report.axis_counts[0] == 0 and report.axis_counts[3] == 3
    missing = [f for f in report.findings if f.code == "axis-missing"]
    assert len(missing) == 1 and missing[0].severity == "warning" and "along x" in missing[0].message


def test_redundant_pairs_and_shared_positions() -> None:
    positions, directions = good_layout()
    pos = np.vstack([positions, positions[0] + [0.05, 0.0, 0.0], positions[4], positions[4]])
    dirs = np.vstack([directions, directions[0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    report = check_layout(pos, dirs, unit="in")
    redundant = [f for f in report.findings if f.code == "redundant-pair"]
    assert [f.sensors for f in redundant] == [(1, 13)]
    assert "same direction" in redundant[0].message
    shared = [f for f in report.findings if f.code == "shared-position"]
    assert [f.sensors for f in shared] == [(1, 13), (5, 14, 15)]
    assert "collinear" not in codes(report.findings)  # clusters are not lines


def test_layout_report_json() -> None:
    doc = layout_report_to_dict(check_layout(*collinear_layout(), unit="in"))
    text = json.dumps(doc, allow_nan=False)
    back = json.loads(text)
    assert back["sensors"] == 12 and back["rank"] == 6 and back["worst"] == "warning"
    assert {"severity", "message", "code", "sensors"} <= set(back["findings"][0])
    assert back["findings"][0]["severity"] == "warning"
    rank_deficient = layout_report_to_dict(check_layout(good_layout()[0], np.tile(Z, (12, 1))))
    assert rank_deficient["condition"] is None and rank_deficient["ok"] is False


def test_bad_layout_inputs() -> None:
    positions, directions = good_layout()
    with pytest.raises(InputError):
        check_layout(positions[:, :2], directions)
    with pytest.raises(InputError):
        check_layout(positions, directions[:5])
    bad = directions.copy()
    bad[3] = 0.0
    with pytest.raises(InputError):
        check_layout(positions, bad)


def test_candidate_grid() -> None:
    positions, _ = good_layout()
    grid = candidate_grid(positions)
    assert grid.shape == (27, 3)
    np.testing.assert_allclose(grid.min(axis=0), positions.min(axis=0))
    np.testing.assert_allclose(grid.max(axis=0), positions.max(axis=0))
    flat = positions.copy()
    flat[:, 2] = 0.0
    assert candidate_grid(flat, per_axis=4).shape == (16, 3)
    wide = candidate_grid(positions, per_axis=2, margin=0.5)
    np.testing.assert_allclose(wide.max(axis=0) - wide.min(axis=0), 2.0 * np.ptp(positions, axis=0))


def test_greedy_addition_reduces_predicted_uncertainty() -> None:
    positions, directions = good_layout()
    start_p, start_d = positions[:6], directions[:6]
    plan = suggest_sensors(body(), start_p, start_d, candidates=positions[6:], add=2, noise=NOISE, draws=100)
    assert len(plan.steps) == 2
    assert plan.candidate_positions.shape == (18, 3)  # six positions x three axes
    first, second = plan.steps
    assert first.figures.score < plan.baseline.score
    assert second.figures.score < first.figures.score
    assert first.candidate != second.candidate
    assert first.ranking[0] == (first.candidate, first.figures.score)
    judged, rest = [s for _, s in first.ranking[:SHORTLIST]], [s for _, s in first.ranking[SHORTLIST:]]
    assert judged == sorted(judged) and rest == sorted(rest)  # the Monte Carlo's short list, then first order
    assert len(first.ranking) == 18 and len(second.ranking) == 17
    # the greedy choice is at least as good as adding the first candidate of the list
    assert first.figures.score <= dict(first.ranking)[0]
    # the prediction of the chosen layout agrees with a direct prediction on the same draws' scale
    direct = predict_uncertainty(
        body(), np.vstack([start_p, first.position]), np.vstack([start_d, first.direction]), noise=NOISE, draws=600
    )
    np.testing.assert_allclose(direct.score, first.figures.score, rtol=0.25)
    doc = sensor_plan_to_dict(plan, ranking=3)
    json.dumps(doc, allow_nan=False)
    assert len(doc["steps"]) == 2 and len(doc["steps"][0]["ranking"]) == 3


def test_a_short_list_by_first_order_chooses_as_the_full_monte_carlo(monkeypatch: pytest.MonkeyPatch) -> None:
    """The first-order ranking keeps the Monte Carlo's choice among its best few: with 4 of 18 candidates
    judged by the Monte Carlo, the same sensors and the same figures (same draws) as with all 18."""
    from rigidid.core import plan as plan_module

    positions, directions = good_layout()
    args = (body(), positions[:6], directions[:6])
    kwargs = {"candidates": positions[6:], "add": 2, "noise": NOISE, "draws": 30}
    monkeypatch.setattr(plan_module, "SHORTLIST", 4)
    short = suggest_sensors(*args, **kwargs)  # type: ignore[arg-type]
    monkeypatch.setattr(plan_module, "SHORTLIST", 100)
    full = suggest_sensors(*args, **kwargs)  # type: ignore[arg-type]
    for a, b in zip(short.steps, full.steps, strict=True):
        assert a.candidate == b.candidate and a.figures.score == b.figures.score
        rough, judged = dict(a.ranking[4:]), dict(b.ranking)
        # the first-order score of the rest is the Monte Carlo's to its error (30 draws; observed within 11 %)
        assert all(abs(rough[c] / judged[c] - 1.0) < 0.3 for c in rough)


def test_greedy_with_directions_and_from_too_few_sensors() -> None:
    positions, directions = good_layout()
    plan = suggest_sensors(
        body(), positions[:4], directions[:4], candidates=positions[4:], candidate_directions=directions[4:],
        add=3, noise=NOISE, draws=60,
    )  # fmt: skip
    assert not np.isfinite(plan.baseline.score)
    chosen = [s.candidate for s in plan.steps]
    assert len(set(chosen)) == 3
    assert np.isfinite(plan.steps[-1].figures.score)  # seven sensors: identifiable
    np.testing.assert_array_equal(plan.steps[0].direction, directions[4 + chosen[0]])
    with pytest.raises(InputError):
        suggest_sensors(body(), positions, directions, candidates=positions[:2], candidate_directions=directions[:2],
                        add=3, draws=10)  # fmt: skip


def test_findings_name_sensors_by_their_ids() -> None:
    pos, dirs = collinear_layout()
    names = [f"acc-{chr(65 + i)}" for i in range(len(pos))]
    report = check_layout(pos, dirs, names=names)
    text = " ".join(f.message for f in report.findings if f.sensors)
    assert "acc-" in text
    assert all(f"sensor {i + 1} " not in text for i in range(len(pos)))


def test_large_layouts_keep_every_warning_of_the_full_line_search(monkeypatch: pytest.MonkeyPatch) -> None:
    # 90 sensors on the x axis and two off it: a line the layout barely sees rotate, among 4005 pairs
    rng = np.random.default_rng(5)
    on = np.column_stack([np.linspace(-9, 9, 90), 0.05 * rng.standard_normal(90), 0.05 * rng.standard_normal(90)])
    positions = np.vstack([on, [[0.0, 1.2, 0.0], [2.0, -1.2, 0.3]]])
    directions = np.vstack([np.eye(3)[np.arange(90) % 3], [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]])
    quick = check_layout(positions, directions)
    monkeypatch.setattr("rigidid.core.layout_check._EVERY_LINE_UP_TO", 10_000)
    full = check_layout(positions, directions)
    warned = [f for f in quick.findings if f.code == "collinear" and f.severity == "warning"]
    assert warned and warned[0].sensors == tuple(range(1, 91))
    assert warned == [f for f in full.findings if f.code == "collinear" and f.severity == "warning"]


def test_prediction_in_windows_of_draws_is_the_prediction_in_one(monkeypatch: pytest.MonkeyPatch) -> None:
    whole = predict_uncertainty(body(), *good_layout(), noise=NOISE, draws=200, seed=4)
    seen: list[tuple[float, float | None]] = []
    monkeypatch.setattr("rigidid.core.uncertainty._VALUES_PER_WINDOW", 12 * 30)  # windows of 30 draws
    parts = predict_uncertainty(
        body(), *good_layout(), noise=NOISE, draws=200, seed=4, progress=lambda _, d, t: seen.append((d, t))
    )
    np.testing.assert_allclose(parts.center_of_gravity_std, whole.center_of_gravity_std, rtol=1e-9)
    np.testing.assert_allclose(parts.principal_moments_std, whole.principal_moments_std, rtol=1e-9)
    assert seen[-1] == (200, 200) and [d for d, _ in seen] == sorted(d for d, _ in seen)
