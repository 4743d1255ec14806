"""Whether correcting the sensors would move the body by more than its noise: a score test (issue 23).

The output-error refit (:mod:`rigidid.core.timedomain.refine`) reads the records through the
sensors as stated. A sensor's gain or axis error adds a signature ``g`` to the weighted
records (``G~`` the signatures less each impact's linear terms, :class:`SensorTerms`); at the
plain refit's minimum the score of the sensors' errors is ``s = G~^T (I - P_J) r`` (``r`` the residual;
``P_J`` takes out what a fit stopped short of its minimum leaves along its own Jacobian: on four-mounts
records with a clipped channel left out, that alone made ``p`` 1e-17 on exact sensors, 0.33 without it),
and with exact sensors ``s ~ N(0, s2 Q)``, ``Q = G~^T (I - P_J) G~`` (``P_J`` the projector on
the fit's Jacobian, ``s2`` the residual's variance per residual: Rao's score, or Lagrange
multiplier, test).

The sensors' errors are never exactly zero; what matters is whether correcting them changes
the body. The correction (the maximum a posteriori estimate with the stated tolerances as
prior, :func:`rigidid.core.timedomain.refine.refine_prepared`) moves the body's figures by
``b = L s`` to first order, ``L = D (J^T J)^+ J^T G~ (V Q + I)^-1 V`` (``D`` the figures'
derivatives, ``V`` the errors' prior variances). With exact sensors ``b ~ N(0, s2 L Q L^T)``
and the statistic ``T = b^T (s2 L Q L^T)^+ b`` is chi-square with ``rank(L Q L^T)`` degrees of
freedom (at most the nine figures tested: CG and the six distinct entries of J/m). The noise at the
fit's rate is not white (the decimation filter correlates it; its level differs between impacts): ``s2``
is taken times the factor by which the refit's sandwich covariance of these figures exceeds the
white-noise bound (:func:`noise_inflation`). So the test
spends its power only on the sensor errors that move the CG and the inertia, not on those the
body does not feel (a common error of all sensors' gains, errors the fit absorbs into the
modal amplitudes); it flags when the move is beyond what the noise explains at the stated
false-alarm rate (:data:`SENSOR_FALSE_ALARM`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from rigidid.core.chisquare import chi2_sf
from rigidid.core.linalg import pseudo_inverse
from rigidid.core.timedomain.acceptance import FALSE_ALARM

__all__ = [
    "AFTER_FALSE_ALARM",
    "SENSOR_FALSE_ALARM",
    "TESTED_OUTPUTS",
    "SensorTest",
    "body_change_test",
    "noise_inflation",
]

Array = NDArray[np.float64]

SENSOR_FALSE_ALARM = FALSE_ALARM
"""The sensor test's false-alarm rate: on exact sensors, the fraction of refits whose sensors are
estimated anyway (then the answer costs the correction's noise, which its intervals include);
the acceptance test's (:data:`rigidid.core.timedomain.acceptance.FALSE_ALARM`)."""

AFTER_FALSE_ALARM = 0.001
"""The after-check's false-alarm rate (:attr:`SensorTest.explains`): the fraction of right corrections (sensor
errors within their stated tolerances, the model right) whose residual it calls unexplained, the plain refit then
kept by default. Below the acceptance test's 1 %: its spread is the pre-trigger's noise level's (about 1.1 % of
the level from 3 x 512 samples per channel, benchmarks/chain_matrix.py), not what the correction leaves. On
chain_matrix's sens seed 411 the after-check read p 0.0016 while the same noise on exact sensors gave the plain
refit's residual the same p (4.5 % over the pre-trigger's level): at 1 % the correct correction (CG 0.013 %, J
0.12 %) was dropped for the plain refit (CG 0.65 %, J 8.6 %). What it guards against sits far beyond: a
one-sample skew that the gains and tilts absorb leaves the corrected residual 3.3 times the noise (p below 1e-15,
skew cell, every tolerance stated)."""

TESTED_OUTPUTS = np.array([0, 1, 2, 3, 4, 5, 7, 8, 11])
"""Rows of the refit's physical outputs the test looks at: CG (3) and J/m's upper triangle (6)."""


@dataclass(frozen=True)
class SensorTest:
    """The score test of the stated sensors against the records.

    Attributes
    ----------
    statistic : float
        ``T``, chi-square with `dof` degrees of freedom when the sensors are exact.
    dof : int
        Rank of the body move's noise covariance (0: the tolerances let nothing move).
    p_value : float
        ``P(chi2_dof >= T)`` (1 when `dof` is 0).
    false_alarm : float
        The rate the test was run at.
    estimated : bool
        Whether the sensors' errors were then estimated with the body (by the test, or forced).
    misfit_after : float or None
        With the sensors estimated: the p-value of the misfit test of the last corrected refit's residual
        against the noise plus what the correction leaves (the estimated errors' remaining part, less the noise
        the correction takes). Below `after_false_alarm` the correction has not explained the records (an
        unmodelled skew, say, that the gains and tilts partly absorb): by default the plain refit is then kept.
    after_false_alarm : float
        The rate the after-check (`misfit_after`) is judged at (:data:`AFTER_FALSE_ALARM`).
    """

    statistic: float
    dof: int
    p_value: float
    false_alarm: float
    estimated: bool = False
    misfit_after: float | None = None
    after_false_alarm: float = AFTER_FALSE_ALARM

    @property
    def explains(self) -> bool:
        """Whether the correction, when made, leaves a residual the noise and what the correction leaves of the
        tolerances explain (`misfit_after` at least `after_false_alarm`)."""
        return self.misfit_after is None or self.misfit_after >= self.after_false_alarm

    @property
    def flagged(self) -> bool:
        """Whether the records show sensor errors that move the body (p-value below the false-alarm rate)."""
        return bool(self.dof > 0 and self.p_value < self.false_alarm)


def body_change_test(
    effect: Array, gram: Array, score: Array, variance: float = 1.0, false_alarm: float = SENSOR_FALSE_ALARM
) -> SensorTest:
    """Test whether the body move ``effect @ score`` exceeds what noise explains.

    Parameters
    ----------
    effect : ndarray, shape (m, k)
        ``L``: the tested figures' move per unit score (see the module's notes).
    gram : ndarray, shape (k, k)
        ``Q``: the score's covariance per unit noise variance.
    score : ndarray, shape (k,)
        ``s = G~^T r``.
    variance : float
        The residual's variance per residual (``s2``, 1 in pre-trigger units at a good fit).
    false_alarm : float
        The stated false-alarm rate.

    Returns
    -------
    SensorTest
    """
    b = effect @ score
    cov = variance * (effect @ gram @ effect.T)
    d = np.sqrt(np.maximum(np.diag(cov), 0.0))
    keep = d > 1e-12 * max(float(np.max(d, initial=0.0)), 1e-300)
    if not np.any(keep):
        return SensorTest(0.0, 0, 1.0, false_alarm)
    z = b[keep] / d[keep]
    inv, rank = pseudo_inverse(cov[np.ix_(keep, keep)] / np.outer(d[keep], d[keep]), symmetric=True)
    t = float(z @ inv @ z)
    p = chi2_sf(t, rank) if rank > 0 else 1.0
    return SensorTest(t, int(rank), p, false_alarm)


def noise_inflation(sandwich: Array, white: Array) -> float:
    """How much wider the refit's noise is than white noise of its residual's variance: the score's factor.

    Parameters
    ----------
    sandwich : ndarray, shape (m,)
        The tested figures' noise variances as the refit reports them (the sandwich covariance of
        :func:`rigidid.core.timedomain.intervals.parameter_covariance`: the decimation filter's
        correlation, the noise per impact and channel).
    white : ndarray, shape (m,)
        The same from ``s2 (J^T J)^+`` (white noise).

    Returns
    -------
    float
        The median ratio, at least 1 (1 where nothing is defined). The score ``G~^T r`` sums the same
        correlated noise along modal responses as ``J^T r`` does, so its covariance widens alike
        (four-mounts at 10 kHz, decimated 36 times, exact sensors, 12 draws: mean statistic 11.3 on 9
        dof without the factor, 9.3 with it, the factor 1.2). Never below 1: the sandwich's own terms
        (noise per impact, the remaining Gauss-Newton step) only widen it, so a ratio below 1 is its
        sampling, and the test stays at most as eager as under white noise.
    """
    ok = (white > 0.0) & np.isfinite(sandwich)
    return max(1.0, float(np.median(sandwich[ok] / white[ok]))) if np.any(ok) else 1.0
