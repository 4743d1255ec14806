"""The after-check of the sensors' correction: the misfit it expects once the gains and tilts are estimated (issue 23).

The refit's correction is a linearised maximum a posteriori step; what it leaves in the residual is derived in
:func:`rigidid.core.timedomain.refine._after_correction`. Checked here on the linear model itself, written afresh
(a residual ``(I - P_J) (G x + e)``, errors drawn from their stated rectangular priors, the correction as the
information form ``(Q_ee + V_e^-1)^-1 R_e^T r``): the after-check's p-values are uniform.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import kstest

from rigidid.core.timedomain.acceptance import budgeted_misfit_test
from rigidid.core.timedomain.refine import _after_correction

CHANNELS, LENGTH, PARAMETERS = 4, 60, 5


def _p_values(draws: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The after-check's p-values over `draws`: as budgeted now, and as budgeted before (the kept kinds' ``Q``
    alone, no noise taken by the correction)."""
    rng = np.random.default_rng(seed)
    n = CHANNELS * LENGTH
    jac = rng.standard_normal((n, PARAMETERS))
    gains = rng.standard_normal((n, 6)) * 0.2  # two sensors x three estimated kinds (gain, two tilts)
    # the kept kinds (positions): largely what the estimated ones can absorb, partly their own
    kept = gains @ rng.standard_normal((6, 6)) + 0.3 * rng.standard_normal((n, 6)) * 0.2
    g = np.hstack([gains, kept])
    basis, _ = np.linalg.qr(jac)
    r_mat = g - basis @ (basis.T @ g)  # R = (I - P_J) G
    q = r_mat.T @ r_mat
    half = np.repeat([3.0, 3.0, 3.0, 2.0, 2.0, 2.0], 2)  # rectangular half-widths
    v, sv = half**2 / 3.0, 4.0 * half**4 / 45.0
    est = np.repeat(np.arange(6), 2) < 3
    q_after, absorbed = _after_correction(q, v, np.where(est, v, 0.0))
    info = q[np.ix_(est, est)] + np.diag(1.0 / v[est])
    rest = ~est
    new, old = [], []
    for _ in range(draws):
        x = rng.uniform(-half, half)
        e = rng.standard_normal(n)
        r = r_mat @ x + (e - basis @ (basis.T @ e))
        x_hat = np.linalg.solve(info, r_mat[:, est].T @ r)
        after = r - r_mat[:, est] @ x_hat
        common = (after, [LENGTH], CHANNELS, (n - PARAMETERS) / n, [10**9], np.ones((1, CHANNELS)), np.ones(1))
        new.append(budgeted_misfit_test(*common, q_after, (v, sv), absorbed=absorbed).p_value)  # type: ignore[union-attr]
        before = budgeted_misfit_test(*common, q, (np.where(rest, v, 0.0), np.where(rest, sv, 0.0)))
        old.append(before.p_value)  # type: ignore[union-attr]
    return np.array(new), np.array(old)


def test_the_after_check_budgets_what_the_correction_leaves_and_its_p_values_are_uniform() -> None:
    new, old = _p_values(600, 23)
    # uniform (KS p observed 0.16, mean p 0.52; seeds 1, 2: 0.08, 0.32): the errors' remaining part, the kept
    # kinds less what the estimated ones absorb, and the noise the correction takes (about one per estimated error)
    assert kstest(new, "uniform").pvalue > 0.01
    assert 0.45 < float(np.mean(new)) < 0.55
    # budgeted as before, the kept kinds' whole misfit expected: p-values crowd at 1 (mean observed 0.97)
    assert float(np.mean(old)) > 0.8
    # (with the noise the correction takes left out, or the estimated errors' share of the kept kinds, or both:
    # KS p 1e-12, 0, 0)
