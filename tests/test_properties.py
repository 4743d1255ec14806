"""Invariances of the identification (hypothesis): origin, rotation, sensor order, mode scaling."""

from __future__ import annotations

import warnings

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rigidid.core.identify import Identification
from rigidid.core.identify import identify as _identify
from rigidid.core.simulate import add_noise, body_modes
from rigidid.errors import RigididWarning

from .bodies import random_body, random_layout
from .tolerances import INVARIANCE_REL

seeds = st.integers(min_value=0, max_value=2**31 - 1)


def identify(*args: object, **kwargs: object) -> Identification:
    """Identify, with rigidid's warnings (expected for some random draws) ignored locally."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RigididWarning)
        return _identify(*args, **kwargs)  # type: ignore[arg-type]


def _case(seed: int, noisy: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    rng = np.random.default_rng(seed)
    body = random_body(rng)
    positions, directions = random_layout(rng, int(rng.integers(7, 13)))
    modes = body_modes(body, positions, directions)
    if noisy:  # invariances must hold for inconsistent (measured-like) data too
        modes = add_noise(modes, frequency=1e-3, damping=0.02, shape=0.003, rng=rng)
    return positions, directions, modes.poles, modes.shapes, body.mass


def _close(a: np.ndarray, b: np.ndarray, scale: float | None = None) -> None:
    ref = scale if scale is not None else float(np.abs(b).max())
    np.testing.assert_allclose(a, b, rtol=0, atol=INVARIANCE_REL * ref)


@settings(max_examples=15, deadline=None)
@given(seed=seeds, noisy=st.booleans(), shift=st.tuples(*[st.floats(-50, 50)] * 3))
def test_origin_shift_moves_only_the_cg(seed: int, noisy: bool, shift: tuple[float, float, float]) -> None:
    positions, directions, poles, shapes, mass = _case(seed, noisy)
    a = identify(positions, directions, poles, shapes, mass=mass)
    b = identify(positions + np.array(shift), directions, poles, shapes, mass=mass)
    _close(b.center_of_gravity - np.array(shift), a.center_of_gravity, 1.0 + float(np.abs(shift).max()))
    _close(b.inertia_per_mass, a.inertia_per_mass)
    _close(b.stiffness_per_mass, a.stiffness_per_mass)


def _rotation(seed: int) -> np.ndarray:
    q, r = np.linalg.qr(np.random.default_rng(seed).standard_normal((3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def _rotated(res: Identification, rot: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    big = np.kron(np.eye(2), rot)
    return rot @ res.center_of_gravity, rot @ res.inertia_per_mass @ rot.T, big @ res.stiffness_per_mass @ big.T


@settings(max_examples=15, deadline=None)
@given(seed=seeds, noisy=st.booleans(), rot_seed=seeds)
def test_rotating_the_axes_rotates_the_result(seed: int, noisy: bool, rot_seed: int) -> None:
    positions, directions, poles, shapes, mass = _case(seed, noisy)
    rot = _rotation(rot_seed)
    a = identify(positions, directions, poles, shapes, mass=mass)
    b = identify(positions @ rot.T, directions @ rot.T, poles, shapes, mass=mass)
    cg, inertia, stiffness = _rotated(a, rot)
    _close(b.center_of_gravity, cg, 1.0 + float(np.abs(cg).max()))
    _close(b.inertia_per_mass, inertia)
    _close(b.stiffness_per_mass, stiffness)


@settings(max_examples=15, deadline=None)
@given(seed=seeds, noisy=st.booleans(), data=st.data())
def test_sensor_order_and_mode_scaling_do_not_matter(seed: int, noisy: bool, data: st.DataObject) -> None:
    positions, directions, poles, shapes, mass = _case(seed, noisy)
    order = np.array(data.draw(st.permutations(range(len(positions)))))
    phase = np.array(data.draw(st.lists(st.floats(0, 2 * np.pi), min_size=6, max_size=6)))
    size = np.array(data.draw(st.lists(st.floats(1e-3, 1e3), min_size=6, max_size=6)))
    a = identify(positions, directions, poles, shapes, mass=mass)
    b = identify(positions[order], directions[order], poles, shapes[order] * size * np.exp(1j * phase), mass=mass)
    _close(b.center_of_gravity, a.center_of_gravity, 1.0 + float(np.abs(a.center_of_gravity).max()))
    _close(b.inertia_per_mass, a.inertia_per_mass)
    _close(b.damping_per_mass, a.damping_per_mass)
