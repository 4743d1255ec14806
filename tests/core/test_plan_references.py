"""plan --references: does a set of hammer points excite all six rigid-body motions, and what to add."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from rigidid import api
from rigidid.core.plan import INERTIAL_PARAMETERS, REFERENCE_CONDITION_LIMIT, check_references
from rigidid.errors import InputError
from rigidid.io import files

from ..conftest import DATA, SAMPLES

FOUR = SAMPLES / "four-mounts"
GOOD = DATA / "frf" / "references.json"  # +x, +y, +z at three corners


@pytest.fixture(scope="module")
def sensors() -> tuple[tuple[str, ...], np.ndarray, np.ndarray]:
    return files.layout_arrays(files.load_layout(FOUR / "layout.json"))


@pytest.fixture(scope="module")
def body() -> object:
    return api.body_from_file(files.load_body(FOUR / "body.json"))


CORNERS = np.array([[0.3, 0.2, 0.15], [-0.3, 0.2, -0.15], [0.3, -0.2, -0.15]])


def test_three_references_along_x_y_z_at_corners_are_accepted(sensors: tuple, body: object) -> None:
    _, pos, dirs = sensors
    for b in (None, body):
        report = check_references(pos, dirs, CORNERS, np.eye(3), body=b)  # type: ignore[arg-type]
        assert report.ok and report.rank == 10
        assert report.condition < 10.0 < REFERENCE_CONDITION_LIMIT
        assert report.load_rank == 3
        assert "determine mass, CG and inertia" in report.statement
    assert report.participation is not None and np.all(report.participation > 0.3)
    # participations are fractions of each reference's generalised force: at most 1
    assert np.all(report.participation <= 1.0 + 1e-12)
    assert report.mode_frequencies is not None and np.all(np.diff(report.mode_frequencies) >= 0)


def test_forces_all_along_z_leave_the_inertia_about_z_free_and_the_fix_is_named(sensors: tuple) -> None:
    ids, pos, dirs = sensors
    report = check_references(pos, dirs, CORNERS, np.tile([0.0, 0.0, 1.0], (3, 1)), unit="m", names=ids)
    assert not report.ok and report.rank == 9 and report.condition == np.inf
    assert report.weakest_parameter == "the inertia about z"
    assert "no reference gives a force along x, a force along y or a moment about z" in report.statement
    np.testing.assert_array_equal(report.coverage[[0, 1, 5]], 0.0)
    # the suggestion is a reference in the xy plane, and with it the set is accepted
    assert report.suggested_direction[2] == 0.0
    assert report.suggestion.startswith("add a reference along +")
    fixed = check_references(
        pos, dirs, np.vstack([CORNERS, report.suggested_position]), np.vstack([np.tile([0, 0, 1.0], (3, 1)),
                                                                             report.suggested_direction]),
    )  # fmt: skip
    assert fixed.ok
    assert fixed.condition == pytest.approx(report.suggested_condition, rel=1e-9)


def test_two_references_never_determine_the_inertia(sensors: tuple, body: object, rng: np.random.Generator) -> None:
    """Structural: an inertia about the normal of the two angular accelerations changes no equation."""
    _, pos, dirs = sensors
    for _ in range(5):
        rpos = rng.uniform(-0.3, 0.3, (2, 3))
        rdirs = rng.standard_normal((2, 3))
        report = check_references(pos, dirs, rpos, rdirs, body=body)  # type: ignore[arg-type]
        assert report.rank == 9 and not report.ok
        assert report.weakest_parameter in INERTIAL_PARAMETERS[4:]
        assert "a third is needed" in report.statement
        # adding the suggested reference makes it ten
        assert report.suggested_condition < REFERENCE_CONDITION_LIMIT


def test_one_reference_needs_two_more_and_says_so(sensors: tuple) -> None:
    _, pos, dirs = sensors
    report = check_references(pos, dirs, CORNERS[:1], np.array([[1.0, 1.0, 1.0]]))
    assert report.rank <= 6 and report.statement.startswith("the reference leaves")
    assert report.suggestion.count(" and one ") == 1 and "condition" in report.suggestion


def test_bad_reference_arrays_are_refused(sensors: tuple) -> None:
    _, pos, dirs = sensors
    with pytest.raises(InputError, match="one direction per reference"):
        check_references(pos, dirs, CORNERS, np.eye(3)[:2])


def _run(*args: str | Path) -> SimpleNamespace:
    """The command line, in this process (a subprocess costs a second of start-up per call)."""
    from typer.testing import CliRunner

    from rigidid.cli import app

    result = CliRunner().invoke(app, [str(a) for a in args])
    return SimpleNamespace(returncode=result.exit_code, stdout=result.stdout, stderr=result.stderr)


def test_plan_references_from_the_command_line(tmp_path: Path) -> None:
    done = _run("plan", FOUR / "layout.json", "--references", GOOD, "--json", "-")
    assert done.returncode == 0, done.stderr
    refs = json.loads(done.stdout)["references"]
    assert refs["ok"] and refs["rank"] == 10 and refs["participation"] is None
    assert set(refs["coverage"]) == {"force along x", "force along y", "force along z", "moment about x",
                                     "moment about y", "moment about z"}  # fmt: skip
    bad = tmp_path / "refs.json"
    bad.write_text(json.dumps({"references": [
        {"id": f"h{k}", "position": p, "direction": "+z"} for k, p in enumerate(CORNERS.tolist())
    ]}))  # fmt: skip
    done = _run("plan", FOUR / "layout.json", "--references", bad)
    assert done.returncode == 1  # the references determine no rigid body
    assert "not usable as it is" in done.stdout and "moment about z" in done.stdout
    other = tmp_path / "mm.json"
    other.write_text(json.dumps({"units": {"length": "mm", "mass": "kg"}, "references": [
        {"id": "h1", "position": [0, 0, 0], "direction": "+z"}]}))  # fmt: skip
    done = _run("plan", FOUR / "layout.json", "--references", other)
    assert done.returncode == 2 and done.stderr.count("\n") == 1
    assert str(other) in done.stderr and "differ from the layout's units" in done.stderr
