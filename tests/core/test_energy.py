"""Kinetic-energy distribution (decoupling table) of rigid-body modes."""

from __future__ import annotations

import numpy as np
import pytest

from rigidid.core.energy import (
    DOF_LABELS,
    PRINCIPAL_DOF_LABELS,
    kinetic_energy_distribution,
    kinetic_energy_distribution_principal,
)
from rigidid.core.identify import identify, principal_axes
from rigidid.core.simulate import Body, Mount, body_modes, system_matrices
from rigidid.errors import InputError

from ..bodies import random_body, random_layout


def cg_modes(body: Body) -> tuple[np.ndarray, np.ndarray]:
    """Poles (Im > 0) and 6xN CG shapes of a body on its mounts (state-space, damped)."""
    m, k, c = system_matrices(body)
    a = np.block([[-np.linalg.solve(m, c), -np.linalg.solve(m, k)], [np.eye(6), np.zeros((6, 6))]])
    mu, vec = np.linalg.eig(a)
    upper = np.flatnonzero(mu.imag > 0)
    order = upper[np.argsort(np.abs(mu[upper]))]
    return mu[order], vec[6:, order]


def decoupled_body() -> Body:
    """Four mounts in the CG's horizontal plane, symmetric: K at the CG is diagonal."""
    mounts = tuple(
        Mount.from_values((sx * 0.4, sy * 0.25, 0.0), (3.0e4, 5.0e4, 9.0e4), (20.0, 30.0, 40.0))
        for sx in (-1, 1)
        for sy in (-1, 1)
    )
    return Body(50.0, np.zeros(3), np.diag([1.1, 2.3, 3.7]), mounts)


def test_labels() -> None:
    assert DOF_LABELS == ("x", "y", "z", "rx", "ry", "rz")
    assert PRINCIPAL_DOF_LABELS == ("x", "y", "z", "r1", "r2", "r3")


def test_hand_computed_real_mode() -> None:
    jm = np.diag([4.0, 2.0, 1.0])
    phi = np.array([[1.0, 0.0, 0.0, 0.0, 0.0, 1.0], [0.0, 2.0, 0.0, 1.0, 0.0, 0.0]]).T
    table = kinetic_energy_distribution(jm, phi)
    np.testing.assert_allclose(table[0], [0.5, 0, 0, 0, 0, 0.5])
    np.testing.assert_allclose(table[1], [0, 0.5, 0, 0.5, 0, 0])


def test_decoupled_body_gives_permutation_table() -> None:
    body = decoupled_body()
    _, k, _ = system_matrices(body)
    assert np.allclose(k, np.diag(np.diag(k)))  # the premise: no coupling at the CG
    _, phi = cg_modes(body)
    jm = body.inertia_tensor / body.mass
    for table in (kinetic_energy_distribution(jm, phi), kinetic_energy_distribution_principal(jm, phi)):
        assert table.shape == (6, 6)
        assert np.allclose(np.sort(table, axis=1)[:, :-1], 0.0, atol=1e-12)
        np.testing.assert_allclose(np.max(table, axis=1), 1.0, atol=1e-12)
        # every DOF is the home of exactly one mode
        assert sorted(np.argmax(table, axis=1).tolist()) == list(range(6))


