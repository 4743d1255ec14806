"""Golden regression: `rigidid identify` on every sample reproduces its committed expected.json."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from .conftest import SAMPLES
from .tolerances import GOLDEN_ABS, GOLDEN_REL

CASES = sorted(p.parent for p in SAMPLES.glob("*/expected.json"))


def _compare(actual: Any, expected: Any, where: str) -> None:
    if isinstance(expected, dict):
        assert isinstance(actual, dict) and set(actual) == set(expected), where
        for key in expected:
            if key != "rigidid_version":
                _compare(actual[key], expected[key], f"{where}.{key}")
    elif isinstance(expected, list) and expected and not isinstance(expected[0], (int, float)):
        assert isinstance(actual, list) and len(actual) == len(expected), where
        for i, (a, e) in enumerate(zip(actual, expected, strict=True)):
            _compare(a, e, f"{where}[{i}]")
    elif isinstance(expected, (int, float, list)) and not isinstance(expected, bool):
        np.testing.assert_allclose(actual, expected, rtol=GOLDEN_REL, atol=GOLDEN_ABS, err_msg=where)
    else:
        assert actual == expected, where


def test_every_sample_has_the_files() -> None:
    assert {c.name for c in CASES} >= {"paper-1994", "engine-on-mounts"}
    for case in CASES:
        for name in ("layout.json", "modes.csv", "README.md"):
            assert (case / name).is_file(), case / name


@pytest.mark.parametrize("case", CASES, ids=lambda p: p.name)
def test_sample_matches_expected(case: Path) -> None:
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "rigidid",
            "identify",
            str(case / "layout.json"),
            str(case / "modes.csv"),
            "--json",
            "-",
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert out.returncode == 0, out.stderr
    _compare(json.loads(out.stdout), json.loads((case / "expected.json").read_text()), case.name)


def test_engine_sample_recovers_its_truth() -> None:
    case = SAMPLES / "engine-on-mounts"
    body = json.loads((case / "body.json").read_text())
    expected = json.loads((case / "expected.json").read_text())
    np.testing.assert_allclose(expected["center_of_gravity"], body["center_of_gravity"], rtol=1e-8)
    np.testing.assert_allclose(expected["inertia_tensor"], body["inertia_tensor"], rtol=1e-8, atol=1e-2)
