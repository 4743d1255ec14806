"""Modal parameters to M^-1 K and M^-1 C: eq. (19) exactly, eqs. (25)-(26) approximately."""

from __future__ import annotations

import numpy as np
import pytest

from rigidid.core.simulate import system_matrices
from rigidid.core.statespace import modal_from_poles, poles_from_modal, state_matrices, state_matrices_paper
from rigidid.errors import IdentificationError, InputError

from ..bodies import random_body
from ..tolerances import EXACT_REL


def _cg_modes(seed: int, proportional: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    body = random_body(rng, proportional=proportional)
    m, k, c = system_matrices(body)
    a = np.block([[-np.linalg.solve(m, c), -np.linalg.solve(m, k)], [np.eye(6), np.zeros((6, 6))]])
    mu, vec = np.linalg.eig(a)
    upper = mu.imag > 0
    return mu[upper], vec[6:, upper], np.linalg.solve(m, k), np.linalg.solve(m, c)


@pytest.mark.parametrize("seed", range(5))
def test_eq19_is_exact_for_non_proportional_damping(seed: int) -> None:
    poles, shapes, mk, mc = _cg_modes(seed, proportional=False)
    q, p = state_matrices(poles, shapes)
    np.testing.assert_allclose(q, mk, rtol=0, atol=EXACT_REL * np.abs(mk).max())
    np.testing.assert_allclose(p, mc, rtol=0, atol=EXACT_REL * np.abs(mk).max() ** 0.5)


def test_eq19_is_invariant_to_mode_scaling(rng: np.random.Generator) -> None:
    poles, shapes, mk, _ = _cg_modes(3, proportional=False)
    scale = rng.standard_normal(6) + 1j * rng.standard_normal(6)
    q, _ = state_matrices(poles, shapes * scale)
    np.testing.assert_allclose(q, mk, atol=EXACT_REL * np.abs(mk).max())


def test_eq26_exact_only_for_proportional_damping() -> None:
    poles, shapes, mk, mc = _cg_modes(1, proportional=True)
    q, p = state_matrices_paper(poles, shapes)
    np.testing.assert_allclose(q, mk, atol=EXACT_REL * np.abs(mk).max())
    np.testing.assert_allclose(p, mc, atol=EXACT_REL * np.abs(mk).max() ** 0.5)
    poles, shapes, mk, mc = _cg_modes(1, proportional=False)
    _, p = state_matrices_paper(poles, shapes)
    assert np.abs(p - mc).max() > 1e-3 * np.abs(mc).max()


def test_poles_round_trip() -> None:
    f, z = np.array([1.0, 6.1, 120.0]), np.array([0.0, 0.0039, 0.3])
    f2, z2 = modal_from_poles(poles_from_modal(f, z))
    np.testing.assert_allclose(f2, f)
    np.testing.assert_allclose(z2, z, atol=1e-15)


@pytest.mark.parametrize(("f", "z"), [(-1.0, 0.01), (0.0, 0.01), (1.0, 1.0), (1.0, -0.1), (float("nan"), 0.0)])
def test_poles_reject_invalid(f: float, z: float) -> None:
    with pytest.raises(InputError):
        poles_from_modal([f], [z])


def test_singular_modal_matrix_is_an_identification_error() -> None:
    poles = poles_from_modal(np.arange(1.0, 7.0), np.full(6, 0.01))
    shapes = np.ones((6, 6), dtype=complex)
    with pytest.raises(IdentificationError):
        state_matrices(poles, shapes)
