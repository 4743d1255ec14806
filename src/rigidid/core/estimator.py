"""The identification kernel: eqs. (3), (19) and (18) of [1] for a stack of tests at once.

Every route from modes to a body goes through here: :func:`rigidid.core.identify.identify`
is a batch of one plus diagnostics; the Monte Carlo intervals
(:mod:`rigidid.core.uncertainty`), the record-segment intervals and the
predictions of :mod:`rigidid.core.plan` are larger batches. There is one
dimensionless frame, one sensor matrix, one projection on rigid motion, one
eq. (19) and one solver.

The steps, per test:

1. :func:`prepare`: a frame centred on the sensors and scaled by their RMS
   radius (:func:`~rigidid.core.geometry.frame_arrays`) and by the RMS natural
   frequency, so that results do not depend on origin and units; the sensor
   matrix ``T`` (eq. (3)); the least-squares rigid-body coordinates of the
   measured shapes (:func:`~rigidid.core.selection.project_rigid_batch`); the
   exact ``Q = M^-1 K`` and ``P = M^-1 C`` at the frame's origin (eq. (19),
   :func:`~rigidid.core.statespace.state_matrices_batch`).
2. :func:`solve_cg`: the CG minimising the antisymmetric part of
   ``diag(I, J/m) X_g`` for ``X = Q`` and, with a weight, ``X = P``
   (eq. (18) and its damping twin), with ``J / m`` eliminated by linear least
   squares for each trial CG (variable projection) and the CG found by
   Levenberg-Marquardt from two starts, eq. (36) and the sensor centroid.
3. :func:`at_cg`: ``K / m = sym(D Q_g)`` and ``C / m = sym(D P_g)``.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rigidid.core.geometry import frame_arrays, sensor_matrix
from rigidid.core.linalg import numerical_rank, pseudo_inverse, solve_rows
from rigidid.core.optimize import levenberg_marquardt
from rigidid.core.selection import project_rigid_batch
from rigidid.core.statespace import state_matrices_batch

__all__ = [
    "DAMPING_WEIGHT",
    "STATUS_MESSAGES",
    "Estimates",
    "Prepared",
    "at_cg",
    "concatenate",
    "eq18_residuals",
    "eq36_system",
    "estimate",
    "estimate_near",
    "inertia_from_params",
    "observability_batch",
    "prepare",
    "solve_cg",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]
BArray = NDArray[np.bool_]
IArray = NDArray[np.int8]

DAMPING_WEIGHT = 0.3
"""Default weight of the damping equations against the stiffness equations."""

OK, NOT_FINITE, UNSTABLE, RANK, SINGULAR_MODES, NO_SOLUTION = range(6)
STATUS_MESSAGES: dict[int, str] = {
    OK: "identified",
    NOT_FINITE: "positions, directions, poles or shapes are not finite",
    UNSTABLE: "poles must be stable with positive imaginary part",
    RANK: "the sensor layout has rank below 6; rigid-body motion needs rank 6",
    SINGULAR_MODES: "the modes do not span the rigid-body motion (singular modal matrix)",
    NO_SOLUTION: "the solution is not finite",
}
"""What each status code of :attr:`Prepared.status` and :attr:`Estimates.status` means."""

_CHUNK = 4096
"""Tests identified together by :func:`estimate` (bounds memory: about 20 kB per test)."""

_FLAT = 1e-10
"""Levenberg-Marquardt stops once a Gauss-Newton step would lower the cost by less than this fraction."""

_MAX_EVALUATIONS = 800
"""Levenberg-Marquardt's budget of cost evaluations per test."""

_POLISH_STEPS = 8
"""Gauss-Newton steps on the gradient after Levenberg-Marquardt (see :func:`solve_cg`)."""

# the six symmetric 3x3 basis matrices of J / m: xx, yy, zz, xy, xz, yz
_SYM_PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
_SYM3 = np.zeros((6, 3, 3))
for _k, (_a, _b) in enumerate(_SYM_PAIRS):
    _SYM3[_k, _a, _b] = _SYM3[_k, _b, _a] = 1.0
_UP3 = ([0, 0, 1], [1, 2, 2])
# S(e_i): the skew matrices of the unit vectors
_SKEW_BASIS = np.zeros((3, 3, 3))
_SKEW_BASIS[0, 2, 1], _SKEW_BASIS[0, 1, 2] = 1.0, -1.0
_SKEW_BASIS[1, 0, 2], _SKEW_BASIS[1, 2, 0] = 1.0, -1.0
_SKEW_BASIS[2, 1, 0], _SKEW_BASIS[2, 0, 1] = 1.0, -1.0


def inertia_from_params(params: Array) -> Array:
    """Symmetric ``(..., 3, 3)`` matrices from their six parameters ``xx, yy, zz, xy, xz, yz``.

    Examples
    --------
    >>> inertia_from_params(np.array([1.0, 2.0, 3.0, 0.1, 0.2, 0.3])).tolist()
    [[1.0, 0.1, 0.2], [0.1, 2.0, 0.3], [0.2, 0.3, 3.0]]
    """
    result: Array = np.einsum("...k,kij->...ij", params, _SYM3)
    return result


