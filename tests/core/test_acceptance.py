"""The refit's acceptance test: its false-alarm rate is the stated one, and a misfit is rejected (issue 23)."""

from __future__ import annotations

import numpy as np

from rigidid.core.timedomain.acceptance import FALSE_ALARM, misfit_test
from rigidid.core.timedomain.intervals import noise_correlation


def _draw(rng: np.random.Generator, excess: float) -> float:
    """p-value of one synthetic fit: 3 impacts x 4 channels, noise levels differing by impact and channel."""
    lengths, p, pre = [900, 700, 800], 4, [120, 90, 150]
    levels = rng.uniform(0.5, 2.0, (3, p))
    residual = np.concatenate([(rng.standard_normal((n, p)) * levels[i] * np.sqrt(excess)).ravel()
                               for i, n in enumerate(lengths)])  # fmt: skip
    pre_var = np.array([np.var(rng.standard_normal((m, p)) * levels[i], axis=0, ddof=1) for i, m in enumerate(pre)])
    test = misfit_test(residual, lengths, p, 1.0, pre, pre_var, noise_correlation(1))
    assert test is not None
    return test.p_value


def test_the_false_alarm_rate_is_the_stated_one_whatever_the_noise_of_each_impact_and_channel() -> None:
    rng = np.random.default_rng(0)
    p = np.array([_draw(rng, 1.0) for _ in range(2000)])
    # observed 0.0125 over 2000 draws (binomial se 0.0022); the p-values uniform
    assert abs(np.mean(p < FALSE_ALARM) - FALSE_ALARM) < 0.007
    assert abs(np.mean(p < 0.5) - 0.5) < 0.04


def test_a_residual_a_quarter_above_the_noise_is_rejected() -> None:
    rng = np.random.default_rng(1)
    p = np.array([_draw(rng, 1.25) for _ in range(200)])
    assert np.mean(p < FALSE_ALARM) > 0.9


def test_the_verdict_keeps_an_accepted_refit_names_a_mild_misfit_and_falls_back_beyond() -> None:
    from types import SimpleNamespace

    from rigidid.api.records import refit_verdict
    from rigidid.core.timedomain.acceptance import MisfitTest

    def fit(ratio: float, p: float, cost: float) -> SimpleNamespace:
        return SimpleNamespace(misfit=MisfitTest(ratio, 0.0, p, FALSE_ALARM), normalised_cost=cost)

    assert refit_verdict(fit(1.01, 0.3, 1.01)) == (True, "")
    keep, reason = refit_verdict(fit(1.44, 1e-9, 1.44))
    assert keep and "p = 1e-09" in reason and "from its residual's level" in reason
    keep, reason = refit_verdict(fit(3.8, 0.0, 3.9))
    assert not keep and "kept the answer from the modes" in reason
    assert refit_verdict(SimpleNamespace(misfit=None, normalised_cost=1.5)) == (True, "")
    assert not refit_verdict(SimpleNamespace(misfit=None, normalised_cost=2.5))[0]


def _budgeted_draw(rng: np.random.Generator, scale: float) -> float:
    """p-value of one synthetic fit whose sensor errors (rectangular, `scale` times the stated bound) leave a misfit.

    Twelve errors' signatures of unequal size, less their projection on a 5-parameter fit; the stated bound 1.
    """
    from rigidid.core.timedomain.acceptance import budgeted_misfit_test

    lengths, p, pre = [300, 250, 280], 4, [120, 90, 150]
    rows = sum(lengths) * p
    g = _SIGNATURES
    x = rng.uniform(-scale, scale, g.shape[1])
    levels = np.concatenate([np.tile(_LEVELS[i], n) for i, n in enumerate(lengths)])
    residual = rng.standard_normal(rows) * levels + g @ x
    pre_var = np.array([np.var(rng.standard_normal((m, p)) * _LEVELS[i], axis=0, ddof=1) for i, m in enumerate(pre)])
    moments = (np.full(g.shape[1], 1.0 / 3.0), np.full(g.shape[1], 1.0 / 5.0 - 1.0 / 9.0))
    test = budgeted_misfit_test(residual, lengths, p, 1.0, pre, pre_var, noise_correlation(1), g.T @ g, moments)
    assert test is not None and rows == g.shape[0]
    return test.p_value


_rng = np.random.default_rng(7)
_LEVELS = _rng.uniform(0.5, 2.0, (3, 4))
_raw = _rng.standard_normal((3320, 12)) * np.geomspace(3.0, 0.3, 12) * 0.8
_fitq = np.linalg.qr(_rng.standard_normal((3320, 5)))[0]
_SIGNATURES = _raw - _fitq @ (_fitq.T @ _raw)


def test_the_budgeted_test_expects_the_misfit_of_errors_within_their_stated_bounds() -> None:
    rng = np.random.default_rng(2)
    p = np.array([_budgeted_draw(rng, 1.0) for _ in range(1000)])
    # errors drawn within the stated bounds: rejected at most at about the stated rate (observed 0.003: the
    # gamma approximation's tail is heavier than a bounded quadratic form's); the p-values' median near 0.5
    assert np.mean(p < FALSE_ALARM) < 0.025 and abs(np.median(p) - 0.5) < 0.1
    # errors twice the stated bounds: the excess is found
    assert np.mean(np.array([_budgeted_draw(rng, 2.0) for _ in range(100)]) < FALSE_ALARM) > 0.6  # observed 0.9
