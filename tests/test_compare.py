"""Issue 25: ``rigidid compare RESULT REFERENCE``: figure by figure, exit 1 on a regression, JUnit XML."""

from __future__ import annotations

import copy
import json
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rigidid import api
from rigidid.api import compare as compare_files
from rigidid.compare import compare_results, parse_tolerances
from rigidid.compare_render import comparison_junit
from rigidid.errors import InputError
from rigidid.jsonout import result_to_dict

from .cli_runner import run
from .conftest import SAMPLES

ENGINE = SAMPLES / "engine-on-mounts"
FOUR = SAMPLES / "four-mounts"


@pytest.fixture(scope="module")
def engine() -> dict[str, Any]:
    return json.loads((ENGINE / "expected.json").read_text())


def _figures(comparison: Any) -> dict[str, Any]:
    return {f.name: f for f in comparison.figures}


def test_a_result_matches_itself_and_every_figure_is_checked(engine: dict[str, Any]) -> None:
    comparison = compare_results(engine, engine, rtol=0.0)
    assert comparison.passed
    names = set(_figures(comparison))
    assert names == {
        "mass",
        "center_of_gravity",
        "inertia_tensor",
        "principal_moments",
        "stiffness_force",
        "damping_force",
    }
    figures = _figures(comparison)
    assert len(figures["stiffness_force"].entries) == 36 and len(figures["inertia_tensor"].entries) == 9


def test_another_mass_moves_everything_but_the_cg(engine: dict[str, Any]) -> None:
    """K, C and J scale with the mass (eq. 18 gives them per mass); the CG does not depend on it."""
    heavier = result_to_dict(api.identify(ENGINE / "layout.json", ENGINE / "modes.csv", mass=143.0))
    ratio = 143.0 / 142.0 - 1.0  # 0.70 %
    tight = compare_results(heavier, engine, rtol=ratio / 2)
    failed = {f.name for f in tight.regressions}
    assert failed == {"mass", "inertia_tensor", "principal_moments", "stiffness_force", "damping_force"}
    for figure in tight.figures:
        for e in figure.entries:
            assert e.difference is not None
            if figure.name == "center_of_gravity":
                assert abs(e.difference) < 1e-9
            elif abs(e.reference or 0) > 1e-6 * e.tolerance / (ratio / 2):  # entries above round-off
                assert e.difference == pytest.approx(ratio * e.reference, rel=1e-6, abs=1e-9 * e.tolerance / ratio)
    assert compare_results(heavier, engine, rtol=ratio * 1.01).passed


def test_tolerances_do_not_depend_on_origin_or_units(engine: dict[str, Any]) -> None:
    """The CG is judged against the radius of gyration, not against its distance from the origin."""
    moved = copy.deepcopy(engine)
    shifted = copy.deepcopy(engine)
    for d in (moved, shifted):
        d["center_of_gravity"] = [v + 1e4 for v in d["center_of_gravity"]]
    shifted["center_of_gravity"][0] += 1.0  # 1 mm, 0.4 % of the largest radius of gyration (237 mm)
    cg = _figures(compare_results(shifted, moved, rtol=1e-3))["center_of_gravity"]
    assert not cg.passed(0.0)
    gyration = np.sqrt(np.linalg.eigvalsh(np.array(engine["inertia_per_mass"]))[-1])
    assert cg.entries[0].tolerance == pytest.approx(1e-3 * gyration)


def _with_se(data: dict[str, Any], cg_std: float) -> dict[str, Any]:
    out = copy.deepcopy(data)
    est = out["center_of_gravity"]
    out["uncertainty"] = {"center_of_gravity": {"estimate": est, "std": [cg_std] * 3, "ci95": [[v, v] for v in est]}}
    return out


def test_within_k_combined_standard_errors(engine: dict[str, Any]) -> None:
    reference = _with_se(engine, 0.3)
    result = _with_se(engine, 0.4)
    result["center_of_gravity"][1] += 1.2  # combined SE 0.5 mm: 2.4 standard errors
    assert not compare_results(result, reference, rtol=1e-6).passed
    assert not compare_results(result, reference, rtol=1e-6, sigma=2.3).passed
    passed = compare_results(result, reference, rtol=1e-6, sigma=2.5)
    assert passed.passed
    y = _figures(passed)["center_of_gravity"].entries[1]
    assert y.sigma == pytest.approx(0.5) and _figures(passed)["center_of_gravity"].sigma_from == "uncertainty"
    only_reference = compare_results(engine | {"center_of_gravity": result["center_of_gravity"]}, reference, sigma=4.1)
    assert only_reference.passed  # 1.2 mm = 4 of the reference's own 0.3 mm


