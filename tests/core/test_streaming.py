"""Records fed as blocks of rows (core/timedomain/streaming.py) give what the whole-record routines give.

The records are written afresh here: free decays of three damped modes after a half-sine
impact, with pre-trigger noise; no file, no reader. Every streaming routine is compared with its
whole-record counterpart on the same samples, cut into blocks of uneven sizes.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import replace

import numpy as np
import pytest

from rigidid.core.spectrum import summed_spectrum
from rigidid.core.timedomain import streaming
from rigidid.core.timedomain.preprocess import FIR_HALF_LENGTH, content_spectrum, decimate, find_impact
from rigidid.core.timedomain.refine import prepare_decays

from ..tolerances import STREAMED_DECIMATION

DT = 1.0 / 4096.0


def _record(rows: int, onset: int, seed: int, dt: float = DT) -> np.ndarray:
    """A hammer impact at row `onset` on three damped modes seen by four channels, plus noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(rows - onset) * dt
    freqs, zetas = np.array([11.0, 23.0, 57.0]), np.array([0.02, 0.03, 0.01])
    shapes = rng.standard_normal((3, 4))
    w = 2.0 * np.pi * freqs
    modal = np.exp(-zetas[None, :] * w[None, :] * t[:, None]) * np.sin(w[None, :] * t[:, None])
    x = np.zeros((rows, 4))
    x[onset:] = modal @ shapes
    return x + 1e-4 * rng.standard_normal((rows, 4))


def _blocks(x: np.ndarray, sizes: tuple[int, ...]) -> Iterator[np.ndarray]:
    """`x` cut into consecutive blocks, sizes taken round-robin from `sizes`."""
    start, k = 0, 0
    while start < x.shape[0]:
        stop = start + sizes[k % len(sizes)]
        yield x[start:stop]
        start, k = stop, k + 1


def _timed(x: np.ndarray, sizes: tuple[int, ...], dt: float = DT) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    start = 0
    for block in _blocks(x, sizes):
        yield np.arange(start, start + block.shape[0]) * dt, block
        start += block.shape[0]


@pytest.mark.parametrize("factor", [1, 3, 8])
def test_streaming_decimation_equals_whole_record_decimation(factor: int) -> None:
    x = _record(9000, 700, seed=1)
    stream = streaming.StreamingDecimation(x.shape[0], x.shape[1], factor=factor)
    stream.run(_timed(x, (1000, 37, 2500)))
    done = stream.finish()
    assert done.factor == factor and done.stages == (factor, 1)
    assert done.offset == (FIR_HALF_LENGTH * factor if factor > 1 else 0)
    np.testing.assert_allclose(done.data, decimate(x, factor), rtol=0.0, atol=STREAMED_DECIMATION)


def test_streaming_decimation_sees_every_block_once_in_order() -> None:
    x = _record(5000, 300, seed=2)
    seen: list[np.ndarray] = []
    stream = streaming.StreamingDecimation(x.shape[0], x.shape[1], factor=2)
    stream.run(_timed(x, (999, 1)), lambda t, values: seen.append(values))
    np.testing.assert_array_equal(np.concatenate(seen), x)


