"""Tests written against the plausible bugs of ``benchmarks/mutation.py`` that the suite let through.

Each test states the physics it guards and names its mutant; run the mutation script to see
each one fail when its bug is planted (issue 20, item 5).
"""

from __future__ import annotations

import numpy as np
import pytest

from rigidid.core.checks import percent_damping, sensor_outliers
from rigidid.core.frf import accelerance, random_elastic_modes
from rigidid.core.frfmodes import with_nonrigid_residual
from rigidid.core.geometry import sensor_matrix, transfer_matrix
from rigidid.core.identify import model_modes
from rigidid.core.layout_check import check_layout
from rigidid.core.massline import _noise_residual, mass_line
from rigidid.core.mounts import _OutputError, mount_rates, torque_roll_axis
from rigidid.core.noise import NoiseLevels, apply_noise, draw_normals, shape_noise_from_residuals
from rigidid.core.plan import _score
from rigidid.core.rigidfrf import mass_matrix_from_parameters
from rigidid.core.selection import elastic_suspect, project_rigid
from rigidid.core.simulate import Body, Mount, system_matrices
from rigidid.core.statespace import modal_from_poles, poles_from_modal
from rigidid.core.timedomain.preprocess import decimate
from rigidid.core.timedomain.refine import Refinement, pretrigger_sigma, record_bound
from rigidid.core.uncertainty import _percentile_interval
from tests.bodies import corner_references, random_body, random_layout


def _rotation(seed: int) -> np.ndarray:
    q, r = np.linalg.qr(np.random.default_rng(seed).standard_normal((3, 3)))
    q = q * np.sign(np.diag(r))
    return q * np.linalg.det(q)


RATES = np.array([[10.0, 25.0, 100.0], [20.0, 25.0, 140.0], [30.0, 25.0, 180.0], [40.0, 25.0, 220.0]])


def _body_on_rotated_mounts() -> tuple[Body, np.ndarray, np.ndarray]:
    """A body on four mounts whose principal axes are rotated, rates :data:`RATES`."""
    where = np.array([[-1.0, 0.5, -0.5], [1.0, 0.6, -0.4], [0.2, -1.0, -0.6], [-0.3, -0.8, -0.5]])
    axes = np.stack([_rotation(i) for i in range(4)])
    mounts = []
    for p, a, kv in zip(where, axes, RATES, strict=True):
        k = a @ np.diag(kv) @ a.T
        mounts.append(Mount.from_values(p, k, 0.02 * k))
    return Body(2.0, np.array([0.05, -0.02, 0.1]), np.diag([1.0, 1.5, 2.0]), tuple(mounts)), where, axes


# --- frfmodes.with_nonrigid_residual (mutant frf-residual-dof) --------------------------------


def test_nonrigid_residual_reads_back_as_the_noise_put_in() -> None:
    # noise of std sigma per sensor value leaves sqrt(p - 6) sigma after a rigid-body fit (6 of
    # the p dimensions go into the fit): the residual put back must read as sigma again through
    # noise.shape_noise_from_residuals, or every FRF-route uncertainty is off by sqrt(p / (p - 6))
    rng = np.random.default_rng(0)
    pos, dirs = random_layout(rng, 9)
    t = sensor_matrix(pos, dirs)
    scaled = t @ (rng.standard_normal((6, 1)) + 1j * rng.standard_normal((6, 1)))
    raw = 0.7 * scaled + 0.3 * (rng.standard_normal((9, 1)) + 1j * rng.standard_normal((9, 1)))
    sigma = 0.02 * float(np.sqrt(np.mean(np.abs(scaled) ** 2)))
    out = with_nonrigid_residual(scaled, raw, pos, dirs, noise=[sigma])
    _, rho = project_rigid(t, out)
    rms = float(np.sqrt(np.mean(np.abs(out) ** 2)))
    assert shape_noise_from_residuals(rho, 9) == pytest.approx(sigma / rms, rel=1e-9)


# --- massline (mutants massline-elastic-sign, third-difference-variance) ----------------------


