"""An elastic mode among the records' modes: seven are estimated and identify uses the six rigid ones (issue 11)."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from rigidid import api
from rigidid.core.selection import elastic_suspect, rigid_fit_residuals, separate_elastic
from rigidid.core.timedomain import impulse_records
from rigidid.errors import ElasticModeWarning, IdentificationError
from rigidid.io.files import layout_arrays, load_body

from .cli_runner import run
from .conftest import SAMPLES
from .tolerances import ELASTIC_MODE_CG_SPAN

LAYOUT = SAMPLES / "four-mounts" / "layout.json"
RATE = 512.0
IMPACTS = [((0.3, 0.2, 0.15), (0.3, -0.5, -1.0)), ((-0.3, -0.1, 0.0), (1.0, 0.6, 0.2))]


def _records(elastic_hz: float | None, seed: int = 0) -> list[np.ndarray]:
    """Four-mounts records, 8 s at 512 Hz, 1 % noise; plus a 1 %-damped mode of random shape at `elastic_hz`."""
    body = api.body_from_file(load_body(SAMPLES / "four-mounts" / "body.json"))
    _, pos, dirs = layout_arrays(api.load_layout(LAYOUT))
    recs = impulse_records(body, pos, dirs, IMPACTS, sample_rate=RATE, duration=8.0, pretrigger=0.1, noise=0.01,
                           seed=seed)  # fmt: skip
    if elastic_hz is None:
        return recs
    rng = np.random.default_rng(100 + seed)
    shape = rng.standard_normal(pos.shape[0])
    n0 = round(0.1 * RATE)
    out = []
    for r in recs:
        t = np.arange(r.shape[0] - n0) / RATE
        w = 2 * np.pi * elastic_hz
        wave = np.exp(-0.01 * w * t) * np.sin(w * t + rng.uniform(0, 2 * np.pi))
        extra = np.zeros_like(r)
        extra[n0:] = np.outer(wave, shape) * (0.2 * np.sqrt(np.mean(r**2)) / np.sqrt(np.mean(wave**2)))
        out.append(r + extra)
    return out


def _cg_error(result: api.IdentifyResult) -> float:
    body = load_body(SAMPLES / "four-mounts" / "body.json")
    _, pos, _ = layout_arrays(api.load_layout(LAYOUT))
    span = float(np.max(np.ptp(pos, axis=0)))
    return float(np.linalg.norm(result.identification.center_of_gravity - np.asarray(body.center_of_gravity)) / span)


def test_suspect_and_separation_on_synthetic_residuals() -> None:
    assert elastic_suspect([1e-3, 2e-3, 0.3, 1e-3, 2e-3, 1e-3]) == 2
    assert elastic_suspect([0.1, 0.12, 0.3, 0.1, 0.11, 0.1]) is None  # every mode noisy alike: nothing stands out
    assert elastic_suspect([1e-3, 2e-3, 0.04, 1e-3, 2e-3, 1e-3]) is None  # below the residual a rigid mode can have
    rng = np.random.default_rng(0)
    t = rng.standard_normal((8, 6))
    rigid = t @ (rng.standard_normal((6, 6)) + 1j * rng.standard_normal((6, 6)))
    elastic = rng.standard_normal((8, 1)) + 0j
    shapes = np.hstack([rigid[:, :3], elastic, rigid[:, 3:]])
    np.testing.assert_array_equal(separate_elastic(t, shapes), [0, 1, 2, 4, 5, 6])
    assert rigid_fit_residuals(t, shapes)[3] > 0.05
    # seven rigid shapes: the one left out fits rigid motion too, so there is no clear separation
    assert separate_elastic(t, np.hstack([rigid, rigid[:, :1] * 1.1])) is None


@pytest.mark.parametrize("elastic_hz", [18.0, 34.0])  # inside the rigid modes' band, and just above it
def test_an_elastic_mode_is_left_out_by_estimating_seven(elastic_hz: float) -> None:
    layout = api.load_layout(LAYOUT)
    records = [(r, 1.0 / RATE) for r in _records(elastic_hz)]
    with pytest.warns(ElasticModeWarning, match=rf"leaving out the mode at {elastic_hz:.0f}(\.\d+)? Hz"):
        table, _ = api.estimate_rigid_modes(layout, records)
    assert len(table.labels) == 7
    result = api.identify(layout, table, mass=40.0)
    assert result.selection == "automatic"
    elastic_label = table.labels[int(np.argmin(np.abs(table.frequency_hz - elastic_hz)))]
    assert elastic_label not in result.modes_used
    assert _cg_error(result) < ELASTIC_MODE_CG_SPAN
    # what the six modes alone give: the elastic mode is taken for a rigid one; no body, or one far off
    six, _ = api.estimate_modes(layout, records)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            wrong = api.identify(layout, six, mass=40.0)
        except IdentificationError:
            return
    assert _cg_error(wrong) > 100 * ELASTIC_MODE_CG_SPAN


def test_rigid_records_keep_six_modes_and_warn_of_nothing() -> None:
    layout = api.load_layout(LAYOUT)
    table, _ = api.estimate_rigid_modes(layout, [(r, 1.0 / RATE) for r in _records(None)])
    assert len(table.labels) == 6


def test_cli_identify_and_modes_leave_the_elastic_mode_out(tmp_path: Path) -> None:
    ids = [s.id for s in api.load_layout(LAYOUT).sensors]
    paths = []
    for k, r in enumerate(_records(18.0, seed=1)):
        path = tmp_path / f"hit{k + 1}.csv"
        np.savetxt(path, np.column_stack([np.arange(r.shape[0]) / RATE, r]), delimiter=",",
                   header="time," + ",".join(ids), comments="")  # fmt: skip
        paths.append(path)
    out = run("identify", LAYOUT, *paths, "--records", "--mass", "40", "--json", tmp_path / "r.json")
    assert out.returncode == 0, out.stderr
    assert "elastic mode" in out.stderr and "leaving out the mode at 18 Hz" in out.stderr
    result = json.loads((tmp_path / "r.json").read_text())
    assert len(result["modes_used"]) == 6
    assert any("leaving out the mode at 18 Hz" in w for w in result["diagnostics"]["warnings"])
    assert out.stderr.count("leaving out the mode") == 1
    # the elastic mode is subtracted from the records before the refit, which is then accepted
    assert "RefinementWarning" not in out.stderr and "kept the answer from the modes" not in out.stderr
    assert result["uncertainty_records_crb"]["normalised_cost"] < 1.3
    modes = run("modes", LAYOUT, *paths, "-o", tmp_path / "modes.csv")
    assert modes.returncode == 0, modes.stderr
    assert "wrote 7 modes x 8 sensors" in modes.stderr
    again = run("identify", LAYOUT, tmp_path / "modes.csv", "--mass", "40", "--json", "-")
    assert again.returncode == 0, again.stderr
    assert json.loads(again.stdout)["modes_used"] == result["modes_used"]