def test_a_head_chooses_a_factor_that_keeps_the_content(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(streaming, "HEAD_ROWS", 16384)
    monkeypatch.setattr(streaming.ContentWelch, "SPAN", 8192)
    dt = 1.0 / 65536.0
    x = _record(40000, 500, seed=3, dt=dt)
    stream = streaming.StreamingDecimation(x.shape[0], x.shape[1])
    stream.run(_timed(x, (1024,), dt))
    done = stream.finish()
    assert done.factor > 1 and done.stages == (done.factor, 1)
    # the highest mode (57 Hz) stays 4 x PRE_SAFETY below the new Nyquist frequency; the pulse keeps its samples
    assert 0.5 / (dt * done.factor) >= 4 * streaming.PRE_SAFETY * 57.0
    assert streaming.PULSE_WIDTH / (dt * done.factor) >= streaming.PULSE_SAMPLES
    # the content spectrum is that of the raw decay after the impact the head shows
    start = find_impact(x[:16384], dt).start
    assert done.spectrum is not None
    np.testing.assert_allclose(done.spectrum[1], content_spectrum([x[start : start + 8192]], dt)[1], rtol=1e-9)
    np.testing.assert_allclose(done.data, decimate(x, done.factor), rtol=0.0, atol=STREAMED_DECIMATION)


def test_locate_impact_equals_find_impact_on_the_whole_record() -> None:
    x = _record(30000, 2000, seed=4)
    whole = find_impact(x, DT)
    found = streaming.locate_impact(_blocks(x, (3000, 411)), 4, DT, lo=1500, hi=whole.start + 4000)
    assert found == whole
    # rows held that miss the largest energy cannot prove the impact: no answer rather than a wrong one
    assert streaming.locate_impact(_blocks(x, (3000,)), 4, DT, lo=whole.start + 500, hi=whole.start + 900) is None


def test_prepared_decays_equal_prepare_decays_on_whole_records() -> None:
    records = [_record(12000, 900, seed=5), _record(11000, 1200, seed=6)]
    impacts = [find_impact(x, DT) for x in records]
    starts, onsets = [i.start for i in impacts], [i.onset for i in impacts]
    whole = prepare_decays(records, DT, starts, onsets, 4)
    streamed = streaming.prepared_decays(
        lambda i: _blocks(records[i], (300, 77)), [x.shape[0] for x in records], 4, DT,
        starts=starts, onsets=onsets, factor=4,
    )  # fmt: skip
    assert streamed.dt == whole.dt and streamed.noise_from == whole.noise_from
    np.testing.assert_allclose(streamed.sigma, whole.sigma, rtol=1e-12)
    assert streamed.pre_held is not None and whole.pre_held is not None  # the pre-trigger's rows held
    for a, b in zip(streamed.pre_held, whole.pre_held, strict=True):
        np.testing.assert_array_equal(a, b)
    for a, b in zip(streamed.decays, whole.decays, strict=True):
        np.testing.assert_allclose(a, b, rtol=0.0, atol=STREAMED_DECIMATION)


def test_summed_power_equals_summed_spectrum() -> None:
    records = [_record(10000, 500, seed=7), _record(9000, 800, seed=8)]
    n = 1024
    window = 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(n) / n)
    total = sum(streaming.record_power(_blocks(x, (700, 2000)), 4, window) for x in records)
    freqs, density = streaming.power_density(np.asarray(total), window, DT)
    f_whole, d_whole = summed_spectrum(records, DT, segment=n)
    np.testing.assert_allclose(freqs, f_whole, rtol=1e-15)
    np.testing.assert_allclose(density, d_whole, rtol=1e-10)
    with pytest.raises(ValueError, match="shorter than one segment"):
        streaming.record_power(_blocks(records[0][:500], (100,)), 4, window)


def test_summed_spectrum_is_welchs_average() -> None:
    """summed_spectrum against scipy's Welch (a reference written apart): Hann, half overlap, mean removed."""
    from scipy.signal import welch

    records = [_record(10000, 500, seed=7), _record(9000, 800, seed=8)]
    f, p = summed_spectrum(records, DT, segment=1024)
    ref = [welch(x, fs=1.0 / DT, nperseg=1024, axis=0, detrend="constant") for x in records]
    np.testing.assert_allclose(f, ref[0][0], rtol=1e-15)
    np.testing.assert_allclose(p, sum(np.sum(q, axis=1) for _, q in ref), rtol=1e-10)
    short = [x[:700] for x in records]  # a record shorter than the segment shortens it
    f, p = summed_spectrum(short, DT, segment=1024)
    _, q = welch(short[0], fs=1.0 / DT, nperseg=700, axis=0, detrend="constant")
    assert f.size == 351 and np.allclose(
        p, np.sum(q, axis=1) + np.sum(welch(short[1], fs=1.0 / DT, nperseg=700, axis=0, detrend="constant")[1], axis=1)
    )


def test_two_stages_equal_decimation_twice_and_the_content_spectrum_is_the_decays() -> None:
    x = _record(20000, 700, seed=9)
    stream = streaming.StreamingDecimation(x.shape[0], x.shape[1], factor=3, second=2)
    stream.run(_timed(x, (1000, 333)))
    done = stream.finish()
    assert done.factor == 6 and done.stages == (3, 2)
    assert done.offset == FIR_HALF_LENGTH * 3 + FIR_HALF_LENGTH * 6
    np.testing.assert_allclose(done.data, decimate(decimate(x, 3), 2), rtol=0.0, atol=STREAMED_DECIMATION)


