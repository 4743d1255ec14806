"""The one Levenberg-Marquardt of the core: a stack of small nonlinear least-squares problems.

It owns the damped Gauss-Newton loop both nonlinear fits of the core share: the CG of
eq. (18) (:func:`rigidid.core.estimator.solve_cg`, three unknowns, thousands of tests at
once) and the output-error fit of the records (:func:`rigidid.core.timedomain.refine.refine_body`,
51 unknowns, one problem, with geodesic acceleration). The caller supplies the cost
``|r|^2``, its gradient ``J^T r`` and the Gauss-Newton matrix ``J^T J``; the loop knows nothing
of the model.

The stop holds at zero residual: besides the statistical test (the Gauss-Newton decrement
against the residual variance, a ratio of round-off to round-off when the data are exact),
a problem stops, converged, once the decrement is below the rounding floor of the cost,
``(ROUNDING_FLOOR eps)^2`` times the scale of the data.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .linalg import rank_tolerance, solve_rows

__all__ = ["ROUNDING_FLOOR", "Minimum", "gauss_newton_decrement", "levenberg_marquardt"]

Array = NDArray[np.float64]
BArray = NDArray[np.bool_]
IArray = NDArray[np.int64]

NormalEquations = Callable[[Array, IArray], tuple[Array, Array, Array]]
"""``(x (k, n), index (k,)) -> (cost (k,), J^T r (k, n), J^T J (k, n, n))`` of the problems ``index``."""
Cost = Callable[[Array, IArray], Array]
"""``(x (k, n), index (k,)) -> cost (k,)``; ``inf`` where the model cannot be evaluated."""
Acceleration = Callable[[Array, Array, IArray], Array]
"""``(x (k, n), step (k, n), index (k,)) -> J^T r''_v (k, n)``, the second directional derivative."""

ROUNDING_FLOOR = 1e5
"""A Gauss-Newton decrement below ``(ROUNDING_FLOOR eps)^2`` times the data's scale is round-off.