def test_mass_line_with_an_elastic_mode_above_the_band_is_exact() -> None:
    # a free body whose first elastic mode (300 Hz) sits above the band: with its frequency given,
    # the upper residual is that mode's own term x / (1 - x), x = (w / w_e)^2, and the mass line
    # is exact (observed 1.6e-11; with x / (1 + x) it is 1.6e-2 off)
    rng = np.random.default_rng(1)
    body = random_body(rng)
    body = Body(body.mass, body.center_of_gravity, body.inertia_tensor,
                tuple(Mount(m.position, m.stiffness * 1e-4, m.damping * 1e-2) for m in body.mounts))  # fmt: skip
    pos, dirs = random_layout(rng, 8, centre=body.center_of_gravity)
    rpos = corner_references(pos)
    f = np.linspace(0.25, 400.0, 1600)
    elastic = random_elastic_modes(rng, [300.0], 8, 3, mass=body.mass, damping=1e-6)
    h = accelerance(body, pos, dirs, rpos, np.eye(3), f, elastic=elastic)
    r = mass_line(f, h, pos, dirs, rpos, np.eye(3), band=(20.0, 200.0), elastic_frequency=300.0,
                  supports="first_order")  # fmt: skip
    assert abs(r.mass / body.mass - 1.0) < 1e-9
    np.testing.assert_allclose(r.center_of_gravity, body.center_of_gravity, atol=1e-9)


def test_noise_residual_reads_white_noise_level() -> None:
    # white noise of variance s^2 gives third differences of variance (1 + 9 + 9 + 1) s^2 = 20 s^2
    rng = np.random.default_rng(2)
    s = 0.01
    misfit = s * rng.standard_normal((4000, 6))
    level = _noise_residual(misfit, np.ones(10), 0)
    assert level == pytest.approx(s, rel=0.05)  # 24 000 values: about 1.5 % scatter


# --- mounts (mutants mounts-norm-axis, mounts-output-damping-weight, axis-angle-sign) ---------


def test_mount_rates_do_not_depend_on_the_length_of_the_axis_vectors() -> None:
    # mount axes are directions: columns of axes[k] scaled by any positive factor (a layout file
    # in other units, unnormalised input) must give the same rates as the unit axes
    body, where, axes = _body_on_rotated_mounts()
    _, k, _ = system_matrices(body)
    unit = mount_rates(k, body.center_of_gravity, where, axes=axes)
    stretched = axes * np.array([0.5, 3.0, 7.0])[None, None, :]
    scaled = mount_rates(k, body.center_of_gravity, where, axes=stretched)
    np.testing.assert_allclose(unit.stiffness, RATES, rtol=1e-9)
    np.testing.assert_allclose(scaled.stiffness, unit.stiffness, rtol=1e-9)


def test_output_error_is_in_units_of_the_stated_noise() -> None:
    # each entry of the output error has unit variance when the noise is as given: a damping ratio
    # measured d (relative) off the model's reads d / noise.damping, a frequency f off f / noise.frequency
    body, where, _ = _body_on_rotated_mounts()
    m, k, c = system_matrices(body)
    j = m[3:, 3:] / body.mass
    lam, phi = model_modes(j, k / body.mass, c / body.mass)
    pos = np.vstack([where + 0.1, where - 0.2])
    dirs = np.tile(np.eye(3), (3, 1))[: pos.shape[0]]
    psi = sensor_matrix(pos, dirs, body.center_of_gravity) @ phi
    f, z = modal_from_poles(lam)
    measured = poles_from_modal(f * 1.002, z * 1.03)
    noise = NoiseLevels(frequency=0.001, damping=0.05, shape=0.01)
    out = _OutputError((pos, dirs), measured, psi, noise)(body.center_of_gravity, j, k / body.mass, c / body.mass)
    per = out.reshape(lam.size, -1)
    np.testing.assert_allclose(per[:, 0], (1.0 / 1.002 - 1.0) / 0.001, rtol=1e-6)
    np.testing.assert_allclose(per[:, 1], (1.0 / 1.03 - 1.0) / 0.05, rtol=1e-6)


def test_angle_to_a_principal_axis_ignores_its_sign() -> None:
    # axes are lines: a torque along -x of a body with principal axes x, y, z rolls it about
    # the x axis, 0 degrees from it (not 180)
    tra = torque_roll_axis(np.diag([1.0, 2.0, 3.0]), [-1.0, 0.0, 0.0])
    np.testing.assert_allclose(tra.angle_to_principal_deg, [0.0, 90.0, 90.0], atol=1e-9)


# --- selection.elastic_suspect (mutant suspect-median-includes-suspect) -----------------------


def test_an_elastic_suspect_does_not_raise_the_median_it_is_judged_by() -> None:
    # the reference a suspect is judged against excludes it: of two modes, an elastic one fitting
    # rigid motion to 0.3 against a rigid one at 0.01 is named (the median of both would be 0.155)
    assert elastic_suspect([0.01, 0.3]) == 1
    assert elastic_suspect([0.3, 0.01]) == 0


# --- checks (mutants sensor-check-leverage, sensor-check-typical-median, percent-damping-mean) -


