"""The pre-trigger's noise in the fit's band (rigidid.core.timedomain.pretrigger, issue 23).

The reference: scipy.signal.decimate (its own FIR design and filtering, the filter rigidid's decimation
reproduces) of long noise records drawn the same way, and the degrees of freedom counted from the draws.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import butter, decimate, sosfilt

from rigidid.core.timedomain.pretrigger import band_noise

RATE, Q = 2048.0, 4


def _coloured(rng: np.random.Generator, n: int, p: int) -> np.ndarray:
    """White noise through an 8th-order Butterworth low-pass at 0.4 of the sample rate (an anti-alias filter)."""
    sos = butter(8, 0.8, output="sos")  # 0.8 of Nyquist = 0.4 fs
    return np.asarray(sosfilt(sos, rng.standard_normal((n + 512, p)), axis=0)[512:])


def test_coloured_noise_is_measured_in_the_fit_band_and_the_hum_taken_out() -> None:
    """Behind the anti-alias filter, the white-noise formula (raw variance times the FIR's noise gain) reads the
    band's variance 21 % low; the band measurement reads it within its own scatter, with 50 Hz hum of 30 noise
    std and an offset in the pre-trigger."""
    rng = np.random.default_rng(7)
    p = 12
    long = decimate(_coloured(rng, 400_000, p), Q, ftype="fir", axis=0)  # the decays' noise at the fit's rate
    truth = long[1000:-1000].var(axis=0)
    t = np.arange(512) / RATE
    held = [_coloured(rng, 512, p) + 3.0 + 30.0 * np.sin(2 * np.pi * 50.0 * t + k)[:, None] for k in range(3)]
    noise = band_noise(held, 1.0 / RATE, Q, [50.0])
    assert noise is not None
    ratio = noise.sigma**2 / truth
    # 3 records of 107 decimated samples less 3 lines: about 300 dof per channel (std 8 %), 12 channels
    assert abs(np.mean(ratio) - 1.0) < 0.08  # observed 0.023
    assert np.all(np.abs(ratio - 1.0) < 0.4)  # observed 0.18 at most
    from rigidid.core.timedomain.preprocess import fir_taps

    white = np.mean([np.var(_coloured(rng, 512, p), axis=0) for _ in range(3)], axis=0) * np.sum(fir_taps(Q) ** 2)
    assert np.mean(white / truth) < 0.88  # observed 0.79: what the white-noise formula would have read
    assert all(80.0 < d < 104.0 for d in noise.dof)  # 107 - 3 over the decimated noise's inflation: 102.6
    np.testing.assert_allclose(noise.variance.mean(axis=0), noise.sigma**2, rtol=1e-12)


def test_the_variances_degrees_of_freedom_are_their_scatter() -> None:
    """Over 400 draws of one record, the band variance's relative scatter is ``sqrt(2 / dof)``: the dof the
    acceptance test is given (white noise, the decimated samples slightly correlated)."""
    rng = np.random.default_rng(8)
    draws = [band_noise([rng.standard_normal((512, 25))], 1.0 / RATE, Q) for _ in range(16)]
    assert all(d is not None for d in draws)
    values = np.concatenate([d.variance[0] for d in draws if d is not None])
    dof = draws[0].dof[0] if draws[0] is not None else 0.0
    scatter = np.var(values / values.mean())
    assert abs(scatter * dof / 2.0 - 1.0) < 0.3  # observed 1.007; 400 values: the estimate's own std about 0.07


def test_too_short_or_only_hum_is_no_measurement() -> None:
    rng = np.random.default_rng(9)
    assert band_noise([rng.standard_normal((100, 3))], 1.0 / RATE, Q) is None  # 4 decimated samples
    t = np.arange(2048) / RATE
    hum = np.sin(2 * np.pi * 50.0 * t)[:, None] * np.ones((1, 3))
    assert band_noise([hum + 1.0], 1.0 / RATE, Q, [50.0]) is None  # nothing but the lines
    assert band_noise([hum + 1.0], 1.0 / RATE, Q) is not None  # the hum not named: it is the noise