The record refit's model (an eigendecomposition, then exponentials over thousands of
samples) rounds to about ``1.6e4 eps`` of the data: observed on the four-mounts body's exact
records, where the decrement stalled at 260 times ``(1e3 eps)^2 |y|^2``. Harmless on real
data: it exceeds the statistical test only at a signal-to-noise ratio above about 1e9."""

_MU0 = 1e-3  # initial damping
_MU_MAX = 1e10  # damping past which no step lowers the cost: give up
_MU_MIN = 1e-12
_GEODESIC_ALPHA = 0.75  # largest 2 |acceleration| / |step| (D norm) of a step that is tried
_ACCELERATION_EVALUATIONS = 2  # a central difference of the residual


@dataclass(frozen=True)
class Minimum:
    """Where :func:`levenberg_marquardt` stopped, per problem.

    Attributes
    ----------
    x : ndarray, shape (m, n)
        The parameters.
    cost : ndarray, shape (m,)
        ``|r|^2`` there.
    converged : ndarray of bool, shape (m,)
        Whether a convergence test fired (rather than the budget, the damping limit or a
        cost that cannot be evaluated).
    evaluations : ndarray of int, shape (m,)
        Evaluations of the cost or normal equations (an acceleration counts two).
    """

    x: Array
    cost: Array
    converged: BArray
    evaluations: IArray


def gauss_newton_decrement(gradient: Array, hessian: Array) -> Array:
    """``g^T (J^T J)^+ g``: the cost decrease a full Gauss-Newton step predicts.

    Parameters
    ----------
    gradient : ndarray, shape (m, n)
        ``g = J^T r``.
    hessian : ndarray, shape (m, n, n)
        ``J^T J``; eigenvalues below the one rank tolerance
        (:func:`rigidid.core.linalg.rank_tolerance`) are dropped (pseudo-inverse).

    Returns
    -------
    ndarray, shape (m,)
        The decrement (cost units; zero at a stationary point).
    """
    w, v = np.linalg.eigh(hessian)
    keep = w > rank_tolerance(np.maximum(w[:, -1:], 1e-300), w.shape[1])  # below: a null direction
    proj = np.einsum("bji,bj->bi", v, gradient)
    out: Array = np.sum(np.where(keep, proj**2 / np.where(keep, w, 1.0), 0.0), axis=1)
    return out


@dataclass
class _State:
    x: Array
    cost: Array
    grad: Array
    hess: Array
    mu: Array
    nu: Array
    drop: Array
    nfev: IArray
    active: BArray
    converged: BArray


def _converged(state: _State, idx: IArray, floor: Array, dof: float, tests: tuple[float, float, float]) -> BArray:
    """The stop tests at the accepted points ``idx``: rounding floor, decrement, stall."""
    tol, stall, stall_decrement = tests
    dec = gauss_newton_decrement(state.grad[idx], state.hess[idx])
    variance = np.maximum(state.cost[idx] / dof, 1e-300)
    done = (dec <= floor[idx]) | (state.cost[idx] <= floor[idx])
    done |= dec <= tol * variance
    done |= (state.drop[idx] <= stall * variance) & (dec <= stall_decrement * variance)
    return done


def _step(state: _State, idx: IArray, acceleration: Acceleration | None) -> tuple[Array, Array, BArray]:
    """Damped step ``(J^T J + mu D) v = -J^T r`` (``D = diag(J^T J)``, floored), with half the
    geodesic acceleration; also the predicted decrease and which steps may be tried."""
    h, g = state.hess[idx], state.grad[idx]
    diag = np.einsum("bii->bi", h)
    d = np.maximum(diag, 1e-12 * np.maximum(np.max(diag, axis=1, keepdims=True), 1e-300))
    lhs = h + state.mu[idx, None, None] * (d[:, :, None] * np.eye(h.shape[1]))
    step, ok = solve_rows(lhs, -g[..., None])
    step = np.nan_to_num(step[..., 0])
    predicted = -(2.0 * np.einsum("bi,bi->b", g, step) + np.einsum("bi,bij,bj->b", step, h, step))
    if acceleration is None:
        return step, predicted, ok
    state.nfev[idx] += _ACCELERATION_EVALUATIONS
    acc, ok_acc = solve_rows(lhs, -acceleration(state.x[idx], step, idx)[..., None])
    acc = np.where(ok_acc[:, None], np.nan_to_num(acc[..., 0]), 0.0)
    size = np.maximum(np.einsum("bi,bi->b", step, d * step), 1e-300)
    ratio = 2.0 * np.sqrt(np.einsum("bi,bi->b", acc, d * acc) / size)
    return step + 0.5 * acc, predicted, ok & (ratio <= _GEODESIC_ALPHA)


def _accept(state: _State, idx: IArray, step: Array, cost_new: Array, predicted: Array) -> None:
    """Take the steps that lowered the cost; Nielsen's damping update from the gain ratio."""
    gained = state.cost[idx] - cost_new
    rho = np.minimum(np.where(predicted > 0.0, gained / np.where(predicted > 0.0, predicted, 1.0), 0.0), 1.0)
    state.drop[idx] = gained
    state.x[idx] += step
    state.mu[idx] = np.maximum(state.mu[idx] * np.maximum(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3), _MU_MIN)
    state.nu[idx] = 2.0


