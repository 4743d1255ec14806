"""identify --records refines the body on the records by default (issue 11); --no-refine keeps the modes' answer."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from .conftest import SAMPLES
from .test_cli import run

FOUR = SAMPLES / "four-mounts"


@pytest.fixture(scope="module")
def records(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    folder = tmp_path_factory.mktemp("records")
    out = run(
        "simulate", FOUR / "body.json", FOUR / "layout.json", "-o", folder / "exact.csv", "--records", folder,
        "--record-noise", "0.01", "--seed", "3", "--sample-rate", "256", "--duration", "4", "--pretrigger", "0.2",
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    return sorted(folder.glob("record-*.csv"))


def test_refined_result_carries_its_cramer_rao_intervals(records: list[Path]) -> None:
    out = run("identify", FOUR / "layout.json", "--records", *records, "--json", "-")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    crb = data["uncertainty_records_crb"]
    assert crb["noise_from"] == "pretrigger"
    assert 0.5 < crb["normalised_cost"] < 2.0
    assert crb["converged"] is True and 0 < crb["evaluations"] < 240
    body = json.loads((FOUR / "body.json").read_text())
    assert crb["center_of_gravity"]["estimate"] == data["center_of_gravity"]
    std = np.array(crb["center_of_gravity"]["std"])
    assert np.all(std > 0)
    # the truth lies within 5 standard errors of every CG coordinate
    assert np.all(np.abs(np.subtract(data["center_of_gravity"], body["center_of_gravity"])) < 5 * std)


def test_no_refine_keeps_the_answer_from_the_modes(records: list[Path]) -> None:
    out = run("identify", FOUR / "layout.json", "--records", *records, "--no-refine", "--json", "-")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert "uncertainty_records_crb" not in data


def test_without_the_refit_records_are_streamed_not_loaded_whole(
    records: list[Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    """identify --records --no-refine estimates through the streamed reader (issue 14): the same answer."""
    from typer.testing import CliRunner

    from rigidid import api
    from rigidid.cli import app

    layout = api.load_layout(FOUR / "layout.json")
    loaded = api.load_records(records, layout)
    modes, _ = api.estimate_modes(layout, loaded)
    expected = api.identify(layout, modes)

    def refuse(*_: object, **__: object) -> None:
        raise AssertionError("records loaded whole")

    monkeypatch.setattr(api, "load_records", refuse)
    out = CliRunner().invoke(app, ["identify", str(FOUR / "layout.json"), "--records", *map(str, records),
                                   "--no-refine", "--json", "-"])  # fmt: skip
    assert out.exit_code == 0, out.output
    data = json.loads(out.stdout)
    cg = expected.identification.center_of_gravity
    np.testing.assert_allclose(data["center_of_gravity"], cg, rtol=1e-9, atol=1e-12)


@pytest.fixture(scope="module")
def long_records(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """Two impacts sampled at 10 kHz for 8 s (80 000 rows each): long enough to be pre-decimated while read."""
    from rigidid.api import body_from_file
    from rigidid.core.timedomain import impulse_records
    from rigidid.io.files import layout_arrays, load_body, load_layout

    folder = tmp_path_factory.mktemp("long")
    body = body_from_file(load_body(FOUR / "body.json"))
    _, pos, dirs = layout_arrays(load_layout(FOUR / "layout.json"))
    impacts = [((0.3, 0.2, 0.15), (0.3, -0.5, -1.0)), ((-0.3, -0.1, 0.0), (1.0, 0.6, 0.2))]
    recs = impulse_records(body, pos, dirs, impacts, sample_rate=10_000.0, duration=8.0, pretrigger=0.1,
                           noise=0.01, seed=8)  # fmt: skip
    paths = []
    for k, rec in enumerate(recs):
        path = folder / f"hit{k + 1}.npy"
        np.save(path, np.column_stack([np.arange(rec.shape[0]) / 10_000.0, rec]))
        paths.append(path)
    return paths


def test_the_refit_reads_long_records_pre_decimated_with_the_same_answer(
    long_records: list[Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    """identify --records (refit) holds the records pre-decimated, not raw (issue 14): the answer within a tenth
    of its standard error of the raw records' refit, the impacts in the files' rows."""
    from typer.testing import CliRunner

    from rigidid import api
    from rigidid.cli import app
    from rigidid.core.timedomain import refine

    monkeypatch.setattr(refine, "MAX_ROWS", 40_000)  # a smaller fit, for the suite's time
    layout = api.load_layout(FOUR / "layout.json")
    raw = api.load_records(long_records, layout)
    modes, estimate = api.estimate_rigid_modes(layout, raw)
    whole = api.with_refinement(api.identify(layout, modes), raw, estimate)
    assert whole.record_bound is not None

    read: list[int] = []
    real = api.load_records_decimated

    def spy(*args: object, **kwargs: object) -> api.DecimatedRecords:
        got = real(*args, **kwargs)  # type: ignore[arg-type]
        read.append(got.factor)
        return got

    monkeypatch.setattr(api, "load_records_decimated", spy)
    out = CliRunner().invoke(app, ["identify", str(FOUR / "layout.json"), "--records", *map(str, long_records),
                                   "--json", "-"])  # fmt: skip
    assert out.exit_code == 0, out.output
    assert read and read[0] > 1  # pre-decimated while read
    data = json.loads(out.stdout)
    crb = data["uncertainty_records_crb"]
    # the pre-trigger noise level right after two filters: without the guard before the onset, 0.92 here
    assert 0.95 < crb["normalised_cost"] < 1.1
    std = np.array(crb["center_of_gravity"]["std"])
    np.testing.assert_allclose(std, whole.record_bound.center_of_gravity.std, rtol=0.15)
    assert np.all(np.abs(np.subtract(data["center_of_gravity"], whole.identification.center_of_gravity)) < 0.5 * std)
    estimation = data["modal_estimation"]
    assert estimation["decimation"] % read[0] == 0
    for impact in estimation["impacts"]:  # file rows: the impacts come 0.1 s (1000 rows) into each record
        assert 990 <= impact["onset"] <= 1010 and impact["start"] > impact["peak"] >= impact["onset"]