def test_two_independent_noisy_tests_agree_within_their_intervals() -> None:
    """Two simulated tests of one body with independent noise: every figure with a standard error
    within 3 combined standard errors (Monte Carlo intervals), none within a tight tolerance."""
    noise = {"frequency_noise": 0.001, "damping_noise": 0.02, "shape_noise": 0.01}
    results = []
    for seed in (11, 12):
        modes = api.simulate(ENGINE / "body.json", ENGINE / "layout.json", seed=seed, **noise)
        noise_levels = {"frequency": 0.001, "damping": 0.02, "shape": 0.01}
        results.append(result_to_dict(api.identify(ENGINE / "layout.json", modes, uncertainty=300, noise=noise_levels)))
    loose = compare_results(results[0], results[1], rtol=1e-9, sigma=3.0)
    figures = _figures(loose)
    for name in ("center_of_gravity", "inertia_tensor", "principal_moments"):
        assert figures[name].passed(3.0), figures[name].worst(3.0)
        assert not figures[name].passed(0.0)


def test_mounts_are_matched_by_id(engine: dict[str, Any]) -> None:
    identified = api.identify(ENGINE / "layout.json", ENGINE / "modes.csv")
    with_mounts = result_to_dict(api.with_mounts(identified, ENGINE / "mounts.json"))
    same = compare_results(with_mounts, with_mounts, rtol=0.0)
    names = {f.name for f in same.figures}
    assert {"mounts.front.stiffness", "mounts.rear-left.stiffness", "mounts.rear-right.damping"} <= names
    assert same.passed
    missing = compare_results(engine, with_mounts)
    assert {f.name for f in missing.regressions} == {n for n in names if n.startswith("mounts.")}
    assert compare_results(with_mounts, engine).passed  # figures the reference lacks are not compared
    softer = copy.deepcopy(with_mounts)
    softer["mounts"]["mounts"][0]["stiffness"][0] *= 0.9  # the largest rate
    assert [f.name for f in compare_results(softer, with_mounts, rtol=0.05).regressions] == ["mounts.front.stiffness"]


def test_cli_exit_status_and_junit(tmp_path: Path, engine: dict[str, Any]) -> None:
    drifted = copy.deepcopy(engine)
    drifted["stiffness_force"][2][2] *= 1.01
    (tmp_path / "r.json").write_text(json.dumps(drifted))
    out = run("compare", tmp_path / "r.json", ENGINE / "expected.json", "--rtol", "1e-3", "--junit", tmp_path / "j.xml")
    assert out.returncode == 1, out.stderr
    assert "regression: stiffness_force [z,z]" in out.stderr and "REGRESSION" in out.stdout
    suite = ET.parse(tmp_path / "j.xml").getroot().find("testsuite")
    assert suite is not None and suite.get("failures") == "1" and suite.get("tests") == "6"
    failures = [c.get("name") for c in suite.iter("testcase") if c.find("failure") is not None]
    assert failures == ["stiffness_force"]
    ok = run("compare", tmp_path / "r.json", ENGINE / "expected.json", "--rtol", "1e-3,stiffness=0.02")
    assert ok.returncode == 0, ok.stderr


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (("{layout}", "{ref}"), "not a result JSON"),
        (("{ref}", "{ref}", "--rtol", "stiffnes=1"), "--rtol: unknown figure 'stiffnes'"),
        (("{ref}", "{ref}", "--rtol", "-1"), "--rtol"),
        (("{ref}", "{ref}", "--sigma", "-1"), "--sigma"),
        (("{metres}", "{ref}"), "different units"),
        (("{ref}", "{tmp}/nothing.json"), "nothing.json"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    tmp_path: Path, engine: dict[str, Any], args: tuple[str, ...], expected: str
) -> None:
    (tmp_path / "m.json").write_text(json.dumps(engine | {"units": {"length": "m", "mass": "kg", "time": "s"}}))
    names = {
        "layout": ENGINE / "layout.json",
        "ref": ENGINE / "expected.json",
        "metres": tmp_path / "m.json",
        "tmp": tmp_path,
    }
    out = run("compare", *(a.format(**names) for a in args))
    assert out.returncode == 2, out.stderr
    assert expected in out.stderr and len(out.stderr.strip().splitlines()) == 1 and "Traceback" not in out.stderr


def test_parse_tolerances() -> None:
    assert parse_tolerances("1e-3, stiffness=0.05") == {"*": 1e-3, "stiffness": 0.05}
    with pytest.raises(InputError, match="not a relative tolerance"):
        parse_tolerances("nan")


def test_junit_is_valid_xml_with_one_case_per_figure(engine: dict[str, Any], tmp_path: Path) -> None:
    (tmp_path / "e.json").write_text(json.dumps(engine))
    comparison = compare_files(tmp_path / "e.json", ENGINE / "expected.json")
    root = ET.fromstring(comparison_junit(comparison))
    assert root.tag == "testsuites" and root.get("failures") == "0"
    assert len(list(root.iter("testcase"))) == len(comparison.figures)


def test_stiffness_in_other_force_units_is_compared_in_mass_units(engine: dict[str, Any]) -> None:
    """A result written with --force-unit kN against one in N: same body, so no regression."""
    in_kn = result_to_dict(api.identify(ENGINE / "layout.json", ENGINE / "modes.csv"), force_unit="kN")
    assert in_kn["stiffness_force"][2][2] == pytest.approx(engine["stiffness_force"][2][2] / 1000)
    comparison = compare_results(in_kn, engine, rtol=1e-9)
    assert comparison.passed
    assert {"stiffness_matrix", "damping_matrix"} <= {f.name for f in comparison.figures}
