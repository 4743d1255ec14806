"""Data-driven intervals from interleaved segments of impact records."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from rigidid import api
from rigidid.core.identify import Identification, identify
from rigidid.core.record_spread import record_spread
from rigidid.core.simulate import Body
from rigidid.core.timedomain import estimate_modes, impulse_records
from rigidid.errors import InputError, RigididWarning
from rigidid.io.files import layout_arrays, load_body, load_layout
from rigidid.jsonout import record_spread_to_dict

from ..conftest import SAMPLES

ENGINE = SAMPLES / "engine-on-mounts"
RATE = 512.0


def _engine(noise: float, seed: int) -> tuple[Body, np.ndarray, np.ndarray, list[np.ndarray], Identification]:
    body = api.body_from_file(load_body(ENGINE / "body.json"))
    _, positions, directions = layout_arrays(load_layout(ENGINE / "layout.json"))
    impacts = [(positions[0], (1.0, 1.0, 1.0)), (positions[5], (-1.0, 1.0, -1.0))]
    records = impulse_records(
        body, positions, directions, impacts, sample_rate=RATE, duration=8.0, pretrigger=0.1, noise=noise, seed=seed
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RigididWarning)
        est = estimate_modes(records, 1.0 / RATE)
        full = identify(positions, directions, est.poles, est.shapes, mass=body.mass)
    return body, positions, directions, records, full


def test_interval_holds_the_truth_at_five_percent_noise() -> None:
    body, positions, directions, records, full = _engine(0.05, seed=2)
    spread = record_spread(records, 1.0 / RATE, positions, directions, full, segments=8, mass=body.mass)
    assert spread.used == 8
    cg = spread.center_of_gravity
    assert np.all(cg.std > 0)
    assert np.all((cg.low <= body.center_of_gravity) & (body.center_of_gravity <= cg.high))
    moments = np.linalg.eigvalsh(body.inertia_tensor)
    pm = spread.principal_moments
    assert np.all((pm.low <= moments) & (moments <= pm.high))
    data = record_spread_to_dict(spread)
    assert data["segments"] == 8 and len(data["center_of_gravity"]["ci95"]) == 3


def test_noise_free_records_give_a_negligible_spread() -> None:
    body, positions, directions, records, full = _engine(0.0, seed=0)
    spread = record_spread(records, 1.0 / RATE, positions, directions, full, segments=4, mass=body.mass)
    span = np.ptp(positions, axis=0).max()
    assert np.all(spread.center_of_gravity.std < 1e-6 * span)


def test_needs_two_segments() -> None:
    _, positions, directions, records, full = _engine(0.0, seed=0)
    with pytest.raises(InputError, match="at least 2 segments"):
        record_spread(records, 1.0 / RATE, positions, directions, full, segments=1)


def test_std_is_the_segment_spread_over_root_k() -> None:
    """std = std(segment estimates, ddof=1) / sqrt(K): the segments hold 1/K of the data each."""
    from scipy.special import stdtrit

    body, positions, directions, records, full = _engine(0.02, seed=4)
    k = 4
    spread = record_spread(records, 1.0 / RATE, positions, directions, full, segments=k, mass=body.mass)
    assert spread.used == k
    cgs = []
    for j in range(k):
        est = estimate_modes([r[j::k] for r in records], k / RATE)
        cgs.append(identify(positions, directions, est.poles, est.shapes, mass=body.mass, warn=False).center_of_gravity)
    expected = np.std(np.stack(cgs), axis=0, ddof=1) / np.sqrt(k)
    np.testing.assert_allclose(spread.center_of_gravity.std, expected, rtol=1e-9)
    half = float(stdtrit(k - 1, 0.975)) * expected
    np.testing.assert_allclose(spread.center_of_gravity.high - spread.center_of_gravity.low, 2 * half, rtol=1e-9)
