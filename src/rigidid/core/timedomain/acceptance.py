"""Whether the output-error refit explains the records to their noise: a test with a stated false-alarm rate.

The refit (:mod:`rigidid.core.timedomain.refine`) models the free decays of eq. (19) of [1]
plus noise. When the model is right, each impact's and channel's residual variance
estimates the same noise variance as the pre-trigger before that impact (no signal there),
and their ratio is F-distributed on the residual's and the pre-trigger's degrees of freedom.
The per-impact, per-channel log ratios are pooled with inverse-variance weights into one
normal score; the fit is accepted when its one-sided p-value is at least the stated
false-alarm rate (:data:`FALSE_ALARM`): on records the model explains, it rejects that
fraction of fits, whatever the noise level of each impact and channel.

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

__all__ = ["FALSE_ALARM", "MisfitTest", "misfit_test"]

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
    """

    ratio: float
    z: float
    p_value: float
    false_alarm: float

    @property
    def accepted(self) -> bool:
        """Whether the p-value is at least the false-alarm rate."""
        return bool(self.p_value >= self.false_alarm)


def misfit_test(
    residual: Array,
    lengths: Sequence[int],
    channels: int,
    dof_fraction: float,
    pre_counts: Sequence[int],
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
    pre_counts : sequence of int
        Pre-trigger samples of each impact.
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
