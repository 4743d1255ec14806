"""Mount by mount: per-mount rates from the identified 6x6 matrices, and the torque roll axis.

The forward model is the one of :func:`rigidid.core.simulate.system_matrices` (eq. (1) of
[1]): mount ``k`` at ``r_k`` with a 3x3 stiffness ``k_k`` adds ``T_k^T k_k T_k`` to the
stiffness at the CG, ``T_k = [I, -S(r_k - g)]``. With the mount's principal axes ``U_k``
given, ``k_k = U_k diag(k_k1, k_k2, k_k3) U_k^T`` is linear in its three rates, so the
rates of all mounts follow from the identified ``K`` by non-negative least squares on the
21 independent entries of the symmetric ``K``. The same holds for the damping.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.geometry import skew
from rigidid.errors import InputError

__all__ = ["MountRates", "TorqueRollAxis", "mount_rates", "torque_roll_axis"]

Array = NDArray[np.float64]

_UPPER = np.triu_indices(6)
_WEIGHT = np.where(_UPPER[0] == _UPPER[1], 1.0, math.sqrt(2.0))
"""Off-diagonal entries count twice in the Frobenius norm of a symmetric matrix."""


@dataclass(frozen=True)
class MountRates:
    """Rates of each mount along its principal axes, fitted to a 6x6 stiffness and damping.

    Attributes
    ----------
    stiffness : ndarray, shape (n, 3)
        Rates of mount ``k`` along its axes ``axes[k][:, a]`` (the units of the 6x6
        matrix's translation block: force/length, or per mass).
    damping : ndarray, shape (n, 3) or None
        Likewise, when a damping matrix was given.
    axes : ndarray, shape (n, 3, 3)
        Column ``a`` of ``axes[k]`` is axis ``a`` of mount ``k``.
    stiffness_residual, damping_residual : float
        ``|X - X_fit| / |X|`` (Frobenius): how well mounts at these points explain
        the matrix (0 when they explain it exactly; NaN for damping when absent).
    unknowns : int
        Rates fitted per matrix (three per mount).
    rank : int
        Rank of the linear map from the rates to the 21 independent entries of the
        6x6 matrix; the rates are unique when it equals `unknowns`.
    statement : str
        In words: unique or not, and what would make it unique.
    """

    stiffness: Array
    damping: Array | None
    axes: Array
    stiffness_residual: float
    damping_residual: float
    unknowns: int
    rank: int
    statement: str

    @property
    def unique(self) -> bool:
        """True when the layout of mounts determines every rate."""
        return self.rank == self.unknowns

    def loss_factor(self, frequency_hz: ArrayLike) -> Array:
        """Loss factor ``eta = 2 pi f c / k`` of each rate at each frequency, shape (f, n, 3).

        NaN where the rate is zero or no damping was fitted.
        """
        f = np.asarray(frequency_hz, dtype=float).reshape(-1, 1, 1)
        if self.damping is None:
            return np.full((f.shape[0], *self.stiffness.shape), np.nan)
        with np.errstate(divide="ignore", invalid="ignore"):
            eta: Array = np.where(self.stiffness > 0.0, 2.0 * np.pi * f * self.damping / self.stiffness, np.nan)
        return eta


def _design(offsets: Array, axes: Array, scale: float) -> Array:
    """Columns: the 21 weighted upper entries of ``D T^T u u^T T D`` for each mount and axis."""
    d = np.concatenate([np.ones(3), np.full(3, 1.0 / scale)])
    cols = []
    for r, u in zip(offsets, axes, strict=True):
        t = np.hstack([np.eye(3), -skew(r)])
        for a in range(3):
            tu = t.T @ u[:, a]
            m = np.outer(tu, tu) * np.outer(d, d)
            cols.append(m[_UPPER] * _WEIGHT)
    return np.stack(cols, axis=1)


def _fit(design: Array, matrix: Array, scale: float) -> tuple[Array, float]:
    from scipy.optimize import nnls

    d = np.concatenate([np.ones(3), np.full(3, 1.0 / scale)])
    target = (0.5 * (matrix + matrix.T) * np.outer(d, d))[_UPPER] * _WEIGHT
    rates, _ = nnls(design, target)
    norm = float(np.linalg.norm(target))
    residual = float(np.linalg.norm(design @ rates - target)) / norm if norm > 0.0 else 0.0
    return rates.reshape(-1, 3), residual


def mount_rates(
    stiffness: ArrayLike,
    center_of_gravity: ArrayLike,
    positions: ArrayLike,
    axes: ArrayLike | None = None,
    damping: ArrayLike | None = None,
) -> MountRates:
    """Per-mount rates along given axes from a 6x6 stiffness (and damping) at the CG.

    Parameters
    ----------
    stiffness : array_like, shape (6, 6)
        Stiffness at the CG, DOF order x, y, z, rx, ry, rz (any consistent units,
        per mass allowed).
    center_of_gravity : array_like, shape (3,)
        The CG (length), the reference point of `stiffness`.
    positions : array_like, shape (n, 3)
        Where each mount acts (length).
    axes : array_like, shape (n, 3, 3), optional
        Column ``a`` of ``axes[k]``: principal axis ``a`` of mount ``k`` (normalised
        here). Default: the layout's axes x, y, z for every mount.
    damping : array_like, shape (6, 6), optional
        Damping at the CG, fitted the same way.

    Returns
    -------
    MountRates

    Raises
    ------
    InputError
        Arrays of the wrong shape, non-finite values, or a zero axis.

    Notes
    -----
    Non-negative least squares (``scipy.optimize.nnls``) on the 21 independent
    entries of the symmetric matrix, rotations scaled by the RMS distance of the
    mounts from the CG so that translation and rotation entries weigh alike. A
    large residual says the mounts alone do not explain the matrix: a mount
    position is off, the axes are wrong, or another support (a hose, a cable)
    carries load.

    Examples
    --------
    Three mounts below a body, rates 10 and 20 in shear, 100 to 300 in compression:

    >>> from rigidid.core.simulate import Body, Mount, system_matrices
    >>> where = [[-1, 0.5, -0.5], [1, 0.5, -0.3], [0, -1, -0.6]]
    >>> mounts = [Mount.from_values(p, (10, 20, 100 * (i + 1))) for i, p in enumerate(where)]
    >>> _, k, _ = system_matrices(Body(1.0, np.zeros(3), np.eye(3), mounts))
    >>> fit = mount_rates(k, np.zeros(3), where)
    >>> fit.stiffness.round(9).tolist(), fit.unique
    ([[10.0, 20.0, 100.0], [10.0, 20.0, 200.0], [10.0, 20.0, 300.0]], True)

    Two mounts on one line along x share the x load any way: not unique.

    >>> mount_rates(k, np.zeros(3), [[-1, 0, 0], [1, 0, 0], [0, 1, -1]]).unique
    False
    """
    k = np.asarray(stiffness, dtype=float)
    g = np.asarray(center_of_gravity, dtype=float).reshape(3)
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    n = pos.shape[0]
    if k.shape != (6, 6) or not np.all(np.isfinite(k)):
        raise InputError(f"stiffness must be a finite 6x6 matrix, got shape {k.shape}", source="stiffness")
    if n == 0 or not np.all(np.isfinite(pos)) or not np.all(np.isfinite(g)):
        raise InputError("mount positions and the CG must be finite, with at least one mount", source="positions")
    u = np.broadcast_to(np.eye(3), (n, 3, 3)).copy() if axes is None else np.asarray(axes, dtype=float)
    if u.shape != (n, 3, 3) or not np.all(np.isfinite(u)):
        raise InputError(f"axes must be ({n}, 3, 3), got {u.shape}", source="axes")
    norms = np.linalg.norm(u, axis=1, keepdims=True)
    if np.any(norms <= 0.0):
        raise InputError("a mount axis is the zero vector", source="axes")
    u = u / norms
    offsets = pos - g
    scale = float(np.sqrt(np.mean(np.sum(offsets**2, axis=1)))) or 1.0
    design = _design(offsets, u, scale)
    s = np.linalg.svd(design, compute_uv=False)
    rank = int(np.sum(s > 1e-10 * s[0])) if s.size and s[0] > 0 else 0
    unknowns = 3 * n
    rates_k, res_k = _fit(design, k, scale)
    rates_c, res_c = (None, math.nan)
    if damping is not None:
        c = np.asarray(damping, dtype=float)
        if c.shape != (6, 6) or not np.all(np.isfinite(c)):
            raise InputError(f"damping must be a finite 6x6 matrix, got shape {c.shape}", source="damping")
        rates_c, res_c = _fit(design, c, scale)
    if rank == unknowns:
        statement = f"unique: {unknowns} rates, all determined by the 21 independent entries of the 6x6 matrix"
    else:
        statement = (
            f"not unique: {unknowns} rates but the mount layout determines only {rank} combinations of them "
            f"(the 6x6 matrix has 21 independent entries); fix some rates (a data sheet's shear rates), use "
            "mounts of one type with equal rates, or fewer mounts, to make the rest unique"
        )
    return MountRates(rates_k, rates_c, u, res_k, res_c, unknowns, rank, statement)


@dataclass(frozen=True)
class TorqueRollAxis:
    """The axis the body turns about under a pure torque.

    Attributes
    ----------
    torque_axis : ndarray, shape (3,)
        The torque's unit direction (for an engine, the crankshaft).
    direction : ndarray, shape (3,)
        Unit direction of the rotation ``J^-1 t`` (sign chosen along `torque_axis`).
    angle_to_torque_deg : float
        Angle between the two (0 when the torque axis is a principal axis).
    angle_to_principal_deg : ndarray, shape (3,)
        Angle to each principal axis (0-90 degrees), ascending moments.
    """

    torque_axis: Array
    direction: Array
    angle_to_torque_deg: float
    angle_to_principal_deg: Array


def _angle(a: Array, b: Array) -> float:
    return math.degrees(math.atan2(float(np.linalg.norm(np.cross(a, b))), abs(float(a @ b))))


def torque_roll_axis(inertia: ArrayLike, torque_axis: ArrayLike) -> TorqueRollAxis:
    """Direction of rotation of a free body under a pure torque about `torque_axis`.

    Parameters
    ----------
    inertia : array_like, shape (3, 3)
        Inertia tensor about the CG (or per mass: only its shape matters).
    torque_axis : array_like, shape (3,)
        Direction of the torque (normalised here).

    Returns
    -------
    TorqueRollAxis
        ``J^-1 t`` normalised, its angle to `torque_axis` and to the principal axes.

    Raises
    ------
    InputError
        A zero or non-finite torque axis, or an inertia that is not positive definite.

    Examples
    --------
    >>> tra = torque_roll_axis(np.diag([1.0, 2.0, 4.0]), [1.0, 1.0, 0.0])
    >>> tra.direction.round(6).tolist(), round(tra.angle_to_torque_deg, 3)
    ([0.894427, 0.447214, 0.0], 18.435)
    """
    j = np.asarray(inertia, dtype=float)
    t = np.asarray(torque_axis, dtype=float).reshape(3)
    norm = float(np.linalg.norm(t))
    if not (math.isfinite(norm) and norm > 0.0):
        raise InputError("the torque axis must be a finite, non-zero vector", source="torque_axis")
    t = t / norm
    moments, vectors = np.linalg.eigh(0.5 * (j + j.T))
    if moments[0] <= 0.0:
        raise InputError("the inertia tensor is not positive definite", source="inertia")
    w = np.linalg.solve(j, t)
    w = w / np.linalg.norm(w)
    if w @ t < 0.0:
        w = -w
    principal = np.array([_angle(w, vectors[:, i]) for i in range(3)])
    return TorqueRollAxis(t, w, _angle(w, t), principal)
