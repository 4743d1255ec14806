"""The paper's own numbers: the printed Q matrix and the identified body."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from rigidid import api
from rigidid.core.geometry import sensor_matrix
from rigidid.core.selection import project_rigid
from rigidid.core.statespace import state_matrices, state_matrices_paper
from rigidid.errors import RigididWarning

from .conftest import DATA, PAPER
from .tolerances import PAPER_Q_ABS

PRINTED_Q = np.loadtxt(DATA / "paper_q_matrix_printed.csv", delimiter=",")


@pytest.mark.parametrize("route", [state_matrices, state_matrices_paper])
def test_q_matches_the_printed_matrix(route: object, paper_arrays: tuple[np.ndarray, ...]) -> None:
    """Q = T_mo^-1 M_m^-1 K_m T_mo, eqs. (17) and (30), at the paper's origin and units."""
    positions, directions, poles, shapes = paper_arrays
    coords, _ = project_rigid(sensor_matrix(positions, directions), shapes)
    q, _ = route(poles, coords)  # type: ignore[operator]
    assert np.abs(q - PRINTED_Q).max() < PAPER_Q_ABS


def _identify(method: str) -> api.IdentifyResult:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RigididWarning)
        return api.identify(PAPER / "layout.json", PAPER / "modes.csv", method=method)  # type: ignore[arg-type]


def test_paper_route_reproduces_the_reference_reading() -> None:
    """Eqs. (25)-(26) and (36)-(40) with eq. (40) corrected: CG (-0.39, -0.19, -1.63) in."""
    ident = _identify("paper").identification
    assert ident.inertia_tensor is not None
    np.testing.assert_allclose(ident.center_of_gravity, [-0.39, -0.19, -1.63], atol=0.01)
    np.testing.assert_allclose(np.diag(ident.inertia_tensor), [2514.0, 3125.0, 5502.0], rtol=0.002)


def test_default_estimator_on_the_paper_sample() -> None:
    """Near the reference reading and the geometry's values (CG (0, 0, -1.40), I (2652, 3087, 5440))."""
    ident = _identify("structured").identification
    assert ident.inertia_tensor is not None
    np.testing.assert_allclose(ident.center_of_gravity, [-0.39, -0.19, -1.63], atol=0.1)
    np.testing.assert_allclose(np.diag(ident.inertia_tensor), [2514.0, 3125.0, 5502.0], rtol=0.1)
    np.testing.assert_allclose(np.diag(ident.inertia_tensor), [2652.0, 3087.0, 5440.0], rtol=0.1)
    assert ident.diagnostics.structure_residual < 0.03
