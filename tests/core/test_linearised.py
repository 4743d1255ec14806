"""Noise-weighted kernel and linearised standard errors: exact recovery, calibration, efficiency."""

from __future__ import annotations

import numpy as np
import pytest

from rigidid.core.estimator import Estimates
from rigidid.core.identify import identify
from rigidid.core.linearised import principal_axis_deviation, spread
from rigidid.core.noise import NoiseLevels
from rigidid.core.simulate import Body, Mount, add_noise, body_modes

from ..tolerances import EXACT_REL

NOISE = NoiseLevels(frequency=0.001, damping=0.05, shape=0.01)


def weak_engine() -> tuple[Body, np.ndarray, np.ndarray]:
    """180 kg on three mounts close to the CG's height, one turned 35 degrees: inertia weakly observable."""
    turn = np.deg2rad(35.0)
    rot = np.array([[np.cos(turn), -np.sin(turn), 0.0], [np.sin(turn), np.cos(turn), 0.0], [0.0, 0.0, 1.0]])
    k = np.diag([1.2e5, 0.9e5, 3.0e5])
    ks = [rot @ k @ rot.T, k, k]
    where = [[0.25, 0.18, 0.0], [-0.25, 0.2, 0.01], [0.0, -0.22, -0.005]]
    mounts = [Mount(np.array(p), km, 6e-4 * km + np.diag([20.0, 35.0, 60.0])) for p, km in zip(where, ks, strict=True)]
    inertia = np.array([[6.0, 0.3, -0.4], [0.3, 9.0, 0.2], [-0.4, 0.2, 7.5]])
    body = Body(180.0, np.array([0.02, -0.01, 0.05]), inertia, mounts)
    corners = np.array([[x, y, z] for x in (0.3, -0.3) for y in (0.25, -0.25) for z in (0.2, -0.2)])
    return body, np.repeat(corners[[0, 3, 5, 6]], 3, axis=0), np.tile(np.eye(3), (4, 1))


def test_weighted_kernel_recovers_an_exact_body() -> None:
    body, pos, dirs = weak_engine()
    modes = body_modes(body, pos, dirs)
    result = identify(pos, dirs, modes.poles, modes.shapes, mass=body.mass, noise=NOISE)
    assert result.diagnostics.misfit is not None and result.diagnostics.misfit < 1e-12
    np.testing.assert_allclose(result.center_of_gravity, body.center_of_gravity, atol=EXACT_REL)
    np.testing.assert_allclose(result.inertia_tensor, body.inertia_tensor, rtol=EXACT_REL, atol=EXACT_REL * 9.0)


def _draws(n: int, seed: int) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]]:
    """Per draw: weighted errors / SE (CG, J diag), weighted and unweighted errors, misfit."""
    body, pos, dirs = weak_engine()
    exact = body_modes(body, pos, dirs)
    rng = np.random.default_rng(seed)
    out = []
    diag = lambda e: np.diagonal(e.inertia_per_mass, axis1=1, axis2=2)  # noqa: E731
    for _ in range(n):
        m = add_noise(exact, frequency=NOISE.frequency, damping=NOISE.damping, shape=NOISE.shape, rng=rng)
        w = identify(pos, dirs, m.poles, m.shapes, mass=body.mass, noise=NOISE, warn=False)
        u = identify(pos, dirs, m.poles, m.shapes, mass=body.mass, warn=False)
        lin = spread(pos, dirs, m.poles, m.shapes, NOISE, weights=w.diagnostics.residual_weights)
        se = np.concatenate([lin.std(lambda e: e.center_of_gravity), lin.std(diag)])
        err_w = np.concatenate([w.center_of_gravity - body.center_of_gravity, np.diag(w.inertia_per_mass)])
        err_u = np.concatenate([u.center_of_gravity - body.center_of_gravity, np.diag(u.inertia_per_mass)])
        truth_j = np.concatenate([np.zeros(3), np.diag(body.inertia_tensor) / body.mass])
        assert w.diagnostics.misfit is not None
        out.append(((err_w - truth_j) / se, err_w - truth_j, err_u - truth_j, se, w.diagnostics.misfit))
    return out


@pytest.fixture(scope="module")
def draws() -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]]:
    return _draws(60, 3)


def test_linearised_errors_are_calibrated(draws: list[tuple[np.ndarray, ...]]) -> None:
    # z = error / own SE: RMS 1 when the SE is right; 60 draws give RMS within about +-0.2
    z = np.array([d[0] for d in draws])
    rms = np.sqrt(np.mean(z**2, axis=0))
    assert np.all((rms > 0.7) & (rms < 1.35)), rms


def test_misfit_is_chi_square_with_21_degrees_of_freedom(draws: list[tuple[np.ndarray, ...]]) -> None:
    misfit = np.array([d[4] for d in draws])
    # mean 21, its standard error sqrt(2 * 21 / 60) = 0.84
    assert 18.5 < misfit.mean() < 23.5, misfit.mean()


