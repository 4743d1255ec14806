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
