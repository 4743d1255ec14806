"""Monte Carlo propagation of measurement uncertainty to the identified body.

Every draw perturbs the measured data (natural frequencies, damping ratios,
mode shapes, sensor positions and directions, optionally the mass) by the
stated standard deviations and identifies the body again with exactly the
estimator of :func:`rigidid.core.identify.identify` (``method="structured"``):
eq. (19) of [1] for ``M^-1 K`` and ``M^-1 C``, then the whole of eq. (18)
solved for the CG and ``J / m`` (:func:`rigidid.core.identify.solve_structured`).
All draws are computed together with stacked numpy arrays
(:func:`identify_batch`); the spread of the results over the draws is the
uncertainty.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.geometry import normalise_directions
from rigidid.core.identify import DAMPING_WEIGHT, identify
from rigidid.core.statespace import modal_from_poles
from rigidid.errors import IdentificationError, IllConditionedWarning, InputError

__all__ = [
    "DEFAULT_NOISE",
    "BatchEstimates",
    "Interval",
    "NoiseLevels",
    "Perturbed",
    "Uncertainty",
    "estimate_noise",
    "identify_batch",
    "perturb",
    "propagate",
    "shape_noise_from_residuals",
    "tilt_directions",
    "uncertainty_to_dict",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]
BArray = NDArray[np.bool_]

_CHUNK = 4096
"""Draws identified together (bounds memory: about 20 kB per draw)."""

_FAILED_WARN_FRACTION = 0.05
"""Fraction of failed draws above which :func:`propagate` warns."""


# --------------------------------------------------------------------------- noise model


@dataclass(frozen=True)
class NoiseLevels:
    """Standard deviations of the measurement errors (all zero by default).

    Attributes
    ----------
    frequency : float
        Relative standard deviation of each natural frequency (0.001 = 0.1 %).
    damping : float
        Relative standard deviation of each damping ratio (0.05 = 5 % of the
        ratio, not 5 percentage points).
    shape : float
        Standard deviation of complex Gaussian noise on each mode-shape value,
        relative to the RMS value of that mode shape over the sensors (real and
        imaginary parts each ``shape / sqrt(2)``), as
        :func:`rigidid.core.simulate.add_noise`.
    position : float
        Standard deviation of each coordinate of each sensor position (length
        units of the layout), isotropic and independent between sensors.
    angle_deg : float
        Standard deviation of the tilt of each measuring direction (degrees)
        about each of the two axes perpendicular to it (the total tilt angle is
        Rayleigh distributed with RMS ``angle_deg * sqrt(2)``).
    mass : float
        Relative standard deviation of the mass (used only when a mass is given).

    Raises
    ------
    InputError
        If a value is negative or not finite.
    """

    frequency: float = 0.0
    damping: float = 0.0
    shape: float = 0.0
    position: float = 0.0
    angle_deg: float = 0.0
    mass: float = 0.0

    def __post_init__(self) -> None:
        for name in ("frequency", "damping", "shape", "position", "angle_deg", "mass"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0.0):
                raise InputError(f"noise level {name} must be a finite number >= 0, got {value!r}")
            object.__setattr__(self, name, float(value))

    @property
    def is_zero(self) -> bool:
        """True when every level is zero (every draw repeats the estimate)."""
        return not any(self.as_dict().values())

    def as_dict(self) -> dict[str, float]:
        """The levels as a plain dict (JSON-ready)."""
        return {
            "frequency": self.frequency,
            "damping": self.damping,
            "shape": self.shape,
            "position": self.position,
            "angle_deg": self.angle_deg,
            "mass": self.mass,
        }


DEFAULT_NOISE = NoiseLevels(frequency=0.001, damping=0.05, shape=0.01)
"""Typical impact test with a good modal fit: 0.1 % on frequencies, 5 % on
damping ratios, 1 % on shapes, geometry exact (the levels of
``benchmarks/noise_accuracy.py``). A default, not a measurement: state your own
when you know better."""


def shape_noise_from_residuals(residual: ArrayLike, sensors: int) -> float:
    """Shape noise level implied by the rigid-body fit residuals of the modes.

    Parameters
    ----------
    residual : array_like, shape (n,)
        Per mode, ``rho_k = |psi_k - T T^+ psi_k| / |psi_k|``: the second output of
        :func:`rigidid.core.selection.project_rigid`, also
        ``Identification.diagnostics.rigid_fit_residual``.
    sensors : int
        Number of sensors ``p``; must exceed 6.

    Returns
    -------
    float
        ``sigma = sqrt(p / (p - 6) * mean_k rho_k^2)``, the relative shape noise
        of :attr:`NoiseLevels.shape`.

    Raises
    ------
    IdentificationError
        With six sensors or fewer (the fit is exact and says nothing about noise).
    InputError
        If a residual is negative or not finite.

    Notes
    -----
    With ``psi = T x + e`` and independent complex noise of variance
    ``sigma^2 rms^2`` per value (``rms^2 = |psi|^2 / p``), the least-squares
    residual is the noise projected on the ``p - 6`` dimensional complement of
    the columns of ``T``, so ``E |psi - T T^+ psi|^2 = (p - 6) sigma^2 rms^2``,
    i.e. ``rho^2 = (p - 6) / p * sigma^2``. Each mode gives an estimate; their
    squares are averaged. Flexible (non-rigid) motion in the modes also
    produces residual, so the figure is an upper bound of the pure measurement
    noise; for a model error it is the right size to use anyway.
    """
    rho = np.asarray(residual, dtype=float).ravel()
    if sensors <= 6:
        raise IdentificationError("estimating shape noise from the rigid-body fit needs more than six sensors")
    if rho.size == 0 or not np.all(np.isfinite(rho)) or np.any(rho < 0.0):
        raise InputError("rigid-body fit residuals must be finite and non-negative")
    return float(np.sqrt(sensors / (sensors - 6.0) * np.mean(rho**2)))


def estimate_noise(
    positions: ArrayLike,
    directions: ArrayLike,
    shapes: ArrayLike,
    *,
    base: NoiseLevels = DEFAULT_NOISE,
) -> NoiseLevels:
    """Default noise levels for a test: `base`, with the shape noise measured when possible.

    Parameters
    ----------
    positions : array_like, shape (p, 3)
        Sensor locations (length).
    directions : array_like, shape (p, 3)
        Measuring axes.
    shapes : array_like of complex, shape (p, 6)
        The six rigid-body mode shapes used.
    base : NoiseLevels
        Levels of everything the data cannot tell (frequencies, damping ratios,
        geometry, mass).

    Returns
    -------
    NoiseLevels
        `base` with :attr:`~NoiseLevels.shape` replaced by
        :func:`shape_noise_from_residuals` of the rigid-body fit when
        ``p > 6``; `base` unchanged otherwise.
    """
    from rigidid.core.geometry import layout_frame, sensor_matrix
    from rigidid.core.selection import project_rigid

    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    dirs = normalise_directions(directions)
    psi = np.asarray(shapes, dtype=complex)
    if psi.ndim != 2 or psi.shape[0] != pos.shape[0] or dirs.shape != pos.shape:
        raise InputError(f"shapes must be (sensors, modes) with {pos.shape[0]} sensors, got {psi.shape}")
    if pos.shape[0] <= 6:
        return base
    frame = layout_frame(pos)
    _, residual = project_rigid(sensor_matrix(frame.to_local(pos), dirs), psi)
    return NoiseLevels(
        frequency=base.frequency,
        damping=base.damping,
        shape=shape_noise_from_residuals(residual, pos.shape[0]),
        position=base.position,
        angle_deg=base.angle_deg,
        mass=base.mass,
    )


# --------------------------------------------------------------------------- perturbation


@dataclass(frozen=True)
class Perturbed:
    """A batch of perturbed test data, one test per draw.

    Attributes
    ----------
    positions : ndarray, shape (B, p, 3)
        Sensor locations (length).
    directions : ndarray, shape (B, p, 3)
        Unit measuring axes.
    poles : ndarray of complex, shape (B, 6)
        Poles (rad/s); NaN for a draw whose perturbed frequency is not positive.
    shapes : ndarray of complex, shape (B, p, 6)
        Mode shapes as the sensors read them.
    mass : ndarray, shape (B,), or None
        Perturbed mass, when a mass was given.
    """

    positions: Array
    directions: Array
    poles: CArray
    shapes: CArray
    mass: Array | None


@dataclass(frozen=True)
class _Normals:
    """Standard normal numbers behind a batch of draws (one stream per quantity and sensor)."""

    frequency: Array  # (B, 6)
    damping: Array  # (B, 6)
    shape: Array  # (B, p, 6, 2)
    position: Array  # (B, p, 3)
    angle: Array  # (B, p, 3)
    mass: Array  # (B,)

    def sensors(self, index: ArrayLike) -> _Normals:
        """The numbers of a subset (or reordering) of the sensors."""
        i = np.asarray(index, dtype=np.intp)
        return _Normals(
            self.frequency, self.damping, self.shape[:, i], self.position[:, i], self.angle[:, i], self.mass
        )


def _draw_normals(rng: np.random.Generator, draws: int, sensors: int) -> _Normals:
    return _Normals(
        frequency=rng.standard_normal((draws, 6)),
        damping=rng.standard_normal((draws, 6)),
        shape=rng.standard_normal((draws, sensors, 6, 2)),
        position=rng.standard_normal((draws, sensors, 3)),
        angle=rng.standard_normal((draws, sensors, 3)),
        mass=rng.standard_normal(draws),
    )


def tilt_directions(directions: ArrayLike, rotation: ArrayLike) -> Array:
    """Rotate unit directions by small rotation vectors (Rodrigues' formula).

    Parameters
    ----------
    directions : array_like, shape (..., 3)
        Unit vectors.
    rotation : array_like, shape (..., 3)
        Rotation vectors (rad), broadcast against `directions`; the component
        along a direction does not move it.

    Returns
    -------
    ndarray, shape (..., 3)
        The rotated unit vectors.
    """
    n = np.asarray(directions, dtype=float)
    w = np.asarray(rotation, dtype=float)
    n, w = np.broadcast_arrays(n, w)
    theta = np.linalg.norm(w, axis=-1, keepdims=True)
    safe = np.where(theta > 0.0, theta, 1.0)
    k = w / safe
    cos, sin = np.cos(theta), np.sin(theta)
    kn = np.sum(k * n, axis=-1, keepdims=True)
    out: Array = n * cos + np.cross(k, n) * sin + k * kn * (1.0 - cos)
    return np.where(theta > 0.0, out, n)


def _apply_noise(
    normals: _Normals,
    noise: NoiseLevels,
    positions: Array,
    directions: Array,
    poles: CArray,
    shapes: CArray,
    mass: float | None,
) -> Perturbed:
    """Perturbed copies of one or several layouts' data.

    `positions`, `directions` (L..., p, 3) and `shapes` (L..., p, 6) may carry
    leading layout axes ``L...``; `poles` (6,) are shared. The result has axes
    ``L... + (B,)`` in front, the same standard normals reused for every layout.
    """
    lead = positions.shape[:-2]
    f, z = modal_from_poles(poles)
    f_b = f * (1.0 + noise.frequency * normals.frequency)
    z_b = np.clip(z * (1.0 + noise.damping * normals.damping), 0.0, 0.999)
    w = 2.0 * np.pi * f_b
    lam = w * (-z_b + 1j * np.sqrt(1.0 - z_b * z_b))
    lam = np.where(f_b > 0.0, lam, np.nan + 0j)
    rms = np.sqrt(np.mean(np.abs(shapes) ** 2, axis=-2))[..., None, None, :]
    unit = (normals.shape[..., 0] + 1j * normals.shape[..., 1]) / np.sqrt(2.0)
    psi = shapes[..., None, :, :] + noise.shape * rms * unit
    pos = positions[..., None, :, :] + noise.position * normals.position
    dirs = tilt_directions(directions[..., None, :, :], np.deg2rad(noise.angle_deg) * normals.angle)
    draws = normals.mass.shape[0]
    m = None if mass is None else np.broadcast_to(mass * (1.0 + noise.mass * normals.mass), (*lead, draws)).copy()
    lam_all = np.broadcast_to(lam, (*lead, *lam.shape)).astype(complex)
    return Perturbed(pos, np.ascontiguousarray(dirs), lam_all, psi.astype(complex), m)


def _checked(
    positions: ArrayLike, directions: ArrayLike, poles: ArrayLike, shapes: ArrayLike
) -> tuple[Array, Array, CArray, CArray]:
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    dirs = normalise_directions(directions)
    lam = np.asarray(poles, dtype=complex).ravel()
    psi = np.asarray(shapes, dtype=complex)
    if lam.shape != (6,):
        raise InputError(f"exactly six rigid-body poles are needed, got {lam.shape[0]}")
    if psi.shape != (pos.shape[0], 6) or dirs.shape != pos.shape:
        raise InputError(
            f"shapes must be (sensors, modes) = ({pos.shape[0]}, 6), got {psi.shape}; directions {dirs.shape}"
        )
    return pos, dirs, lam, psi


def perturb(
    positions: ArrayLike,
    directions: ArrayLike,
    poles: ArrayLike,
    shapes: ArrayLike,
    noise: NoiseLevels,
    draws: int,
    *,
    mass: float | None = None,
    seed: int | None = None,
    rng: np.random.Generator | None = None,
) -> Perturbed:
    """Draw `draws` perturbed copies of one test's data.

    Parameters
    ----------
    positions : array_like, shape (p, 3)
        Stated sensor locations (length).
    directions : array_like, shape (p, 3)
        Stated measuring axes (normalised here).
    poles : array_like of complex, shape (6,)
        Measured poles (rad/s).
    shapes : array_like of complex, shape (p, 6)
        Measured mode shapes.
    noise : NoiseLevels
        Standard deviations of the perturbations.
    draws : int
        Number of copies ``B``.
    mass : float, optional
        Measured mass.
    seed : int, optional
        Seed of the generator (ignored when `rng` is given).
    rng : numpy.random.Generator, optional
        Generator to draw from.

    Returns
    -------
    Perturbed

    Notes
    -----
    Frequencies and damping ratios are perturbed as
    :func:`rigidid.core.simulate.add_noise` does (damping ratios clipped to
    ``[0, 0.999]``), shapes likewise, relative to each measured mode's RMS.
    Directions are tilted by :func:`tilt_directions` with independent normal
    rotation-vector components of standard deviation ``angle_deg``.
    """
    pos, dirs, lam, psi = _checked(positions, directions, poles, shapes)
    if draws < 1:
        raise InputError(f"the number of draws must be at least 1, got {draws}")
    gen = rng if rng is not None else np.random.default_rng(seed)
    normals = _draw_normals(gen, int(draws), pos.shape[0])
    return _apply_noise(normals, noise, pos, dirs, lam, psi, mass)


# --------------------------------------------------------------------------- batched estimator

_SYM3 = np.zeros((6, 3, 3))
for _k, (_a, _b) in enumerate([(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]):
    _SYM3[_k, _a, _b] = _SYM3[_k, _b, _a] = 1.0
_UP3 = ([0, 0, 1], [1, 2, 2])
_SKEW_BASIS = np.zeros((3, 3, 3))
_SKEW_BASIS[0, 2, 1], _SKEW_BASIS[0, 1, 2] = 1.0, -1.0
_SKEW_BASIS[1, 0, 2], _SKEW_BASIS[1, 2, 0] = 1.0, -1.0
_SKEW_BASIS[2, 1, 0], _SKEW_BASIS[2, 0, 1] = 1.0, -1.0


def _skew_b(g: Array) -> Array:
    """``S(g)`` for stacked vectors: (..., 3) -> (..., 3, 3)."""
    result: Array = np.einsum("...i,ijk->...jk", g, _SKEW_BASIS)
    return result


def _anti_up(y: Array) -> Array:
    """Upper entries of ``Y - Y^T`` of stacked 3x3 matrices: (..., 3, 3) -> (..., 3)."""
    d: Array = (y - np.swapaxes(y, -1, -2))[..., _UP3[0], _UP3[1]]
    return d


def _solve_vec(a: Array, b: Array) -> Array:
    """Stacked ``a x = b`` with vector right-hand sides (numpy >= 2 broadcasting rules)."""
    x = np.linalg.solve(a, b[..., None])[..., 0]
    return np.asarray(x, dtype=float)


def _inv_safe(n: Array) -> Array:
    """Stacked inverse of symmetric positive semi-definite matrices; pseudo-inverse if singular."""
    try:
        result = np.linalg.inv(n)
    except np.linalg.LinAlgError:
        result = np.linalg.pinv(n, hermitian=True)
    return np.asarray(result, dtype=float)


class _VarPro:
    """The residual of eq. (18) of [1] as a function of the CG, ``J / m`` eliminated, for stacked draws.

    For each matrix ``X`` (``Q`` and optionally ``P``, weight ``w``) the 15
    residuals are the upper entries of the antisymmetric part of
    ``diag(I, J) X_g``, ``X_g = G_go X G_og`` (the same set as
    ``rigidid.core.identify._asym_system``, in another order):
    ``w [anti(X_g11), X_g12 - X21^T J, anti(J X_g22)]``.
    """

    def __init__(self, mats: Array, weights: Array):
        # mats: (B, n, 6, 6); weights: (n,)
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
        """The same problem restricted to some draws."""
        out = object.__new__(_VarPro)
        out.w = self.w
        for name in ("x11", "x12", "x21", "x22", "a12", "n12"):
            setattr(out, name, getattr(self, name)[index])
        return out

    def blocks(self, g: Array) -> tuple[Array, Array, Array, Array]:
        s = _skew_b(g)[:, None]  # (m, 1, 3, 3)
        xg11 = self.x11 - s @ self.x21
        xg12 = xg11 @ s + self.x12 - s @ self.x22
        xg22 = self.x21 @ s + self.x22
        return s, xg11, xg12, xg22

    def evaluate(self, g: Array) -> tuple[Array, Array, Array, Array, tuple[Array, ...]]:
        """Residual (m, 15 n), ``J / m`` parameters (m, 6), A (m, 15 n, 6) and N^-1 (m, 6, 6) at CGs `g`."""
        s, xg11, xg12, xg22 = self.blocks(g)
        m = g.shape[0]
        ey = _SYM3 @ xg22[:, :, None]  # E_k X_g22, (m, n, 6, 3, 3)
        a22 = np.swapaxes(_anti_up(ey), 2, 3) * self.w[..., None]  # (m, n, 3, 6)
        r12_0 = xg12.reshape(m, -1, 9) * self.w  # (m, n, 9)
        a22_flat = a22.reshape(m, -1, 6)
        a12_flat = self.a12.reshape(m, -1, 6)
        normal = self.n12 + np.swapaxes(a22_flat, 1, 2) @ a22_flat
        rhs = -(np.swapaxes(a12_flat, 1, 2) @ r12_0.reshape(m, -1, 1))
        ninv = _inv_safe(normal)
        j = (ninv @ rhs)[..., 0]
        r11 = _anti_up(xg11) * self.w
        r12 = r12_0 + (self.a12 @ j[:, None, :, None])[..., 0]
        r22 = (a22 @ j[:, None, :, None])[..., 0]
        resid = np.concatenate([r11, r12, r22], axis=2).reshape(m, -1)
        zeros = np.zeros((*a22.shape[:2], 3, 6))
        amat = np.concatenate([zeros, self.a12, a22], axis=2).reshape(m, -1, 6)
        return resid, j, amat, ninv, (s, xg11, xg22)

    def jacobian(self, j: Array, amat: Array, ninv: Array, cache: tuple[Array, ...]) -> Array:
        """Kaufman's variable-projection Jacobian (m, 15 n, 3) of the residual in the CG.

        ``P (dr0 + dA j)`` with ``P = I - A A^+``: it gives the exact gradient
        of the cost; the dropped term ``(A^+)^T dA^T r`` of Golub and Pereyra
        only changes the Gauss-Newton curvature (tried: no fewer iterations,
        more work per iteration).
        """
        s, xg11, _ = cache
        m = j.shape[0]
        jm = np.einsum("bk,kij->bij", j, _SYM3)[:, None]  # (m, 1, 3, 3)
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
        proj = ninv @ (np.swapaxes(amat, 1, 2) @ raw)
        result: Array = raw - amat @ proj
        return result


_STEP_TOL = 1e-11
"""A CG step (dimensionless frame) this small relative to ``1 + |g|`` ends the iterations."""


def _levenberg_marquardt_b(problem: _VarPro, g0: Array, max_iter: int = 400) -> tuple[Array, Array]:
    """Batched twin of ``identify._levenberg_marquardt`` for the CG; returns CGs (m, 3) and costs (m,)."""
    m = g0.shape[0]
    g = g0.copy()
    r, j, amat, ninv, cache = problem.evaluate(g)
    cost = np.einsum("bi,bi->b", r, r)
    jac = problem.jacobian(j, amat, ninv, cache)
    hess = np.swapaxes(jac, 1, 2) @ jac
    grad = (np.swapaxes(jac, 1, 2) @ r[..., None])[..., 0]
    damping = np.full(m, 1e-3)
    active = np.isfinite(cost) & (cost > 0.0)
    for _ in range(max_iter):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        h = hess[idx]
        scale2 = np.maximum(np.einsum("bii->bi", h), 1e-30)
        lhs = h + damping[idx, None, None] * (scale2[:, :, None] * np.eye(3))
        try:
            step = -_solve_vec(lhs, grad[idx])
        except np.linalg.LinAlgError:
            step = -np.einsum("bij,bj->bi", np.linalg.pinv(lhs), grad[idx])
        sub = problem.take(idx)
        trial = g[idx] + step
        r_new, j_new, a_new, ninv_new, cache_new = sub.evaluate(trial)
        cost_new = np.einsum("bi,bi->b", r_new, r_new)
        better = cost_new < cost[idx]
        acc = idx[better]
        rej = idx[~better]
        step_norm = np.linalg.norm(step, axis=1)
        tiny = step_norm <= _STEP_TOL * (1.0 + np.linalg.norm(g[idx], axis=1))
        # rejected: more damping; give up past 1e12 as the scalar version does, or once the
        # steps are below what can change the result (a stuck, converged draw)
        damping[rej] *= 4.0
        active[rej[(damping[rej] >= 1e12) | tiny[~better]]] = False
        if acc.size:
            small = tiny[better]
            flat = cost[acc] - cost_new[better] <= 1e-15 * cost[acc]
            g[acc] = trial[better]
            r[acc] = r_new[better]
            cost[acc] = cost_new[better]
            damping[acc] = np.maximum(damping[acc] / 5.0, 1e-12)
            done = small | flat | (cost_new[better] == 0.0)
            active[acc[done]] = False
            go = ~done
            if np.any(go):
                keep = np.flatnonzero(better)[go]
                sub_cache = tuple(c[keep] for c in cache_new)
                jac_new = sub.take(keep).jacobian(j_new[keep], a_new[keep], ninv_new[keep], sub_cache)
                target = acc[go]
                jac_t = np.swapaxes(jac_new, 1, 2)
                hess[target] = jac_t @ jac_new
                grad[target] = (jac_t @ r_new[keep][..., None])[..., 0]
    return g, cost


def _eq36_start(q: Array) -> Array:
    """Batched start of ``solve_structured``: eq. (36) of [1] by least squares with ``rcond=1e-6``."""
    q11, q21 = q[:, :3, :3], q[:, 3:, :3]
    a = np.stack([_anti_up(-_SKEW_BASIS[i] @ q21) for i in range(3)], axis=-1)  # (B, 3, 3)
    b = -_anti_up(q11)
    u, sv, vt = np.linalg.svd(a)
    keep = sv > 1e-6 * sv[:, :1]
    inv_s = np.where(keep, 1.0 / np.where(keep, sv, 1.0), 0.0)
    coef = np.einsum("bji,bj->bi", u, b) * inv_s
    result: Array = np.einsum("bji,bj->bi", vt, coef)
    return result


def _solve_structured_b(stiffness: Array, damping: Array, damping_weight: float) -> tuple[Array, Array, Array]:
    """Batched :func:`rigidid.core.identify.solve_structured`: CG (B, 3), ``J / m`` (B, 3, 3), cost (B,)."""
    if damping_weight > 0.0:
        mats = np.stack([stiffness, damping], axis=1)
        weights = np.array([1.0, damping_weight])
    else:
        mats = stiffness[:, None]
        weights = np.array([1.0])
    b = stiffness.shape[0]
    problem = _VarPro(mats, weights)
    starts = np.concatenate([_eq36_start(stiffness), np.zeros((b, 3))])
    both = problem.take(np.concatenate([np.arange(b), np.arange(b)]))
    g_all, cost_all = _levenberg_marquardt_b(both, starts)
    g1, g2 = g_all[:b], g_all[b:]
    c1, c2 = cost_all[:b], cost_all[b:]
    # the scalar version keeps the first start unless the second is strictly better
    second = (c2 < c1) | ~np.isfinite(c1)
    g = np.where(second[:, None], g2, g1)
    _, j, *_ = problem.evaluate(g)
    jm: Array = np.einsum("bk,kij->bij", j, _SYM3)
    return g, jm, np.where(second, c2, c1)


@dataclass(frozen=True)
class BatchEstimates:
    """Results of :func:`identify_batch`, one row per draw, in the layout's units.

    Attributes
    ----------
    center_of_gravity : ndarray, shape (B, 3)
        CG (length).
    inertia_per_mass : ndarray, shape (B, 3, 3)
        ``J / m`` about the CG (length^2).
    principal_moments_per_mass : ndarray, shape (B, 3)
        Eigenvalues of `inertia_per_mass`, ascending (length^2).
    stiffness_diagonal_per_mass : ndarray, shape (B, 6)
        Diagonal of ``K_g / m`` (1/s^2 for translations, length^2/s^2 for rotations).
    damping_diagonal_per_mass : ndarray, shape (B, 6)
        Diagonal of ``C_g / m`` (1/s, length^2/s).
    ok : ndarray of bool, shape (B,)
        False for a draw that failed (layout of rank below 6, singular modal
        matrix, non-positive frequency, non-finite result); its rows are NaN.
    """

    center_of_gravity: Array
    inertia_per_mass: Array
    principal_moments_per_mass: Array
    stiffness_diagonal_per_mass: Array
    damping_diagonal_per_mass: Array
    ok: BArray

    @property
    def plausible(self) -> BArray:
        """Draws whose inertia is positive definite and obeys the triangle inequality."""
        w = self.principal_moments_per_mass
        with np.errstate(invalid="ignore"):
            good: BArray = self.ok & (w[:, 0] > 0.0) & (w[:, 2] <= (w[:, 0] + w[:, 1]) * (1.0 + 1e-9))
        return good


def _patch(values: NDArray[Any], ok: BArray, donor: int) -> NDArray[Any]:
    """Rows of failed draws replaced by those of a good draw, so that stacked solvers never see them."""
    if np.all(ok):
        return values
    out = values.copy()
    out[~ok] = values[donor]
    return out


def _robust_solve(a: NDArray[Any], b: NDArray[Any]) -> tuple[NDArray[Any], BArray]:
    """Stacked ``solve(a, b)``; rows whose matrix is singular come back as NaN with ok False."""
    try:
        x: NDArray[Any] = np.linalg.solve(a, b)
        return x, np.ones(a.shape[0], dtype=bool)
    except np.linalg.LinAlgError:
        out = np.full(b.shape, np.nan, dtype=np.result_type(a, b))
        ok = np.ones(a.shape[0], dtype=bool)
        for i in range(a.shape[0]):
            try:
                out[i] = np.linalg.solve(a[i], b[i])
            except np.linalg.LinAlgError:
                ok[i] = False
        return out, ok


def _failed_batch(b: int) -> BatchEstimates:
    return BatchEstimates(
        np.full((b, 3), np.nan), np.full((b, 3, 3), np.nan), np.full((b, 3), np.nan),
        np.full((b, 6), np.nan), np.full((b, 6), np.nan), np.zeros(b, dtype=bool),
    )  # fmt: skip


def _identify_chunk(pos: Array, dirs: Array, lam: CArray, psi: CArray, damping_weight: float) -> BatchEstimates:
    b, p, _ = pos.shape
    ok = np.all(np.isfinite(lam), axis=1) & np.all(np.isfinite(psi), axis=(1, 2))
    ok &= np.all(np.isfinite(pos), axis=(1, 2)) & np.all(np.isfinite(dirs), axis=(1, 2))
    ok &= np.all(lam.imag > 0.0, axis=1) & np.all(lam.real <= 0.0, axis=1)
    if not np.any(ok):
        return _failed_batch(b)
    donor = int(np.flatnonzero(ok)[0])
    pos, dirs, lam, psi = (_patch(x, ok, donor) for x in (pos, dirs, lam, psi))
    # dimensionless frame of each draw (geometry.layout_frame)
    centre = pos.mean(axis=1)
    rel = pos - centre[:, None]
    scale = np.sqrt(np.mean(np.sum(rel**2, axis=2), axis=1))
    scale = np.where(scale > 0.0, scale, 1.0)
    local = rel / scale[:, None, None]
    t = np.concatenate([dirs, np.cross(local, dirs)], axis=2)  # (b, p, 6), eq. (3) of [1]
    # rank check (geometry.layout_condition)
    sv = np.linalg.svd(t, compute_uv=False)
    tol = max(p, 6) * np.finfo(float).eps * sv[:, :1] * 1e3
    ok &= np.sum(sv > tol, axis=1) == 6
    if not np.any(ok):
        return _failed_batch(b)
    donor = int(np.flatnonzero(ok)[0])
    t, lam, psi = (_patch(x, ok, donor) for x in (t, lam, psi))
    # rigid-body coordinates (selection.project_rigid), real and imaginary parts together
    rhs = np.concatenate([psi.real, psi.imag], axis=2)
    if p == 6:
        coords, solved = _robust_solve(t, rhs)
    else:
        qm, rm = np.linalg.qr(t)
        coords, solved = _robust_solve(rm, np.swapaxes(qm, 1, 2) @ rhs)
    ok &= solved
    if not np.any(ok):
        return _failed_batch(b)
    donor = int(np.flatnonzero(ok)[0])
    phi = _patch(coords[:, :, :6] + 1j * coords[:, :, 6:], ok, donor)
    lam = _patch(lam, ok, donor)
    # exact state matrix, eq. (19) of [1] (statespace.state_matrices), in scaled time
    omega = np.sqrt(np.mean(np.abs(lam) ** 2, axis=1))
    lam_s = lam / omega[:, None]
    mu = np.concatenate([lam_s, lam_s.conj()], axis=1)
    ell = np.concatenate([phi, phi.conj()], axis=2)
    v = np.concatenate([ell * mu[:, None, :], ell], axis=1)
    a_t, solved = _robust_solve(np.swapaxes(v, 1, 2), np.swapaxes(v * mu[:, None, :], 1, 2))
    a = np.swapaxes(a_t, 1, 2).real
    ok &= solved & np.all(np.isfinite(a), axis=(1, 2))
    if not np.any(ok):
        return _failed_batch(b)
    a = _patch(a, ok, int(np.flatnonzero(ok)[0]))
    q = np.ascontiguousarray(-a[:, :6, 6:])
    pmat = np.ascontiguousarray(-a[:, :6, :6])
    g, j, _ = _solve_structured_b(q, pmat, damping_weight)
    # K / m and C / m diagonals at the CG: diagonal of sym(D X_g), X_g = G_go X G_og
    s = _skew_b(g)[:, None]
    mats = np.stack([q, pmat], axis=1)
    x11, x21, x22 = mats[..., :3, :3], mats[..., 3:, :3], mats[..., 3:, 3:]
    xg11 = x11 - s @ x21
    xg22 = x21 @ s + x22
    diag = np.concatenate([np.einsum("bnii->bni", xg11), np.einsum("bij,bnji->bni", j, xg22)], axis=2)
    # back to the layout's units
    dof2 = np.concatenate([np.ones((b, 3)), np.repeat(scale[:, None] ** 2, 3, axis=1)], axis=1)
    cg = centre + scale[:, None] * g
    inertia = scale[:, None, None] ** 2 * j
    stiff = (omega**2)[:, None] * diag[:, 0] * dof2
    damp = omega[:, None] * diag[:, 1] * dof2
    moments = np.asarray(np.linalg.eigvalsh(0.5 * (inertia + np.swapaxes(inertia, 1, 2))), dtype=float)
    ok &= (
        np.all(np.isfinite(cg), axis=1)
        & np.all(np.isfinite(inertia), axis=(1, 2))
        & np.all(np.isfinite(stiff), axis=1)
        & np.all(np.isfinite(damp), axis=1)
    )
    bad = ~ok
    for arr in (cg, inertia, moments, stiff, damp):
        arr[bad] = np.nan
    return BatchEstimates(cg, inertia, moments, stiff, damp, ok)


def identify_batch(
    positions: ArrayLike,
    directions: ArrayLike,
    poles: ArrayLike,
    shapes: ArrayLike,
    *,
    damping_weight: float = DAMPING_WEIGHT,
) -> BatchEstimates:
    """Identify many tests at once with the estimator of :func:`rigidid.core.identify.identify`.

    Parameters
    ----------
    positions : array_like, shape (B, p, 3)
        Sensor locations of each test (length).
    directions : array_like, shape (B, p, 3)
        Measuring axes (normalised here).
    poles : array_like of complex, shape (B, 6)
        Poles of the six rigid-body modes (rad/s), ``Im > 0``.
    shapes : array_like of complex, shape (B, p, 6)
        Mode shapes as the sensors read them.
    damping_weight : float
        As in :func:`~rigidid.core.identify.identify`.

    Returns
    -------
    BatchEstimates
        Per-mass results; draws that fail are flagged, never raised.

    Notes
    -----
    Same steps as ``identify(..., method="structured")``: dimensionless frame
    per test, least-squares rigid-body coordinates (eq. (30) of [1] in
    spirit), exact ``M^-1 K`` and ``M^-1 C`` from eq. (19), and the CG by
    Levenberg-Marquardt from the same two starts (eq. (36) and the sensor
    centroid) with ``J / m`` eliminated by linear least squares (variable
    projection). The Jacobian is analytic (Kaufman's approximation) instead of
    central differences, so the iterations differ but the converged minimum
    is the same: results agree with the scalar function to about 1e-8
    relative (worst seen 1.5e-7), the precision to which a sum of squares
    pins its minimiser once the cost is flat to rounding, where both stop.
    Warnings (conditioning, plausibility) are not raised; see
    :attr:`BatchEstimates.plausible`. Tests are processed in chunks of 4096.
    """
    pos = np.asarray(positions, dtype=float)
    dirs_in = np.asarray(directions, dtype=float)
    lam = np.asarray(poles, dtype=complex)
    psi = np.asarray(shapes, dtype=complex)
    if pos.ndim != 3 or pos.shape[2] != 3 or dirs_in.shape != pos.shape:
        raise InputError(f"positions and directions must be (draws, sensors, 3), got {pos.shape}, {dirs_in.shape}")
    b, p, _ = pos.shape
    if lam.shape != (b, 6) or psi.shape != (b, p, 6):
        raise InputError(f"poles must be ({b}, 6) and shapes ({b}, {p}, 6), got {lam.shape}, {psi.shape}")
    if p < 6:
        raise IdentificationError(f"the sensor layout has {p} sensors; rigid-body motion needs at least 6")
    norms = np.linalg.norm(dirs_in, axis=2, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        dirs = np.where(norms > 0.0, dirs_in / norms, np.nan)
    parts = [
        _identify_chunk(pos[i : i + _CHUNK], dirs[i : i + _CHUNK], lam[i : i + _CHUNK], psi[i : i + _CHUNK],
                        damping_weight)
        for i in range(0, b, _CHUNK)
    ]  # fmt: skip
    if len(parts) == 1:
        return parts[0]
    return BatchEstimates(
        *(np.concatenate([getattr(part, name) for part in parts]) for name in (
            "center_of_gravity", "inertia_per_mass", "principal_moments_per_mass",
            "stiffness_diagonal_per_mass", "damping_diagonal_per_mass", "ok",
        ))
    )  # fmt: skip


# --------------------------------------------------------------------------- propagation


@dataclass(frozen=True)
class Interval:
    """Estimate and Monte Carlo spread of one quantity (arrays of the quantity's shape).

    Attributes
    ----------
    estimate : ndarray
        From the unperturbed data (what :func:`~rigidid.core.identify.identify` returns).
    std : ndarray
        Standard deviation over the successful draws (``ddof=1``; 0 with one draw).
    low, high : ndarray
        2.5 and 97.5 percentiles over the successful draws: the 95 % interval.
    """

    estimate: Array
    std: Array
    low: Array
    high: Array

    def to_dict(self) -> dict[str, Any]:
        """``{"estimate", "std", "ci95"}`` as nested lists of floats; ``ci95`` pairs ``[low, high]``."""
        ci = np.stack([self.low, self.high], axis=-1)
        return {"estimate": _plain(self.estimate), "std": _plain(self.std), "ci95": _plain(ci)}


def _plain(a: Array) -> Any:
    """Nested lists of Python floats; NaN becomes None (valid JSON)."""
    return _nan_none(np.asarray(a, dtype=float).tolist())


def _nan_none(x: Any) -> Any:
    if isinstance(x, list):
        return [_nan_none(v) for v in x]
    value = float(x)
    return value if math.isfinite(value) else None


def _interval(estimate: Array, samples: Array) -> Interval:
    if samples.shape[0] == 0:
        nan = np.full(estimate.shape, np.nan)
        return Interval(estimate, nan, nan.copy(), nan.copy())
    std = samples.std(axis=0, ddof=1) if samples.shape[0] > 1 else np.zeros(estimate.shape)
    low, high = np.percentile(samples, [2.5, 97.5], axis=0)
    return Interval(np.asarray(estimate, dtype=float), std, low, high)


@dataclass(frozen=True)
class Uncertainty:
    """Uncertainty of every identified quantity, from :func:`propagate`.

    Attributes
    ----------
    center_of_gravity : Interval
        Shape (3,), length.
    inertia : Interval
        Shape (3, 3): the inertia tensor about the CG (mass length^2), or
        ``J / m`` (length^2) when `per_mass`.
    principal_moments : Interval
        Shape (3,), ascending; same units as `inertia`.
    stiffness_diagonal : Interval
        Shape (6,): diagonal of the support stiffness at the CG, x, y, z, rx,
        ry, rz (mass/s^2 and mass length^2/s^2), or per mass when `per_mass`.
    damping_diagonal : Interval
        Shape (6,): diagonal of the support damping at the CG (mass/s, mass
        length^2/s), or per mass.
    per_mass : bool
        True when no mass was given.
    noise : NoiseLevels
        The levels propagated.
    draws : int
        Number of draws requested.
    failed : int
        Draws that could not be identified (left out of the statistics).
    implausible : int
        Successful draws whose inertia is not positive definite or breaks the
        triangle inequality (kept in the statistics).
    seed : int or None
        Seed of the draws.
    """

    center_of_gravity: Interval
    inertia: Interval
    principal_moments: Interval
    stiffness_diagonal: Interval
    damping_diagonal: Interval
    per_mass: bool
    noise: NoiseLevels
    draws: int
    failed: int
    implausible: int
    seed: int | None


def propagate(
    positions: ArrayLike,
    directions: ArrayLike,
    poles: ArrayLike,
    shapes: ArrayLike,
    *,
    mass: float | None = None,
    noise: NoiseLevels = DEFAULT_NOISE,
    draws: int = 1000,
    seed: int | None = None,
    damping_weight: float = DAMPING_WEIGHT,
) -> Uncertainty:
    """Monte Carlo uncertainty of the CG, inertia and mount stiffness/damping.

    Parameters
    ----------
    positions : array_like, shape (p, 3)
        Sensor locations as stated (length), ``p >= 6``.
    directions : array_like, shape (p, 3)
        Measuring axes as stated.
    poles : array_like of complex, shape (6,)
        Measured poles of the six rigid-body modes (rad/s).
    shapes : array_like of complex, shape (p, 6)
        Measured mode shapes as the sensors read them.
    mass : float, optional
        Mass; without it inertia, stiffness and damping are per mass.
    noise : NoiseLevels
        Standard deviations of the measurement errors (see
        :func:`estimate_noise` for defaults from the data).
    draws : int
        Number of Monte Carlo draws (1000 gives percentiles to about 1 %).
    seed : int, optional
        Seed of the random generator, for reproducible intervals.
    damping_weight : float
        As in :func:`~rigidid.core.identify.identify`.

    Returns
    -------
    Uncertainty

    Raises
    ------
    InputError
        Invalid data (as :func:`~rigidid.core.identify.identify`) or ``draws < 1``.
    IdentificationError
        If the unperturbed data cannot be identified, or every draw fails.

    Warns
    -----
    IllConditionedWarning
        When more than 5 % of the draws fail: the noise stated is large enough
        to make the problem singular, and the intervals (over the successful
        draws only) understate the uncertainty.

    Notes
    -----
    Each draw perturbs the measured data by the stated noise and identifies
    again (:func:`perturb`, :func:`identify_batch`); the spread of the draws
    around the estimate stands for the spread of the estimate around the truth
    (parametric bootstrap). The 95 % interval is the 2.5-97.5 percentile range
    of the draws; it covers the truth about 95 % of the time when the noise
    levels are right and the estimator is close to linear over the spread
    (checked by simulation in ``tests/core/test_uncertainty.py``). With large
    noise the estimator is biased and nonlinear and the intervals lose
    coverage. Errors not in the noise model (flexible modes, a wrong mode
    chosen, mass-loaded sensors) are not covered. Only the structured method
    is propagated. The estimate itself comes from
    :func:`~rigidid.core.identify.identify`, whose warnings are suppressed
    here (call it directly to see them).
    """
    pos, dirs, lam, psi = _checked(positions, directions, poles, shapes)
    if not (isinstance(draws, int | np.integer) and draws >= 1):
        raise InputError(f"the number of draws must be a positive integer, got {draws!r}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        base = identify(pos, dirs, lam, psi, mass=mass, method="structured", damping_weight=damping_weight)
    data = perturb(pos, dirs, lam, psi, noise, int(draws), mass=mass, seed=seed)
    batch = identify_batch(data.positions, data.directions, data.poles, data.shapes, damping_weight=damping_weight)
    return summarise(base_estimate(base), batch, data.mass, noise=noise, seed=seed)


def base_estimate(result: Any) -> dict[str, Array]:
    """Per-mass quantities of an :class:`~rigidid.core.identify.Identification` as :func:`summarise` wants them."""
    return {
        "center_of_gravity": np.asarray(result.center_of_gravity, dtype=float),
        "inertia": np.asarray(result.inertia_per_mass, dtype=float),
        "principal_moments": np.asarray(result.principal_moments_per_mass, dtype=float),
        "stiffness_diagonal": np.diag(result.stiffness_per_mass).astype(float),
        "damping_diagonal": np.diag(result.damping_per_mass).astype(float),
        "mass": np.asarray(np.nan if result.mass is None else result.mass, dtype=float),
    }


def summarise(
    estimate: dict[str, Array],
    batch: BatchEstimates,
    mass: Array | None,
    *,
    noise: NoiseLevels,
    seed: int | None,
) -> Uncertainty:
    """Statistics of a batch of draws around an estimate (used by :func:`propagate`).

    Parameters
    ----------
    estimate : dict
        Per-mass estimate from :func:`base_estimate` (key ``"mass"``: the mass,
        NaN when unknown).
    batch : BatchEstimates
        The identified draws.
    mass : ndarray, shape (B,), or None
        Mass of each draw; None for per-mass results.
    noise : NoiseLevels
        Recorded in the result.
    seed : int or None
        Recorded in the result.

    Returns
    -------
    Uncertainty

    Raises
    ------
    IdentificationError
        If every draw failed.
    """
    ok = batch.ok
    n_ok = int(np.sum(ok))
    draws = int(ok.shape[0])
    if n_ok == 0:
        raise IdentificationError(f"all {draws} Monte Carlo draws failed: the noise stated makes the problem singular")
    failed = draws - n_ok
    if failed > _FAILED_WARN_FRACTION * draws:
        warnings.warn(
            f"{failed} of {draws} Monte Carlo draws failed; the intervals (from the others) understate the uncertainty",
            IllConditionedWarning,
            stacklevel=3,
        )
    per_mass = mass is None
    m_est = 1.0 if per_mass else float(estimate["mass"])
    m_draw = np.ones(n_ok) if mass is None else np.asarray(mass, dtype=float)[ok]
    return Uncertainty(
        center_of_gravity=_interval(estimate["center_of_gravity"], batch.center_of_gravity[ok]),
        inertia=_interval(m_est * estimate["inertia"], m_draw[:, None, None] * batch.inertia_per_mass[ok]),
        principal_moments=_interval(
            m_est * estimate["principal_moments"], m_draw[:, None] * batch.principal_moments_per_mass[ok]
        ),
        stiffness_diagonal=_interval(
            m_est * estimate["stiffness_diagonal"], m_draw[:, None] * batch.stiffness_diagonal_per_mass[ok]
        ),
        damping_diagonal=_interval(
            m_est * estimate["damping_diagonal"], m_draw[:, None] * batch.damping_diagonal_per_mass[ok]
        ),
        per_mass=per_mass,
        noise=noise,
        draws=draws,
        failed=failed,
        implausible=int(np.sum(ok & ~batch.plausible)),
        seed=seed,
    )


def uncertainty_to_dict(result: Uncertainty) -> dict[str, Any]:
    """JSON-ready form of an :class:`Uncertainty` (plain lists and floats; NaN as None).

    Parameters
    ----------
    result : Uncertainty

    Returns
    -------
    dict
        ``{"center_of_gravity": {"estimate": [3], "std": [3], "ci95": [[lo, hi] x 3]},
        "inertia_tensor": {... 3x3, ci95 3x3x2}, "principal_moments": {...},
        "stiffness_diagonal": {...}, "damping_diagonal": {...}, "per_mass": bool,
        "draws": int, "failed": int, "implausible": int, "seed": int | None,
        "noise": {...}}``. Without a mass the keys of the per-mass quantities
        end in ``_per_mass`` (``"inertia_per_mass"``,
        ``"principal_moments_per_mass"``, ``"stiffness_diagonal_per_mass"``,
        ``"damping_diagonal_per_mass"``), as the attributes of
        :class:`~rigidid.core.identify.Identification`.
    """
    suffix = "_per_mass" if result.per_mass else ""
    inertia_key = "inertia_per_mass" if result.per_mass else "inertia_tensor"
    return {
        "center_of_gravity": result.center_of_gravity.to_dict(),
        inertia_key: result.inertia.to_dict(),
        "principal_moments" + suffix: result.principal_moments.to_dict(),
        "stiffness_diagonal" + suffix: result.stiffness_diagonal.to_dict(),
        "damping_diagonal" + suffix: result.damping_diagonal.to_dict(),
        "per_mass": result.per_mass,
        "draws": result.draws,
        "failed": result.failed,
        "implausible": result.implausible,
        "seed": result.seed,
        "noise": result.noise.as_dict(),
    }
