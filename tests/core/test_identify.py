"""Identification: exact recovery of simulated bodies, both routes, diagnostics and warnings."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from rigidid.core.identify import identify, principal_axes
from rigidid.core.simulate import Body, Modes, Mount, add_noise, body_modes, system_matrices
from rigidid.errors import IdentificationError, IllConditionedWarning, InputError, PhysicalPlausibilityWarning

from ..bodies import flat_layout_on_symmetric_mounts, random_body, random_layout
from ..tolerances import EXACT_REL


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def _assert_recovers(body: Body, result_seed: int, positions: np.ndarray, directions: np.ndarray) -> None:
    modes = body_modes(body, positions, directions)
    r = identify(positions, directions, modes.poles, modes.shapes, mass=body.mass)
    _, k, c = system_matrices(body)
    assert r.inertia_tensor is not None and r.stiffness_matrix is not None and r.damping_matrix is not None
    span = np.ptp(positions, axis=0).max()
    assert np.linalg.norm(r.center_of_gravity - body.center_of_gravity) / span < EXACT_REL, result_seed
    assert _rel(r.inertia_tensor, body.inertia_tensor) < EXACT_REL
    assert _rel(r.stiffness_matrix, k) < EXACT_REL
    assert _rel(r.damping_matrix, c) < EXACT_REL
    assert r.diagnostics.structure_residual < EXACT_REL
    assert r.diagnostics.warnings == ()
    np.testing.assert_allclose(r.diagnostics.model_mac, 1.0, atol=1e-9)


@pytest.mark.parametrize("seed", range(12))
def test_exact_recovery_of_random_bodies(seed: int) -> None:
    """Non-proportional damping, 6 to 24 sensors, skewed directions, any origin and scale."""
    rng = np.random.default_rng(seed)
    scale = float(10.0 ** rng.uniform(-2, 3))  # metres to millimetres
    body = random_body(rng, n_mounts=int(rng.integers(3, 6)), scale=scale)
    n_sensors = [6, 7, 9, 12, 24][seed % 5]
    centre = body.center_of_gravity + scale * rng.uniform(-3, 3, 3)
    positions, directions = random_layout(rng, n_sensors, scale=1.5 * scale, centre=centre, skewed=seed % 3 != 0)
    _assert_recovers(body, seed, positions, directions)


def _identical_mounts_rig() -> tuple[Body, np.ndarray, np.ndarray]:
    mounts = tuple(
        Mount.from_values([x, y, -2.5], [45000.0, 45000.0, 70000.0], [60.0, 60.0, 35.0])
        for x, y in ((7.0, 3.0), (-6.0, 4.5), (-2.0, -6.0))
    )
    inertia = np.array([[2652.0, 40.0, -25.0], [40.0, 3087.0, 15.0], [-25.0, 15.0, 5440.0]])
    body = Body(136.0, np.array([0.0, 0.0, -1.4]), inertia, mounts)
    positions, directions = random_layout(np.random.default_rng(5), 8, scale=9.0, skewed=False)
    return body, positions, directions


def test_exact_recovery_identical_mounts_at_one_height() -> None:
    """The paper's own rig type, where the sequential route's Q21 is singular."""
    body, positions, directions = _identical_mounts_rig()
    _assert_recovers(body, 0, positions, directions)


def test_paper_route_refuses_identical_mounts_at_one_height() -> None:
    body, positions, directions = _identical_mounts_rig()
    modes = body_modes(body, positions, directions)
    # Q21 is singular in exact arithmetic; eq. (26)'s approximation leaves it merely ill-conditioned
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        r = identify(positions, directions, modes.poles, modes.shapes, mass=body.mass, method="paper")
    assert any(issubclass(w.category, IllConditionedWarning) and "Q21" in str(w.message) for w in record)
    assert r.inertia_tensor is not None
    assert _rel(r.inertia_tensor, body.inertia_tensor) > 0.01


def test_paper_route_is_exact_for_proportional_damping_and_generic_mounts() -> None:
    rng = np.random.default_rng(11)
    body = random_body(rng, proportional=True)
    positions, directions = random_layout(rng, 10)
    modes = body_modes(body, positions, directions)
    r = identify(positions, directions, modes.poles, modes.shapes, mass=body.mass, method="paper")
    assert r.inertia_tensor is not None
    assert _rel(r.inertia_tensor, body.inertia_tensor) < EXACT_REL
    assert np.linalg.norm(r.center_of_gravity - body.center_of_gravity) < EXACT_REL


def test_without_mass_only_per_mass_results() -> None:
    rng = np.random.default_rng(2)
    body = random_body(rng)
    positions, directions = random_layout(rng, 8)
    modes = body_modes(body, positions, directions)
    r = identify(positions, directions, modes.poles, modes.shapes)
    assert r.mass is None and r.inertia_tensor is None and r.stiffness_matrix is None and r.principal_moments is None
    assert _rel(r.inertia_per_mass, body.inertia_tensor / body.mass) < EXACT_REL


def test_model_modes_reproduce_measured_poles() -> None:
    rng = np.random.default_rng(4)
    body = random_body(rng)
    positions, directions = random_layout(rng, 7)
    modes = body_modes(body, positions, directions)
    r = identify(positions, directions, modes.poles, modes.shapes, mass=body.mass)
    poles, shapes = r.model_modes()
    np.testing.assert_allclose(poles, modes.poles, rtol=EXACT_REL)
    assert shapes.shape == (6, 6)


def test_principal_axes_form_a_right_handed_frame(rng: np.random.Generator) -> None:
    q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    tensor = q @ np.diag([1.0, 2.0, 2.5]) @ q.T
    moments, axes = principal_axes(tensor)
    np.testing.assert_allclose(moments, [1.0, 2.0, 2.5])
    np.testing.assert_allclose(axes.T @ axes, np.eye(3), atol=1e-12)
    assert np.linalg.det(axes) == pytest.approx(1.0)
    np.testing.assert_allclose(axes @ np.diag(moments) @ axes.T, tensor, atol=1e-12)


def test_impossible_result_warns_and_is_listed() -> None:
    rng = np.random.default_rng(8)
    body = random_body(rng)
    positions, directions = random_layout(rng, 8)
    modes = body_modes(body, positions, directions)
    shapes = modes.shapes + 0.3 * rng.standard_normal(modes.shapes.shape)
    with pytest.warns(PhysicalPlausibilityWarning) as record:
        r = identify(positions, directions, modes.poles, shapes, mass=body.mass)
    assert r.diagnostics.warnings
    assert {str(w.message) for w in record} == set(r.diagnostics.warnings)


def test_rank_deficient_layout_is_an_identification_error() -> None:
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0], [1, 2, 0]], dtype=float)
    directions = np.tile([0.0, 0.0, 1.0], (6, 1))
    poles = np.array([-0.1 + 10j] * 6) * np.arange(1, 7)
    with pytest.raises(IdentificationError, match="rank 3"):
        identify(positions, directions, poles, np.eye(6, dtype=complex))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [({"mass": -1.0}, "mass"), ({"method": "magic"}, "unknown method")],
)
def test_bad_arguments(kwargs: dict[str, object], match: str) -> None:
    rng = np.random.default_rng(1)
    body = random_body(rng)
    positions, directions = random_layout(rng, 6)
    modes = body_modes(body, positions, directions)
    with pytest.raises(InputError, match=match):
        identify(positions, directions, modes.poles, modes.shapes, **kwargs)  # type: ignore[arg-type]


def test_wrong_number_of_modes_is_an_input_error() -> None:
    rng = np.random.default_rng(1)
    body = random_body(rng)
    positions, directions = random_layout(rng, 6)
    modes = body_modes(body, positions, directions)
    five = Modes(modes.poles[:5], modes.shapes[:, :5])
    with pytest.raises(InputError, match="six"):
        identify(positions, directions, five.poles, five.shapes)


def test_no_warning_leaks_for_clean_data() -> None:
    rng = np.random.default_rng(3)
    body = random_body(rng)
    positions, directions = random_layout(rng, 9)
    modes = body_modes(body, positions, directions)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        identify(positions, directions, modes.poles, modes.shapes, mass=body.mass)


def _decoupled_body() -> Body:
    """Mounts symmetric about the CG: the stiffness at the CG is diagonal."""
    mounts = tuple(
        Mount.from_values(p, [1e4, 2e4, 3e4], [10.0, 10.0, 10.0])
        for p in ([1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0])
    )
    return Body(10.0, np.zeros(3), np.diag([1.0, 2.0, 2.5]), mounts)


def test_unobservable_inertia_is_an_identification_error() -> None:
    body = _decoupled_body()
    positions, directions = random_layout(np.random.default_rng(0), 8)
    modes = body_modes(body, positions, directions)
    with pytest.raises(IdentificationError, match="inertia is not observable"):
        identify(positions, directions, modes.poles, modes.shapes, mass=body.mass)


def test_weakly_observable_inertia_warns() -> None:
    body = _decoupled_body()
    positions, directions = random_layout(np.random.default_rng(0), 8)
    modes = add_noise(body_modes(body, positions, directions), shape=0.005, seed=1)
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        r = identify(positions, directions, modes.poles, modes.shapes, mass=body.mass)
    assert r.diagnostics.inertia_observability < 0.03
    assert any(issubclass(w.category, IllConditionedWarning) and "poorly determined" in str(w.message) for w in record)


def test_observability_of_a_coupled_rig_is_high() -> None:
    body, positions, directions = _identical_mounts_rig()
    modes = body_modes(body, positions, directions)
    r = identify(positions, directions, modes.poles, modes.shapes, mass=body.mass)
    assert r.diagnostics.inertia_observability > 0.05


def test_measured_shapes_at_the_cg_match_the_body_modes() -> None:
    rng = np.random.default_rng(6)
    body = random_body(rng)
    positions, directions = random_layout(rng, 9)
    modes = body_modes(body, positions, directions)
    r = identify(positions, directions, modes.poles, modes.shapes, mass=body.mass)
    m, k, c = system_matrices(body)
    a = np.block([[-np.linalg.solve(m, c), -np.linalg.solve(m, k)], [np.eye(6), np.zeros((6, 6))]])
    mu, vec = np.linalg.eig(a)
    for col in range(6):
        truth = vec[6:, np.argmin(np.abs(mu - modes.poles[col]))]
        mac = abs(np.vdot(truth, r.mode_shapes_cg[:, col])) ** 2 / (np.vdot(truth, truth).real)
        assert mac == pytest.approx(1.0, abs=1e-9)


def test_a_warning_before_an_error_reaches_the_caller() -> None:
    """Notices are emitted when the error is known, not lost with it."""
    body, pos, dirs = flat_layout_on_symmetric_mounts()
    modes = body_modes(body, pos, dirs)
    with (
        pytest.warns(IllConditionedWarning, match="ill-conditioned"),
        pytest.raises(IdentificationError, match="not observable"),
    ):
        identify(pos, dirs, modes.poles, modes.shapes, mass=body.mass)


def test_quiet_identification_keeps_its_findings_in_the_diagnostics() -> None:
    _, positions, directions = flat_layout_on_symmetric_mounts()
    body = random_body(np.random.default_rng(3))
    modes = body_modes(body, positions, directions)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = identify(positions, directions, modes.poles, modes.shapes, warn=False)
    assert any("ill-conditioned" in w for w in result.diagnostics.warnings)
    with pytest.warns(IllConditionedWarning, match="ill-conditioned"):
        identify(positions, directions, modes.poles, modes.shapes)
