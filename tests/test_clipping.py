"""Clipped channels named and left out of the fit (issue 23; issue 22's clipped-record case)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rigidid import api
from rigidid.core.timedomain.clipping import PeakCount, clipped_channels
from rigidid.errors import ClippedChannelWarning

from .cli_runner import run
from .conftest import SAMPLES

FOUR = SAMPLES / "four-mounts"


def _decay(n: int = 4096, rate: float = 512.0, seed: int = 0) -> np.ndarray:
    """Three decaying modes (8-26 Hz, 20-60 samples a period) with 1 % noise: no flat top."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / rate
    y = sum(np.exp(-2 * np.pi * f * 0.03 * t) * np.sin(2 * np.pi * f * t + f) for f in (8.0, 14.5, 26.1))
    return np.asarray(y + 0.01 * rng.standard_normal(n))


@pytest.mark.parametrize("seed", range(5))
def test_a_noisy_decay_is_not_clipped_and_any_clip_level_is(seed: int) -> None:
    y = _decay(seed=seed)
    peak = np.abs(y).max()
    columns = [y] + [np.clip(y, -f * peak, f * peak) for f in (0.9, 0.8, 0.3)]
    assert clipped_channels([np.column_stack(columns)]).tolist() == [False, True, True, True]


def test_peak_count_in_blocks_is_the_whole_records() -> None:
    y = _decay()
    x = np.column_stack([y, np.clip(y, -0.5, 0.5), np.zeros_like(y)])
    count = PeakCount(3)
    for start in range(0, x.shape[0], 333):
        count.add(x[start : start + 333])
    assert count.clipped().tolist() == clipped_channels([x]).tolist() == [False, True, False]
    np.testing.assert_array_equal(count.peak, np.abs(x).max(axis=0))


def test_a_flat_top_during_the_pulse_only_leaves_the_decay_unclipped() -> None:
    """Issue 23: the acceleration peaks during the hammer's pulse; an overload there (chain_matrix's clip80 cell:
    every flat top in the 3 ms pulse) does not clip the free decay after it, which the fit reads."""
    y = _decay()
    start = 8
    pulse = np.zeros_like(y)
    pulse[start - 6 : start - 2] = 4.0 * np.abs(y).max()  # the pulse's peak, clipped at 80 % of it
    x = y + pulse
    limit, lower = 0.8 * np.abs(x).max(), 0.3 * np.abs(y).max()  # the second: the decay's peaks clipped too
    columns = np.column_stack([np.clip(x, -limit, limit), np.clip(x, -lower, lower), x])
    assert clipped_channels([columns]).tolist() == [True, True, False]
    assert clipped_channels([columns], [start]).tolist() == [False, True, False]
    count = PeakCount(3)
    for first in range(0, columns.shape[0], 37):
        count.add(columns[first : first + 37])
    assert count.clipped(start).tolist() == [False, True, False]
    assert count.last[0] == start - 3


