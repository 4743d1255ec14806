"""rigidid.core.checks: findings on simulated tests with a known fault."""

from __future__ import annotations

import numpy as np
import pytest

from rigidid import api
from rigidid.core.checks import inertia_not_positive, nonrigid_modes, percent_damping, sensor_outliers
from rigidid.core.geometry import sensor_matrix
from rigidid.core.simulate import add_noise, body_modes
from rigidid.io import files

from ..conftest import SAMPLES

ENGINE = SAMPLES / "engine-on-mounts"


@pytest.fixture(scope="module")
def engine() -> tuple[tuple[str, ...], np.ndarray, np.ndarray, object]:
    layout = files.load_layout(ENGINE / "layout.json")
    body = api.body_from_file(files.load_body(ENGINE / "body.json"))
    ids, positions, directions = files.layout_arrays(layout)
    return ids, positions, directions, body_modes(body, positions, directions)


def test_exact_modes_blame_no_sensor(engine) -> None:  # type: ignore[no-untyped-def]
    _, positions, directions, modes = engine
    assert sensor_outliers(sensor_matrix(positions, directions), modes.shapes) == ()


@pytest.mark.parametrize(("sensor", "axis"), [(1, 0), (2, 1), (8, 0), (11, 1)])
def test_misplaced_sensor_is_named(engine, sensor: int, axis: int) -> None:  # type: ignore[no-untyped-def]
    _, positions, directions, modes = engine
    wrong = positions.copy()
    wrong[sensor, axis] += 120.0  # 120 mm on a 600 mm body
    found = sensor_outliers(sensor_matrix(wrong, directions), add_noise(modes, shape=0.01, seed=3).shapes)
    assert [f.index for f in found] == [sensor]
    assert found[0].misfit > 0.1 > found[0].typical
    assert found[0].share > 0.6


def test_reversed_sensor_is_named(engine) -> None:  # type: ignore[no-untyped-def]
    _, positions, directions, modes = engine
    flipped = directions.copy()
    flipped[4] *= -1.0
    found = sensor_outliers(sensor_matrix(positions, flipped), modes.shapes)
    assert [f.index for f in found] == [4]


def test_noise_alone_blames_no_sensor(engine) -> None:  # type: ignore[no-untyped-def]
    _, positions, directions, modes = engine
    t = sensor_matrix(positions, directions)
    for seed in range(5):
        assert sensor_outliers(t, add_noise(modes, shape=0.03, seed=seed).shapes) == ()


def test_seven_sensors_cannot_tell_which(engine) -> None:  # type: ignore[no-untyped-def]
    _, positions, directions, modes = engine
    keep = [0, 1, 2, 3, 6, 9, 10]
    wrong = positions[keep].copy()
    wrong[2, 0] += 120.0
    assert sensor_outliers(sensor_matrix(wrong, directions[keep]), modes.shapes[keep]) == ()


def test_percent_damping() -> None:
    assert percent_damping([0.39, 0.5, 0.2]) is not None
    assert percent_damping([0.39, 0.395, 0.045, 0.111, 0.193, 0.133]) is not None  # the paper's, in percent
    assert percent_damping([0.0039, 0.05, 0.2]) is None
    assert percent_damping([0.05, 0.077]) is None


def test_nonrigid_modes_keep_labels() -> None:
    found = nonrigid_modes([1, 2, 3, 5, 6, 7], [1e-3, 0.01, 0.02, 0.03, 0.04, 0.91])
    assert found is not None
    assert found.labels == (7,)
    assert found.residuals == pytest.approx((0.91,))
    assert nonrigid_modes([1, 2], [0.1, 0.2]) is None


def test_inertia_not_positive() -> None:
    assert inertia_not_positive(np.diag([1.0, 2.0, 3.0])) is None
    found = inertia_not_positive(np.diag([-4.0, 2.0, 3.0]))
    assert found is not None
    assert found.principal_moments_per_mass[0] == pytest.approx(-4.0)