def _skew(g: Array) -> Array:
    """``S(g)`` for stacked vectors: (..., 3) -> (..., 3, 3)."""
    result: Array = np.einsum("...i,ijk->...jk", g, _SKEW_BASIS)
    return result


def _anti_up(y: Array) -> Array:
    """Upper entries of ``Y - Y^T`` of stacked 3x3 matrices: (..., 3, 3) -> (..., 3)."""
    d: Array = (y - np.swapaxes(y, -1, -2))[..., _UP3[0], _UP3[1]]
    return d


def _pinv_psd(n: Array) -> Array:
    """Stacked inverse of symmetric positive semi-definite matrices; pseudo-inverse where singular."""
    x, ok = solve_rows(n, np.broadcast_to(np.eye(n.shape[-1]), n.shape).copy())
    if not np.all(ok):
        x[~ok] = [pseudo_inverse(m, symmetric=True)[0] for m in n[~ok]]
    return np.asarray(x, dtype=float)


class _Statuses:
    """A stack of tests, each with a status code (0 for usable, else a key of :data:`STATUS_MESSAGES`)."""

    status: IArray

    @property
    def ok(self) -> BArray:
        """Tests with status 0."""
        result: BArray = self.status == OK
        return result


# --------------------------------------------------------------------------- step 1: data -> Q, P


@dataclass(frozen=True)
class Prepared(_Statuses):
    """A stack of tests in the dimensionless frame, ready for eq. (18).

    Attributes
    ----------
    centre : ndarray, shape (B, 3)
        Sensor centroid of each test (length).
    scale : ndarray, shape (B,)
        RMS radius of the sensors about it (length).
    omega : ndarray, shape (B,)
        RMS modulus of the six poles (rad/s): the time scale.
    transformation : ndarray, shape (B, p, 6)
        Sensor matrix ``T`` (eq. (3)) in the dimensionless frame.
    coordinates : ndarray of complex, shape (B, 6, 6)
        Least-squares rigid-body coordinates of the measured shapes at the
        centroid (dimensionless lengths, rad), one column per mode.
    fit_residual : ndarray, shape (B, 6)
        ``|psi - T T^+ psi| / |psi|`` per mode (0 with six sensors).
    stiffness, damping : ndarray, shape (B, 6, 6)
        ``Q = M^-1 K`` and ``P = M^-1 C`` at the centroid, dimensionless.
    status : ndarray of int8, shape (B,)
        0 for a usable test, else a key of :data:`STATUS_MESSAGES`; the other
        arrays of a failed test hold a copy of a good test's values (so that
        stacked solvers never see them) or NaN.
    """

    centre: Array
    scale: Array
    omega: Array
    transformation: Array
    coordinates: CArray
    fit_residual: Array
    stiffness: Array
    damping: Array
    status: IArray


def _patch(values: NDArray[Any], ok: BArray) -> NDArray[Any]:
    """Rows of failed tests replaced by those of the first good one."""
    if np.all(ok) or not np.any(ok):
        return values
    out = values.copy()
    out[~ok] = values[int(np.flatnonzero(ok)[0])]
    return out


def _fail(status: IArray, where: BArray, code: int) -> None:
    status[(status == OK) & where] = code


def prepare(positions: Array, directions: Array, poles: CArray, shapes: CArray) -> Prepared:
    """Frame, sensor matrix, rigid-body coordinates and eq. (19) of [1] for a stack of tests.

    Parameters
    ----------
    positions : ndarray, shape (B, p, 3)
        Sensor locations (length), ``p >= 6``.
    directions : ndarray, shape (B, p, 3)
        Unit measuring axes.
    poles : ndarray of complex, shape (B, 6)
        One pole per rigid-body mode (rad/s), ``Im > 0``.
    shapes : ndarray of complex, shape (B, p, 6)
        Mode shapes as each sensor reads them along its own direction.

    Returns
    -------
    Prepared
        Failed tests are flagged in :attr:`Prepared.status`, never raised.
    """
    b = positions.shape[0]
    status = np.zeros(b, dtype=np.int8)
    finite = (
        np.all(np.isfinite(positions), axis=(1, 2))
        & np.all(np.isfinite(directions), axis=(1, 2))
        & np.all(np.isfinite(poles), axis=1)
        & np.all(np.isfinite(shapes), axis=(1, 2))
    )
    _fail(status, ~finite, NOT_FINITE)
    with np.errstate(invalid="ignore"):
        _fail(status, ~(np.all(poles.imag > 0.0, axis=1) & np.all(poles.real <= 0.0, axis=1)), UNSTABLE)
    pos, dirs, lam, psi = (_patch(x, status == OK) for x in (positions, directions, poles, shapes))
    centre, scale = frame_arrays(pos)
    t = sensor_matrix((pos - centre[:, None, :]) / scale[:, None, None], dirs)
    rank = numerical_rank(np.linalg.svd(t, compute_uv=False), t.shape[1])
    _fail(status, rank < 6, RANK)
    t = _patch(t, status == OK)
    coords, residual, solved = project_rigid_batch(t, psi)
    _fail(status, ~solved, RANK)
    coords, lam = _patch(coords, status == OK), _patch(lam, status == OK)
    omega = np.sqrt(np.mean(np.abs(lam) ** 2, axis=1))
    q, p, good = state_matrices_batch(lam / omega[:, None], coords)
    _fail(status, ~good, SINGULAR_MODES)
    q, p = _patch(q, status == OK), _patch(p, status == OK)
    return Prepared(centre, scale, omega, t, coords, residual, q, p, status)


