"""Monte Carlo uncertainty: batched estimator, calibration of the intervals, noise from residuals."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from rigidid.api import load_arrays
from rigidid.core.estimator import Estimates
from rigidid.core.geometry import layout_frame, sensor_matrix
from rigidid.core.identify import DAMPING_WEIGHT, Identification, identify
from rigidid.core.noise import NoiseLevels, estimate_noise, perturb, shape_noise_from_residuals, tilt_directions
from rigidid.core.selection import project_rigid
from rigidid.core.simulate import Body, Modes, add_noise, body_modes
from rigidid.core.uncertainty import identify_batch, propagate, summarise
from rigidid.errors import IdentificationError, IllConditionedWarning, InputError
from rigidid.jsonout import uncertainty_to_dict

from ..bodies import random_body, random_layout
from ..tolerances import (
    BATCH_REL,
    NOISE_ESTIMATE_REL,
    SPREAD_SCALING_REL,
    ZERO_SPREAD_REL,
)

PAPER = Path(__file__).resolve().parent.parent.parent / "samples" / "paper-1994"
FULL_NOISE = NoiseLevels(frequency=0.001, damping=0.05, shape=0.01, position=0.02, angle_deg=1.0)


def paper_sample() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """Positions (in), directions, poles (rad/s), raw shapes and mass (lb) of the paper's test."""
    case = load_arrays(PAPER / "layout.json", PAPER / "modes.csv")
    assert case.mass is not None
    return case.positions, case.directions, case.poles, case.shapes, case.mass


