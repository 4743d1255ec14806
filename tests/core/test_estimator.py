"""The identification kernel (rigidid.core.estimator): status of each test, polish, plausibility."""

from __future__ import annotations

import numpy as np

from rigidid.core import estimator
from rigidid.core.geometry import transfer_matrix
from rigidid.core.simulate import body_modes

from ..bodies import random_body, random_layout
from ..tolerances import EXACT_REL


def _stack(*tests: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
    return tuple(np.stack(parts) for parts in zip(*tests, strict=True))


def _test(seed: int, sensors: int = 8) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    body = random_body(rng)
    pos, dirs = random_layout(rng, sensors)
    modes = body_modes(body, pos, dirs)
    return pos, dirs, modes.poles, modes.shapes


def test_a_layout_of_rank_five_fails_its_own_draw_only() -> None:
    """Sensors on one oblique line never see rotation about it: rank 5 in exact arithmetic.

    After rounding, T has a singular value near 1e-16 and every solve goes through, so only
    the rank check stops the draw: without it the draw returns a finite, meaningless body.
    """
    pos, dirs, poles, shapes = _test(1)
    u = np.array([1.0, 2.0, 3.0]) / np.sqrt(14.0)
    line = np.outer(np.linspace(-1.0, 1.0, 8), u) + np.array([0.1, -0.2, 0.3])
    data = _stack((pos, dirs, poles, shapes), (line, dirs, poles, shapes), (pos, dirs, poles, shapes))
    out = estimator.estimate(*data)
    np.testing.assert_array_equal(out.status, [estimator.OK, estimator.RANK, estimator.OK])
    assert np.all(np.isnan(out.center_of_gravity[1]))
    np.testing.assert_array_equal(out.center_of_gravity[0], out.center_of_gravity[2])


def test_other_failures_are_flagged_with_their_reason() -> None:
    pos, dirs, poles, shapes = _test(2)
    bad_pole = poles.copy()
    bad_pole[0] = bad_pole[0].conj()
    nan_shape = shapes.copy()
    nan_shape[3, 2] = np.nan
    twin = shapes.copy()
    twin[:, 1] = twin[:, 0]  # two modes with one shape and (below) one pole: singular modal matrix
    twin_poles = poles.copy()
    twin_poles[1] = twin_poles[0]
    tests = [(pos, dirs, bad_pole, shapes), (pos, dirs, poles, nan_shape), (pos, dirs, twin_poles, twin)]
    out = estimator.estimate(*_stack(*tests))
    np.testing.assert_array_equal(out.status, [estimator.UNSTABLE, estimator.NOT_FINITE, estimator.SINGULAR_MODES])
    assert set(estimator.STATUS_MESSAGES) >= set(out.status.tolist())


def test_the_cg_is_the_stationary_point_not_where_the_cost_went_flat() -> None:
    """After Levenberg-Marquardt, Gauss-Newton on the exact gradient: a further Newton step is nil."""
    pos, dirs, poles, shapes = _test(3)
    rng = np.random.default_rng(3)
    noisy = shapes * (1.0 + 0.01 * rng.standard_normal(shapes.shape))  # inconsistent data: cost > 0
    prepared = estimator.prepare(*_stack((pos, dirs, poles, noisy)))
    g, _, cost = estimator.solve_cg(prepared.stiffness, prepared.damping)
    assert cost[0] > 0.0
    problem = estimator._problem(prepared.stiffness, prepared.damping, estimator.DAMPING_WEIGHT)
    _, grad, hess = problem.normal_equations(g)
    step = np.linalg.solve(hess[0], grad[0])
    assert np.linalg.norm(step) < 1e-13 * (1.0 + np.linalg.norm(g))


def test_at_cg_moves_a_matrix_as_eqs_11_to_14() -> None:
    rng = np.random.default_rng(4)
    q = rng.standard_normal((6, 6))
    g = rng.standard_normal(3)
    expected = transfer_matrix(g) @ q @ transfer_matrix(-g)
    np.testing.assert_allclose(estimator.at_cg(q[None], g[None])[0], expected, atol=EXACT_REL)
    j = np.diag([1.0, 2.0, 3.0])
    d = np.eye(6)
    d[3:, 3:] = j
    np.testing.assert_allclose(estimator.at_cg(q[None], g[None], j[None])[0], d @ expected, atol=EXACT_REL)


def test_plausible_rejects_an_inertia_breaking_the_triangle_inequality() -> None:
    inertia = np.stack([np.diag([1.0, 2.0, 2.5]), np.diag([1.0, 1.0, 2.0 + 1e-6]), np.diag([-1.0, 2.0, 2.5])])
    nan6 = np.zeros((3, 6, 6))
    out = estimator.Estimates(np.zeros((3, 3)), inertia, nan6, nan6, np.zeros(3, dtype=np.int8))
    np.testing.assert_array_equal(out.plausible, [True, False, False])