# --------------------------------------------------------------------------- step 2: eq. (18) -> CG, J / m


class _VarPro:
    """The residual of eq. (18) of [1] as a function of the CG, ``J / m`` eliminated, for stacked tests.

    For each matrix ``X`` (``Q`` and optionally ``P``, weight ``w``) the 15
    residuals are the upper entries of the antisymmetric part of
    ``diag(I, J) X_g`` with ``X_g = G_go X G_og``:
    ``w [anti(X_g11), X_g12 - X21^T J, anti(J X_g22)]``.
    """

    def __init__(self, mats: Array, weights: Array, white: Array | None = None):
        # mats: (B, n, 6, 6); weights: (n,); white: (15 n, 15 n) shared, (B, 15 n, 15 n) or None
        self.white = white
        if white is not None:
            weights = np.ones_like(weights)
        self.w = weights[None, :, None]
        self.x11 = mats[..., :3, :3]
        self.x12 = mats[..., :3, 3:]
        self.x21 = mats[..., 3:, :3]
        self.x22 = mats[..., 3:, 3:]
        # columns of the g-independent block X21^T E_k -> (B, n, 9, 6)
        e_cols = np.einsum("bnji,kjl->bnkil", self.x21, _SYM3)
        self.a12 = -np.moveaxis(e_cols.reshape(*e_cols.shape[:3], 9), 2, -1) * self.w[..., None]
        a12_flat = self.a12.reshape(self.a12.shape[0], -1, 6)
        self.n12 = np.swapaxes(a12_flat, 1, 2) @ a12_flat

    def take(self, index: NDArray[np.intp]) -> _VarPro:
        """The same problem restricted to some tests."""
        out = object.__new__(_VarPro)
        out.w = self.w
        out.white = self.white if self.white is None or self.white.ndim == 2 else self.white[index]
        for name in ("x11", "x12", "x21", "x22", "a12", "n12"):
            setattr(out, name, getattr(self, name)[index])
        return out

    def evaluate(self, g: Array) -> tuple[Array, Array, Array, Array, tuple[Array, ...]]:
        """Residual (m, 15 n), ``J / m`` parameters (m, 6), A (m, 15 n, 6) and N^-1 (m, 6, 6) at CGs `g`."""
        s = _skew(g)[:, None]  # (m, 1, 3, 3)
        xg11 = self.x11 - s @ self.x21
        xg12 = xg11 @ s + self.x12 - s @ self.x22
        xg22 = self.x21 @ s + self.x22
        m = g.shape[0]
        ey = _SYM3 @ xg22[:, :, None]  # E_k X_g22, (m, n, 6, 3, 3)
        a22 = np.swapaxes(_anti_up(ey), 2, 3) * self.w[..., None]  # (m, n, 3, 6)
        r12_0 = xg12.reshape(m, -1, 9) * self.w  # (m, n, 9)
        if self.white is not None:
            return self._evaluate_white(xg11, r12_0, a22, (s, xg11))
        a22_flat = a22.reshape(m, -1, 6)
        a12_flat = self.a12.reshape(m, -1, 6)
        normal = self.n12 + np.swapaxes(a22_flat, 1, 2) @ a22_flat
        rhs = -(np.swapaxes(a12_flat, 1, 2) @ r12_0.reshape(m, -1, 1))
        ninv = _pinv_psd(normal)
        j = (ninv @ rhs)[..., 0]
        r11 = _anti_up(xg11) * self.w
        r12 = r12_0 + (self.a12 @ j[:, None, :, None])[..., 0]
        r22 = (a22 @ j[:, None, :, None])[..., 0]
        resid = np.concatenate([r11, r12, r22], axis=2).reshape(m, -1)
        zeros = np.zeros((*a22.shape[:2], 3, 6))
        amat = np.concatenate([zeros, self.a12, a22], axis=2).reshape(m, -1, 6)
        return resid, j, amat, ninv, (s, xg11)

    def _evaluate_white(
        self, xg11: Array, r12_0: Array, a22: Array, cache: tuple[Array, ...]
    ) -> tuple[Array, Array, Array, Array, tuple[Array, ...]]:
        """:meth:`evaluate` with the residual whitened by :attr:`white` (``L r``, ``L A``)."""
        assert self.white is not None
        m = xg11.shape[0]
        r0 = np.concatenate([_anti_up(xg11), r12_0, np.zeros((*r12_0.shape[:2], 3))], axis=2).reshape(m, -1)
        zeros = np.zeros((*a22.shape[:2], 3, 6))
        amat = self.white @ np.concatenate([zeros, self.a12, a22], axis=2).reshape(m, -1, 6)
        r0w = (self.white @ r0[..., None])[..., 0]
        ninv = _pinv_psd(np.swapaxes(amat, 1, 2) @ amat)
        j = -(ninv @ (np.swapaxes(amat, 1, 2) @ r0w[..., None]))[..., 0]
        resid = r0w + (amat @ j[..., None])[..., 0]
        return resid, j, amat, ninv, cache

    def jacobian(self, j: Array, amat: Array, ninv: Array, cache: tuple[Array, ...]) -> Array:
        """Kaufman's variable-projection Jacobian (m, 15 n, 3) of the residual in the CG.

        ``P (dr0 + dA j)`` with ``P = I - A A^+``: it gives the exact gradient
        of the cost; the dropped term ``(A^+)^T dA^T r`` of Golub and Pereyra
        only changes the Gauss-Newton curvature (tried: no fewer iterations,
        more work per iteration).
        """
        s, xg11 = cache
        m = j.shape[0]
        jm = inertia_from_params(j)[:, None]  # (m, 1, 3, 3)
        cols = []
        for i in range(3):
            si = _SKEW_BASIS[i]
            d11 = -si @ self.x21
            d12 = d11 @ s + xg11 @ si - si @ self.x22
            d22 = self.x21 @ si
            cols.append(
                np.concatenate(
                    [_anti_up(d11) * self.w, d12.reshape(m, -1, 9) * self.w, _anti_up(jm @ d22) * self.w], axis=2
                ).reshape(m, -1)
            )
        raw = np.stack(cols, axis=-1)  # (m, 15 n, 3): derivative at fixed J / m
        if self.white is not None:
            raw = self.white @ raw
        proj = ninv @ (np.swapaxes(amat, 1, 2) @ raw)
        result: Array = raw - amat @ proj
        return result

    def normal_equations(self, g: Array) -> tuple[Array, Array, Array]:
        """Cost (m,), gradient ``J^T r`` (m, 3) and Gauss-Newton matrix ``J^T J`` (m, 3, 3) at `g`."""
        r, j, amat, ninv, cache = self.evaluate(g)
        jac = self.jacobian(j, amat, ninv, cache)
        jac_t = np.swapaxes(jac, 1, 2)
        return np.einsum("bi,bi->b", r, r), (jac_t @ r[..., None])[..., 0], jac_t @ jac