def scalar(
    positions: np.ndarray,
    directions: np.ndarray,
    poles: np.ndarray,
    shapes: np.ndarray,
    *,
    mass: float | None = None,
    damping_weight: float = DAMPING_WEIGHT,
) -> Identification:
    """identify() without its (expected, here irrelevant) plausibility warnings."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return identify(positions, directions, poles, shapes, mass=mass, damping_weight=damping_weight)


def rel_err(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def assert_batch_matches_scalar(batch: Estimates, data_positions: np.ndarray, data_directions: np.ndarray,
                                data_poles: np.ndarray, data_shapes: np.ndarray,
                                damping_weight: float = DAMPING_WEIGHT) -> float:  # fmt: skip
    """Each draw of `batch` against identify() on the same data; returns the worst relative difference."""
    worst = 0.0
    for i in range(data_positions.shape[0]):
        ref = scalar(
            data_positions[i], data_directions[i], data_poles[i], data_shapes[i], damping_weight=damping_weight
        )
        span = layout_frame(data_positions[i]).scale
        assert batch.ok[i]
        errors = [
            float(np.max(np.abs(batch.center_of_gravity[i] - ref.center_of_gravity)) / span),
            rel_err(batch.inertia_per_mass[i], ref.inertia_per_mass),
            rel_err(batch.principal_moments_per_mass[i], ref.principal_moments_per_mass),
            rel_err(batch.stiffness_per_mass[i], ref.stiffness_per_mass),
            rel_err(batch.damping_per_mass[i], ref.damping_per_mass),
        ]
        worst = max(worst, *errors)
    assert worst < BATCH_REL
    return worst


@pytest.mark.parametrize("damping_weight", [0.0, 0.3])
def test_batch_matches_scalar_on_paper_draws(damping_weight: float) -> None:
    pos, dirs, poles, shapes, _ = paper_sample()
    data = perturb(pos, dirs, poles, shapes, FULL_NOISE, 12, seed=11)
    batch = identify_batch(data.positions, data.directions, data.poles, data.shapes, damping_weight=damping_weight)
    assert_batch_matches_scalar(
        batch, data.positions, data.directions, data.poles, data.shapes, damping_weight=damping_weight
    )


def test_batch_matches_scalar_with_more_sensors() -> None:
    """More than six sensors: least-squares rigid-body fit (QR) instead of a square solve."""
    rng = np.random.default_rng(7)
    for n_sensors in (7, 10):
        body = random_body(rng)
        pos, dirs = random_layout(rng, n_sensors)
        noisy = add_noise(body_modes(body, pos, dirs), frequency=0.001, damping=0.05, shape=0.01, rng=rng)
        data = perturb(pos, dirs, noisy.poles, noisy.shapes, FULL_NOISE, 6, rng=rng)
        batch = identify_batch(data.positions, data.directions, data.poles, data.shapes)
        assert_batch_matches_scalar(batch, data.positions, data.directions, data.poles, data.shapes)


def test_batch_flags_failed_draws_and_keeps_the_others() -> None:
    pos, dirs, poles, shapes, _ = paper_sample()
    data = perturb(pos, dirs, poles, shapes, FULL_NOISE, 4, seed=2)
    positions, directions = data.positions.copy(), data.directions.copy()
    lam, psi = data.poles.copy(), data.shapes.copy()
    directions[1] = [0.0, 0.0, 1.0]  # every sensor along z: rank 3
    psi[2, 0, 0] = np.nan
    batch = identify_batch(positions, directions, lam, psi)
    np.testing.assert_array_equal(batch.ok, [True, False, False, True])
    assert np.all(np.isnan(batch.center_of_gravity[1:3]))
    assert_batch_matches_scalar(
        Estimates(*(getattr(batch, f)[[0, 3]] for f in Estimates.__dataclass_fields__)),
        positions[[0, 3]], directions[[0, 3]], lam[[0, 3]], psi[[0, 3]],
    )  # fmt: skip


def test_zero_noise_gives_zero_spread_around_identify() -> None:
    pos, dirs, poles, shapes, mass = paper_sample()
    result = propagate(pos, dirs, poles, shapes, mass=mass, noise=NoiseLevels(), draws=50, seed=1)
    ref = scalar(pos, dirs, poles, shapes, mass=mass)
    assert result.failed == 0
    assert ref.inertia_tensor is not None and ref.principal_moments is not None
    np.testing.assert_array_equal(result.center_of_gravity.estimate, ref.center_of_gravity)
    np.testing.assert_array_equal(result.inertia.estimate, ref.inertia_tensor)
    np.testing.assert_array_equal(result.principal_moments.estimate, ref.principal_moments)
    for quantity in (result.center_of_gravity, result.principal_moments, result.stiffness_diagonal):
        scale = np.max(np.abs(quantity.estimate))
        assert np.all(quantity.std <= ZERO_SPREAD_REL * scale)
        assert np.all(quantity.high - quantity.low <= ZERO_SPREAD_REL * scale)
        np.testing.assert_allclose(quantity.low, quantity.estimate, rtol=BATCH_REL, atol=BATCH_REL * scale)


def test_per_mass_without_mass() -> None:
    pos, dirs, poles, shapes, mass = paper_sample()
    noise = NoiseLevels(shape=0.01)
    with_mass = propagate(pos, dirs, poles, shapes, mass=mass, noise=noise, draws=200, seed=5)
    per_mass = propagate(pos, dirs, poles, shapes, noise=noise, draws=200, seed=5)
    assert per_mass.per_mass and not with_mass.per_mass
    np.testing.assert_allclose(with_mass.principal_moments.std, mass * per_mass.principal_moments.std, rtol=1e-12)
    np.testing.assert_allclose(with_mass.center_of_gravity.low, per_mass.center_of_gravity.low, rtol=1e-12)
    doc = uncertainty_to_dict(per_mass)
    assert "inertia_per_mass" in doc and "principal_moments_per_mass" in doc and "inertia_tensor" not in doc


def test_spread_grows_linearly_with_noise_and_intervals_hold_the_estimate() -> None:
    pos, dirs, poles, shapes, mass = paper_sample()
    small = propagate(pos, dirs, poles, shapes, mass=mass, noise=NoiseLevels(shape=0.001), draws=1000, seed=3)
    large = propagate(pos, dirs, poles, shapes, mass=mass, noise=NoiseLevels(shape=0.002), draws=1000, seed=3)
    ratio = large.center_of_gravity.std / small.center_of_gravity.std
    np.testing.assert_allclose(ratio, 2.0, rtol=SPREAD_SCALING_REL)
    ratio = large.principal_moments.std / small.principal_moments.std
    np.testing.assert_allclose(ratio, 2.0, rtol=SPREAD_SCALING_REL)
    for q in (small.center_of_gravity, small.principal_moments, small.stiffness_diagonal, small.damping_diagonal):
        assert np.all(q.low < q.estimate) and np.all(q.estimate < q.high)
        assert np.all(q.std > 0.0)


def test_mass_noise_reaches_inertia_but_not_cg() -> None:
    pos, dirs, poles, shapes, mass = paper_sample()
    result = propagate(pos, dirs, poles, shapes, mass=mass, noise=NoiseLevels(mass=0.01), draws=400, seed=4)
    assert np.all(result.center_of_gravity.std <= ZERO_SPREAD_REL * 10.0)
    np.testing.assert_allclose(
        result.principal_moments.std / result.principal_moments.estimate, 0.01, rtol=SPREAD_SCALING_REL
    )


def test_seed_reproduces_and_changes() -> None:
    pos, dirs, poles, shapes, mass = paper_sample()
    a = propagate(pos, dirs, poles, shapes, mass=mass, noise=FULL_NOISE, draws=100, seed=9)
    b = propagate(pos, dirs, poles, shapes, mass=mass, noise=FULL_NOISE, draws=100, seed=9)
    c = propagate(pos, dirs, poles, shapes, mass=mass, noise=FULL_NOISE, draws=100, seed=10)
    np.testing.assert_array_equal(a.inertia.std, b.inertia.std)
    assert not np.array_equal(a.inertia.std, c.inertia.std)


def test_json_form() -> None:
    pos, dirs, poles, shapes, mass = paper_sample()
    result = propagate(pos, dirs, poles, shapes, mass=mass, noise=FULL_NOISE, draws=50, seed=1)
    doc = uncertainty_to_dict(result)
    text = json.dumps(doc, allow_nan=False)
    back = json.loads(text)
    assert set(back) >= {"center_of_gravity", "inertia_tensor", "principal_moments", "stiffness_diagonal",
                         "damping_diagonal", "draws", "failed", "noise"}  # fmt: skip
    cg = back["center_of_gravity"]
    assert len(cg["estimate"]) == 3 and len(cg["std"]) == 3
    assert np.array(cg["ci95"]).shape == (3, 2)
    assert np.array(back["inertia_tensor"]["ci95"]).shape == (3, 3, 2)
    np.testing.assert_allclose(np.array(cg["ci95"])[:, 0], result.center_of_gravity.low)
    assert back["draws"] == 50 and back["noise"]["angle_deg"] == 1.0


def test_too_many_failures_warn_and_all_failures_raise() -> None:
    pos, dirs, poles, shapes, _ = paper_sample()
    data = perturb(pos, dirs, poles, shapes, NoiseLevels(shape=0.01), 20, seed=1)
    batch = identify_batch(data.positions, data.directions, data.poles, data.shapes)
    estimate = {
        "center_of_gravity": np.zeros(3), "inertia": np.eye(3), "principal_moments": np.ones(3),
        "stiffness_diagonal": np.ones(6), "damping_diagonal": np.ones(6), "mass": np.asarray(np.nan),
    }  # fmt: skip
    fields = {f: getattr(batch, f) for f in Estimates.__dataclass_fields__}
    some = Estimates(**{**fields, "status": np.where(np.arange(20) >= 3, 0, 2).astype(np.int8)})
    with pytest.warns(IllConditionedWarning, match="3 of 20"):
        result = summarise(estimate, some, None, noise=NoiseLevels(), seed=None)
    assert result.failed == 3
    none = Estimates(**{**fields, "status": np.full(20, 2, dtype=np.int8)})
    with pytest.raises(IdentificationError, match="all 20"):
        summarise(estimate, none, None, noise=NoiseLevels(), seed=None)


def test_bad_inputs() -> None:
    pos, dirs, poles, shapes, _ = paper_sample()
    with pytest.raises(InputError):
        NoiseLevels(shape=-0.1)
    with pytest.raises(InputError):
        NoiseLevels(frequency=float("nan"))
    with pytest.raises(InputError):
        propagate(pos, dirs, poles, shapes, draws=0)
    with pytest.raises(InputError):
        propagate(pos, dirs, poles[:5], shapes[:, :5])
    with pytest.raises(IdentificationError):
        propagate(pos, np.tile([0.0, 0.0, 1.0], (6, 1)), poles, shapes, draws=10)


def test_tilt_directions() -> None:
    rng = np.random.default_rng(1)
    n = np.tile([0.0, 0.0, 1.0], (20000, 1))
    sigma = np.deg2rad(2.0)
    tilted = tilt_directions(n, sigma * rng.standard_normal(n.shape))
    np.testing.assert_allclose(np.linalg.norm(tilted, axis=1), 1.0, rtol=1e-12)
    angle = np.arccos(np.clip(tilted[:, 2], -1.0, 1.0))
    np.testing.assert_allclose(np.sqrt(np.mean(angle**2)), sigma * np.sqrt(2.0), rtol=0.02)
    np.testing.assert_allclose(tilt_directions(n[:1], [[0.0, 0.0, 0.3]]), n[:1], atol=1e-15)
    np.testing.assert_allclose(tilt_directions([[1.0, 0.0, 0.0]], [[0.0, 0.0, np.pi / 2]]), [[0.0, 1.0, 0.0]],
                               atol=1e-15)  # fmt: skip


def test_perturbation_levels() -> None:
    pos, dirs, poles, shapes, _ = paper_sample()
    noise = NoiseLevels(frequency=0.002, damping=0.1, shape=0.05, position=0.3, angle_deg=0.0)
    data = perturb(pos, dirs, poles, shapes, noise, 4000, seed=8)
    f0 = np.abs(poles)
    np.testing.assert_allclose(np.std(np.abs(data.poles) / f0, axis=0), 0.002, rtol=0.1)
    np.testing.assert_allclose(np.std(data.positions - pos, axis=0), 0.3, rtol=0.1)
    rms = np.sqrt(np.mean(np.abs(shapes) ** 2, axis=0))
    np.testing.assert_allclose(np.sqrt(np.mean(np.abs(data.shapes - shapes) ** 2, axis=(0, 1))) / rms, 0.05, rtol=0.05)
    np.testing.assert_array_equal(data.directions, np.broadcast_to(dirs, data.directions.shape))


def test_shape_noise_from_residuals_recovers_the_simulated_level() -> None:
    rng = np.random.default_rng(21)
    body = random_body(rng)
    pos, dirs = random_layout(rng, 12)
    exact = body_modes(body, pos, dirs)
    t = sensor_matrix(layout_frame(pos).to_local(pos), dirs)
    estimates = []
    for _ in range(40):
        noisy = add_noise(exact, shape=0.02, rng=rng)
        estimates.append(shape_noise_from_residuals(project_rigid(t, noisy.shapes)[1], 12))
    np.testing.assert_allclose(np.sqrt(np.mean(np.square(estimates))), 0.02, rtol=NOISE_ESTIMATE_REL)
    levels = estimate_noise(pos, dirs, add_noise(exact, shape=0.02, rng=rng).shapes)
    np.testing.assert_allclose(levels.shape, 0.02, rtol=0.5)
    assert levels.frequency == 0.001  # from DEFAULT_NOISE
    with pytest.raises(IdentificationError, match="more than six"):
        shape_noise_from_residuals([0.1] * 6, 6)
    assert estimate_noise(pos[:6], dirs[:6], exact.shapes[:6]).shape == 0.01  # six sensors: the default


def _simulated_test(rng: np.random.Generator, noise: NoiseLevels) -> tuple[Body, np.ndarray, np.ndarray, Modes]:
    """A random body and layout, measured with the given noise (geometry stated with error too)."""
    body = random_body(rng)
    true_pos, true_dirs = random_layout(rng, 9)
    noisy = add_noise(body_modes(body, true_pos, true_dirs), frequency=noise.frequency, damping=noise.damping,
                      shape=noise.shape, rng=rng)  # fmt: skip
    stated_pos = true_pos + noise.position * rng.standard_normal(true_pos.shape)
    stated_dirs = tilt_directions(true_dirs, np.deg2rad(noise.angle_deg) * rng.standard_normal(true_dirs.shape))
    return body, stated_pos, stated_dirs, noisy


def test_calibration_of_the_monte_carlo_spread() -> None:
    """50 simulated tests: the draws' spread is the estimate's error, ``z = (truth - estimate) / std``.

    The statistic is the median of the 300 ``|z|`` over its value for a normal error, 0.6745
    (robust to the heavy tail of the principal moments' errors): 1.11 here, 0.91-1.03 with three
    other seeds. Its standard deviation from ``n`` independent values is ``1.166 / sqrt(n)``
    (0.067; 0.09 observed over the seeds, the figures of one test are correlated), so the band is
    1 +- 3 of them; spreads 20 % too narrow give 1.38 here and fail. The coverage of the
    percentile intervals over 200 tests and 150 draws (0.952 CG, 0.933 moments) is
    ``benchmarks/mc_calibration.py``.
    """
    noise = NoiseLevels(frequency=0.001, damping=0.05, shape=0.01, position=0.01, angle_deg=1.0)
    rng = np.random.default_rng(2024)
    z = []
    for k in range(50):
        body, pos, dirs, modes = _simulated_test(rng, noise)
        result = propagate(pos, dirs, modes.poles, modes.shapes, mass=body.mass, noise=noise, draws=30, seed=k)
        truth = np.concatenate([body.center_of_gravity, np.linalg.eigvalsh(body.inertia_tensor)])
        cg, mom = result.center_of_gravity, result.principal_moments
        z.append((truth - np.concatenate([cg.estimate, mom.estimate])) / np.concatenate([cg.std, mom.std]))
    scale = float(np.median(np.abs(z)) / 0.6745)
    band = 3.0 * 1.166 / np.sqrt(np.size(z))
    assert abs(scale - 1.0) < band, (scale, band)


def test_progress_counts_the_draws_identified() -> None:
    pos, dirs, poles, shapes, mass = paper_sample()
    calls: list[tuple[str, float, float | None]] = []
    propagate(pos, dirs, poles, shapes, mass=mass, draws=50, seed=1, progress=lambda *a: calls.append(a))
    assert calls and calls[-1][1:] == (50, 50)
    assert all(0 < done <= 50 for _, done, _ in calls)