def test_content_spectrum_fed_in_blocks_is_that_of_the_decay(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(streaming.ContentWelch, "SPAN", 8192)
    x = _record(30000, 700, seed=10)
    welch = streaming.ContentWelch(900, DT, 4)
    row = 0
    for block in _blocks(x, (1000, 333)):
        welch.add(block, row)
        row += block.shape[0]
    assert welch.complete(row)
    spectrum = welch.spectrum()
    assert spectrum is not None
    freqs, total = content_spectrum([x[900 : 900 + 8192]], DT)
    np.testing.assert_allclose(spectrum[0], freqs, rtol=1e-15)
    np.testing.assert_allclose(spectrum[1], total, rtol=1e-9)


def test_a_larger_hit_after_the_rows_held_is_not_taken_for_the_impact() -> None:
    x = _record(30000, 2000, seed=11)
    x[20000:] += 5.0 * _record(10000, 0, seed=12)  # a second, larger hit
    first = find_impact(x[:15000], DT)
    assert streaming.locate_impact(_blocks(x, (3000,)), 4, DT, lo=1500, hi=first.start + 4000) is None


def test_impacts_and_decays_read_in_one_pass_equal_the_whole_record_routines() -> None:
    # io's locate_and_read: the window held, the decay decimated from the impact found in it as the
    # rest arrives (the first record is longer than the window, the second ends inside it)
    from rigidid.core.timedomain.preprocess import Impact

    records = [_record(80000, 2000, seed=7), _record(30000, 1500, seed=8)]
    whole = [find_impact(x, DT) for x in records]
    near = [Impact(i.onset - 40, i.peak, i.start + 30) for i in whole]
    found = streaming.located_decays(
        lambda i: _blocks(records[i], (3000, 411)), [x.shape[0] for x in records], 4, DT, near, 200, 4
    )
    assert found is not None and found[1] is not None
    impacts, passes, q = found
    assert impacts == whole
    ref = prepare_decays(records, DT, [i.start for i in whole], [i.onset for i in whole], 4)
    data = streaming.prepared_from(passes, 4, DT, q)
    assert data.dt == ref.dt and data.pre_counts == ref.pre_counts
    np.testing.assert_allclose(data.sigma, ref.sigma, rtol=1e-12)
    assert data.pre_held is not None and ref.pre_held is not None
    for a, b in zip(data.pre_held, ref.pre_held, strict=True):
        np.testing.assert_array_equal(a, b)
    for a, b in zip(data.decays, ref.decays, strict=True):
        np.testing.assert_allclose(a, b, rtol=0.0, atol=STREAMED_DECIMATION)


def test_the_decay_captured_while_decimating_is_the_refits_pass_at_its_factor() -> None:
    # issue 23: the modes' reading keeps the refit's impact and decay (StreamingDecimation's capture), so the
    # file is parsed once: the same impact as find_impact on the whole record, the same pre-trigger statistics
    # and decimated decay as a pass of its own at the factor the capture chose (fit_factor of the rows, up to
    # the reader's total factor)
    from rigidid.core.timedomain.refine import MAX_ROWS, fit_factor

    dt = DT / 10.0  # 40 kHz: decimated while read
    x = _record(300000, 3000, seed=9, dt=dt)  # past the window held (2^18 rows of decay)
    whole = find_impact(x, dt)
    stream = streaming.StreamingDecimation(x.shape[0], 4, cascade=True, capture=[])
    stream.run(_timed(x, (16000, 1613), dt))
    done = stream.finish(dt)
    captured = done.captured
    assert captured is not None and captured.impact == whole
    assert captured.factor == fit_factor([x.shape[0]], 4, done.factor) > 1
    ref = streaming.decay_pass(_blocks(x, (5000,)), 4, whole.start, whole.onset - 2, captured.factor,
                               MAX_ROWS // 4 + 1)  # fmt: skip
    assert captured.decay.rows == ref.rows and captured.decay.pre_count == ref.pre_count
    np.testing.assert_allclose(captured.decay.pre_m2, ref.pre_m2, rtol=1e-12)
    assert captured.decay.pre_held is not None and ref.pre_held is not None
    np.testing.assert_array_equal(captured.decay.pre_held, ref.pre_held)
    np.testing.assert_allclose(captured.decay.decay, ref.decay, rtol=0.0, atol=STREAMED_DECIMATION)
    near = [replace(whole, onset=whole.onset + 30, start=whole.start - 20)]
    assert streaming.captured_decays([captured], 4, 4 * captured.factor, near, 100) is not None
    # the estimate decimated less than the capture: the band would be cut, read again
    assert streaming.captured_decays([captured], 4, captured.factor - 1, near, 100) is None
    # the estimate's impact elsewhere (the head held another hit): read again
    assert streaming.captured_decays([captured], 4, 4 * captured.factor, [replace(whole, start=9000)], 100) is None