def _levenberg_marquardt(problem: _VarPro, g0: Array, scale: Array) -> tuple[Array, Array]:
    """Minimise the cost of each test from `g0` (m, 3); returns CGs (m, 3) and costs (m,).

    :func:`rigidid.core.optimize.levenberg_marquardt`, stopped once the Gauss-Newton
    decrement is below :data:`_FLAT` of the cost (or below the rounding floor of
    `scale`, the data's ``|Q|^2 + w^2 |P|^2``): :func:`_polish` takes it from there.
    """

    m = g0.shape[0]

    def rows(index: NDArray[np.int64]) -> _VarPro:  # the optimiser's indices are ascending
        return problem if index.size == m else problem.take(index)

    def normal(g: Array, index: NDArray[np.int64]) -> tuple[Array, Array, Array]:
        return rows(index).normal_equations(g)

    def cost(g: Array, index: NDArray[np.int64]) -> Array:
        r = rows(index).evaluate(g)[0]
        out: Array = np.einsum("bi,bi->b", r, r)
        return out

    out = levenberg_marquardt(normal, cost, g0, max_evaluations=_MAX_EVALUATIONS, scale=scale, decrement=_FLAT)
    return out.x, out.cost


def _polish(problem: _VarPro, g: Array, cost: Array) -> tuple[Array, Array]:
    """Gauss-Newton steps on the gradient from Levenberg-Marquardt's answer.

    Levenberg-Marquardt stops when the cost is flat to rounding, which pins
    the CG only to about ``sqrt(eps)``; the gradient (exact, from the
    variable-projection Jacobian) pins it to about ``eps`` times the
    condition. A step is kept when it does not raise the cost beyond rounding,
    so results do not depend on where the iterations stopped. Each test stops
    when its step is below ``1e-13 (1 + |g|)`` or is refused.
    """
    g, cost = g.copy(), cost.copy()
    active = np.flatnonzero(np.isfinite(cost))
    sub = problem.take(active)
    c, grad, hess = sub.normal_equations(g[active])
    for _ in range(_POLISH_STEPS):
        if active.size == 0:
            break
        step, solved = solve_rows(hess, -grad[..., None])
        step = np.where(solved[:, None], np.nan_to_num(step[..., 0]), 0.0)
        trial = g[active] + step
        r_new, j, amat, ninv, cache = sub.evaluate(trial)
        c_new = np.einsum("bi,bi->b", r_new, r_new)
        keep = np.isfinite(c_new) & (c_new <= c * (1.0 + 1e-12) + 1e-300)
        g[active[keep]] = trial[keep]
        cost[active[keep]] = c_new[keep]
        moving = keep & (np.linalg.norm(step, axis=1) > 1e-13 * (1.0 + np.linalg.norm(trial, axis=1)))
        if not np.any(moving):
            break
        index = np.flatnonzero(moving)
        active, sub = active[index], sub.take(index)
        jac = sub.jacobian(j[index], amat[index], ninv[index], tuple(x[index] for x in cache))
        jac_t = np.swapaxes(jac, 1, 2)
        c, grad, hess = c_new[index], (jac_t @ r_new[index][..., None])[..., 0], jac_t @ jac
    return g, cost


