"""Mains hum in impact records: found by its fixed frequency, modelled as nuisance sinusoids in the refit.

Hum is a sinusoid of fixed frequency (the mains' 50 or 60 Hz and its harmonics) and a fixed
amplitude and phase per channel, picked up by the cables or a ground loop. It is not a mode of
the body (undamped, and at a frequency known in advance), so the refit
(:mod:`rigidid.core.timedomain.refine`) models it as two linear nuisance columns per channel and
impact, ``cos(2 pi f t)`` and ``sin(2 pi f t)``, like the offsets, once the records show it.

The test: at each candidate frequency ``f``, each impact's and channel's residual (whitened, so
of unit variance where the model fits) is projected on that pair; under white noise the summed
reduction of the residual's sum of squares, divided by the residual variance, is chi-square with
``2 p I`` degrees of freedom (``p`` channels, ``I`` impacts). Its standard score
``(q - 2 p I) / sqrt(4 p I)`` above :data:`HUM_Z` declares hum at ``f``: beyond any chance at
the sizes of impact tests (the score's false-alarm rate is far below 1e-6 for white noise),
provided the line is steady: hum keeps its amplitude along the decay, so the line's excess power
(``q / s^2`` less its degrees of freedom) in the later half of each decay must be at least
:data:`STEADY` times that in the earlier half. A mode's misfit near 50 or 60 Hz (sensor errors the
start's model cannot reproduce, the tail of a decaying sinusoid at 47 or 63 Hz) projects on the
pair as strongly, but decays: on 25 kg bodies with modes at 45-63 Hz and sensors within +-3 %,
+-3 degrees, it scored z = 16-73 in the earlier half and below 1 in the later
(``benchmarks/chain_regimes.py``, cell ``compact``).

The pre-trigger holds the hum too: its noise is measured with the lines found taken out
(:mod:`rigidid.core.timedomain.pretrigger`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ["HUM_Z", "MAINS_HZ", "STEADY", "HumFound", "find_hum", "hum_columns"]

Array = NDArray[np.float64]

MAINS_HZ = (50.0, 100.0, 150.0, 60.0, 120.0, 180.0)
"""The candidate frequencies: the mains of both standards and their second and third harmonics."""

HUM_Z = 10.0
"""Standard score of the chi-square test above which hum is declared."""

STEADY = 0.25
"""Least ratio of a hum line's excess power in the later half of the decays to the earlier half's (its
amplitude's ratio at least 0.5; steady hum reads 1, a decaying mode ``exp(-zeta w T)`` over the decays' span T)."""

HumFound = tuple[float, float, float]
"""``(frequency Hz, z score, RMS amplitude over the channels in noise standard deviations)``."""


def _pair(n: int, dt: float, hz: float) -> Array:
    """The orthonormalised cosine and sine at `hz` on ``n`` samples of interval `dt`, shape (n, 2)."""
    t = np.arange(n) * dt
    basis = np.column_stack([np.cos(2 * math.pi * hz * t), np.sin(2 * math.pi * hz * t)])
    q, _ = np.linalg.qr(basis)
    out: Array = q
    return out


def find_hum(residuals: Sequence[Array], dt: float, candidates: Sequence[float] = MAINS_HZ) -> list[HumFound]:
    """Mains hum in the whitened residuals of a fit (module notes).

    Parameters
    ----------
    residuals : sequence of ndarray, shape (n_i, p)
        Per impact, the residual of each channel divided by its noise level.
    dt : float
        Their sample interval (s); frequencies above 0.45 / dt are not tested.
    candidates : sequence of float
        Frequencies tested (Hz).

    Returns
    -------
    list of (float, float, float)
        Each frequency found: its z score and the hum's RMS amplitude over channels and impacts
        (in units of the residual's standard deviation).
    """
    res = [np.array(r, dtype=float) for r in residuals]
    count = sum(r.size for r in res)
    left = [float(hz) for hz in candidates if hz < 0.45 / dt]
    found: list[tuple[float, float, float]] = []  # (hz, z, mean square amplitude)
    while left and count:
        total = sum(float(np.sum(r**2)) for r in res)
        scores = []
        for hz in left:
            proj = [_pair(r.shape[0], dt, hz).T @ r for r in res]  # (2, p) each
            q, k = sum(float(np.sum(x**2)) for x in proj), sum(x.size for x in proj)
            s2 = (total - q) / max(count - k, 1)  # the noise's variance without this line
            amp2 = sum(float(np.sum(x**2)) * 2.0 / r.shape[0] for x, r in zip(proj, res, strict=True)) / (k // 2)
            scores.append(((q / s2 - k) / math.sqrt(2.0 * k) if s2 > 0.0 else math.inf, hz, amp2, s2))
        z, hz, amp2, s2 = max(scores)
        if not z > HUM_Z:
            break
        if not _steady(res, dt, hz, s2):
            left.remove(hz)  # a decaying line: a mode's misfit near the mains frequency, not hum
            continue
        found.append((hz, z, amp2))
        left.remove(hz)
        res = [r - (b := _pair(r.shape[0], dt, hz)) @ (b.T @ r) for r in res]  # the strongest line out, then the next
    s2 = sum(float(np.sum(r**2)) for r in res) / max(count, 1)
    return [(hz, z, math.sqrt(amp2 / s2) if s2 > 0.0 else math.inf) for hz, z, amp2 in found]


def _power(res: Sequence[Array], dt: float, hz: float) -> float:
    """The residuals' summed squares on the orthonormal cosine and sine at `hz` (each decay on its own)."""
    return sum(float(np.sum((_pair(r.shape[0], dt, hz).T @ r) ** 2)) for r in res)


def _steady(res: Sequence[Array], dt: float, hz: float, s2: float) -> bool:
    """Whether the line at `hz` keeps its power along the decays: its excess power (over the noise `s2`) in
    the later half of each decay at least :data:`STEADY` times the earlier half's (module notes)."""
    halves = [[r[: r.shape[0] // 2] for r in res], [r[r.shape[0] // 2 :] for r in res]]
    early, late = (_power(h, dt, hz) / s2 - 2 * sum(r.shape[1] for r in h) if s2 > 0.0 else math.inf for h in halves)
    return late >= STEADY * early


def hum_columns(t: Array, omega: float, frequencies: Sequence[float], p: int) -> Array:
    """Nuisance columns of hum at `frequencies` for every channel, shape (n, p, 2 m).

    Parameters
    ----------
    t : ndarray, shape (n,)
        Times from the decay's start in the refit's units (s times `omega`).
    omega : float
        The refit's time scale (rad/s).
    frequencies : sequence of float
        The hum's frequencies (Hz).
    p : int
        Number of channels.
    """
    out = np.empty((t.size, p, 2 * len(frequencies)))
    for m, hz in enumerate(frequencies):
        arg = 2 * math.pi * hz / omega * t
        out[:, :, 2 * m] = np.cos(arg)[:, None]
        out[:, :, 2 * m + 1] = np.sin(arg)[:, None]
    return out