@pytest.fixture(scope="module")
def clipped(tmp_path_factory: pytest.TempPathFactory) -> dict[str, list[Path]]:
    folder = tmp_path_factory.mktemp("clipped")
    out = run(
        "simulate", FOUR / "body.json", FOUR / "layout.json", "-o", folder / "exact.csv", "--records", folder,
        "--record-noise", "0.01", "--seed", "3", "--sample-rate", "512", "--duration", "6", "--pretrigger", "0.2",
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    clean = sorted(folder.glob("record-*.csv"))
    sets: dict[str, list[Path]] = {"clean": clean}
    for level in (0.8, 0.3):
        sets[str(level)] = []
        for path in clean:
            header = path.read_text().splitlines()[0]
            values = np.loadtxt(path, delimiter=",", skiprows=1)
            limit = level * np.abs(values[:, 3]).max()  # column 3: sensor '3'
            values[:, 3] = np.clip(values[:, 3], -limit, limit)
            target = folder / f"clip{level}-{path.name}"
            np.savetxt(target, values, delimiter=",", header=header, comments="", fmt="%.10g")
            sets[str(level)].append(target)
    return sets


@pytest.mark.parametrize("level", ["0.8", "0.3"])
def test_a_clipped_channel_is_named_left_out_and_the_intervals_hold_the_truth(
    clipped: dict[str, list[Path]], level: str
) -> None:
    out = run("identify", FOUR / "layout.json", "--records", *clipped[level], "--json", "-")
    assert out.returncode == 0, out.stderr
    assert "clipped channels (flat tops at their peak) left out of the fit: '3' (record 1, 2)" in out.stderr
    data = json.loads(out.stdout)
    assert any("'3'" in note for note in data["diagnostics"]["warnings"])
    body = json.loads((FOUR / "body.json").read_text())
    crb = data["uncertainty_records_crb"]  # the refit is accepted on the seven channels left
    cg_std = np.array(crb["center_of_gravity"]["std"])
    j_std = np.diag(np.array(crb["inertia_tensor"]["std"]))
    # observed: |error| below 1.1 standard errors on seed 3; 4 allowed
    assert np.all(np.abs(np.subtract(data["center_of_gravity"], body["center_of_gravity"])) < 4 * cg_std)
    j_err = np.diag(np.subtract(data["inertia_tensor"], body["inertia_tensor"]))
    assert np.all(np.abs(j_err) < 4 * j_std)


def test_estimate_from_arrays_leaves_the_clipped_channel_out(clipped: dict[str, list[Path]]) -> None:
    lay = api.load_layout(FOUR / "layout.json")
    arrays = api.load_records(clipped["0.8"], lay)
    with pytest.warns(ClippedChannelWarning, match="left out of the fit: '3'"):
        table, estimate = api.estimate_modes(lay, arrays)
    assert table.sensor_ids == ("1", "2", "4", "5", "6", "7", "8")
    assert estimate.channels == (0, 1, 3, 4, 5, 6, 7) and estimate.shapes.shape[0] == 7
    assert [s.id for s in api.fitted_layout(lay, table).sensors] == list(table.sensor_ids)


def test_the_records_intervals_carry_the_sensor_budget_stated_in_the_layout(
    clipped: dict[str, list[Path]], tmp_path: Path
) -> None:
    """Issue 23: the sensors' tolerances (type B) in every refit std; zero tolerances leave the noise's."""
    layout = json.loads((FOUR / "layout.json").read_text())
    stated = tmp_path / "layout.json"
    layout["tolerances"] = {"sensitivity": 0.0, "orientation_deg": 0.0, "transverse": 0.0, "position": 0.0}
    stated.write_text(json.dumps(layout))
    zero = json.loads(run("identify", stated, "--records", *clipped["clean"], "--json", "-").stdout)
    crb0 = zero["uncertainty_records_crb"]
    np.testing.assert_array_equal(crb0["center_of_gravity"]["std"], crb0["sensor_budget"]["noise"]["center_of_gravity"])
    layout["tolerances"] = {"sensitivity": 0.02, "orientation_deg": 1.0, "transverse": 0.03, "position": 0.002}
    stated.write_text(json.dumps(layout))
    out = run("identify", stated, "--records", *clipped["clean"], "--json", "-")
    assert out.returncode == 0, out.stderr
    crb = json.loads(out.stdout)["uncertainty_records_crb"]
    assert crb["tolerances"] == layout["tolerances"]
    budget = crb["sensor_budget"]
    assert list(budget) == ["noise", "sensitivity", "orientation", "transverse", "position"]
    rss = np.sqrt(sum(np.square(budget[s]["center_of_gravity"]) for s in budget))
    np.testing.assert_allclose(crb["center_of_gravity"]["std"], rss, rtol=1e-9)
    assert np.all(np.array(budget["orientation"]["center_of_gravity"]) > 0)
    # the noise part is the bound without tolerances; the estimate does not move
    np.testing.assert_allclose(budget["noise"]["center_of_gravity"], crb0["center_of_gravity"]["std"], rtol=1e-9)
    assert crb["center_of_gravity"]["estimate"] == crb0["center_of_gravity"]["estimate"]
    # plan predicts the type-B parts before the test by the modal kernel's propagation at the body's exact
    # modes. The refit reports its own linearisation, a different estimator's (calibrated: coverage 0.95 and
    # 0.92 in benchmarks/chain_matrix.py's orient and transverse cells, where the kernel's gave 0.97-0.98,
    # RMS z 0.81): here 0.25-1.28 of plan's (orientation narrowest, four-mounts' J is weakly observed by the
    # kernel); the kernel's at the identified modes, which was reported before, was within 1.11 of plan's
    plan = api.plan(stated, body=FOUR / "body.json", draws=20, sample_rate=512.0, duration=6.0)
    planned = plan.sensor_budget
    assert planned is not None and list(planned) == [*budget, "combined"]
    ratios = np.concatenate([np.ravel(np.divide(budget[source][key], planned[source][key]))
                             for source in ("sensitivity", "orientation", "transverse", "position")
                             for key in ("center_of_gravity", "inertia_tensor")])  # fmt: skip
    assert np.max(ratios) < 1.6  # plan does not under-predict much (observed 1.28)
    assert np.min(ratios) < 0.6  # the refit's own, not the kernel's (observed 0.25; the kernel's: 0.89)
    # the records route's prediction for the same test (512 Hz, 6 s, the two default impacts): the refit's own map
    # at the body estimate, on plan's own simulated records, is what identify reports at the fitted body
    records = plan.records_budget
    assert records is not None and list(records) == [*budget, "sensors", "combined"]
    ratios = np.concatenate([np.ravel(np.divide(budget[source][key], records[source][key]))
                             for source in ("sensitivity", "orientation", "transverse", "position")
                             for key in ("center_of_gravity", "inertia_tensor")])  # fmt: skip
    np.testing.assert_allclose(ratios, 1.0, atol=0.15)  # observed 0.947-1.041
    # the noise's part too: 1 % of each channel's RMS, simulate's convention, is plan's default
    keys = ("center_of_gravity", "inertia_tensor")
    noise = [np.ravel(np.divide(budget["noise"][key], records["noise"][key])) for key in keys]
    np.testing.assert_allclose(np.concatenate(noise), 1.0, atol=0.12)  # observed 1.013-1.037