def _loo_misfits(t: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """Each sensor's reading minus the rigid motion the other sensors give, over the mode RMS."""
    rms = np.sqrt(np.mean(np.abs(psi) ** 2, axis=0))
    out = np.full(t.shape[0], np.nan)
    for i in range(t.shape[0]):
        keep = np.arange(t.shape[0]) != i
        if np.linalg.matrix_rank(t[keep]) < np.linalg.matrix_rank(t):
            continue
        coords = np.linalg.lstsq(t[keep].astype(complex), psi[keep], rcond=None)[0]
        out[i] = np.sqrt(np.mean(np.abs((psi[i] - t[i] @ coords) / rms) ** 2))
    return out


def _misplaced(seed: int, uncheckable: bool) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = rng.standard_normal((11, 6))
    if uncheckable:  # sensors 0 and 1 alone see coordinates 0 and 1: no other sensor can check them
        t[2:, :2] = 0.0
        t[:2] = np.eye(6)[:2] + 0.0
    coords = rng.standard_normal((6, 3)) + 1j * rng.standard_normal((6, 3))
    psi = t @ coords + 1e-3 * (rng.standard_normal((11, 3)) + 1j * rng.standard_normal((11, 3)))
    psi[5] += 0.5 * np.mean(np.abs(psi), axis=0)  # sensor 5 reads something else
    return t, psi


def test_sensor_misfit_is_the_leave_one_out_prediction_error() -> None:
    # the misfit a finding reports is exactly how far the sensor's reading is from the rigid motion
    # fitted to the other sensors: r_i / (1 - h_ii), not the residual r_i it spoils itself
    t, psi = _misplaced(3, uncheckable=False)
    (finding,) = sensor_outliers(t, psi)
    loo = _loo_misfits(t, psi)
    assert finding.index == 5
    assert finding.misfit == pytest.approx(loo[5], rel=1e-9)


def test_typical_misfit_ignores_sensors_that_cannot_be_checked() -> None:
    # sensors that alone see a rigid motion have no leave-one-out misfit; the typical misfit is the
    # median over the sensors that can be checked, not pulled down by zeros for the others
    t, psi = _misplaced(4, uncheckable=True)
    (finding,) = sensor_outliers(t, psi)
    loo = _loo_misfits(t, psi)
    assert np.isnan(loo[:2]).all() and finding.index == 5
    assert finding.typical == pytest.approx(float(np.median(loo[2:])), rel=1e-9)


def test_one_heavily_damped_mode_does_not_look_like_percentages() -> None:
    # five modes at 1 % and one at 80 % (a mode on a damped support): the typical ratio is 1 %,
    # so nothing suggests the file holds percentages
    assert percent_damping([0.01, 0.01, 0.012, 0.01, 0.011, 0.8]) is None
    assert percent_damping([0.5, 0.4, 0.6, 0.5, 0.45, 0.55]) is not None


# --- noise (mutants shape-noise-dof, draw-complex-noise-scale) --------------------------------


def test_shape_noise_read_from_residuals_is_the_noise_drawn() -> None:
    # complex noise of std sigma (relative to each mode's RMS) drawn by apply_noise and read back
    # from the rigid-fit residuals: 300 draws x 6 modes x 2 (p - 6) = 25 200 real residual
    # dimensions give the level to about 0.45 % (std); allowed 2 %
    rng = np.random.default_rng(5)
    p, sigma = 9, 0.03
    pos, dirs = random_layout(rng, p)
    t = sensor_matrix(pos, dirs)
    shapes = t @ (rng.standard_normal((6, 6)) + 1j * rng.standard_normal((6, 6)))
    poles = poles_from_modal(np.linspace(3.0, 9.0, 6), np.full(6, 0.02))
    draws = apply_noise(draw_normals(rng, 300, p), NoiseLevels(shape=sigma), pos, dirs, poles, shapes, None)
    rho = np.concatenate([project_rigid(t, psi)[1] for psi in draws.shapes])
    assert shape_noise_from_residuals(rho, p) == pytest.approx(sigma, rel=0.02)


# --- uncertainty (mutant percentile-interval) --------------------------------------------------


def test_percentile_interval_holds_95_percent_of_the_draws() -> None:
    samples = np.random.default_rng(6).standard_normal((4000, 3))
    iv = _percentile_interval(np.zeros(3), samples)
    inside = np.mean((samples >= iv.low) & (samples <= iv.high), axis=0)
    np.testing.assert_allclose(inside, 0.95, atol=1e-3)  # by construction, to one draw in 1000


# --- rigidfrf (mutant rigid-mass-matrix-skew) -------------------------------------------------


def test_mass_matrix_from_parameters_is_a_bodys() -> None:
    # M about the origin of a body of mass m, CG g, inertia J_g: G^T diag(m I, J_g) G with
    # G = transfer_matrix(g) (the CG's motion from the origin's), eq. (12)
    m, g = 3.0, np.array([0.2, -0.1, 0.3])
    jg = np.array([[2.0, 0.1, -0.2], [0.1, 3.0, 0.3], [-0.2, 0.3, 4.0]])
    jo = jg + m * (g @ g * np.eye(3) - np.outer(g, g))
    theta = np.array([m, *(m * g), jo[0, 0], jo[1, 1], jo[2, 2], jo[0, 1], jo[0, 2], jo[1, 2]])
    gm = transfer_matrix(g)
    expected = gm.T @ np.block([[m * np.eye(3), np.zeros((3, 3))], [np.zeros((3, 3)), jg]]) @ gm
    np.testing.assert_allclose(mass_matrix_from_parameters(theta), expected, atol=1e-12)


# --- plan (mutant plan-score-units) -------------------------------------------------------------


def test_plan_score_is_dimensionless() -> None:
    # the score ranks layouts; the ranking must not depend on the length unit (m or mm)
    cg_std, rel = np.array([[1e-3, 2e-3, 0.5e-3]]), np.array([[0.01, 0.02, 0.015]])
    np.testing.assert_allclose(_score(cg_std * 1000.0, rel, 0.4 * 1000.0), _score(cg_std, rel, 0.4), rtol=1e-12)


# --- timedomain (mutants refine-interval-z, pretrigger-fir-gain) ------------------------------


def test_refit_intervals_are_95_percent_normal_intervals() -> None:
    ref = Refinement(
        center_of_gravity=np.array([0.1, 0.2, 0.3]), inertia_per_mass=np.diag([1.0, 2.0, 3.0]),
        stiffness_per_mass=np.eye(6) * 100.0, damping_per_mass=np.eye(6), poles=np.full(6, -1 + 10j),
        std={"center_of_gravity": np.array([0.01, 0.02, 0.03]), "inertia_per_mass": np.full((3, 3), 0.01),
             "stiffness_per_mass": np.full((6, 6), 1.0)},
        normalised_cost=1.0, noise_from="pretrigger", residuals=1000, evaluations=10, converged=True,
    )  # fmt: skip
    bound = record_bound(ref, 2.0)
    z = 1.959963984540054  # the 97.5 % point of the normal distribution
    for iv in (bound.center_of_gravity, bound.inertia, bound.principal_moments, bound.stiffness_diagonal):
        np.testing.assert_allclose(iv.high - iv.estimate, z * iv.std, rtol=1e-12)
        np.testing.assert_allclose(iv.estimate - iv.low, z * iv.std, rtol=1e-12)


@pytest.mark.parametrize("factor", [2, 4])
def test_pretrigger_noise_after_decimation_is_the_decimated_noise(factor: int) -> None:
    # the refit fits decimated decays: its noise level is that of white noise through the
    # decimation filter, sigma sqrt(sum h^2), measured here on 200 000 samples (0.2 % std)
    rng = np.random.default_rng(7)
    x = 0.3 * rng.standard_normal((200_000, 2))
    level, source = pretrigger_sigma([x.shape[0]], [np.sum((x - x.mean(axis=0)) ** 2, axis=0)], 1, factor)
    assert source == "pretrigger"
    np.testing.assert_allclose(level, np.std(decimate(x, factor), axis=0), rtol=0.02)


# --- layout_check (mutant layout-antiparallel) ------------------------------------------------


def test_a_reversed_sensor_next_to_another_is_as_redundant_as_a_parallel_one() -> None:
    # a sensor measures along a line, not a sense: two sensors 1 cm apart along +x and -x read
    # the same motion (one negated) exactly as +x and +x do, and both pairs are flagged
    rng = np.random.default_rng(8)
    pos, dirs = random_layout(rng, 8)
    pos[1], dirs[0], dirs[1] = pos[0] + 0.01, [1.0, 0.0, 0.0], [1.0, 0.0, 0.0]
    same = {f.sensors for f in check_layout(pos, dirs).findings if f.code == "redundant-pair"}
    dirs[1] = [-1.0, 0.0, 0.0]
    reversed_ = {f.sensors for f in check_layout(pos, dirs).findings if f.code == "redundant-pair"}
    assert (1, 2) in same and reversed_ == same
