"""The one Levenberg-Marquardt (rigidid.core.optimize): properties, not iteration counts.

Where it must stop: at the minimum from a far start; converged on exact data (zero residual,
where the statistical test divides round-off by round-off); not converged when the budget is
clearly too small; a stack of problems as each alone; the noisy minimum an independent
optimiser (scipy's MINPACK) finds.
"""

from __future__ import annotations

import numpy as np
import pytest

from rigidid.core.optimize import gauss_newton_decrement, levenberg_marquardt
from rigidid.core.timedomain.refine import _levenberg_marquardt

T = np.linspace(0.0, 4.0, 80)
TRUTH = np.array([2.0, 1.3, 0.5, 3.0])
FAR = np.array([1.0, 0.5, 1.0, 2.9])  # residual ~100x the data's noise-free scale at the minimum


def _model(p: np.ndarray) -> np.ndarray:
    return np.asarray(p[0] * np.exp(-p[1] * T) + p[2] * np.cos(p[3] * T))


def _jac(p: np.ndarray) -> np.ndarray:
    e = np.exp(-p[1] * T)
    return np.column_stack([e, -p[0] * T * e, np.cos(p[3] * T), -p[2] * T * np.sin(p[3] * T)])


def _problem(y: np.ndarray):  # type: ignore[no-untyped-def]
    """Stacked callbacks of the decay-plus-cosine fit to the rows of `y` (m, 80)."""

    def cost(x: np.ndarray, index: np.ndarray) -> np.ndarray:
        return np.array([float(np.sum((_model(p) - y[i]) ** 2)) for p, i in zip(x, index, strict=True)])

    def normal(x: np.ndarray, index: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        r = [_model(p) - y[i] for p, i in zip(x, index, strict=True)]
        jm = [_jac(p) for p in x]
        return (np.array([ri @ ri for ri in r]), np.array([j.T @ ri for j, ri in zip(jm, r, strict=True)]),
                np.array([j.T @ j for j in jm]))  # fmt: skip

    return normal, cost


def test_reaches_the_exact_minimum_from_far_and_says_converged() -> None:
    y = _model(TRUTH)[None]
    normal, cost = _problem(y)
    out = levenberg_marquardt(normal, cost, FAR[None], max_evaluations=400, residuals=T.size, decrement=0.05,
                              scale=np.array([y @ y[0]]).ravel())  # fmt: skip
    np.testing.assert_allclose(out.x[0], TRUTH, atol=1e-9)
    assert out.cost[0] < 1e-20 * float(y[0] @ y[0])
    # the zero-residual stop: the statistical test alone never fires on exact data
    assert out.converged[0]
    assert out.evaluations[0] < 400


@pytest.mark.parametrize("budget", [100, 200, 400])
def test_exact_data_converge_whatever_the_budget_with_geodesic_acceleration(budget: int) -> None:
    # the refit's route (refine._levenberg_marquardt): the failure was 101/104/104
    # evaluations for budgets 100/200/400, converged False at |r|^2 1e-27
    y = _model(TRUTH)

    def fun(p: np.ndarray) -> np.ndarray:
        return _model(p) - y

    def both(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return fun(p), _jac(p)

    theta, nfev, r, jm, converged = _levenberg_marquardt(fun, both, FAR, budget, T.size, float(y @ y))
    np.testing.assert_allclose(theta, TRUTH, atol=1e-9)
    assert converged and nfev < budget
    np.testing.assert_allclose(r, fun(theta), atol=1e-14)  # the residual and Jacobian at the answer
    np.testing.assert_allclose(jm, _jac(theta), atol=1e-14)


def test_a_budget_clearly_too_small_is_not_converged() -> None:
    y = _model(TRUTH)[None]
    normal, cost = _problem(y)
    out = levenberg_marquardt(normal, cost, FAR[None], max_evaluations=4, residuals=T.size, decrement=0.05)
    assert not out.converged[0]
    assert np.max(np.abs(out.x[0] - TRUTH)) > 1e-3  # and indeed far from the minimum


def test_noisy_minimum_is_minpacks_and_the_decrement_is_below_the_test() -> None:
    from scipy.optimize import least_squares

    rng = np.random.default_rng(3)
    y = _model(TRUTH) + 0.05 * rng.standard_normal(T.size)
    normal, cost = _problem(y[None])
    out = levenberg_marquardt(normal, cost, FAR[None], max_evaluations=400, residuals=T.size, decrement=1e-6)
    oracle = least_squares(lambda p: _model(p) - y, FAR, jac=lambda p: _jac(p), method="lm", xtol=1e-15, ftol=1e-15)
    assert out.converged[0]
    # standard errors of the oracle's fit: the answers agree to a small fraction of them
    jm = _jac(oracle.x)
    s2 = 2.0 * oracle.cost / (T.size - 4)
    std = np.sqrt(s2 * np.diag(np.linalg.inv(jm.T @ jm)))
    assert np.max(np.abs(out.x[0] - oracle.x) / std) < 1e-2
    _, g, h = normal(out.x, np.array([0]))
    assert gauss_newton_decrement(g, h)[0] <= 1e-6 * out.cost[0] / (T.size - 4)


def test_a_stack_is_each_problem_alone() -> None:
    rng = np.random.default_rng(4)
    y = _model(TRUTH)[None] + np.array([0.0, 0.02, 0.1])[:, None] * rng.standard_normal((3, T.size))
    starts = np.stack([FAR, TRUTH * 1.1, FAR * 0.9])
    normal, cost = _problem(y)
    stack = levenberg_marquardt(normal, cost, starts, max_evaluations=400, residuals=T.size, decrement=1e-6)
    for i in range(3):
        n1, c1 = _problem(y[i : i + 1])
        alone = levenberg_marquardt(n1, c1, starts[i : i + 1], max_evaluations=400, residuals=T.size, decrement=1e-6)
        np.testing.assert_array_equal(stack.x[i], alone.x[0])
        assert stack.converged[i] and alone.evaluations[0] == stack.evaluations[i]


def test_a_cost_that_cannot_be_evaluated_is_refused_not_taken() -> None:
    # a model undefined for p[1] < 0.9 (inf there): the fit stays inside and still converges
    y = _model(TRUTH)[None]
    normal, cost = _problem(y)

    def guarded(x: np.ndarray, index: np.ndarray) -> np.ndarray:
        return np.where(x[:, 1] < 0.9, np.inf, cost(x, index))

    out = levenberg_marquardt(normal, guarded, np.array([[1.5, 1.0, 0.6, 2.95]]), max_evaluations=400,
                              residuals=T.size, decrement=0.05)  # fmt: skip
    assert out.converged[0]
    np.testing.assert_allclose(out.x[0], TRUTH, atol=1e-8)


def test_a_parameter_the_data_do_not_determine_does_not_stop_the_fit() -> None:
    # a fifth parameter the residual does not depend on (a mode the impacts do not excite): its
    # column of J is zero, J^T J singular; Marquardt's scaling must stay regular and the fit
    # reach the minimum of the others, the undetermined one left where it started
    y = _model(TRUTH)[None]
    normal, cost = _problem(y)

    def normal5(x: np.ndarray, index: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        c, g, h = normal(x[:, :4], index)
        return c, np.pad(g, ((0, 0), (0, 1))), np.pad(h, ((0, 0), (0, 1), (0, 1)))

    out = levenberg_marquardt(normal5, lambda x, i: cost(x[:, :4], i), np.append(FAR, 0.7)[None],
                              max_evaluations=400, residuals=T.size, decrement=0.05)  # fmt: skip
    assert out.converged[0]
    np.testing.assert_allclose(out.x[0], [*TRUTH, 0.7], atol=1e-9)
