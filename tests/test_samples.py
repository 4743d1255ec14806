"""The bundled samples: what a result must be (properties, truth), then golden regression.

The properties are checked on the result itself, whatever expected.json says: K and C
symmetric, the inertia positive definite, principal axes orthonormal, M^-1 K of the
result reproducing the measured poles, and the truth of the simulated samples. The
golden comparison (expected.json, written by rigidid itself) is a regression test only:
it says that a change moved a result, not that the result is right.
"""

from __future__ import annotations

import json
import re
from collections import defaultdict
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from . import cli_runner
from .conftest import SAMPLES
from .tolerances import CSV_DIGITS_REL, GOLDEN_REL, STANDARD_ERROR_REL

CASES = sorted(p.parent for p in SAMPLES.glob("*/expected.json") if (p.parent / "modes.csv").is_file())
"""Samples identified from modes (samples/frf-uff, FRFs, has its own test: tests/test_frf_lab_file.py)."""


def identify_json(case: Path) -> dict[str, Any]:
    out = cli_runner.run("identify", case / "layout.json", case / "modes.csv", "--json", "-")
    assert out.returncode == 0, out.stderr
    result: dict[str, Any] = json.loads(out.stdout)
    return result


@pytest.fixture(scope="module", params=CASES, ids=lambda p: p.name)
def sample(request: pytest.FixtureRequest) -> tuple[Path, dict[str, Any]]:
    case: Path = request.param
    return case, identify_json(case)


def test_every_sample_has_the_files() -> None:
    assert {c.name for c in CASES} >= {"paper-1994", "engine-on-mounts", "four-mounts"}
    for case in CASES:
        for name in ("layout.json", "modes.csv", "README.md"):
            assert (case / name).is_file(), case / name


# --- properties, asserted directly ----------------------------------------------------------


def test_stiffness_and_damping_are_symmetric(sample: tuple[Path, dict[str, Any]]) -> None:
    """Symmetric by construction (sym(D Q_g)), noisy data included (the paper's are noisy)."""
    _, data = sample
    for key in ("stiffness_per_mass", "damping_per_mass"):
        a = np.asarray(data[key])
        np.testing.assert_array_equal(a, a.T, err_msg=key)


def test_inertia_is_positive_definite_with_orthonormal_axes(sample: tuple[Path, dict[str, Any]]) -> None:
    _, data = sample
    j = np.asarray(data["inertia_per_mass"])
    np.testing.assert_array_equal(j, j.T)
    moments = np.linalg.eigvalsh(j)
    assert moments[0] > 0.0
    assert moments[2] <= moments[0] + moments[1]
    axes = np.asarray(data["principal_axes"])
    np.testing.assert_allclose(axes.T @ axes, np.eye(3), atol=1e-12)
    assert np.linalg.det(axes) > 0.0
    np.testing.assert_allclose(axes.T @ j @ axes, np.diag(data["principal_moments_per_mass"]), atol=1e-12 * moments[2])


def test_identified_model_reproduces_the_measured_modes(sample: tuple[Path, dict[str, Any]]) -> None:
    """The modes of diag(I, J/m)^-1 K/m, C/m are the measured ones (to the data's consistency)."""
    _, data = sample
    structure = data["diagnostics"]["structure_residual"]
    for mode in data["diagnostics"]["modes"]:
        assert mode["model_frequency_hz"] == pytest.approx(mode["frequency_hz"], rel=max(10 * structure, 1e-9))
        assert mode["model_mac"] > 1.0 - max(10 * structure, 1e-9)


@pytest.mark.parametrize("name", ["engine-on-mounts", "four-mounts"])
def test_simulated_samples_recover_their_truth(name: str) -> None:
    """These samples' modes were simulated from body.json and written with 10 digits."""
    case = SAMPLES / name
    body = json.loads((case / "body.json").read_text())
    data = identify_json(case)
    span = max(np.linalg.norm(np.subtract(a["position"], b["position"]))
               for a in body["mounts"] for b in body["mounts"])  # fmt: skip
    assert np.linalg.norm(np.subtract(data["center_of_gravity"], body["center_of_gravity"])) < CSV_DIGITS_REL * span
    inertia = np.asarray(body["inertia_tensor"])
    np.testing.assert_allclose(data["inertia_tensor"], inertia, rtol=0, atol=CSV_DIGITS_REL * np.abs(inertia).max())


# --- golden regression --------------------------------------------------------------------


def _numbers(x: Any, path: str = "") -> Iterator[tuple[str, float]]:
    if isinstance(x, dict):
        for key, value in x.items():
            if key != "rigidid_version":
                yield from _numbers(value, f"{path}.{key}")
    elif isinstance(x, list):
        for i, value in enumerate(x):
            yield from _numbers(value, f"{path}[{i}]")
    elif isinstance(x, int | float) and not isinstance(x, bool):
        yield path, float(x)


def _same_structure(actual: Any, expected: Any, where: str = "") -> None:
    if isinstance(expected, dict):
        assert isinstance(actual, dict) and set(actual) == set(expected), where
        for key in expected:
            if key != "rigidid_version":
                _same_structure(actual[key], expected[key], f"{where}.{key}")
    elif isinstance(expected, list):
        assert isinstance(actual, list) and len(actual) == len(expected), where
        for i, (a, e) in enumerate(zip(actual, expected, strict=True)):
            _same_structure(a, e, f"{where}[{i}]")
    elif not isinstance(expected, int | float) or isinstance(expected, bool):
        assert actual == expected, where


def test_regression_against_expected_json(sample: tuple[Path, dict[str, Any]]) -> None:
    """Every number within GOLDEN_REL of the largest magnitude of its array (regression only)."""
    case, data = sample
    expected = json.loads((case / "expected.json").read_text())
    _same_structure(data, expected)
    actual = dict(_numbers(data))
    groups: dict[str, list[str]] = defaultdict(list)
    for key, _ in _numbers(expected):
        groups[re.sub(r"\[\d+\]", "[]", key)].append(key)
    golden = dict(_numbers(expected))
    for group, keys in groups.items():
        scale = max(max(abs(golden[k]) for k in keys), 1.0 if group.startswith(".diagnostics") else 0.0) or 1.0
        tolerance = GOLDEN_REL
        if group.startswith(".standard_errors."):
            # statistics: compared to the figure they qualify; on exact samples they come from
            # rounding-level noise (the measured shape noise) and only their size is stable
            figure = groups.get(group.replace(".standard_errors", "", 1), [])
            floor = 1e-6 * max(abs(golden[k]) for k in figure) if figure else 1e-4
            scale = max(max(abs(golden[k]) for k in keys), floor)
            tolerance = STANDARD_ERROR_REL
        worst = max(abs(actual[k] - golden[k]) for k in keys)
        assert worst <= tolerance * scale, f"{case.name}{group}: {worst / scale:.2e} of its scale"