def levenberg_marquardt(
    normal: NormalEquations,
    cost: Cost,
    x0: Array,
    *,
    max_evaluations: int,
    scale: Array | None = None,
    residuals: int = 0,
    decrement: float = 0.0,
    stall: tuple[float, float] = (0.0, 0.0),
    acceleration: Acceleration | None = None,
    damping: float = _MU0,
) -> Minimum:
    """Minimise the costs ``|r_i(x_i)|^2`` of a stack of problems by Levenberg-Marquardt.

    Parameters
    ----------
    normal : callable
        ``normal(x, index) -> (cost, J^T r, J^T J)`` for the problems ``index``, evaluated
        at the start and at every accepted point (the expensive call).
    cost : callable
        ``cost(x, index) -> |r|^2`` at trial points (``inf`` where the model fails).
    x0 : ndarray, shape (m, n)
        Starting points.
    max_evaluations : int
        Budget of evaluations per problem (may overrun by the three of one iteration).
    scale : ndarray, shape (m,), optional
        The scale of each problem's data (``|y|^2`` in cost units) for the rounding floor;
        the cost at the start by default.
    residuals : int
        Residuals per problem, for the variance ``cost / (residuals - n)`` of the
        statistical tests.
    decrement : float
        Converged once the Gauss-Newton decrement ``g^T (J^T J)^+ g`` is below this many
        residual variances (0: only the rounding floor).
    stall : (float, float)
        ``(s, d)``: also converged once the last accepted step lowered the cost by less than
        ``s`` variances while the decrement is below ``d`` variances (a minimum on the
        boundary of the parameterisation, where the Gauss-Newton step points out of reach).
    acceleration : callable, optional
        ``acceleration(x, v, index) -> J^T r''_v``: adds half the geodesic acceleration
        ``a``, ``(J^T J + mu D) a = -J^T r''_v``, to each step; a step with
        ``2 |a| / |v| > 0.75`` (``D`` norm) is refused untried.
    damping : float
        The initial damping ``mu`` (1e-3; a start already near the minimum, e.g. a
        coarser fit's end, takes Gauss-Newton steps at once with a small one).

    Returns
    -------
    Minimum

    Notes
    -----
    Each iteration solves ``(J^T J + mu D) v = -J^T r`` with Marquardt's scaling
    ``D = diag(J^T J)`` and tries ``x + v``. The damping follows Nielsen's rule: times
    ``max(1/3, 1 - (2 rho - 1)^3)`` after a step that lowers the cost (``rho`` the actual
    over the predicted decrease), times 2, 4, 8... after each refused one; a problem past
    damping 1e10 stops unconverged. Converged when the decrement is below the rounding
    floor ``(ROUNDING_FLOOR eps)^2 scale`` (or the cost itself is), so exact data stop
    where the statistical test, round-off over round-off, never fires.

    Examples
    --------
    The minimum of ``(x - 3)^2`` from 0:

    >>> fun = lambda x, i: (x[:, 0] - 3.0) ** 2
    >>> nrm = lambda x, i: (fun(x, i), x - 3.0, np.ones((x.shape[0], 1, 1)))
    >>> out = levenberg_marquardt(nrm, fun, np.zeros((1, 1)), max_evaluations=50)
    >>> round(float(out.x[0, 0]), 9), bool(out.converged[0])
    (3.0, True)
    """
    x = np.array(x0, dtype=float, copy=True)
    m, n = x.shape
    every = np.arange(m)
    c0, g0, h0 = normal(x, every)
    state = _State(
        x, np.asarray(c0, float).copy(), g0.copy(), h0.copy(), np.full(m, float(damping)), np.full(m, 2.0),
        np.full(m, math.inf), np.ones(m, dtype=np.int64), np.isfinite(c0), np.zeros(m, dtype=bool),
    )  # fmt: skip
    floor = (ROUNDING_FLOOR * np.finfo(float).eps) ** 2 * (state.cost if scale is None else np.asarray(scale, float))
    tests = (decrement, *stall)
    dof = float(max(residuals - n, 1))
    check = every[state.active]
    while True:
        if check.size:
            hit = _converged(state, check, floor, dof, tests)
            state.converged[check[hit]] = True
            state.active[check[hit]] = False
        state.active &= (state.nfev < max_evaluations) & (state.mu < _MU_MAX)
        idx = np.flatnonzero(state.active)
        if idx.size == 0:
            break
        step, predicted, ok = _step(state, idx, acceleration)
        cost_new = np.full(idx.size, math.inf)
        tried = idx[ok]
        if tried.size:
            cost_new[ok] = cost(state.x[tried] + step[ok], tried)
            state.nfev[tried] += 1
        better = cost_new < state.cost[idx]
        rej = idx[~better]
        state.mu[rej] *= state.nu[rej]
        state.nu[rej] *= 2.0
        check = idx[better]
        if check.size:
            _accept(state, check, step[better], cost_new[better], predicted[better])
            state.cost[check], state.grad[check], state.hess[check] = normal(state.x[check], check)
            state.nfev[check] += 1
    return Minimum(state.x, state.cost, state.converged, state.nfev)