def eq36_system(stiffness: Array) -> tuple[Array, Array]:
    """Linear system ``A g = b`` of eq. (36) of [1] (symmetry of ``Q11 - S(g) Q21``), stacked.

    Parameters
    ----------
    stiffness : ndarray, shape (B, 6, 6)
        ``Q`` at the origin.

    Returns
    -------
    a : ndarray, shape (B, 3, 3)
    b : ndarray, shape (B, 3)
    """
    q11, q21 = stiffness[:, :3, :3], stiffness[:, 3:, :3]
    a = np.stack([_anti_up(-_SKEW_BASIS[i] @ q21) for i in range(3)], axis=-1)
    return a, -_anti_up(q11)


def _eq36_start(stiffness: Array) -> Array:
    """Eq. (36) by least squares with singular values below 1e-6 of the largest dropped."""
    a, b = eq36_system(stiffness)
    u, sv, vt = np.linalg.svd(a)
    keep = sv > 1e-6 * sv[:, :1]
    inv_s = np.where(keep, 1.0 / np.where(keep, sv, 1.0), 0.0)
    coef = np.einsum("bji,bj->bi", u, b) * inv_s
    result: Array = np.einsum("bji,bj->bi", vt, coef)
    return result


def _problem(stiffness: Array, damping: Array | None, damping_weight: float, weights: Array | None = None) -> _VarPro:
    if weights is not None:
        if damping is None:
            raise ValueError("residual weights need the damping matrices")
        white = np.asarray(weights, dtype=float)
        return _VarPro(np.stack([stiffness, damping], axis=1), np.array([1.0, 1.0]), white)
    if damping is not None and damping_weight > 0.0:
        return _VarPro(np.stack([stiffness, damping], axis=1), np.array([1.0, damping_weight]))
    return _VarPro(stiffness[:, None], np.array([1.0]))


def eq18_residuals(stiffness: Array, damping: Array, cg: Array, inertia_params: Array) -> Array:
    """The 30 residuals of eq. (18) of [1] and its damping twin, unweighted, at a CG and ``J / m``.

    Parameters
    ----------
    stiffness, damping : ndarray, shape (B, 6, 6)
        ``Q`` and ``P`` at the origin, dimensionless (or their changes: the
        residuals are linear in them at a fixed CG and ``J / m``).
    cg : ndarray, shape (B, 3)
        The CG in the same frame.
    inertia_params : ndarray, shape (B, 6)
        ``J / m`` as ``xx, yy, zz, xy, xz, yz``.

    Returns
    -------
    ndarray, shape (B, 30)
        For ``Q`` then ``P``: the upper entries of ``X_g11 - X_g11^T``, the
        nine entries of ``X_g12 - X_21^T J / m`` and the upper entries of
        ``J X_g22 - (J X_g22)^T`` (the order the weights of :func:`solve_cg`
        use).
    """
    problem = _VarPro(np.stack([stiffness, damping], axis=1), np.array([1.0, 1.0]))
    s = _skew(cg)[:, None]
    xg11 = problem.x11 - s @ problem.x21
    xg12 = xg11 @ s + problem.x12 - s @ problem.x22
    xg22 = problem.x21 @ s + problem.x22
    jm = inertia_from_params(inertia_params)[:, None]
    r12 = xg12 - np.swapaxes(problem.x21, -1, -2) @ jm
    parts = [_anti_up(xg11), r12.reshape(*r12.shape[:2], 9), _anti_up(jm @ xg22)]
    result: Array = np.concatenate(parts, axis=2).reshape(cg.shape[0], -1)
    return result


