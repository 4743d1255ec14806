"""Whether the output-error refit explains the records to their noise: a test with a stated false-alarm rate.

The refit (:mod:`rigidid.core.timedomain.refine`) models the free decays of eq. (19) of [1]
plus noise. When the model is right, each impact's and channel's residual variance
estimates the same noise variance as the pre-trigger before that impact (no signal there),
and their ratio is F-distributed on the residual's and the pre-trigger's degrees of freedom.
The per-impact, per-channel log ratios are pooled with inverse-variance weights into one
normal score; the fit is accepted when its one-sided p-value is at least the stated
false-alarm rate (:data:`FALSE_ALARM`): on records the model explains, it rejects that
fraction of fits, whatever the noise level of each impact and channel.

Sensors within stated tolerances (gain, axis, position: :mod:`rigidid.core.sensor_budget`)
read a motion the rigid-body model cannot quite reproduce, so a right model leaves more
than the noise. :func:`budgeted_misfit_test` expects that excess: the part of each
sensor error's signature the fit cannot absorb is a quadratic form in the errors, whose
mean and variance follow from the errors' stated distributions (a type-B term of the
expected residual, GUM 4.3); the test asks whether the residual exceeds noise plus that.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["FALSE_ALARM", "MisfitTest", "budgeted_misfit_test", "misfit_test"]

Array = NDArray[np.float64]

FALSE_ALARM = 0.01
"""The acceptance test's false-alarm rate: the fraction of fits of a right model it rejects."""


@dataclass(frozen=True)
class MisfitTest:
    """The refit's residual against the pre-trigger noise.

    Attributes
    ----------
    ratio : float
        The residual's variance over the pre-trigger's (about 1 at a good fit; the
        geometric mean of the per-impact, per-channel ratios, inverse-variance weighted).
    z : float
        Normal score of the pooled log ratio (0 at a good fit, on average).
    p_value : float
        One-sided: the probability of a score at least `z` when the model is right.
    false_alarm : float
        The rate the test was run at.
    expected : float
        The ratio a right model is expected to leave: 1, or above when the stated sensor
        tolerances explain part of the residual (:func:`budgeted_misfit_test`).
    """

    ratio: float
    z: float
    p_value: float
    false_alarm: float
    expected: float = 1.0

    @property
    def accepted(self) -> bool:
        """Whether the p-value is at least the false-alarm rate."""
        return bool(self.p_value >= self.false_alarm)


def misfit_test(
    residual: Array,
    lengths: Sequence[int],
    channels: int,
    dof_fraction: float,
    pre_counts: Sequence[float],
    pre_variance: Array,
    correlation: Array,
    false_alarm: float = FALSE_ALARM,
) -> MisfitTest | None:
    """F-test of each impact's and channel's residual against its pre-trigger, pooled.

    Parameters
    ----------
    residual : ndarray, shape (sum(lengths) * channels,)
        The fit's weighted residual, impact after impact, rows of `channels` values.
    lengths : sequence of int
        Samples of each impact's decay fitted.
    channels : int
        Channels per row.
    dof_fraction : float
        The residual's degrees of freedom over its length (parameters and linear terms out).
    pre_counts : sequence of float
        Pre-trigger samples of each impact: its variance's degrees of freedom plus one (white-equivalent
        samples when the variance was measured in the fit's band, :mod:`rigidid.core.timedomain.pretrigger`).
    pre_variance : ndarray, shape (impacts, channels)
        The pre-trigger's noise variance per impact and channel, in the residual's
        weighted units and at the fit's rate (the decimation filter's noise gain applied).
    correlation : ndarray
        Correlation of the fitted noise between samples ``0, 1, 2...`` apart (the
        decimation filter's, :func:`rigidid.core.timedomain.intervals.noise_correlation`):
        it lowers the residual variance's effective degrees of freedom.
    false_alarm : float
        The stated false-alarm rate.

    Returns
    -------
    MisfitTest or None
        None when no impact has a pre-trigger of 8 samples or more.

    Notes
    -----
    ``log F`` of ``F(d1, d2)`` has mean about ``1 / d2 - 1 / d1`` (taken off) and variance about
    ``2 / d1 + 2 / d2`` (delta method); with
    ``d1 = n f / (1 + 2 sum_k rho_k^2)`` (``n`` samples, ``f`` the dof fraction, ``rho`` the
    noise's correlation) and ``d2`` the pre-trigger samples less one. The score is
    ``sum w log F / sqrt(sum w)`` with ``w = 1 / var``.
    """
    inflation = 1.0 + 2.0 * float(np.sum(np.asarray(correlation)[1:] ** 2))
    logs, weights = [], []
    at = 0
    for i, n in enumerate(lengths):
        part = residual[at : at + n * channels].reshape(n, channels)
        at += n * channels
        if pre_counts[i] < 8:
            continue
        v = np.sum(part**2, axis=0) / (n * dof_fraction)
        u = pre_variance[i]
        ok = (v > 0.0) & (u > 0.0)
        d1 = n * dof_fraction / inflation
        d2 = pre_counts[i] - 1.0
        var = 2.0 / d1 + 2.0 / d2
        logs.extend((np.log(v[ok] / u[ok]) - (1.0 / d2 - 1.0 / d1)).tolist())  # E log F(d1, d2) ~ 1/d2 - 1/d1
        weights.extend([1.0 / var] * int(ok.sum()))
    if not logs:
        return None
    w, lg = np.asarray(weights), np.asarray(logs)
    z = float(np.sum(w * lg) / math.sqrt(float(np.sum(w))))
    ratio = float(np.exp(np.sum(w * lg) / np.sum(w)))
    return MisfitTest(ratio, z, 0.5 * math.erfc(z / math.sqrt(2.0)), false_alarm)


