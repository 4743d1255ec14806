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
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.geometry import transfer_matrix
from rigidid.core.linalg import numerical_rank, rank_tolerance
from rigidid.errors import InputError

if TYPE_CHECKING:
    from collections.abc import Hashable, Sequence

    from rigidid.core.estimator import Estimates
    from rigidid.core.identify import Identification
    from rigidid.core.linearised import Linearised
    from rigidid.core.noise import NoiseLevels
    from rigidid.core.simulate import Body

__all__ = [
    "ADEQUATE_P",
    "FEASIBLE_FLOOR",
    "MountModel",
    "MountModelPrediction",
    "MountRates",
    "TorqueRollAxis",
    "eigen_residual",
    "feasible_inertia",
    "fit_mount_model",
    "group_matrix",
    "identify_mount_model",
    "mount_rates",
    "predict_mount_model",
    "predict_mount_model_linearised",
    "split_misfit",
    "split_uniqueness",
    "torque_roll_axis",
]

Array = NDArray[np.float64]

ADEQUATE_P = 0.01
"""The mount model is flagged inadequate when its F test's p-value is below this."""
SHAPE_NOISE_FLOOR = 1e-6
"""Shape noise below this (exact or 10-digit data) is taken as this, a known level: the F test
then compares the mount model's misfit with it (chi-square) rather than with the data's own."""

_UPPER = np.triu_indices(6)
_WEIGHT = np.where(_UPPER[0] == _UPPER[1], 1.0, math.sqrt(2.0))
"""Off-diagonal entries count twice in the Frobenius norm of a symmetric matrix."""


def group_matrix(groups: Sequence[Hashable | None] | None, count: int) -> Array:
    """Map from the shared rates of groups of identical mounts to every mount's rates.

    Parameters
    ----------
    groups : sequence of hashable or None, length `count`, or None
        A label per mount: mounts with one label are identical (they share their
        three rates along their own axes, so mirrored mounts can share); None
        (for the whole or an entry) leaves a mount independent.
    count : int
        Number of mounts.

    Returns
    -------
    ndarray, shape (3 count, 3 g)
        ``rates.ravel() = S @ shared``, ``g`` the number of distinct mounts.

    Raises
    ------
    InputError
        `groups` of the wrong length.

    Examples
    --------
    >>> group_matrix(["a", None, "a"], 3).shape
    (9, 6)
    """
    labels = [None] * count if groups is None else list(groups)
    if len(labels) != count:
        raise InputError(f"groups must give one label per mount ({count}), got {len(labels)}", source="groups")
    column: dict[Hashable, int] = {}
    index = []
    for k, label in enumerate(labels):
        key = ("independent", k) if label is None else ("group", label)
        index.append(column.setdefault(key, len(column)))
    out = np.zeros((3 * count, 3 * len(column)))
    for k, c in enumerate(index):
        out[3 * k : 3 * k + 3, 3 * c : 3 * c + 3] = np.eye(3)
    return out


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
        t = transfer_matrix(r)[:3]
        for a in range(3):
            tu = t.T @ u[:, a]
            m = np.outer(tu, tu) * np.outer(d, d)
            cols.append(m[_UPPER] * _WEIGHT)
    return np.stack(cols, axis=1)


def _fit(design: Array, matrix: Array, scale: float, ties: Array) -> tuple[Array, float]:
    from scipy.optimize import nnls

    d = np.concatenate([np.ones(3), np.full(3, 1.0 / scale)])
    target = (0.5 * (matrix + matrix.T) * np.outer(d, d))[_UPPER] * _WEIGHT
    rates, _ = nnls(design, target)
    norm = float(np.linalg.norm(target))
    residual = float(np.linalg.norm(design @ rates - target)) / norm if norm > 0.0 else 0.0
    return (ties @ rates).reshape(-1, 3), residual


def _uniqueness(design: Array) -> tuple[int, int, str]:
    """Unknowns, rank and the statement of a design matrix (21 rows, one column per shared rate)."""
    unknowns = design.shape[1]
    s = np.linalg.svd(design, compute_uv=False)
    rank = int(numerical_rank(s, design.shape[0])) if s.size and s[0] > 0 else 0
    if rank == unknowns:
        statement = f"unique: {unknowns} rates, all determined by the 21 independent entries of the 6x6 matrix"
    else:
        statement = (
            f"not unique: {unknowns} rates but the mount layout determines only {rank} combinations of them "
            f"(the 6x6 matrix has 21 independent entries); fix some rates (a data sheet's shear rates), declare "
            "mounts of one type identical (a common group), or use fewer mounts, to make the rest unique"
        )
    return unknowns, rank, statement


def split_uniqueness(
    positions: ArrayLike, axes: ArrayLike | None = None, groups: Sequence[Hashable | None] | None = None
) -> tuple[int, int, str]:
    """Whether a mount layout determines every per-mount rate from a 6x6 matrix (before a test).

    Parameters
    ----------
    positions : array_like, shape (n, 3)
        Where the mounts act (length).
    axes : array_like, shape (n, 3, 3), optional
        Their principal axes (columns); default x, y, z.
    groups : sequence of hashable or None, optional
        Groups of identical mounts (:func:`group_matrix`).

    Returns
    -------
    unknowns, rank : int
        Shared rates and the rank of their map to the 21 entries of ``K``
        (unique when equal); as :class:`MountRates`.
    statement : str
        In words, with what would make it unique.

    Notes
    -----
    The rank does not depend on the reference point (moving it is a congruence of
    ``K``), so the mounts' centroid serves as the CG.

    Examples
    --------
    >>> split_uniqueness([[-1, 0, 0], [1, 0, 0], [0, 1, -1]])[:2]
    (9, 8)
    """
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    n = pos.shape[0]
    if n == 0 or not np.all(np.isfinite(pos)):
        raise InputError("mount positions must be finite, with at least one mount", source="positions")
    u = np.broadcast_to(np.eye(3), (n, 3, 3)).copy() if axes is None else np.asarray(axes, dtype=float)
    if u.shape != (n, 3, 3) or not np.all(np.isfinite(u)) or np.any(np.linalg.norm(u, axis=1) <= 0.0):
        raise InputError(f"axes must be ({n}, 3, 3) non-zero finite vectors", source="axes")
    u = u / np.linalg.norm(u, axis=1, keepdims=True)
    offsets = pos - pos.mean(axis=0)
    scale = float(np.sqrt(np.mean(np.sum(offsets**2, axis=1)))) or 1.0
    return _uniqueness(_design(offsets, u, scale) @ group_matrix(groups, n))