def solve_cg(
    stiffness: Array,
    damping: Array | None = None,
    damping_weight: float = DAMPING_WEIGHT,
    weights: Array | None = None,
    start: Array | None = None,
) -> tuple[Array, Array, Array]:
    """CG and inertia per mass from the whole of eq. (18) of [1], for a stack of tests.

    Parameters
    ----------
    stiffness : ndarray, shape (B, 6, 6)
        ``Q = M_o^-1 K_o`` at the origin, in a dimensionless frame (lengths
        and times scaled to order one; see :func:`prepare`).
    damping : ndarray, shape (B, 6, 6), optional
        ``P = M_o^-1 C_o``, used when `damping_weight` is positive.
    damping_weight : float
        Weight of the damping twin of eq. (18) against the stiffness
        equations (0: stiffness only).
    weights : ndarray, shape (30, 30) or (B, 30, 30), optional
        A whitening matrix ``L`` of the 30 residuals (:func:`eq18_residuals`
        order): the cost becomes ``|L r|^2``, a chi-square when ``L^T L`` is
        the inverse covariance of the residuals under the measurement noise
        (:func:`rigidid.core.linearised.residual_weights`). Replaces
        `damping_weight`; needs `damping`.
    start : ndarray, shape (B, 3), optional
        One start per test (a nearby solution, e.g. for small changes of the
        data) instead of the two default starts.

    Returns
    -------
    cg : ndarray, shape (B, 3)
        Centre of gravity in the origin's frame.
    inertia_per_mass : ndarray, shape (B, 3, 3)
        Symmetric ``J / m``.
    cost : ndarray, shape (B,)
        Sum of squares of the 15 (or 30) residuals at the solution.

    Notes
    -----
    Unknowns: the CG (3) and the symmetric ``J / m`` (6); equations: the 15
    entries of the antisymmetric part of ``D Q_g`` (and of ``D P_g``), which
    hold eqs. (32)-(35) once the symmetric ``K / m = sym(D Q_g)`` is
    eliminated. ``J / m`` enters linearly and is solved by least squares for
    each trial CG (variable projection, Kaufman's Jacobian); the CG is found
    by Levenberg-Marquardt from two starts, eq. (36) and the origin, the
    better kept (the first on a tie), then polished by Gauss-Newton steps on
    the gradient. Unlike the sequential route (eqs. (36)-(40)) this needs
    neither eq. (36) nor ``Q21`` to be regular, so identical mounts at one
    height are fine.

    Examples
    --------
    A unit-mass body, ``J = diag(1, 2, 3)``, CG at ``(0.1, 0, 0)``, on three
    mounts below it; ``Q`` moved from the CG to the origin:

    >>> from rigidid.core.geometry import transfer_matrix
    >>> from rigidid.core.simulate import Body, Mount, system_matrices
    >>> mounts = [Mount.from_values(p, (1.0, 2.0, 3.0)) for p in ([1, 0, -1], [-1, 1, -1], [0, -1, -1.0])]
    >>> g_true = np.array([0.1, 0.0, 0.0])
    >>> m, k, _ = system_matrices(Body(1.0, g_true, np.diag([1.0, 2.0, 3.0]), mounts))
    >>> q = transfer_matrix(-g_true) @ np.linalg.solve(m, k) @ transfer_matrix(g_true)
    >>> cg, j, _ = solve_cg(q[None])
    >>> (cg.round(9) + 0.0).tolist(), np.diag(j[0]).round(9).tolist()
    ([[0.1, 0.0, 0.0]], [1.0, 2.0, 3.0])
    """
    b = stiffness.shape[0]
    problem = _problem(stiffness, damping, damping_weight, weights)
    scale = np.sum(stiffness**2, axis=(1, 2))
    if weights is not None and damping is not None:
        # the data's scale in whitened units: |L|^2 (|Q|^2 + |P|^2)
        gain = np.linalg.norm(np.asarray(weights, dtype=float), ord=2, axis=(-2, -1)) ** 2
        scale = gain * (scale + np.sum(damping**2, axis=(1, 2)))
    elif damping is not None and damping_weight > 0.0:
        scale = scale + damping_weight**2 * np.sum(damping**2, axis=(1, 2))
    if start is not None:
        g0 = np.asarray(start, dtype=float).reshape(b, 3).copy()
        g, cost = _levenberg_marquardt(problem, g0, np.broadcast_to(scale, (b,)).copy())
        g, cost = _polish(problem, g, cost)
        _, j, *_ = problem.evaluate(g)
        return g, inertia_from_params(j), cost
    starts = np.concatenate([_eq36_start(stiffness), np.zeros((b, 3))])
    both = problem.take(np.concatenate([np.arange(b), np.arange(b)]))
    g_all, cost_all = _levenberg_marquardt(both, starts, np.concatenate([scale, scale]))
    c1, c2 = cost_all[:b], cost_all[b:]
    second = (c2 < c1) | ~np.isfinite(c1)
    g = np.where(second[:, None], g_all[b:], g_all[:b])
    g, cost = _polish(problem, g, np.where(second, c2, c1))
    _, j, *_ = problem.evaluate(g)
    return g, inertia_from_params(j), cost


def observability_batch(stiffness: Array, cg: Array) -> Array:
    """How well eq. (18) of [1] determines the inertia, 0 (not at all) to 1, for stacked tests.

    Parameters
    ----------
    stiffness : ndarray, shape (B, 6, 6)
        ``Q`` in the dimensionless frame.
    cg : ndarray, shape (B, 3)
        The CG in that frame.

    Returns
    -------
    ndarray, shape (B,)
        Ratio of the smallest to the largest singular value of the linear map
        from ``J / m`` to the antisymmetric part of ``D Q_g`` (stiffness
        equations only: damping is too uncertain to carry the inertia).
    """
    amat = _VarPro(stiffness[:, None], np.array([1.0])).evaluate(cg)[2]
    s = np.linalg.svd(amat, compute_uv=False)
    result: Array = np.divide(s[:, -1], s[:, 0], out=np.zeros(s.shape[0]), where=s[:, 0] > 0.0)
    return result


# --------------------------------------------------------------------------- step 3: K and C at the CG