def budgeted_misfit_test(
    residual: Array,
    lengths: Sequence[int],
    channels: int,
    dof_fraction: float,
    pre_counts: Sequence[float],
    pre_variance: Array,
    correlation: Array,
    systematic: Array,
    moments: tuple[Array, Array],
    false_alarm: float = FALSE_ALARM,
    absorbed: float = 0.0,
) -> MisfitTest | None:
    """The residual against the pre-trigger's noise plus the misfit the stated sensor errors leave.

    Parameters
    ----------
    residual, lengths, channels, dof_fraction, pre_counts, pre_variance, correlation, false_alarm
        As for :func:`misfit_test`.
    systematic : ndarray, shape (k, k)
        ``G^T (I - P) G``: the sensor errors' signatures in the weighted residual
        (columns of ``G``, one per unit error), less what the fit absorbs (``P``, the
        projector on the fit's Jacobian and linear terms).
    moments : (ndarray, ndarray), shape (k,) each
        Per error, ``E x^2`` and ``Var x^2`` (:meth:`rigidid.core.sensor_budget.SensorBounds.moments`).
    absorbed : float
        Degrees of freedom of the noise that a correction fitted from the same residual took
        (the sensors' errors estimated with the body: ``2 tr(S Q) - tr(S Q S Q)``, about one per
        well-determined error; ``_after_correction`` in :mod:`rigidid.core.timedomain.refine`): the noise's
        expected part is less by that many times the mean noise variance per residual.

    Returns
    -------
    MisfitTest or None
        None when an impact has a pre-trigger of fewer than 8 samples (then
        :func:`misfit_test` applies).

    Notes
    -----
    The weighted residual sum of squares ``R`` is noise, ``sum u_ic m_ic`` on average
    (``u`` the pre-trigger variance, ``m = n f`` the degrees of freedom), plus the sensor
    errors' part ``X = x^T Q x`` with ``E X = sum Q_kk v_k`` and, the errors independent
    and symmetric, ``Var X = 2 sum_{k != l} Q_kl^2 v_k v_l + sum Q_kk^2 Var x_k^2``
    (GUM 4.3 for the distributions; the moments of a quadratic form). ``R``'s variance
    adds the noise's (``2 u^2 m`` times the decimation filter's inflation, and ``2 u^2
    m^2 / d2`` for ``u`` estimated from ``d2`` pre-trigger samples) and their cross term
    ``4 E X``. ``R`` is taken as a gamma variable of that mean and variance
    (Satterthwaite), its upper tail by the Wilson-Hilferty cube root. A correction's `absorbed`
    degrees of freedom come off the noise's mean (its variance's change, of the same relative
    order, is left out).
    """
    if any(c < 8 for c in pre_counts[: len(lengths)]):
        return None
    inflation = 1.0 + 2.0 * float(np.sum(np.asarray(correlation)[1:] ** 2))
    rss = noise_mean = noise_var = 0.0
    at = 0
    for i, n in enumerate(lengths):
        part = residual[at : at + n * channels].reshape(n, channels)
        at += n * channels
        m, u = n * dof_fraction, np.asarray(pre_variance[i], dtype=float)
        rss += float(np.sum(part**2))
        noise_mean += float(np.sum(u) * m)
        noise_var += float(np.sum(2.0 * u**2 * m * inflation + 2.0 * u**2 * m**2 / (pre_counts[i] - 1.0)))
    if noise_mean <= 0.0:
        return None
    v, sv = (np.asarray(x, dtype=float) for x in moments)
    q = np.asarray(systematic, dtype=float)
    d = np.diag(q)
    mean_x = float(d @ v)
    var_x = float(2.0 * (v @ (q**2) @ v - np.sum(d**2 * v**2)) + np.sum(d**2 * sv))
    unit = noise_mean / sum(n * dof_fraction * channels for n in lengths)  # mean noise variance per residual
    mean = noise_mean - absorbed * unit + mean_x
    var = noise_var + var_x + 4.0 * mean_x * unit
    nu = 2.0 * mean**2 / var  # chi-square degrees of freedom of the gamma approximation
    z = ((rss / mean) ** (1.0 / 3.0) - (1.0 - 2.0 / (9.0 * nu))) / math.sqrt(2.0 / (9.0 * nu))
    p = 0.5 * math.erfc(z / math.sqrt(2.0))
    return MisfitTest(rss / noise_mean, z, p, false_alarm, expected=mean / noise_mean)
