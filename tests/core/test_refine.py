"""Output-error refinement on the records (rigidid.core.timedomain.refine)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from rigidid.api import body_from_file
from rigidid.core.geometry import layout_frame
from rigidid.core.identify import identify
from rigidid.core.simulate import system_matrices
from rigidid.core.timedomain import estimate_modes, impulse_records
from rigidid.core.timedomain.refine import (
    MAX_ROWS,
    N_PARAMETERS,
    _Data,
    _evaluate,
    _fit_factor,
    _Frame,
    _modes,
    _projector,
    good_fit,
    record_bound,
    refine_body,
)
from rigidid.io.files import layout_arrays, load_body, load_layout

from ..tolerances import REFINE_EXACT_REL, REFINE_JACOBIAN_REL, REFINE_NOISE_FREE_ABS

SAMPLE = Path(__file__).resolve().parents[2] / "samples" / "four-mounts"
IMPACTS = [((0.3, 0.2, 0.15), (0.3, -0.5, -1.0)), ((-0.3, -0.1, 0.0), (1.0, 0.6, 0.2))]


@pytest.fixture(scope="module")
def rig() -> tuple[object, np.ndarray, np.ndarray]:
    body = body_from_file(load_body(SAMPLE / "body.json"))
    _, pos, dirs = layout_arrays(load_layout(SAMPLE / "layout.json"))
    return body, pos, dirs


def _truth_per_mass(body) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # type: ignore[no-untyped-def]
    _, k, c = system_matrices(body)
    return body.inertia_tensor / body.mass, k / body.mass, c / body.mass


def test_jacobian_matches_finite_differences(rig) -> None:  # type: ignore[no-untyped-def]
    body, pos, dirs = rig
    records = impulse_records(body, pos, dirs, IMPACTS, sample_rate=128.0, duration=1.0, noise=1e-5, seed=0)
    lf = layout_frame(pos)
    j, k, c = _truth_per_mass(body)
    frame = _Frame(lf.centre, lf.scale, 60.0)
    theta = frame.to_theta(body.center_of_gravity, j, k, c)
    data = _Data([r[:100] for r in records], np.ones(pos.shape[0]), 1.0 / 128.0, "residual")
    pos_l = lf.to_local(pos)
    r0, jac = _evaluate(theta, data, pos_l, dirs, 60.0, True)
    assert jac.shape == (r0.size, N_PARAMETERS)
    rng = np.random.default_rng(1)
    for i in rng.choice(N_PARAMETERS, 8, replace=False):
        h = 1e-6 * max(1.0, abs(theta[i]))
        up, down = theta.copy(), theta.copy()
        up[i] += h
        down[i] -= h
        r_up = _evaluate(up, data, pos_l, dirs, 60.0, False)[0]
        fd = (r_up - _evaluate(down, data, pos_l, dirs, 60.0, False)[0]) / (2 * h)
        # Kaufman's Jacobian drops a term that vanishes at a zero residual; near it they agree closely
        assert np.linalg.norm(jac[:, i] - fd) <= REFINE_JACOBIAN_REL * np.linalg.norm(fd) + 1e-9


def test_model_poles_are_the_bodys(rig) -> None:  # type: ignore[no-untyped-def]
    body, pos, dirs = rig
    lf = layout_frame(pos)
    frame = _Frame(lf.centre, lf.scale, 1.0)
    theta = frame.to_theta(body.center_of_gravity, *_truth_per_mass(body))
    lam, *_ = _modes(theta, lf.to_local(pos), dirs, False)
    m, k, c = system_matrices(body)
    a = np.block([[-np.linalg.solve(m, c), -np.linalg.solve(m, k)], [np.eye(6), np.zeros((6, 6))]])
    ev = np.linalg.eigvals(a)
    ev = np.sort_complex(ev[ev.imag > 0])
    np.testing.assert_allclose(np.sort(np.abs(lam)), np.sort(np.abs(ev)), rtol=1e-10)


def test_refinement_recovers_the_body_from_exact_records(rig) -> None:  # type: ignore[no-untyped-def]
    body, pos, dirs = rig
    records = impulse_records(
        body, pos, dirs, IMPACTS, sample_rate=128.0, duration=3.0, pretrigger=0.4, noise=1e-6, seed=0
    )
    est = estimate_modes(records, 1.0 / 128.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        start = identify(pos, dirs, est.poles, est.shapes, mass=body.mass)
    ref = refine_body(
        records, 1.0 / 128.0, pos, dirs, starts=[i.start for i in est.impacts], onsets=[i.onset for i in est.impacts],
        decimation=est.decimation, center_of_gravity=start.center_of_gravity, inertia_per_mass=start.inertia_per_mass,
        stiffness_per_mass=start.stiffness_per_mass, damping_per_mass=start.damping_per_mass,
        max_evaluations=8,
    )  # fmt: skip
    j, _, _ = _truth_per_mass(body)
    assert good_fit(ref)
    assert ref.noise_from == "pretrigger"
    np.testing.assert_allclose(ref.inertia_per_mass, j, atol=REFINE_EXACT_REL * np.max(np.abs(j)))
    np.testing.assert_allclose(ref.center_of_gravity, body.center_of_gravity, atol=REFINE_EXACT_REL * 0.5)
    bound = record_bound(ref, body.mass)
    assert np.all(bound.center_of_gravity.std > 0)
    assert np.all(bound.center_of_gravity.low < bound.center_of_gravity.high)
    # the bound scales with the noise: tiny here
    assert np.max(bound.center_of_gravity.std) < 1e-4


def test_a_bad_start_is_flagged_by_the_cost(rig) -> None:  # type: ignore[no-untyped-def]
    body, pos, dirs = rig
    records = impulse_records(
        body, pos, dirs, IMPACTS, sample_rate=256.0, duration=4.0, pretrigger=0.2, noise=0.01, seed=0
    )
    j, k, c = _truth_per_mass(body)
    ref = refine_body(
        records, 1.0 / 256.0, pos, dirs, starts=[52, 52], onsets=[51, 51], decimation=1,
        center_of_gravity=body.center_of_gravity, inertia_per_mass=j, stiffness_per_mass=k * 1.3,
        damping_per_mass=c, max_evaluations=2,
    )  # fmt: skip
    assert not good_fit(ref)


def test_fit_runs_on_the_raw_samples_when_they_fit() -> None:
    # decimation's filter drops FIR_HALF_LENGTH q samples at the start of each decay, where the
    # most signal is: the refinement decimates only when the raw decays exceed MAX_ROWS
    assert _fit_factor([4000, 4000], 8, 2) == 1
    assert _fit_factor([MAX_ROWS // 8, MAX_ROWS // 8], 8, 4) == 2
    assert _fit_factor([MAX_ROWS, MAX_ROWS], 8, 3) == 3  # nothing fits: the modal estimate's factor
    assert _fit_factor([10, 10], 8, 0) == 1


def test_projector_matches_least_squares() -> None:
    rng = np.random.default_rng(3)
    design = rng.standard_normal((200, 12)) * np.logspace(-3, 3, 12)  # badly scaled columns
    y = rng.standard_normal((200, 3))
    for x in (y[:, 0], y):
        coef, resid = _projector(design)(x)
        ref = np.linalg.lstsq(design, x, rcond=None)[0]
        np.testing.assert_allclose(coef, ref, rtol=1e-8, atol=1e-12)
        np.testing.assert_allclose(resid, x - design @ ref, atol=1e-10)


def test_exact_records_refit_reports_converged(rig) -> None:  # type: ignore[no-untyped-def]
    # noise-free records: the decrement test alone (round-off over round-off) never fired, so
    # every exact refit said converged False; the optimiser's rounding floor stops it
    body, pos, dirs = rig
    records = impulse_records(body, pos, dirs, IMPACTS, sample_rate=128.0, duration=1.5, pretrigger=0.4, noise=0.0)
    j, k, c = _truth_per_mass(body)
    ref = refine_body(
        records, 1.0 / 128.0, pos, dirs, starts=[52, 52], onsets=[51, 51], decimation=1,
        center_of_gravity=body.center_of_gravity + 1e-3, inertia_per_mass=j * 1.002, stiffness_per_mass=k * 1.002,
        damping_per_mass=c * 1.01, max_evaluations=240,
    )  # fmt: skip
    assert ref.converged and ref.evaluations < 240
    np.testing.assert_allclose(ref.center_of_gravity, body.center_of_gravity, atol=REFINE_NOISE_FREE_ABS)


def test_fit_on_the_rigid_combinations_gives_the_per_channel_residual_jacobian_and_errors(rig) -> None:  # type: ignore[no-untyped-def]
    # the fit runs on six combinations of the weighted channels; its residual and Jacobian on every
    # channel, and the calibrated standard errors from the combinations' rows, are those of a full
    # evaluation on every channel at the same parameters (exact, to rounding)
    from rigidid.core.timedomain.refine import _bound, _fit, _output_gradient

    body, pos, dirs = rig
    records = impulse_records(body, pos, dirs, IMPACTS, sample_rate=128.0, duration=1.0, noise=0.02, seed=4)
    lf = layout_frame(pos)
    frame = _Frame(lf.centre, lf.scale, 60.0)
    theta0 = frame.to_theta(body.center_of_gravity, *_truth_per_mass(body))
    sigma = np.sqrt(np.mean(records[0] ** 2, axis=0)) * np.linspace(0.01, 0.03, pos.shape[0])
    data = _Data([r[:90] for r in records], sigma, 1.0 / 128.0, "pretrigger")
    pos_l = lf.to_local(pos)
    theta, _, r, jm, _, reduced = _fit(data, pos_l, dirs, 60.0, theta0, 8)
    assert reduced is not None and reduced[1].shape == (pos.shape[0], 6)
    r_full, j_full = _evaluate(theta, data, pos_l, dirs, 60.0, True)
    np.testing.assert_allclose(r, r_full, rtol=0.0, atol=1e-9 * np.abs(r_full).max())
    np.testing.assert_allclose(jm, j_full, rtol=0.0, atol=1e-9 * np.abs(j_full).max())
    grad = _output_gradient(theta, frame, pos_l, dirs)
    args = (theta, j_full, 1.0, frame, pos_l, dirs, r_full, [90, 90], 2, None, grad)
    plain, fast = _bound(*args), _bound(*args[:-5], r, [90, 90], 2, None, grad, reduced)
    for key, value in plain.items():
        np.testing.assert_allclose(fast[key], value, rtol=1e-8, atol=0.0)
    from rigidid.core.timedomain.refine import _residual

    at_start = _evaluate(theta0, data, pos_l, dirs, 60.0, False)[0]
    np.testing.assert_allclose(
        _residual(theta0, data, pos_l, dirs, 60.0, None), at_start, atol=1e-9 * np.abs(at_start).max()
    )