def at_cg(matrix: Array, cg: Array, inertia_per_mass: Array | None = None) -> Array:
    """``D X_g`` with ``X_g = G_go X G_og`` (eqs. (11)-(14), (18) of [1]), stacked.

    Parameters
    ----------
    matrix : ndarray, shape (B, 6, 6)
        ``Q`` or ``P`` at the origin.
    cg : ndarray, shape (B, 3)
        The point to move to.
    inertia_per_mass : ndarray, shape (B, 3, 3), optional
        ``J / m``; without it ``D = I`` and the result is ``X_g`` itself.

    Returns
    -------
    ndarray, shape (B, 6, 6)
        ``X_g``, or ``diag(I, J/m) X_g`` (whose symmetric part is ``K / m``
        or ``C / m`` at the CG).
    """
    s = _skew(cg)
    x11, x12, x21, x22 = matrix[:, :3, :3], matrix[:, :3, 3:], matrix[:, 3:, :3], matrix[:, 3:, 3:]
    xg11 = x11 - s @ x21
    xg12 = xg11 @ s + x12 - s @ x22
    xg22 = x21 @ s + x22
    lower = np.concatenate([x21, xg22], axis=2)
    if inertia_per_mass is not None:
        lower = inertia_per_mass @ lower
    return np.concatenate([np.concatenate([xg11, xg12], axis=2), lower], axis=1)


def _sym(a: Array) -> Array:
    result: Array = 0.5 * (a + np.swapaxes(a, -1, -2))
    return result


@dataclass(frozen=True)
class Estimates(_Statuses):
    """Per-mass results of :func:`estimate`, one row per test, in the layout's units.

    Attributes
    ----------
    center_of_gravity : ndarray, shape (B, 3)
        CG (length).
    inertia_per_mass : ndarray, shape (B, 3, 3)
        ``J / m`` about the CG (length^2).
    stiffness_per_mass : ndarray, shape (B, 6, 6)
        ``K_g / m``, DOF order x, y, z, rx, ry, rz (1/s^2, length/s^2,
        length^2/s^2 blocks).
    damping_per_mass : ndarray, shape (B, 6, 6)
        ``C_g / m`` (1/s, length/s, length^2/s).
    status : ndarray of int8, shape (B,)
        0 for a test identified, else a key of :data:`STATUS_MESSAGES`; the
        rows of a failed test are NaN.
    """

    center_of_gravity: Array
    inertia_per_mass: Array
    stiffness_per_mass: Array
    damping_per_mass: Array
    status: IArray

    @property
    def principal_moments_per_mass(self) -> Array:
        """Eigenvalues of :attr:`inertia_per_mass`, ascending (length^2); NaN for failed tests."""
        out = np.full((self.status.shape[0], 3), np.nan)
        ok = self.ok
        out[ok] = np.linalg.eigvalsh(_sym(self.inertia_per_mass[ok]))
        return out

    @property
    def plausible(self) -> BArray:
        """Tests whose inertia is positive definite and obeys the triangle inequality."""
        w = self.principal_moments_per_mass
        with np.errstate(invalid="ignore"):
            good: BArray = self.ok & (w[:, 0] > 0.0) & (w[:, 2] <= (w[:, 0] + w[:, 1]) * (1.0 + 1e-9))
        return good


def _estimate_chunk(
    prepared: Prepared, damping_weight: float, weights: Array | None = None, start: Array | None = None
) -> Estimates:
    g0 = None if start is None else (start[None, :] - prepared.centre) / prepared.scale[:, None]
    g, j, _ = solve_cg(prepared.stiffness, prepared.damping, damping_weight, weights, g0)
    return _estimates(prepared, g, j)


def _estimates(prepared: Prepared, g: Array, j: Array) -> Estimates:
    """Per-mass estimates in the layout's units from the CG and ``J / m`` in each test's frame."""
    k = _sym(at_cg(prepared.stiffness, g, j))
    c = _sym(at_cg(prepared.damping, g, j))
    scale, omega = prepared.scale, prepared.omega
    dof = np.concatenate([np.ones((scale.size, 3)), np.repeat(scale[:, None], 3, axis=1)], axis=1)
    units = dof[:, :, None] * dof[:, None, :]
    status = prepared.status.copy()
    cg = prepared.centre + scale[:, None] * g
    inertia = scale[:, None, None] ** 2 * j
    stiff = (omega**2)[:, None, None] * k * units
    damp = omega[:, None, None] * c * units
    finite = (
        np.all(np.isfinite(cg), axis=1)
        & np.all(np.isfinite(inertia), axis=(1, 2))
        & np.all(np.isfinite(stiff), axis=(1, 2))
        & np.all(np.isfinite(damp), axis=(1, 2))
    )
    _fail(status, ~finite, NO_SOLUTION)
    bad = status != OK
    for arr in (cg, inertia, stiff, damp):
        arr[bad] = np.nan
    return Estimates(cg, inertia, stiff, damp, status)