def mount_rates(
    stiffness: ArrayLike,
    center_of_gravity: ArrayLike,
    positions: ArrayLike,
    axes: ArrayLike | None = None,
    damping: ArrayLike | None = None,
    groups: Sequence[Hashable | None] | None = None,
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
    groups : sequence of hashable or None, optional
        A label per mount; mounts with one label share their rates
        (:func:`group_matrix`). Default: every mount independent.

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
    ties = group_matrix(groups, n)
    design = _design(offsets, u, scale) @ ties
    unknowns, rank, statement = _uniqueness(design)
    rates_k, res_k = _fit(design, k, scale, ties)
    rates_c, res_c = (None, math.nan)
    if damping is not None:
        c = np.asarray(damping, dtype=float)
        if c.shape != (6, 6) or not np.all(np.isfinite(c)):
            raise InputError(f"damping must be a finite 6x6 matrix, got shape {c.shape}", source="damping")
        rates_c, res_c = _fit(design, c, scale, ties)
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


@dataclass(frozen=True)
class MountModel:
    """CG, inertia and per-mount rates fitted together to the modes (:func:`fit_mount_model`).

    Attributes
    ----------
    center_of_gravity : ndarray, shape (3,)
        CG (length).
    inertia_per_mass : ndarray, shape (3, 3)
        ``J / m`` about the CG (length^2), positive definite by construction.
    stiffness_per_mass, damping_per_mass : ndarray, shape (n, 3)
        Rates of each mount along its axes, per unit mass (1/s^2 and 1/s).
    axes : ndarray, shape (n, 3, 3)
        Column ``a`` of ``axes[k]``: axis ``a`` of mount ``k``.
    residual : float
        RMS of the eigenproblem residual ``(lambda^2 M + lambda C + K) phi`` over the
        modes, each mode's equations scaled by ``|lambda|^2 |phi|`` (dimensionless).
    parameters : int
        Unknowns of the model: 9 (CG, inertia) + 6 per distinct mount (mounts of a
        group count once).
    equations : int
        Real equations: 12 per mode.
    f_statistic : float or None
        F test of the mount model against any linear model of the rigid-body
        motion (see Notes of :func:`fit_mount_model`); None when the noise levels
        were not given or the test has no degrees of freedom.
    f_dof : tuple of int or None
        Its degrees of freedom (numerator, denominator).
    p_value : float or None
        Probability of an F statistic at least this large when the mount model is
        right and the noise is as given.
    cost : float or None
        Sum of squared noise-weighted output residuals (None without noise levels).
    linearised : Linearised or None
        The fit's response to one standard deviation of each independent
        combination of the noise (from the Jacobian of its noise-weighted output
        error at the solution), for the standard error of any figure (None
        without noise levels).
    misfit_dof : int
        Degrees of freedom of `cost`: the residuals less the modes' complex
        scales and the parameters.
    """

    center_of_gravity: Array
    inertia_per_mass: Array
    stiffness_per_mass: Array
    damping_per_mass: Array
    axes: Array
    residual: float
    parameters: int
    equations: int
    f_statistic: float | None = None
    f_dof: tuple[int, int] | None = None
    p_value: float | None = None
    cost: float | None = None
    linearised: Linearised | None = None
    misfit_dof: int = 0

    @property
    def aic(self) -> float:
        """Akaike's criterion ``N ln(RSS / N) + 2 P`` (RSS floored at 1e-30 N)."""
        rss = max(self.residual**2 * self.equations, 1e-30 * self.equations)
        return float(self.equations * math.log(rss / self.equations) + 2 * self.parameters)

    @property
    def adequate(self) -> bool | None:
        """F test verdict: False when ``p_value < ADEQUATE_P`` (a support or position is wrong)."""
        return None if self.p_value is None else bool(self.p_value >= ADEQUATE_P)


def _mount_columns(phi: NDArray[np.complex128], offsets: Array, axes: Array) -> NDArray[np.complex128]:
    """Columns ``T_k^T u u^T T_k phi`` (6,) for each mount and axis: (6, 3 n)."""
    cols = []
    for r, u in zip(offsets, axes, strict=True):
        t = transfer_matrix(r)[:3]
        tphi = t @ phi
        for a in range(3):
            cols.append(t.T @ u[:, a] * (u[:, a] @ tphi))
    return np.stack(cols, axis=1)


FEASIBLE_FLOOR = 0.05
"""Smallest principal moment of a start inertia, as a fraction of the mean of their moduli."""


def feasible_inertia(inertia: ArrayLike) -> Array:
    """The nearest positive definite inertia with every principal moment at least a floor.

    Parameters
    ----------
    inertia : array_like, shape (3, 3)
        A start inertia (per mass), perhaps indefinite (a noisy free route's answer).

    Returns
    -------
    ndarray, shape (3, 3)
        Symmetric part, principal moments raised to at least :data:`FEASIBLE_FLOOR` times
        the mean of their moduli, axes kept; ``0.3 I`` when not finite or zero. A start
        the mount model's Cholesky parameterisation can always take.

    Examples
    --------
    >>> np.linalg.eigvalsh(feasible_inertia(np.diag([-1.0, 2.0, 5.0]))).round(6).tolist()
    [0.133333, 2.0, 5.0]
    """
    j = np.asarray(inertia, dtype=float)
    if j.shape != (3, 3) or not np.all(np.isfinite(j)):
        return 0.3 * np.eye(3)
    w, v = np.linalg.eigh(0.5 * (j + j.T))
    floor = FEASIBLE_FLOOR * float(np.mean(np.abs(w)))
    if not floor > 0.0:
        return 0.3 * np.eye(3)
    result: Array = (v * np.maximum(w, floor)) @ v.T
    return 0.5 * (result + result.T)


def _inertia(params: Array) -> Array:
    lower = np.zeros((3, 3))
    lower[np.tril_indices(3)] = params
    return lower @ lower.T


class _OutputError:
    """Noise-weighted misfit of a mount model's modes to the measured poles and shapes (local frame).

    Per measured mode: natural frequency over ``frequency``, damping ratio over
    ``damping`` (both relative), and the shape misfit after the best complex scale
    over ``shape / sqrt(2)`` of the mode's RMS value per real and imaginary part:
    each entry has unit variance when the noise is as given.
    """

    def __init__(
        self,
        sensors: tuple[Array, Array],
        mu: NDArray[np.complex128],
        psi: NDArray[np.complex128],
        noise: NoiseLevels,
    ) -> None:
        from rigidid.core.statespace import modal_from_poles

        self.pos, self.dirs = sensors
        self.psi = psi
        self.wn = np.abs(mu)
        _, self.zeta = modal_from_poles(mu)
        self.freq = max(noise.frequency, 1e-6)
        self.damp = max(noise.damping, 1e-4)
        rms = np.sqrt(np.mean(np.abs(psi) ** 2, axis=0))
        self.shape_scale = rms * max(noise.shape, SHAPE_NOISE_FLOOR) / math.sqrt(2.0)
        self.floored = noise.shape < SHAPE_NOISE_FLOOR

    def __call__(self, g: Array, j: Array, k: Array, c: Array) -> Array:
        from scipy.optimize import linear_sum_assignment

        from rigidid.core.geometry import sensor_matrix
        from rigidid.core.identify import model_modes
        from rigidid.core.statespace import mac_matrix, modal_from_poles

        n = self.wn.size
        size = n * (2 + 2 * self.psi.shape[0])
        if not (np.all(np.isfinite(j)) and np.all(np.isfinite(k)) and np.all(np.isfinite(c))):
            return np.full(size, 1e6)
        lam, phi = model_modes(j, k, c)
        model = sensor_matrix(self.pos, self.dirs, g) @ phi
        wn = np.abs(lam)
        _, zeta = modal_from_poles(lam)
        cost = np.abs(wn[None, :] - self.wn[:, None]) / self.wn[:, None] + (1.0 - mac_matrix(self.psi, model))
        rows, cols = linear_sum_assignment(cost)
        out = np.zeros((n, 2 + 2 * self.psi.shape[0]))
        for i, m in zip(rows, cols, strict=True):
            out[i, 0] = (wn[m] - self.wn[i]) / self.wn[i] / self.freq
            out[i, 1] = (zeta[m] - self.zeta[i]) / max(self.zeta[i], 1e-4) / self.damp
            v = model[:, m]
            alpha = (v.conj() @ self.psi[:, i]) / max(float(np.real(v.conj() @ v)), 1e-300)
            miss = (self.psi[:, i] - alpha * v) / self.shape_scale[i]
            out[i, 2:] = np.concatenate([miss.real, miss.imag])
        return out.ravel()

    def free_cost(self, t: Array) -> float:
        """The same weighted shape misfit for the best rigid motion of each mode (any linear model's floor)."""
        coords = np.linalg.lstsq(t, self.psi, rcond=None)[0]
        miss = (self.psi - t @ coords) / self.shape_scale
        return float(np.sum(np.abs(miss) ** 2))


def _f_test(
    cost: float, free_cost: float, modes: int, sensors: int, parameters: int, known: bool
) -> tuple[float, tuple[int, int], float] | None:
    """F statistic, degrees of freedom and p-value of the mount model against any linear rigid-body model.

    With `known` (the shape noise was below its floor, so the floor is the noise), the
    denominator is its expectation, 1, and the p-value that of chi-square.
    """
    from scipy.stats import chi2
    from scipy.stats import f as f_dist

    numerator = 12 * modes - parameters
    denominator = 2 * modes * (sensors - 6)
    if numerator <= 0 or denominator <= 0:
        return None
    excess = max(cost - free_cost, 0.0)
    if known:
        return excess / numerator, (numerator, denominator), float(chi2.sf(excess, numerator))
    statistic = (excess / numerator) / (max(free_cost, 1e-12 * denominator) / denominator)
    return statistic, (numerator, denominator), float(f_dist.sf(statistic, numerator, denominator))


def fit_mount_model(
    positions: ArrayLike,
    directions: ArrayLike,
    poles: ArrayLike,
    shapes: ArrayLike,
    mount_positions: ArrayLike,
    mount_axes: ArrayLike | None = None,
    *,
    start: tuple[ArrayLike, ArrayLike] | None = None,
    groups: Sequence[Hashable | None] | None = None,
    noise: NoiseLevels | None = None,
) -> MountModel:
    """CG, inertia and per-mount rates fitted together to five or more rigid-body modes.

    Parameters
    ----------
    positions, directions : array_like, shape (p, 3)
        The sensors (length; unit measuring axes).
    poles : array_like of complex, shape (n,)
        Poles of the rigid-body modes used (rad/s), ``n >= 5``.
    shapes : array_like of complex, shape (p, n)
        Their shapes as the sensors read them.
    mount_positions : array_like, shape (q, 3)
        Where the mounts act (length).
    mount_axes : array_like, shape (q, 3, 3), optional
        Column ``a`` of ``mount_axes[k]``: axis ``a`` of mount ``k``; default x, y, z.
    start : (cg, inertia_per_mass), optional
        Starting point (e.g. from :func:`rigidid.core.identify.identify`); default
        the sensor centroid and an inertia from the sensors' spread.
    groups : sequence of hashable or None, optional
        A label per mount; mounts with one label are identical and share their
        rates (:func:`group_matrix`). Default: every mount independent.
    noise : NoiseLevels, optional
        Standard deviations of the measured frequencies, damping ratios and shapes
        (:class:`rigidid.core.noise.NoiseLevels`). Given, the equation-error fit is
        refined by a noise-weighted output-error fit and the F test is made;
        without, only the equation-error fit.

    Returns
    -------
    MountModel

    Raises
    ------
    InputError
        Fewer than five modes, or arrays that do not match.

    Notes
    -----
    Each measured mode, projected on rigid motion (eq. (30) of [1] in spirit) and
    moved to the trial CG, must satisfy eq. (1): ``(lambda^2 M + lambda C + K) phi = 0``
    with ``M = diag(I, J/m)`` and ``K``, ``C`` the sums of the mounts' rates. For a
    trial CG and inertia the rates enter linearly and are solved by non-negative
    least squares (variable projection); CG and the Cholesky factor of ``J / m``
    are found by ``scipy.optimize.least_squares``. Far fewer unknowns than a free
    6x6 ``K`` and ``C`` (9 + 6 per mount instead of 51), so five modes can do, and
    noise is averaged over more equations per unknown. Computed in the frame of
    :func:`rigidid.core.geometry.layout_frame`, times scaled by the RMS pole.

    With `noise`, that fit starts an output-error fit: the model's poles and its
    shapes at the sensors against the measured ones, each residual divided by its
    noise level (so every entry has unit variance), rates bounded at zero. Its
    weighted sum of squares ``S_m`` is compared with ``S_f``, the misfit of the
    best rigid motion of each mode, which is what any linear model of the six
    rigid-body degrees of freedom (a free ``M^-1 K`` and ``M^-1 C``) leaves:
    ``F = ((S_m - S_f) / d_1) / (S_f / d_2)`` with ``d_1 = 12 n - P`` (two
    pole and ten scale-free shape entries in the rigid subspace per mode, less the
    model's ``P`` unknowns) and ``d_2 = 2 n (p - 6)``. To first order in the noise
    ``F`` follows Fisher's distribution when the model is right, whatever the
    common noise scale; the ratio of the frequency and damping levels to the shape
    level must be right. A p-value below :data:`ADEQUATE_P` flags the model.
    Shape noise below :data:`SHAPE_NOISE_FLOOR` is taken as the floor, a known
    level: the misfit is then tested against it by chi-square (F with ``d_2``
    infinite), so data exact to rounding pass.
    """
    from scipy.optimize import least_squares, nnls

    from rigidid.core.geometry import layout_frame, normalise_directions, sensor_matrix
    from rigidid.core.selection import project_rigid

    pos, dirs = np.asarray(positions, dtype=float).reshape(-1, 3), normalise_directions(directions)
    lam, psi = np.asarray(poles, dtype=complex).ravel(), np.asarray(shapes, dtype=complex)
    if lam.size < 5 or psi.shape != (pos.shape[0], lam.size):
        raise InputError(f"need five or more modes with shapes (sensors, modes); got {psi.shape}", source="shapes")
    mp, u, ties = _mount_geometry(mount_positions, mount_axes, groups)
    q = mp.shape[0]
    shared = ties.shape[1]
    frame = layout_frame(pos)
    length = frame.scale
    omega = float(np.sqrt(np.mean(np.abs(lam) ** 2)))
    mu = np.asarray(lam / omega, dtype=np.complex128)
    local_pos = frame.to_local(pos)
    coords, _ = project_rigid(sensor_matrix(local_pos, dirs), psi)
    coords = coords / np.linalg.norm(coords, axis=0)
    local_mounts = frame.to_local(mp)

    def system(x: Array) -> tuple[Array, Array]:
        g, j = x[:3], _inertia(x[3:])
        mass = np.eye(6)
        mass[3:, 3:] = j
        rows, rhs = [], []
        for i in range(mu.size):
            phi = transfer_matrix(g) @ coords[:, i]
            cols = _mount_columns(phi, local_mounts - g, u) @ ties
            scale = 1.0 / (abs(mu[i]) ** 2 * np.linalg.norm(phi))
            block = np.hstack([cols, mu[i] * cols]) * scale
            target = -(mu[i] ** 2) * (mass @ phi) * scale
            rows.append(np.vstack([block.real, block.imag]))
            rhs.append(np.concatenate([target.real, target.imag]))
        return np.vstack(rows), np.concatenate(rhs)

    def rates_and_residual(x: Array) -> tuple[Array, Array]:
        a, b = system(x)
        rates, _ = nnls(a, b)
        return rates, a @ rates - b

    if start is None:
        g0, j0 = np.zeros(3), 0.3 * np.eye(3)
    else:
        g0, j0 = frame.to_local(np.asarray(start[0], dtype=float)), np.asarray(start[1], dtype=float) / length**2
    x0 = np.concatenate([g0, np.linalg.cholesky(feasible_inertia(j0))[np.tril_indices(3)]])
    sol = least_squares(lambda x: rates_and_residual(x)[1], x0, method="lm", xtol=1e-12, ftol=1e-12)
    x, (rates, resid) = sol.x, rates_and_residual(sol.x)
    f_result = cost = lin = None
    if noise is not None:
        x, rates, cost, f_result, jac = _refit_output_error(
            x, rates, (local_pos, dirs), mu, psi, noise, (local_mounts, u, ties)
        )
        a, b = system(x)
        resid = a @ rates - b
        lin = _model_spread(np.concatenate([x, rates]), jac, noise, (frame.centre, length, omega), (mp, u, ties))
    return MountModel(
        center_of_gravity=frame.centre + length * x[:3],
        inertia_per_mass=length**2 * _inertia(x[3:]),
        stiffness_per_mass=(ties @ rates[:shared]).reshape(q, 3) * omega**2,
        damping_per_mass=(ties @ rates[shared:]).reshape(q, 3) * omega,
        axes=u,
        residual=float(np.sqrt(np.mean(resid**2))),
        parameters=9 + 2 * shared,
        equations=resid.size,
        f_statistic=None if f_result is None else f_result[0],
        f_dof=None if f_result is None else f_result[1],
        p_value=None if f_result is None else f_result[2],
        cost=cost,
        linearised=lin,
        misfit_dof=0 if lin is None else 2 * psi.size - 9 - 2 * shared,
    )


def _model_estimates(z: Array, frame: tuple[Array, float, float], mounts: tuple[Array, Array, Array]) -> Estimates:
    """The mount model's figures (layout units, per mass) for parameter rows ``z`` (B, 9 + 2 s)."""
    from rigidid.core.estimator import Estimates

    centre, length, omega = frame
    mp, u, ties = mounts
    b, q, shared = z.shape[0], mp.shape[0], ties.shape[1]
    cg = centre + length * z[:, :3]
    inertia = np.stack([_inertia(row) for row in z[:, 3:9]]) * length**2
    kr = (z[:, 9 : 9 + shared] @ ties.T).reshape(b, q, 3) * omega**2
    cr = (z[:, 9 + shared :] @ ties.T).reshape(b, q, 3) * omega
    k = np.stack([_support_matrix(kr[i], mp - cg[i], u) for i in range(b)])
    c = np.stack([_support_matrix(cr[i], mp - cg[i], u) for i in range(b)])
    return Estimates(cg, inertia, k, c, np.zeros(b, dtype=np.int8))


def _model_spread(
    z: Array, jac: Array, noise: NoiseLevels, frame: tuple[Array, float, float], mounts: tuple[Array, Array, Array]
) -> Linearised:
    """The mount model's response to the noise, from the Jacobian of its noise-weighted output error.

    The residuals have unit variance, so the parameters' covariance is ``(J^T J)^+``:
    with ``J = U S V^T`` the moves ``V_i / s_i`` are independent, one standard
    deviation each. Each is taken by a small step (:data:`~rigidid.core.linearised.STEP`
    of the largest parameter) and the figures are moved by it.
    """
    from rigidid.core.linalg import rank_tolerance
    from rigidid.core.linearised import STEP, Linearised

    _, s, vt = np.linalg.svd(jac, full_matrices=False)
    keep = s > rank_tolerance(s[0], jac.shape[0])
    moves = vt[keep] / s[keep, None]
    step = STEP * max(1.0, float(np.max(np.abs(z)))) / np.max(np.abs(moves), axis=1)
    base = _model_estimates(z[None], frame, mounts)
    moved = _model_estimates(z[None] + step[:, None] * moves, frame, mounts)
    return Linearised(base, moved, 1.0 / step, noise)


_REFINE_EVALUATIONS = 100
"""Budget of the output-error refinement (iterations of ``least_squares``, each with a Jacobian of
``9 + 2 s`` more evaluations): from the equation-error fit it converges in 5-7 on noisy tests of
a model that fits (``benchmarks/verdict_regimes.py crash``); a model that cannot fit (F test
inadequate) crawled through ``100 (9 + 2 s)`` of them, minutes with four mounts."""


def _mount_geometry(
    mount_positions: ArrayLike, mount_axes: ArrayLike | None, groups: Any
) -> tuple[Array, Array, Array]:
    """Mount positions (q, 3), unit axes (q, 3, 3) as columns, and the group ties of their rates."""
    mp = np.asarray(mount_positions, dtype=float).reshape(-1, 3)
    q = mp.shape[0]
    u = np.broadcast_to(np.eye(3), (q, 3, 3)).copy() if mount_axes is None else np.asarray(mount_axes, dtype=float)
    return mp, u / np.linalg.norm(u, axis=1, keepdims=True), group_matrix(groups, q)


def _refit_output_error(
    x: Array,
    rates: Array,
    sensors: tuple[Array, Array],
    mu: NDArray[np.complex128],
    psi: NDArray[np.complex128],
    noise: Any,
    mounts: tuple[Array, Array, Array],
) -> tuple[Array, Array, float, tuple[float, tuple[int, int], float] | None, Array]:
    """The mount model refined by noise-weighted output error, its cost, the F test against the free model
    and the Jacobian of its noise-weighted residuals at the solution.

    `x` holds the CG and the inertia's Cholesky factor (local frame), `rates` the grouped mount rates
    (stiffness then damping); `mounts` is (local positions, axes, group ties).
    """
    from scipy.optimize import least_squares

    from rigidid.core.geometry import sensor_matrix

    local_mounts, u, ties = mounts
    q, shared = local_mounts.shape[0], ties.shape[1]
    output = _OutputError(sensors, mu, psi, noise)

    def build(z: Array) -> tuple[Array, Array, Array, Array]:
        g = z[:3]
        kr = (ties @ z[9 : 9 + shared]).reshape(q, 3)
        cr = (ties @ z[9 + shared :]).reshape(q, 3)
        return (
            g,
            _inertia(z[3:9]),
            _support_matrix(kr, local_mounts - g, u),
            _support_matrix(cr, local_mounts - g, u),
        )

    z0 = np.concatenate([x, rates])
    lower = np.concatenate([np.full(9, -np.inf), np.zeros(2 * shared)])
    refined = least_squares(
        lambda z: output(*build(z)), z0, bounds=(lower, np.inf), method="trf", x_scale="jac",
        max_nfev=_REFINE_EVALUATIONS,
    )  # fmt: skip
    cost = float(np.sum(output(*build(refined.x)) ** 2))
    f_result = _f_test(
        cost, output.free_cost(sensor_matrix(*sensors)), mu.size, sensors[0].shape[0], 9 + 2 * shared,
        output.floored,
    )  # fmt: skip
    return refined.x[:9], refined.x[9:], cost, f_result, np.asarray(refined.jac, dtype=float)


def split_misfit(
    stiffness: ArrayLike, covariance: ArrayLike, center_of_gravity: ArrayLike, positions: ArrayLike, axes: ArrayLike
) -> tuple[float, int]:
    """How well point mounts explain a 6x6 stiffness, in noise units: a chi-square and its degrees of freedom.

    Parameters
    ----------
    stiffness : array_like, shape (6, 6)
        ``K`` at the CG (any units, per mass allowed).
    covariance : array_like, shape (21, 21)
        Covariance of its 21 upper entries (``numpy.triu_indices(6)`` order).
    center_of_gravity : array_like, shape (3,)
        The reference point of `stiffness`.
    positions : array_like, shape (n, 3)
        Where the mounts act.
    axes : array_like, shape (n, 3, 3)
        Their principal axes (columns).

    Returns
    -------
    chi2 : float
        ``min_r (k - A r)^T C^+ (k - A r)`` over unconstrained rates ``r`` (three
        per mount, eq. (31)'s support matrices summed), ``k`` the upper entries.
    dof : int
        ``21 - rank(A)``.

    Notes
    -----
    A support missing from the list (a hose, a torque rod) or a mount placed
    wrong leaves a misfit far above its degrees of freedom; the noise alone gives
    a chi-square with `dof` degrees of freedom (linearised).
    """
    k = np.asarray(stiffness, dtype=float)
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    u = np.asarray(axes, dtype=float).reshape(-1, 3, 3)
    offsets = pos - np.asarray(center_of_gravity, dtype=float).reshape(3)
    iu = np.triu_indices(6)
    cols = []
    for m in range(pos.shape[0]):
        for a in range(3):
            unit = np.zeros((pos.shape[0], 3))
            unit[m, a] = 1.0
            cols.append(_support_matrix(unit, offsets, u)[iu])
    design = np.stack(cols, axis=1)
    cov = np.asarray(covariance, dtype=float)
    w, v = np.linalg.eigh(0.5 * (cov + cov.T))
    keep = w > rank_tolerance(max(float(w[-1]), 1e-300), w.size)
    white = (v[:, keep] / np.sqrt(w[keep])).T
    a_w, k_w = white @ design, white @ k[iu]
    rates, *_ = np.linalg.lstsq(a_w, k_w, rcond=None)
    rank = int(numerical_rank(np.linalg.svd(a_w, compute_uv=False), a_w.shape[0]))
    resid = k_w - a_w @ rates
    return float(resid @ resid), int(np.sum(keep)) - rank


def _support_matrix(rates: Array, offsets: Array, axes: Array) -> Array:
    """``sum_k T_k^T U_k diag(rates_k) U_k^T T_k`` at the reference of `offsets`."""
    out = np.zeros((6, 6))
    for r, u, k in zip(offsets, axes, rates, strict=True):
        t = transfer_matrix(r)[:3]
        out += t.T @ (u @ np.diag(k) @ u.T) @ t
    return out


def eigen_residual(
    poles: ArrayLike,
    cg_motions: ArrayLike,
    inertia_per_mass: ArrayLike,
    stiffness: ArrayLike,
    damping: ArrayLike,
    length: float = 1.0,
) -> float:
    """RMS of ``(lambda^2 M + lambda C + K) phi / (|lambda|^2 |phi|)`` over the modes, ``M = diag(I, J/m)``.

    Parameters
    ----------
    poles : array_like of complex, shape (n,)
        Measured poles (rad/s).
    cg_motions : array_like of complex, shape (6, n)
        Measured rigid motions at the CG (length, rad).
    inertia_per_mass : array_like, shape (3, 3)
    stiffness, damping : array_like, shape (6, 6)
        Per mass, at the CG.
    length : float
        Length scale (e.g. the sensors' RMS radius): translations are divided by
        it and moments by its square, so that the figure does not depend on units.

    Returns
    -------
    float
        0 when the model reproduces every mode exactly (how well a model explains
        the modes, comparable between the mount model and a free 6x6 ``K``).
    """
    lam = np.asarray(poles, dtype=complex).ravel()
    phi = np.asarray(cg_motions, dtype=complex)
    mass = np.eye(6)
    mass[3:, 3:] = np.asarray(inertia_per_mass, dtype=float)
    k, c = np.asarray(stiffness, dtype=float), np.asarray(damping, dtype=float)
    rows = np.array([1.0, 1.0, 1.0, 1.0 / length, 1.0 / length, 1.0 / length]) / length
    motion = np.array([1.0, 1.0, 1.0, length, length, length]) / length
    r = []
    for i in range(lam.size):
        force = (lam[i] ** 2 * mass + lam[i] * c + k) @ phi[:, i]
        r.append(rows * force / (abs(lam[i]) ** 2 * np.linalg.norm(motion * phi[:, i])))
    stacked = np.concatenate([np.concatenate([x.real, x.imag]) for x in r])
    return float(np.sqrt(np.mean(stacked**2)))


def identify_mount_model(
    positions: ArrayLike,
    directions: ArrayLike,
    poles: ArrayLike,
    shapes: ArrayLike,
    mount_positions: ArrayLike,
    mount_axes: ArrayLike | None = None,
    *,
    mass: float | None = None,
    start: tuple[ArrayLike, ArrayLike] | None = None,
    groups: Sequence[Hashable | None] | None = None,
    noise: NoiseLevels | None = None,
) -> tuple[Identification, MountModel]:
    """The mount model as an :class:`~rigidid.core.identify.Identification` (method ``"mounts"``).

    Parameters
    ----------
    positions, directions, poles, shapes, mount_positions, mount_axes, start, groups, noise
        As :func:`fit_mount_model`.
    mass : float, optional
        The mass, for absolute results.

    Returns
    -------
    identification : Identification
        ``K`` and ``C`` built from the fitted rates (symmetric positive semi-definite
        by construction), ``J / m`` positive definite, and the diagnostics of the
        free route (layout, rigid fit, model modes against the measured ones).
    model : MountModel
        The rates and the fit's residual and parameter count.
    """
    from rigidid.core import estimator
    from rigidid.core.geometry import layout_condition, layout_frame, normalise_directions, sensor_matrix
    from rigidid.core.identify import (
        FitDiagnostics,
        Identification,
        inertia_observability,
        match_modes,
        model_modes,
    )
    from rigidid.core.selection import project_rigid
    from rigidid.core.statespace import modal_from_poles

    model = fit_mount_model(
        positions, directions, poles, shapes, mount_positions, mount_axes, start=start, groups=groups, noise=noise
    )
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    dirs = normalise_directions(directions)
    lam = np.asarray(poles, dtype=complex).ravel()
    psi = np.asarray(shapes, dtype=complex)
    g = model.center_of_gravity
    offsets = np.asarray(mount_positions, dtype=float).reshape(-1, 3) - g
    k = _support_matrix(model.stiffness_per_mass, offsets, model.axes)
    c = _support_matrix(model.damping_per_mass, offsets, model.axes)
    j = model.inertia_per_mass
    cond, rank = layout_condition(pos, dirs)
    frame = layout_frame(pos)
    phi, fit = project_rigid(sensor_matrix(frame.to_local(pos), dirs), psi)
    length = frame.scale
    omega = float(np.sqrt(np.mean(np.abs(lam) ** 2)))
    dof = np.array([1.0, 1.0, 1.0, length, length, length])
    d = np.eye(6)
    d[3:, 3:] = j / length**2
    q_g = np.asarray(np.linalg.solve(d, k / np.outer(dof, dof) / omega**2), dtype=np.float64)
    g_local = frame.to_local(g)
    q_o = estimator.at_cg(q_g[None], -g_local[None])[0]
    observability = inertia_observability(q_o, g_local)
    model_poles, model_phi = model_modes(j, k, c)
    matched, mac = match_modes(psi, model_poles, sensor_matrix(pos, dirs, g) @ model_phi)
    model_f, model_z = modal_from_poles(matched)
    f, z = modal_from_poles(lam)
    shapes_cg = transfer_matrix(g_local) @ phi * np.array([length, length, length, 1.0, 1.0, 1.0])[:, None]
    ident = Identification(
        center_of_gravity=g,
        inertia_per_mass=j,
        stiffness_per_mass=k,
        damping_per_mass=c,
        mass=None if mass is None else float(mass),
        frequency_hz=f,
        damping_ratio=z,
        mode_shapes_cg=shapes_cg / np.linalg.norm(shapes_cg, axis=0),
        method="mounts",
        diagnostics=FitDiagnostics(
            layout_condition=cond,
            layout_rank=rank,
            rigid_fit_residual=fit,
            structure_residual=0.0,
            inertia_observability=observability,
            model_frequency_hz=model_f,
            model_damping_ratio=model_z,
            model_mac=mac,
        ),
    )
    return ident, model


@dataclass(frozen=True)
class MountModelPrediction:
    """Predicted precision of the mount model for a body, a layout and mounts (:func:`predict_mount_model`).

    Attributes
    ----------
    center_of_gravity_std : ndarray, shape (3,)
        Standard deviation of the CG coordinates over the draws (length).
    inertia_std : ndarray, shape (3, 3)
        Standard deviation of each inertia tensor entry (mass length^2).
    flagged : float
        Share of the draws the F test flags (about :data:`ADEQUATE_P` when the
        mounts describe the body's supports); for the first-order prediction
        (:func:`predict_mount_model_linearised`) the expected share.
    draws : int
        Draws made; 0 for the first-order prediction.
    """

    center_of_gravity_std: Array
    inertia_std: Array
    flagged: float
    draws: int


def predict_mount_model(
    body: Body,
    positions: ArrayLike,
    directions: ArrayLike,
    mount_positions: ArrayLike,
    mount_axes: ArrayLike | None = None,
    *,
    groups: Sequence[Hashable | None] | None = None,
    noise: NoiseLevels,
    draws: int = 50,
    seed: int | None = 0,
    modes: int = 6,
) -> MountModelPrediction:
    """Monte Carlo precision of the mount model: simulated noisy modes of `body`, fitted by :func:`fit_mount_model`.

    Parameters
    ----------
    body : Body
        The body estimate (:class:`rigidid.core.simulate.Body`), its own mounts the truth.
    positions, directions : array_like, shape (p, 3)
        The sensors.
    mount_positions, mount_axes, groups
        The mounts the model assumes (as :func:`fit_mount_model`).
    noise : NoiseLevels
        Frequency, damping and shape noise of each draw, also the fit's weights.
    draws : int
        Number of noisy tests (each about 0.1 s).
    seed : int, optional
        Seed of the noise.
    modes : int
        Modes used per draw (5 or 6: the five lowest when 5).

    Returns
    -------
    MountModelPrediction

    Raises
    ------
    InputError
        Fewer than two draws, or `modes` not 5 or 6.
    """
    from rigidid.core.simulate import add_noise, body_modes

    if draws < 2 or modes not in (5, 6):
        raise InputError(f"need draws >= 2 and modes 5 or 6, got {draws} and {modes}", source="draws")
    exact = body_modes(body, positions, directions)
    rng = np.random.default_rng(seed)
    cgs, inertias, flagged = [], [], 0
    for _ in range(draws):
        test = add_noise(exact, frequency=noise.frequency, damping=noise.damping, shape=noise.shape, rng=rng)
        fit = fit_mount_model(
            positions, directions, test.poles[:modes], test.shapes[:, :modes], mount_positions, mount_axes,
            groups=groups, noise=noise,
        )  # fmt: skip
        cgs.append(fit.center_of_gravity)
        inertias.append(body.mass * fit.inertia_per_mass)
        flagged += fit.adequate is False
    return MountModelPrediction(
        center_of_gravity_std=np.std(cgs, axis=0, ddof=1),
        inertia_std=np.std(inertias, axis=0, ddof=1),
        flagged=flagged / draws,
        draws=draws,
    )


def predict_mount_model_linearised(
    body: Body,
    positions: ArrayLike,
    directions: ArrayLike,
    mount_positions: ArrayLike,
    mount_axes: ArrayLike | None = None,
    *,
    groups: Sequence[Hashable | None] | None = None,
    noise: NoiseLevels,
    modes: int = 6,
) -> MountModelPrediction:
    """First-order precision of the mount model: one fit of the exact modes of `body`, its Cramer-Rao spread.

    Parameters
    ----------
    body : Body
        The body estimate (:class:`rigidid.core.simulate.Body`), its own mounts the truth.
    positions, directions : array_like, shape (p, 3)
        The sensors.
    mount_positions, mount_axes, groups
        The mounts the model assumes (as :func:`fit_mount_model`).
    noise : NoiseLevels
        Frequency, damping and shape noise to expect (the fit's weights).
    modes : int
        Modes used (5 or 6: the five lowest when 5).

    Returns
    -------
    MountModelPrediction
        ``draws`` 0; ``flagged`` the probability that the F test flags a noisy test.

    Raises
    ------
    InputError
        `modes` not 5 or 6.

    Notes
    -----
    The exact modes of the body as the layout reads them are fitted once with the
    noise-weighted output error of :func:`fit_mount_model`; its residuals have unit
    variance, so the parameters' covariance is ``(J^T J)^+`` (the Cramer-Rao bound of
    the output-error fit, the delta method of :attr:`MountModel.linearised`), carried
    to the CG and ``J``. This is what :func:`predict_mount_model` estimates from
    noisy refits, to first order in the noise and without their Monte Carlo error
    (``1 / sqrt(2 (draws - 1))`` relative, 10 % with 50 draws); a rate at its bound
    of zero is where the two may part. The weighted cost of the exact fit is the
    non-centrality of the F test's numerator (zero when the mounts describe the
    body's supports), so the share flagged is that of a non-central F (chi-square
    when the shape noise is below :data:`SHAPE_NOISE_FLOOR`) beyond the critical
    value at :data:`ADEQUATE_P`. Without frequency, damping and shape noise every
    test is the exact one: no spread, none flagged.
    """
    from rigidid.core.simulate import body_modes

    if modes not in (5, 6):
        raise InputError(f"need modes 5 or 6, got {modes}", source="modes")
    if not (noise.frequency or noise.damping or noise.shape):  # every test is the exact one, which passes
        return MountModelPrediction(np.zeros(3), np.zeros((3, 3)), 0.0, 0)
    exact = body_modes(body, positions, directions)
    fit = fit_mount_model(
        positions, directions, exact.poles[:modes], exact.shapes[:, :modes], mount_positions, mount_axes,
        groups=groups, noise=noise,
    )  # fmt: skip
    assert fit.linearised is not None
    lin = fit.linearised
    return MountModelPrediction(
        center_of_gravity_std=lin.std(lambda e: e.center_of_gravity),
        inertia_std=body.mass * lin.std(lambda e: e.inertia_per_mass),
        flagged=_flagged_share(fit, noise.shape < SHAPE_NOISE_FLOOR),
        draws=0,
    )


def _flagged_share(fit: MountModel, known: bool) -> float:
    """Probability that the F test of a noisy test flags the model, the exact fit's cost its non-centrality."""
    from scipy.stats import chi2, ncf, ncx2
    from scipy.stats import f as f_dist

    if fit.f_dof is None or fit.cost is None:
        return 0.0
    d1, d2 = fit.f_dof
    nc = max(float(fit.cost), 0.0)
    if known:
        critical = float(chi2.isf(ADEQUATE_P, d1))
        return float(ncx2.sf(critical, d1, nc)) if nc > 0.0 else ADEQUATE_P
    critical = float(f_dist.isf(ADEQUATE_P, d1, d2))
    return float(ncf.sf(critical, d1, d2, nc)) if nc > 0.0 else ADEQUATE_P