def test_weighting_beats_the_fixed_weights_on_a_weakly_observable_body(draws: list[tuple[np.ndarray, ...]]) -> None:
    weighted = np.sqrt(np.mean(np.array([d[1] for d in draws]) ** 2, axis=0))
    fixed = np.sqrt(np.mean(np.array([d[2] for d in draws]) ** 2, axis=0))
    # observed: CG 1.4-4x and inertia 1.5-5x smaller RMS error
    assert np.all(weighted < fixed / 1.2), (weighted, fixed)


def test_principal_axis_deviation_is_zero_at_the_reference_and_an_angle_when_turned() -> None:
    j = np.diag([1.0, 2.0, 3.0])
    angle = 1e-3
    c, s = np.cos(angle), np.sin(angle)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    stack = np.stack([j, rot @ j @ rot.T])
    est = Estimates(np.zeros((2, 3)), stack, np.zeros((2, 6, 6)), np.zeros((2, 6, 6)), np.zeros(2, dtype=np.int8))
    dev = principal_axis_deviation(np.eye(3))(est)
    np.testing.assert_allclose(dev[0], 0.0, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(dev[1], axis=1), [angle, angle, 0.0], rtol=1e-6, atol=1e-15)


@pytest.mark.parametrize("weighted", [False, True])
def test_one_newton_step_gives_the_responses_of_identifying_again(weighted: bool) -> None:
    # a noisy draw: the residual is not zero, so the step needs the cost's full Hessian, not J^T J
    # (observed: 6e-5 of the largest response; with J^T J 1.6e-2)
    body, pos, dirs = weak_engine()
    levels = NoiseLevels(frequency=0.001, damping=0.05, shape=0.03)
    m = add_noise(body_modes(body, pos, dirs), frequency=0.001, damping=0.05, shape=0.03, rng=np.random.default_rng(5))
    ident = identify(pos, dirs, m.poles, m.shapes, mass=body.mass, noise=levels if weighted else None, warn=False)
    white = ident.diagnostics.residual_weights
    assert (white is not None) == weighted
    again = spread(pos, dirs, m.poles, m.shapes, levels, weights=white)
    near = spread(pos, dirs, m.poles, m.shapes, levels, weights=white, start=ident.center_of_gravity)
    figures = (
        lambda e: e.center_of_gravity, lambda e: e.inertia_per_mass, lambda e: e.stiffness_per_mass,
        lambda e: e.damping_per_mass,
    )  # fmt: skip
    for figure in figures:
        d_again, d_near = again.responses(figure), near.responses(figure)
        scale = np.max(np.abs(d_again), axis=0)
        assert np.all(np.abs(d_near - d_again) <= 2e-4 * scale + 1e-300), np.max(np.abs(d_near - d_again) / scale)


def test_paper_route_standard_errors_are_calibrated() -> None:
    """``--method paper`` gets linearised standard errors too: its errors over their own SE have RMS 1."""
    from rigidid.api.checks import paper_standard_errors

    body, pos, dirs = weak_engine()
    exact = body_modes(body, pos, dirs)
    rng = np.random.default_rng(11)
    z = []
    for _ in range(6):
        m = add_noise(exact, frequency=NOISE.frequency, damping=NOISE.damping, shape=NOISE.shape, rng=rng)
        ident = identify(pos, dirs, m.poles, m.shapes, mass=body.mass, method="paper", warn=False)
        errors = paper_standard_errors(ident, pos, dirs, m.poles, m.shapes, NOISE)
        assert errors is not None and ident.inertia_tensor is not None
        z.append(np.concatenate([
            (ident.center_of_gravity - body.center_of_gravity) / errors.center_of_gravity,
            np.diag(ident.inertia_tensor - body.inertia_tensor) / np.diag(errors.inertia),
        ]))  # fmt: skip
    rms = np.sqrt(np.mean(np.square(z)))
    # observed 0.79 (6 draws x 6 figures, correlated); with the standard errors halved 1.59
    assert 0.45 < rms < 1.3, rms


def test_plan_predicts_the_noise_weighted_identification() -> None:
    """``plan`` draws through the kernel ``identify`` uses: its spread is the weighted estimator's SE."""
    from rigidid.core.plan import predict_uncertainty

    body, pos, dirs = weak_engine()
    exact = body_modes(body, pos, dirs)
    ident = identify(pos, dirs, exact.poles, exact.shapes, mass=body.mass, noise=NOISE, warn=False)
    lin = spread(pos, dirs, exact.poles, exact.shapes, NOISE, weights=ident.diagnostics.residual_weights)
    planned = predict_uncertainty(body, pos, dirs, noise=NOISE, draws=300, seed=2)
    ratio = planned.figures.center_of_gravity_std / lin.std(lambda e: e.center_of_gravity)
    # observed 1.01-1.05 (300 draws: +-4 %); with the fixed weights 1.5-6.3
    assert np.all((ratio > 0.8) & (ratio < 1.25)), ratio