@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_rows_sum_to_one_and_principal_is_nonnegative(seed: int) -> None:
    rng = np.random.default_rng(seed)
    body = random_body(rng, proportional=False, damping=0.05)
    _, phi = cg_modes(body)
    assert np.max(np.abs(phi.imag)) > 1e-6 * np.max(np.abs(phi))  # complex modes indeed
    jm = body.inertia_tensor / body.mass
    plain = kinetic_energy_distribution(jm, phi)
    principal = kinetic_energy_distribution_principal(jm, phi)
    np.testing.assert_allclose(plain.sum(axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(principal.sum(axis=1), 1.0, atol=1e-12)
    assert np.all(principal >= -1e-14)
    # translations are untouched, and the rotational total is the same in both frames
    np.testing.assert_allclose(principal[:, :3], plain[:, :3], atol=1e-12)
    np.testing.assert_allclose(principal[:, 3:].sum(axis=1), plain[:, 3:].sum(axis=1), atol=1e-12)


def test_layout_frame_fractions_can_be_negative_with_products_of_inertia() -> None:
    jm = np.array([[2.0, -1.5, 0.0], [-1.5, 2.0, 0.0], [0.0, 0.0, 1.0]])
    phi = np.array([[0.0, 0.0, 0.0, 1.0, 0.2, 0.0]]).T
    plain = kinetic_energy_distribution(jm, phi)
    assert plain[0, 4] < 0.0
    assert np.all(kinetic_energy_distribution_principal(jm, phi) >= 0.0)


def test_invariant_to_mode_scaling() -> None:
    rng = np.random.default_rng(7)
    body = random_body(rng, proportional=False)
    _, phi = cg_modes(body)
    jm = body.inertia_tensor / body.mass
    scale = rng.standard_normal(6) + 1j * rng.standard_normal(6)
    for f in (kinetic_energy_distribution, kinetic_energy_distribution_principal):
        np.testing.assert_allclose(f(jm, phi * scale), f(jm, phi), atol=1e-12)


def test_complex_mode_is_the_cycle_average_of_kinetic_energy() -> None:
    rng = np.random.default_rng(11)
    a = rng.standard_normal((3, 3))
    jm = a @ a.T + 3.0 * np.eye(3)
    phi = rng.standard_normal(6) + 1j * rng.standard_normal(6)
    mass = np.eye(6)
    mass[3:, 3:] = jm
    t = np.linspace(0.0, 2.0 * np.pi, 400, endpoint=False)  # one period, omega = 1
    velocity = np.real(1j * phi[:, None] * np.exp(1j * t)[None, :])  # (6, times)
    per_dof = np.mean(velocity * (mass @ velocity), axis=1)
    expected = per_dof / per_dof.sum()
    np.testing.assert_allclose(kinetic_energy_distribution(jm, phi[:, None])[0], expected, atol=1e-12)


def test_principal_frame_is_independent_of_the_test_axes() -> None:
    rng = np.random.default_rng(5)
    body = random_body(rng, proportional=False)
    _, phi = cg_modes(body)
    jm = body.inertia_tensor / body.mass
    q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    rotated_phi = np.vstack([q @ phi[:3], q @ phi[3:]])
    before = kinetic_energy_distribution_principal(jm, phi)
    after = kinetic_energy_distribution_principal(q @ jm @ q.T, rotated_phi)
    np.testing.assert_allclose(after[:, 3:], before[:, 3:], atol=1e-10)
    np.testing.assert_allclose(after[:, :3].sum(axis=1), before[:, :3].sum(axis=1), atol=1e-10)


def test_principal_columns_follow_principal_axes() -> None:
    jm = np.array([[3.0, 1.0, 0.0], [1.0, 3.0, 0.0], [0.0, 0.0, 1.0]])
    moments, axes = principal_axes(jm)
    phi = np.concatenate([np.zeros(3), axes[:, 1]])[:, None]  # rotation about principal axis 2 only
    np.testing.assert_allclose(kinetic_energy_distribution_principal(jm, phi)[0], [0, 0, 0, 0, 1, 0], atol=1e-12)
    assert moments[1] == pytest.approx(2.0)


@pytest.mark.parametrize(
    ("inertia", "shapes", "match"),
    [
        (np.eye(2), np.ones((6, 1)), "3x3"),
        (np.eye(3), np.ones((5, 1)), r"\(6, modes\)"),
        (np.eye(3), np.ones(6), r"\(6, modes\)"),
        (np.eye(3), np.zeros((6, 2)), "mode 1 has no positive kinetic energy"),
        (-np.eye(3), np.array([[0, 0, 0, 1.0, 0, 0]]).T, "mode 1 has no positive"),
        (np.eye(3) * np.nan, np.ones((6, 1)), "finite"),
    ],
)
def test_bad_input(inertia: np.ndarray, shapes: np.ndarray, match: str) -> None:
    for f in (kinetic_energy_distribution, kinetic_energy_distribution_principal):
        with pytest.raises(InputError, match=match):
            f(inertia, shapes)


def test_table_of_an_identified_body_matches_the_true_body() -> None:
    rng = np.random.default_rng(8)
    body = random_body(rng, proportional=False)
    positions, directions = random_layout(rng, 8, scale=1.5)
    modes = body_modes(body, positions, directions)
    ident = identify(positions, directions, modes.poles, modes.shapes, mass=body.mass)
    _, shapes = ident.model_modes()  # ascending frequency, like cg_modes
    _, true_shapes = cg_modes(body)
    true_jm = body.inertia_tensor / body.mass
    for f in (kinetic_energy_distribution, kinetic_energy_distribution_principal):
        np.testing.assert_allclose(f(ident.inertia_per_mass, shapes), f(true_jm, true_shapes), atol=1e-7)
