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
