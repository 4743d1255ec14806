"""Accelerance simulation against a direct evaluation about another origin."""

from __future__ import annotations

import numpy as np
import pytest

from rigidid.core.frf import ElasticMode, accelerance, random_elastic_modes
from rigidid.core.geometry import sensor_matrix, skew
from rigidid.errors import InputError
from tests.bodies import random_body, random_layout


def _direct(body, pos, dirs, rpos, rdirs, f_hz):
    """One frequency, rigid coordinates at the origin (not the CG), built from scratch."""
    c = body.center_of_gravity
    m_o = np.zeros((6, 6))
    m_o[:3, :3] = body.mass * np.eye(3)
    m_o[:3, 3:] = -body.mass * skew(c)
    m_o[3:, :3] = body.mass * skew(c)
    m_o[3:, 3:] = body.inertia_tensor - body.mass * skew(c) @ skew(c)
    k_o = np.zeros((6, 6))
    c_o = np.zeros((6, 6))
    for mount in body.mounts:
        t = np.hstack([np.eye(3), -skew(mount.position)])
        k_o += t.T @ mount.stiffness @ t
        c_o += t.T @ mount.damping @ t
    w = 2 * np.pi * f_hz
    t_s = sensor_matrix(pos, dirs)
    t_f = sensor_matrix(rpos, rdirs)
    out = np.empty((len(pos), len(rpos)), complex)
    for j in range(len(rpos)):
        x = np.linalg.solve(k_o - w**2 * m_o + 1j * w * c_o, t_f[j].astype(complex))
        out[:, j] = -(w**2) * t_s @ x
    return out


def test_accelerance_matches_direct_evaluation_about_the_origin():
    rng = np.random.default_rng(3)
    body = random_body(rng)
    pos, dirs = random_layout(rng, 8)
    rpos, rdirs = random_layout(rng, 3)
    freqs = np.array([2.0, 9.0, 40.0, 300.0])
    h = accelerance(body, pos, dirs, rpos, rdirs, freqs)
    assert h.shape == (8, 3, 4)
    for k, f in enumerate(freqs):
        np.testing.assert_allclose(h[:, :, k], _direct(body, pos, dirs, rpos, rdirs, f), rtol=1e-9, atol=1e-12)


def test_far_above_the_mounts_accelerance_is_the_mass_line():
    rng = np.random.default_rng(4)
    body = random_body(rng)
    pos, dirs = random_layout(rng, 6)
    rpos, rdirs = random_layout(rng, 2)
    h = accelerance(body, pos, dirs, rpos, rdirs, [1e5])[:, :, 0]
    m = np.zeros((6, 6))
    m[:3, :3] = body.mass * np.eye(3)
    m[3:, 3:] = body.inertia_tensor
    t = sensor_matrix(pos, dirs, body.center_of_gravity)
    tf = sensor_matrix(rpos, rdirs, body.center_of_gravity)
    np.testing.assert_allclose(h.real, t @ np.linalg.solve(m, tf.T), rtol=1e-5, atol=1e-9)


def test_elastic_mode_is_added_modally_and_noise_is_relative():
    rng = np.random.default_rng(5)
    body = random_body(rng)
    pos, dirs = random_layout(rng, 6)
    rpos, rdirs = random_layout(rng, 2)
    mode = ElasticMode(500.0, 0.02, rng.standard_normal(6), rng.standard_normal(2))
    freqs = np.array([100.0, 500.0])
    base = accelerance(body, pos, dirs, rpos, rdirs, freqs)
    with_mode = accelerance(body, pos, dirs, rpos, rdirs, freqs, elastic=[mode])
    w = 2 * np.pi * freqs[1]
    expected = -(w**2) / (2j * 0.02 * w * w) * np.outer(mode.sensor_shape, mode.reference_shape)
    np.testing.assert_allclose(with_mode[:, :, 1] - base[:, :, 1], expected, rtol=1e-9)
    noisy = accelerance(body, pos, dirs, rpos, rdirs, np.linspace(50, 60, 200), noise=0.01, rng=rng)
    exact = accelerance(body, pos, dirs, rpos, rdirs, np.linspace(50, 60, 200))
    rel = np.abs(noisy / exact - 1.0)
    assert 0.005 < np.sqrt(np.mean(rel**2)) < 0.02
    modes = random_elastic_modes(rng, [300.0, 400.0], 6, 2, mass=body.mass)
    assert [m.frequency for m in modes] == [300.0, 400.0]


def test_bad_arguments_are_refused():
    rng = np.random.default_rng(6)
    body = random_body(rng)
    pos, dirs = random_layout(rng, 6)
    with pytest.raises(InputError, match="positive"):
        accelerance(body, pos, dirs, pos[:1], dirs[:1], [0.0, 1.0])
    with pytest.raises(InputError, match="rng"):
        accelerance(body, pos, dirs, pos[:1], dirs[:1], [1.0], noise=0.01)
