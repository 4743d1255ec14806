"""DC offset and drift, double hits: the records route names them and still holds the truth (issue 23)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rigidid.core.timedomain.preprocess import find_impact, last_hit
from rigidid.core.timedomain.trend import fit_trend, remove_trend, trend_matters

from .cli_runner import run
from .conftest import SAMPLES

FOUR = SAMPLES / "four-mounts"
RATE = 512.0


def _decay(n: int = 4096, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    t = np.arange(n) / RATE
    x = np.column_stack([np.exp(-2.0 * t) * np.sin(2 * np.pi * f * t + 0.3 * k) for k, f in enumerate((9.0, 14.0))])
    x[: n // 20] = 0.0
    return x + 0.01 * rng.standard_normal(x.shape)


def test_a_line_is_fitted_exactly_and_matters_only_when_it_explains_the_tail() -> None:
    x = _decay()
    line = np.array([0.05, -0.08]) + np.arange(x.shape[0])[:, None] * np.array([1e-5, -2e-5])
    trend = fit_trend(x + line)
    clean = fit_trend(x)
    np.testing.assert_allclose(trend.offset - clean.offset, [0.05, -0.08], atol=1e-12)
    np.testing.assert_allclose(trend.slope - clean.slope, [1e-5, -2e-5], atol=1e-15)
    assert trend_matters(x + line, remove_trend(x + line, trend), trend).all()
    assert not trend_matters(x, remove_trend(x, clean), clean).any()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_one_hit_is_one_and_a_second_is_found_where_it_is(seed: int) -> None:
    x = _decay(seed=seed)
    t = np.arange(x.shape[0]) / RATE
    onset = x.shape[0] // 20
    pulse = np.where((t >= t[onset]) & (t < t[onset] + 0.006), np.sin(np.pi * (t - t[onset]) / 0.006), 0.0)
    one = x + 5.0 * pulse[:, None] * np.array([1.0, -0.6])
    assert find_impact(one, 1 / RATE).hits == 1
    assert last_hit(one[onset - 16 :], 18, 3) is None
    second = onset + 40
    two = one + 2.0 * np.roll(pulse, 40)[:, None] * np.array([1.0, -0.6])
    impact = find_impact(two, 1 / RATE)
    assert impact.hits == 2 and second < impact.start < second + 6


@pytest.fixture(scope="module")
def chain(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """four-mounts' records (1 % noise) with a DC offset, a drift and a bounce 60-70 ms after the hit."""
    folder = tmp_path_factory.mktemp("chain")
    out = run(
        "simulate", FOUR / "body.json", FOUR / "layout.json", "-o", folder / "exact.csv", "--records", folder,
        "--record-noise", "0.01", "--seed", "5", "--sample-rate", "512", "--duration", "6", "--pretrigger", "0.2",
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    paths = []
    for k, path in enumerate(sorted(folder.glob("record-*.csv"))):
        header = path.read_text().splitlines()[0]
        values = np.loadtxt(path, delimiter=",", skiprows=1)
        t, y = values[:, 0], values[:, 1:]
        shift = 31 + 5 * k  # the bounce at 40 % (linear: the record shifted and scaled)
        data = y.copy()
        data[shift:] += 0.4 * y[:-shift]
        data += np.abs(y).max(axis=0) * (0.05 + 0.02 * (t - t[0])[:, None] / (t[-1] - t[0]))
        target = folder / f"chain-{path.name}"
        np.savetxt(target, np.column_stack([t, data]), delimiter=",", header=header, comments="", fmt="%.10g")
        paths.append(target)
    return paths


def test_offset_drift_and_a_double_hit_are_named_and_the_refit_holds_the_truth(chain: list[Path]) -> None:
    out = run("identify", FOUR / "layout.json", "--records", *chain, "--json", "-")
    assert out.returncode == 0, out.stderr
    assert "DC offset or drift" in out.stderr and "double hit" in out.stderr
    data = json.loads(out.stdout)
    body = json.loads((FOUR / "body.json").read_text())
    crb = data["uncertainty_records_crb"]  # the refit is accepted
    cg_std = np.array(crb["center_of_gravity"]["std"])
    j_std = np.diag(np.array(crb["inertia_tensor"]["std"]))
    cg_err = np.abs(np.subtract(data["center_of_gravity"], body["center_of_gravity"]))
    j_err = np.abs(np.diag(np.subtract(data["inertia_tensor"], body["inertia_tensor"])))
    assert np.all(cg_err < 4 * cg_std) and np.all(j_err < 4 * j_std)