def estimate(
    positions: Array,
    directions: Array,
    poles: CArray,
    shapes: CArray,
    *,
    damping_weight: float = DAMPING_WEIGHT,
    weights: Array | None = None,
    progress: Callable[[str, float, float | None], None] | None = None,
    start: Array | None = None,
) -> Estimates:
    """Identify a stack of tests: :func:`prepare`, :func:`solve_cg`, :func:`at_cg`, in chunks.

    Parameters
    ----------
    positions : ndarray, shape (B, p, 3)
        Sensor locations (length).
    directions : ndarray, shape (B, p, 3)
        Unit measuring axes.
    poles : ndarray of complex, shape (B, 6)
        Poles of the six rigid-body modes (rad/s).
    shapes : ndarray of complex, shape (B, p, 6)
        Mode shapes as the sensors read them.
    damping_weight : float
        Weight of the damping twin of eq. (18).
    weights : ndarray, shape (30, 30), optional
        Residual whitening shared by every test (see :func:`solve_cg`);
        replaces `damping_weight`.
    progress : callable, optional
        ``progress("identifying", done, total)`` after each chunk of tests.
    start : ndarray, shape (3,), optional
        A CG (length, the layout's axes) near every test's, to start from
        instead of the two default starts (for small changes of one test).

    Returns
    -------
    Estimates
        Tests that fail are flagged, never raised.
    """
    parts = []
    for i in range(0, positions.shape[0], _CHUNK):
        window = slice(i, i + _CHUNK)
        prepared = prepare(positions[window], directions[window], poles[window], shapes[window])
        if not np.any(prepared.ok):
            b = prepared.status.shape[0]
            nan6 = np.full((b, 6, 6), np.nan)
            parts.append(Estimates(np.full((b, 3), np.nan), np.full((b, 3, 3), np.nan), nan6, nan6.copy(),
                                   prepared.status))  # fmt: skip
            continue
        parts.append(_estimate_chunk(prepared, damping_weight, weights, start))
        if progress is not None:
            progress("identifying", min(i + _CHUNK, positions.shape[0]), positions.shape[0])
    return parts[0] if len(parts) == 1 else concatenate(parts)


def concatenate(parts: Sequence[Estimates]) -> Estimates:
    """One :class:`Estimates` of several stacks of tests, in order."""
    names = ("center_of_gravity", "inertia_per_mass", "stiffness_per_mass", "damping_per_mass", "status")
    return Estimates(*(np.concatenate([getattr(part, name) for part in parts]) for name in names))


_HESSIAN_STEP = 1e-4
"""Central-difference step (dimensionless CG) of the cost's Hessian in :func:`estimate_near`."""


def _cost_hessian(problem: _VarPro, g: Array) -> Array:
    """The exact Hessian (3, 3) of the variable-projection cost at one test's CG `g` (3,).

    Central differences of the exact gradient (Kaufman's Jacobian gives it: the dropped
    Golub-Pereyra term is orthogonal to the residual); unlike the Gauss-Newton matrix
    ``J^T J`` it holds the curvature of a residual that is not zero.
    """
    h = _HESSIAN_STEP * max(1.0, float(np.max(np.abs(g))))
    moves = np.concatenate([np.eye(3), -np.eye(3)]) * h
    grad = problem.take(np.zeros(6, dtype=np.intp)).normal_equations(g[None] + moves)[1]
    hess = (grad[:3] - grad[3:]) / (2.0 * h)
    result: Array = 0.5 * (hess + hess.T)
    return result


def estimate_near(
    positions: Array,
    directions: Array,
    poles: CArray,
    shapes: CArray,
    *,
    start: Array,
    damping_weight: float = DAMPING_WEIGHT,
    weights: Array | None = None,
) -> Estimates | None:
    """:func:`estimate` of tests that differ slightly from the first one, solved at `start`, by one Newton step.

    Parameters
    ----------
    positions, directions : ndarray, shape (B, p, 3)
        Sensor locations (length) and unit measuring axes; test 0 is the one
        identified.
    poles : ndarray of complex, shape (B, 6)
        Poles of the six rigid-body modes (rad/s).
    shapes : ndarray of complex, shape (B, p, 6)
        Mode shapes as the sensors read them.
    start : ndarray, shape (3,)
        Test 0's CG from :func:`estimate` with the same weights (length, the
        layout's axes): the minimum of its eq. (18) cost.
    damping_weight : float
        As in :func:`estimate`.
    weights : ndarray, shape (30, 30), optional
        As in :func:`estimate`.

    Returns
    -------
    Estimates or None
        Every test's estimate to first order in its difference from test 0
        (exact to second order), with test 0's too (from the same step, so that
        differences are clean); None when test 0 cannot be prepared or its
        cost's Hessian is singular (use :func:`estimate`).

    Notes
    -----
    The CG minimises the cost of eq. (18) of [1] with ``J / m`` eliminated
    (:func:`solve_cg`); by the implicit function theorem a small change of
    the data moves it by ``-H^-1 dgrad``, with ``H`` the cost's Hessian at the
    minimum and ``dgrad`` the change of the gradient at the old CG. One Newton
    step with test 0's Hessian is that, and ``J / m``, ``K`` and ``C`` follow
    at the new CG. The cost: one gradient per test and six for the Hessian,
    against a Levenberg-Marquardt run per test.
    """
    prepared = prepare(positions, directions, poles, shapes)
    if not prepared.ok[0]:
        return None
    problem = _problem(prepared.stiffness, prepared.damping, damping_weight, weights)
    g0 = (np.asarray(start, dtype=float)[None, :] - prepared.centre) / prepared.scale[:, None]
    hess = _cost_hessian(problem.take(np.zeros(1, dtype=np.intp)), g0[0])
    grad = problem.normal_equations(g0)[1]
    try:
        step = -np.linalg.solve(hess, grad.T).T
    except np.linalg.LinAlgError:
        return None
    if not np.all(np.isfinite(step)) or np.linalg.cond(hess) > 1e12:
        return None
    g = g0 + step
    _, j, *_ = problem.evaluate(g)
    return _estimates(prepared, g, inertia_from_params(j))
