"""The estimation's cheap paths: two-stage decimation, the finer content, the impact from block peaks."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rigidid.core.timedomain import estimate_modes, impulse_records
from rigidid.core.timedomain.estimate import decimation_factors
from rigidid.core.timedomain.preprocess import (
    FIR_HALF_LENGTH,
    block_peaks,
    channel_energy,
    content_range,
    decimate,
    decimate_in_stages,
    find_impact,
    impact_from_blocks,
    presum,
    stage_factors,
)
from rigidid.errors import InputError

from ..tolerances import MODAL_DAMPING_REL, MODAL_FREQUENCY_REL, PRESUM_ALIAS_DB, PRESUM_DROOP
from .test_timedomain import BODY, DIRECTIONS, IMPACTS, POSITIONS, TRUE_F, TRUE_Z

# --- stage_factors -------------------------------------------------------------------------


@given(st.integers(1, 20_000))
def test_stage_factors_split_an_automatic_factor(factor: int) -> None:
    q1, q2 = stage_factors(factor)
    if factor < 12:
        assert (q1, q2) == (1, factor)
        return
    assert q1 % 2 == 1 and q1 >= 3 and q2 >= 4
    assert q1 * q2 <= factor  # never decimates more than asked
    assert q1 * q2 >= 0.8 * factor  # and loses at most a fifth
    assert q1 == max(q for q in range(3, factor // 4 + 1, 2))  # the largest first stage


@given(st.integers(1, 5_000))
def test_stage_factors_keep_a_users_factor(factor: int) -> None:
    q1, q2 = stage_factors(factor, exact=True)
    assert q1 * q2 == factor
    assert q1 == 1 or (q1 % 2 == 1 and q2 >= 4)


# --- presum: the first stage ----------------------------------------------------------------


def _tone(freq: float, rate: float, n: int) -> np.ndarray:
    t = np.arange(n) / rate
    return np.cos(2 * np.pi * freq * t)[:, None]


@pytest.mark.parametrize("q1", [3, 7, 39])
def test_presum_is_zero_phase_with_a_small_droop_in_band(q1: int) -> None:
    rate, q2 = 10_000.0, 4
    band = rate / (2 * q1 * q2)  # the Nyquist frequency after the second stage
    x = _tone(0.8 * band, rate, 400 * q1 * q2)
    y = presum(x, q1)
    rows = (np.arange(y.shape[0]) + 2) * q1  # output k is the filtered record at raw sample (k + 2) q1
    gain = float(np.sum(y[:, 0] * x[rows, 0]) / np.sum(x[rows, 0] ** 2))
    assert 1.0 - PRESUM_DROOP < gain <= 1.0  # the third-order CIC's droop at 0.8 of the band's edge
    np.testing.assert_allclose(y[:, 0], gain * x[rows, 0], atol=1e-9)  # no phase shift


@pytest.mark.parametrize("q1", [3, 7, 39])
def test_presum_attenuates_what_would_fold_onto_the_band(q1: int) -> None:
    rate, q2 = 10_000.0, 4
    edge = rate / (2 * q1 * q2)
    for fold in (rate / q1 - edge, rate / q1 + edge, 2 * rate / q1 - edge):
        y = presum(_tone(fold, rate, 400 * q1 * q2), q1)
        assert 20 * np.log10(np.max(np.abs(y))) < -PRESUM_ALIAS_DB, fold


def test_presum_refuses_an_even_factor_and_a_short_record() -> None:
    with pytest.raises(ValueError, match="odd"):
        presum(np.zeros((100, 1)), 4)
    with pytest.raises(InputError, match="too short"):
        presum(np.zeros((20, 1)), 5)


def test_two_stages_agree_with_one_in_band() -> None:
    rate = 20_000.0
    rng = np.random.default_rng(3)
    t = np.arange(400_000) / rate
    # tones within a quarter of the Nyquist frequency after decimation by 156 (64 Hz), where the
    # factor's margin puts the modes
    x = np.stack([np.sin(2 * np.pi * f * t + rng.uniform(0, 6)) for f in (3.0, 9.0, 15.0)], axis=1)
    q1, q2 = stage_factors(156)
    staged = decimate_in_stages(x, q1, q2)
    whole = decimate(x, q1 * q2)
    rows_staged = (FIR_HALF_LENGTH * q2 + 2) * q1 + q1 * q2 * np.arange(staged.shape[0])
    rows_whole = FIR_HALF_LENGTH * q1 * q2 + q1 * q2 * np.arange(whole.shape[0])
    # both are the tones at those samples, within the presum's droop there (0.4 % at 15 Hz) and the FIR's ripple
    np.testing.assert_allclose(staged, x[rows_staged], atol=5e-3)
    np.testing.assert_allclose(whole, x[rows_whole], atol=5e-3)


# --- the finer content, and the factor it allows ---------------------------------------------


@pytest.fixture(scope="module")
def fast_records() -> list[np.ndarray]:
    """The four-mounts body at 20 kHz (modes 8-26 Hz): the spectrum at that rate resolves 4.9 Hz."""
    return impulse_records(
        BODY, POSITIONS, DIRECTIONS, IMPACTS, sample_rate=20_000.0, duration=6.0, pretrigger=0.1, noise=0.01, seed=5
    )


def test_a_record_sampled_far_above_its_modes_is_decimated_as_far_as_its_modes_allow(
    fast_records: list[np.ndarray],
) -> None:
    dt = 1.0 / 20_000.0
    decays = [r[find_impact(r, dt).start :] for r in fast_records]
    coarse = decimation_factors(decays, dt, None, content_range(decays, dt))[0]
    est = estimate_modes(fast_records, dt)
    # the content judged at the records' rate reaches several times above 26 Hz (window leakage of
    # modes in its lowest bins); judged again on the presummed decays it allows a larger factor
    assert est.decimation >= 2 * coarse
    assert 0.5 / est.sample_interval >= 4 * TRUE_F.max()  # the margin the factor keeps above the modes
    np.testing.assert_allclose(est.frequency_hz, TRUE_F, rtol=MODAL_FREQUENCY_REL)
    np.testing.assert_allclose(est.damping_ratio, TRUE_Z, rtol=MODAL_DAMPING_REL)


def test_a_users_factor_is_kept(fast_records: list[np.ndarray]) -> None:
    est = estimate_modes(fast_records, 1.0 / 20_000.0, decimate=105)
    assert est.decimation == 105  # 7 x 15 in two stages
    est = estimate_modes(fast_records, 1.0 / 20_000.0, decimate=101)
    assert est.decimation == 101  # prime: one stage


# --- block peaks and the impact --------------------------------------------------------------


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(1, 30_000),
    p=st.integers(1, 40),
    onset=st.floats(0.0, 0.95),
    seed=st.integers(0, 2**16),
    dead=st.booleans(),
)
def test_impact_from_blocks_is_find_impact(n: int, p: int, onset: float, seed: int, dead: bool) -> None:
    rng = np.random.default_rng(seed)
    x = 1e-3 * rng.standard_normal((n, p)) * rng.uniform(0.1, 10.0, p)
    at = int(onset * n)
    t = np.arange(n - at)[:, None]
    x[at:] += rng.standard_normal(p) * np.exp(-t / max(1.0, 0.2 * n)) * np.cos(0.05 * t)
    if dead and p > 1:
        x[:, 0] = 0.0  # a channel that reads nothing
    peaks, maxima, rows = block_peaks(x)
    np.testing.assert_array_equal(peaks, np.abs(x).max(axis=0))
    for b in range(maxima.shape[0]):
        np.testing.assert_array_equal(maxima[b], np.abs(x[b * rows : (b + 1) * rows]).max(axis=0))
    dt = 1e-4
    expected = find_impact(x, dt, energy=channel_energy(x, peaks))
    assert impact_from_blocks(x, dt, peaks, maxima, rows) == expected


def test_impact_from_blocks_refuses_an_all_zero_record() -> None:
    x = np.zeros((5000, 3))
    with pytest.raises(InputError, match="all zero"):
        impact_from_blocks(x, 1e-3, *block_peaks(x))


def test_channel_energy_is_the_weighted_sum_of_squares() -> None:
    x = np.random.default_rng(2).standard_normal((70_001, 5)) * [1.0, 10.0, 0.1, 3.0, 0.0]
    peaks = np.abs(x).max(axis=0)
    scale = np.divide(1.0, peaks, out=np.zeros(5), where=peaks > 0)
    np.testing.assert_allclose(channel_energy(x), ((x * scale) ** 2).sum(axis=1), rtol=1e-13, atol=0.0)
