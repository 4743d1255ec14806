"""Sensor transformation and change of reference point, eqs. (2)-(14) of the paper."""

from __future__ import annotations

import numpy as np
import pytest

from rigidid.core.geometry import layout_condition, normalise_directions, sensor_matrix, skew, transfer_matrix
from rigidid.errors import InputError

# T_mo printed in the paper's section 3 (rows for sensors along +z, +x, -y, +y, +z, -z).
PAPER_T_MO = np.array(
    [
        [0, 0, 1, 1.5, -6.75, 0],
        [1, 0, 0, 0, -0.8, -5.7],
        [0, -1, 0, 0.75, 0, -7.25],
        [0, 1, 0, 3.25, 0, -8.4],
        [0, 0, 1, -4.0, -4.5, 0],
        [0, 0, -1, 0.7, -9.0, 0],
    ]
)


def test_sensor_matrix_reproduces_printed_t_mo(paper_arrays: tuple[np.ndarray, ...]) -> None:
    positions, directions, _, _ = paper_arrays
    np.testing.assert_allclose(sensor_matrix(positions, directions), PAPER_T_MO, atol=1e-12)


def test_eq3_rows_for_axis_directions() -> None:
    u, v, w = 1.0, 2.0, 3.0
    g = np.array([0.5, -0.25, 0.125])
    rows = sensor_matrix(np.tile([u, v, w], (3, 1)), np.eye(3), g)
    ug, vg, wg = g
    expected = np.array(
        [
            [1, 0, 0, 0, w - wg, vg - v],
            [0, 1, 0, wg - w, 0, u - ug],
            [0, 0, 1, v - vg, ug - u, 0],
        ]
    )
    np.testing.assert_allclose(rows, expected)


def test_skew_is_cross_product(rng: np.random.Generator) -> None:
    a, b = rng.standard_normal(3), rng.standard_normal(3)
    np.testing.assert_allclose(skew(a) @ b, np.cross(a, b))


def test_transfer_inverse_is_reverse_transfer_eq14(rng: np.random.Generator) -> None:
    d = rng.standard_normal(3)
    np.testing.assert_allclose(transfer_matrix(d) @ transfer_matrix(-d), np.eye(6), atol=1e-15)


def test_eq11_t_mg_equals_t_mo_g_og(rng: np.random.Generator) -> None:
    positions, directions = rng.standard_normal((8, 3)), normalise_directions(rng.standard_normal((8, 3)))
    g = rng.standard_normal(3)
    t_mg = sensor_matrix(positions, directions, g)
    t_mo = sensor_matrix(positions, directions)
    np.testing.assert_allclose(t_mg, t_mo @ transfer_matrix(-g), atol=1e-12)


def test_rigid_motion_reading_matches_kinematics(rng: np.random.Generator) -> None:
    positions, directions = rng.standard_normal((5, 3)), normalise_directions(rng.standard_normal((5, 3)))
    translation, rotation = rng.standard_normal(3), 1e-3 * rng.standard_normal(3)
    motion = translation + np.cross(rotation, positions)
    readings = np.sum(motion * directions, axis=1)
    np.testing.assert_allclose(sensor_matrix(positions, directions) @ np.r_[translation, rotation], readings)


def test_normalise_rejects_zero_vector() -> None:
    with pytest.raises(InputError, match="sensor 2"):
        normalise_directions([[1, 0, 0], [0, 0, 0]])


def test_layout_condition_is_origin_and_unit_invariant(rng: np.random.Generator) -> None:
    positions, directions = rng.standard_normal((9, 3)), normalise_directions(rng.standard_normal((9, 3)))
    cond, rank = layout_condition(positions, directions)
    cond2, rank2 = layout_condition(25.4 * positions + [100.0, -3.0, 7.0], directions)
    assert rank == rank2 == 6
    assert cond2 == pytest.approx(cond, rel=1e-9)


def test_layout_condition_detects_rank_deficiency() -> None:
    # every sensor along z: x, y translations and rotation about z are invisible
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0], [1, 2, 0]], dtype=float)
    cond, rank = layout_condition(positions, np.tile([0.0, 0.0, 1.0], (6, 1)))
    assert rank == 3
    assert cond == float("inf")
