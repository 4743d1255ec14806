"""Rigid-body fit of mode shapes and the choice of the six rigid-body modes."""

from __future__ import annotations

import numpy as np
import pytest

from rigidid.core.geometry import sensor_matrix
from rigidid.core.selection import project_rigid, select_rigid_modes
from rigidid.core.simulate import body_modes
from rigidid.errors import IdentificationError

from ..bodies import random_body, random_layout


def test_rigid_shapes_fit_exactly_and_elastic_ones_do_not(rng: np.random.Generator) -> None:
    body = random_body(rng)
    positions, directions = random_layout(rng, 10)
    modes = body_modes(body, positions, directions)
    t = sensor_matrix(positions, directions)
    elastic = rng.standard_normal((10, 2)) + 1j * rng.standard_normal((10, 2))
    _, residual = project_rigid(t, np.hstack([modes.shapes, elastic]))
    assert np.all(residual[:6] < 1e-12)
    assert np.all(residual[6:] > 0.1)


def test_selection_finds_rigid_modes_among_elastic(rng: np.random.Generator) -> None:
    body = random_body(rng)
    positions, directions = random_layout(rng, 12)
    modes = body_modes(body, positions, directions)
    t = sensor_matrix(positions, directions)
    elastic = rng.standard_normal((12, 3)).astype(complex)
    mixed = np.hstack([elastic[:, :1], modes.shapes[:, :3], elastic[:, 1:], modes.shapes[:, 3:]])
    assert select_rigid_modes(t, mixed).tolist() == [1, 2, 3, 6, 7, 8]


def test_selection_needs_more_than_six_sensors(rng: np.random.Generator) -> None:
    positions, directions = random_layout(rng, 6)
    with pytest.raises(IdentificationError, match="more than six sensors"):
        select_rigid_modes(sensor_matrix(positions, directions), np.ones((6, 8), dtype=complex))
