"""Linearised (delta-method) standard errors of the identification kernel, and its noise weights.

The kernel (:func:`rigidid.core.estimator.estimate`) is a smooth function of the
measured data near a good estimate. Its first-order response to each
independent source of measurement noise is found by forward differences: the
data are moved by a small relative step along each noise direction and
identified again, all in one batch. The standard error of
any figure derived from the estimate (CG, inertia, principal moments and axes,
``K``, ``C``, per-mount rates, a torque roll axis) is then the root sum of
squares of its responses: ``cov = D D^T`` with ``D`` the responses per unit
standard deviation. This costs one batch of ``12 + 72`` identifications,
whatever the number of sensors, against the thousand of a Monte Carlo run.

Noise directions (independent, unit standard deviation each):

- per mode, its natural frequency (relative level ``frequency``) and damping
  ratio (relative level ``damping``);
- per mode, the shape noise seen by the rigid-body fit: complex noise of
  relative level ``shape`` on every sensor reaches the least-squares rigid-body
  coordinates only through the six-dimensional column space of the sensor
  matrix ``T`` (eq. (3) of [1]); with ``T = U S V^T`` the components of the noise
  along the columns of ``U`` are independent with the per-entry level, so the
  twelve directions ``U e_i`` and ``1j U e_i`` carry all of it (the rest is the
  rigid-body fit residual, which the estimator ignores);
- when stated, each coordinate of each sensor position and each component of
  each direction's tilt.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from rigidid.core.estimator import DAMPING_WEIGHT, Estimates, estimate
from rigidid.core.linalg import pseudo_inverse
from rigidid.core.noise import NoiseLevels, tilt_directions
from rigidid.core.statespace import modal_from_poles

__all__ = [
    "ACCEPTABLE_MISFIT",
    "STEP",
    "Linearised",
    "StandardErrors",
    "misfit_parts",
    "noise_directions",
    "principal_axis_deviation",
    "residual_weights",
    "spread",
    "standard_errors",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

STEP = 1e-5
"""Central-difference step: the relative move of each quantity (frequency, damping ratio, a
mode's RMS reading, the layout's RMS radius; radians for tilts), whatever its noise level, so
that derivatives stay exact to rounding when a level is tiny (exact data) or large."""


@dataclass(frozen=True)
class Directions:
    """The data moved by ``+step`` and ``-step`` along each noise direction.

    Attributes
    ----------
    positions, directions : ndarray, shape (k or 2 k, p, 3)
    poles : ndarray of complex, shape (k or 2 k, 6)
    shapes : ndarray of complex, shape (k or 2 k, p, 6)
        Rows ``0..k-1`` moved forwards, then (central differences) ``k..2k-1`` backwards.
    sigma : ndarray, shape (k,)
        Standard deviation of each direction's noise in units of its move.
    central : bool
        Whether the backward moves are there.
    """

    positions: Array
    directions: Array
    poles: CArray
    shapes: CArray
    sigma: Array
    central: bool = False


def _poles_from(f: Array, z: Array) -> CArray:
    w = 2.0 * np.pi * f
    result: CArray = w * (-z + 1j * np.sqrt(1.0 - z * z))
    return result


def _shape_moves(positions: Array, directions: Array, shapes: CArray, step: float) -> CArray:
    """Shape moves (12 per mode, 72 in all) along the rigid-body part of the shape noise: (72, p, 6).

    Each moves one mode by `step` of its RMS reading along ``U e_i`` or ``1j U e_i``.
    """
    from rigidid.core.geometry import local_sensor_matrix

    u = np.linalg.svd(local_sensor_matrix(positions, directions), full_matrices=False)[0]  # (p, 6)
    rms = np.sqrt(np.mean(np.abs(shapes) ** 2, axis=0))  # (6,)
    p = positions.shape[0]
    moves = np.zeros((72, p, 6), dtype=complex)
    row = 0
    for k in range(6):
        for part in (1.0, 1j):
            for i in range(6):
                moves[row, :, k] = part * u[:, i] * step * rms[k]
                row += 1
    return moves


def noise_directions(
    positions: Array,
    directions: Array,
    poles: CArray,
    shapes: CArray,
    noise: NoiseLevels,
    *,
    step: float = STEP,
    central: bool = False,
) -> Directions:
    """The test's data moved along every noise direction of `noise`, by ``+-step`` (relative).

    Parameters
    ----------
    positions, directions : ndarray, shape (p, 3)
        Sensor locations (length) and unit measuring axes.
    poles : ndarray of complex, shape (6,)
        Poles of the six rigid-body modes (rad/s).
    shapes : ndarray of complex, shape (p, 6)
        Mode shapes as the sensors read them.
    noise : NoiseLevels
        Standard deviations; sources at zero get no direction.
    step : float
        Relative size of the moves.
    central : bool
        Also the backward moves (central differences; forward differences
        otherwise, exact to about `step` relative, half the cost).

    Returns
    -------
    Directions
    """
    p = positions.shape[0]
    f, z = modal_from_poles(poles)
    radius = float(np.sqrt(np.mean(np.sum((positions - positions.mean(axis=0)) ** 2, axis=1))))
    moves_lam: list[CArray] = []
    moves_psi: list[CArray] = []
    moves_pos: list[Array] = []
    moves_dir: list[Array] = []
    sigma: list[float] = []

    def add(
        level: float,
        lam: CArray | None = None,
        psi: CArray | None = None,
        pos: Array | None = None,
        dirs: Array | None = None,
    ) -> None:
        sigma.append(level / step)
        moves_lam.append(np.zeros((1, 6), dtype=complex) if lam is None else lam[None] - poles[None])
        moves_psi.append(np.zeros((1, p, 6), dtype=complex) if psi is None else psi[None])
        moves_pos.append(np.zeros((1, p, 3)) if pos is None else pos[None])
        moves_dir.append(np.zeros((1, p, 3)) if dirs is None else dirs[None] - directions[None])

    for k in range(6):
        unit = np.eye(6)[k]
        if noise.frequency > 0.0:
            add(noise.frequency, lam=_poles_from(f * (1.0 + step * unit), z))
        if noise.damping > 0.0 and z[k] > 0.0:
            add(noise.damping, lam=_poles_from(f, np.clip(z * (1.0 + step * unit), 0.0, 0.999)))
    if noise.shape > 0.0:
        # real and imaginary parts each carry shape / sqrt(2) of the RMS reading
        for move in _shape_moves(positions, directions, shapes, step):
            add(noise.shape / np.sqrt(2.0), psi=move)
    if noise.position > 0.0:
        for i in range(p * 3):
            add(noise.position / radius, pos=(step * radius * np.eye(p * 3)[i]).reshape(p, 3))
    if noise.angle_deg > 0.0:
        for i in range(p * 3):
            add(np.deg2rad(noise.angle_deg), dirs=tilt_directions(directions, (step * np.eye(p * 3)[i]).reshape(p, 3)))
    d_lam, d_psi = np.concatenate(moves_lam), np.concatenate(moves_psi)
    d_pos, d_dir = np.concatenate(moves_pos), np.concatenate(moves_dir)
    signs = (1.0, -1.0) if central else (1.0,)
    return Directions(
        positions=np.concatenate([positions + s * d_pos for s in signs]),
        directions=np.concatenate([directions + s * d_dir for s in signs]),
        poles=np.concatenate([poles + s * d_lam for s in signs]),
        shapes=np.concatenate([shapes + s * d_psi for s in signs]),
        sigma=np.asarray(sigma, dtype=float),
        central=central,
    )


@dataclass(frozen=True)
class Linearised:
    """The kernel's estimates at the data moved along each noise direction (see :func:`spread`).

    Attributes
    ----------
    base : Estimates
        The estimate from the data as measured (a batch of one).
    moved : Estimates
        ``k`` estimates moved forwards (then ``k`` backwards with central differences).
    sigma : ndarray, shape (k,)
        Standard deviation of each direction's noise in units of its move.
    noise : NoiseLevels
        The levels the moves were scaled by.
    """

    base: Estimates
    moved: Estimates
    sigma: Array
    noise: NoiseLevels

    @property
    def failed(self) -> int:
        """Moved estimates the kernel could not identify (their responses are left out)."""
        return int(np.sum(~self.moved.ok))

    def responses(self, figure: Callable[[Estimates], Array]) -> Array:
        """Response ``D`` (k, ...) of a figure to one standard deviation of each noise source.

        Parameters
        ----------
        figure : callable
            Maps an :class:`~rigidid.core.estimator.Estimates` of ``B`` tests to
            an array ``(B, ...)``; called once on the moved estimates.
        """
        values = np.asarray(figure(self.moved), dtype=float)
        k = self.sigma.shape[0]
        shape = (-1, *([1] * (values.ndim - 1)))
        if values.shape[0] == 2 * k:  # central differences
            d: Array = (values[:k] - values[k:]) * (self.sigma / 2.0).reshape(shape)
            ok = self.moved.ok[:k] & self.moved.ok[k:]
        else:
            d = (values - np.asarray(figure(self.base), dtype=float)) * self.sigma.reshape(shape)
            ok = self.moved.ok
        d[~ok] = 0.0
        return d

    def std(self, figure: Callable[[Estimates], Array]) -> Array:
        """Linearised standard error of a figure (its shape without the batch axis)."""
        d = self.responses(figure)
        result: Array = np.sqrt(np.sum(d * d, axis=0))
        return result

    def covariance(self, figure: Callable[[Estimates], Array]) -> Array:
        """Linearised covariance ``D^T D`` of a flattened figure: (n, n)."""
        d = self.responses(figure)
        flat = d.reshape(d.shape[0], -1)
        result: Array = flat.T @ flat
        return result


def spread(
    positions: Array,
    directions: Array,
    poles: CArray,
    shapes: CArray,
    noise: NoiseLevels,
    *,
    damping_weight: float = DAMPING_WEIGHT,
    weights: Array | None = None,
    step: float = STEP,
    start: Array | None = None,
) -> Linearised:
    """The kernel's first-order response to each source of measurement noise.

    Parameters
    ----------
    positions, directions : ndarray, shape (p, 3)
        Sensor locations (length) and unit measuring axes.
    poles : ndarray of complex, shape (6,)
        Poles of the six rigid-body modes (rad/s).
    shapes : ndarray of complex, shape (p, 6)
        Mode shapes as the sensors read them.
    noise : NoiseLevels
        Standard deviations of the measurement errors.
    damping_weight : float
        As in :func:`rigidid.core.estimator.estimate` (unweighted kernel).
    weights : ndarray, optional
        The kernel's residual whitening (:func:`rigidid.core.estimator.residual_weights`),
        held fixed at the estimate's: its own dependence on the data moves the
        estimate only to second order.
    step : float
        Relative central-difference step (:data:`STEP`).
    start : ndarray, shape (3,), optional
        The estimate's CG (length): every moved test starts there (faster, and
        the same local solution).

    Returns
    -------
    Linearised

    Notes
    -----
    The delta method: ``cov(theta) = D D^T`` with ``D`` the derivative of the
    estimator along the noise directions scaled by their standard deviations
    (:func:`noise_directions`). Right when the noise is small enough for the
    estimator to be linear over its spread and the levels are right; the
    misfit of eq. (18) of [1] in noise units tests the second.
    """
    moved = noise_directions(positions, directions, poles, shapes, noise, step=step)
    batch = np.concatenate
    all_est = estimate(
        batch([positions[None], moved.positions]),
        batch([directions[None], moved.directions]),
        batch([poles[None], moved.poles]),
        batch([shapes[None], moved.shapes]),
        damping_weight=damping_weight,
        weights=weights,
        start=start,
    )
    names = ("center_of_gravity", "inertia_per_mass", "stiffness_per_mass", "damping_per_mass", "status")
    base = Estimates(*(getattr(all_est, n)[:1] for n in names))
    rest = Estimates(*(getattr(all_est, n)[1:] for n in names))
    return Linearised(base, rest, moved.sigma, noise)


def principal_axis_deviation(reference: Array) -> Callable[[Estimates], Array]:
    """A figure for :meth:`Linearised.std`: how far each principal axis turns from `reference` (rad).

    Parameters
    ----------
    reference : ndarray, shape (3, 3)
        Unit principal axes of the estimate, column ``i`` for moment ``i``
        (ascending).

    Returns
    -------
    callable
        Estimates -> (B, 3, 3): per axis ``i`` (second index), the rotation
        that carries reference axis ``i`` to the estimate's axis ``i`` (sign
        matched), as a small rotation vector ``a_i x b_i``; its norm is the
        angle. The standard error of its components combines to the axis'
        angular standard error.
    """

    def figure(est: Estimates) -> Array:
        j = 0.5 * (est.inertia_per_mass + np.swapaxes(est.inertia_per_mass, 1, 2))
        out = np.zeros((j.shape[0], 3, 3))
        ok = np.all(np.isfinite(j), axis=(1, 2))
        _, v = np.linalg.eigh(np.where(ok[:, None, None], j, np.eye(3)))
        sign = np.sign(np.einsum("bki,ki->bi", v, reference))
        v = v * np.where(sign == 0.0, 1.0, sign)[:, None, :]
        out[ok] = np.cross(np.broadcast_to(reference.T, (j.shape[0], 3, 3)), np.swapaxes(v, 1, 2))[ok]
        return out

    return figure


def residual_weights(
    positions: Array,
    directions: Array,
    poles: CArray,
    shapes: CArray,
    noise: NoiseLevels,
    cg: Array,
    inertia_params: Array,
) -> Array | None:
    """Whitening ``L`` (30, 30) of the kernel's eq. (18) residuals under the measurement noise.

    Parameters
    ----------
    positions, directions : ndarray, shape (p, 3)
        Sensor locations (length) and unit measuring axes.
    poles : ndarray of complex, shape (6,)
        Poles of the six rigid-body modes (rad/s).
    shapes : ndarray of complex, shape (p, 6)
        Mode shapes as the sensors read them.
    noise : NoiseLevels
        Frequency, damping and shape levels (geometry errors are not weighted).
    cg : ndarray, shape (3,)
        Current CG in the kernel's dimensionless frame (:func:`rigidid.core.estimator.prepare`).
    inertia_params : ndarray, shape (6,)
        Current ``J / m`` in that frame, as ``xx, yy, zz, xy, xz, yz``.

    Returns
    -------
    ndarray, shape (30, 30), or None
        ``L`` with ``L Sigma L^T = I`` for ``Sigma`` the linearised covariance
        of the 30 residuals of :func:`rigidid.core.estimator.eq18_residuals`
        at (`cg`, `inertia_params`) (eigenvalues floored at ``1e-10`` of the
        largest); None when the noise is zero or the data cannot be prepared.

    Notes
    -----
    At a fixed CG and ``J / m`` the residuals are linear in ``Q`` and ``P``
    (eq. (19) of [1]); their response to each noise direction
    (:func:`noise_directions`) follows from the responses of ``Q`` and ``P``,
    found by forward differences through
    :func:`rigidid.core.estimator.prepare`. Minimising ``|L r|^2`` over the CG
    and ``J / m`` is then the first-order maximum-likelihood fit of the free
    model (CG, ``J``, symmetric ``K`` and ``C``) to the measured poles and
    rigid-body coordinates: the symmetric parts of ``D Q_g`` and ``D P_g`` are
    free, the antisymmetric parts are the constraints, weighted by their
    covariance (a Sampson-type approximation), and ``|L r|^2`` is chi-square
    with ``30 - 9 = 21`` degrees of freedom when the model and the noise levels
    are right.
    """
    d = _residual_responses(positions, directions, poles, shapes, noise, cg, inertia_params)
    if d is None:
        return None
    ev, vec = np.linalg.eigh(d.T @ d)
    ev = np.maximum(ev, 1e-10 * max(float(ev[-1]), 1e-300))
    result: Array = (vec / np.sqrt(ev)).T
    return result


def _residual_responses(
    positions: Array,
    directions: Array,
    poles: CArray,
    shapes: CArray,
    noise: NoiseLevels,
    cg: Array,
    inertia_params: Array,
) -> Array | None:
    """Response (k, 30) of the eq. (18) residuals at a fixed CG and ``J / m`` to each noise direction."""
    from rigidid.core.estimator import eq18_residuals, prepare

    levels = NoiseLevels(frequency=noise.frequency, damping=noise.damping, shape=noise.shape)
    if levels.is_zero:
        return None
    moved = noise_directions(positions, directions, poles, shapes, levels)
    prep = prepare(
        np.broadcast_to(positions, (moved.poles.shape[0] + 1, *positions.shape)),
        np.broadcast_to(directions, (moved.poles.shape[0] + 1, *directions.shape)),
        np.concatenate([poles[None], moved.poles]),
        np.concatenate([shapes[None], moved.shapes]),
    )
    if not np.all(prep.ok):
        return None
    ratio = prep.omega[1:] / prep.omega[0]
    q = prep.stiffness[1:] * (ratio**2)[:, None, None]
    p = prep.damping[1:] * ratio[:, None, None]
    sigma = moved.sigma[:, None, None]
    k = sigma.shape[0]
    dq, dp = (q - prep.stiffness[:1]) * sigma, (p - prep.damping[:1]) * sigma
    result: Array = eq18_residuals(dq, dp, np.broadcast_to(cg, (k, 3)), np.broadcast_to(inertia_params, (k, 6)))
    return result


def misfit_parts(
    positions: Array,
    directions: Array,
    poles: CArray,
    shapes: CArray,
    noise: NoiseLevels,
    center_of_gravity: Array,
    inertia_per_mass: Array,
) -> tuple[float, float] | None:
    """Misfit of the stiffness and of the damping equations of eq. (18) of [1], each in noise units.

    Parameters
    ----------
    positions, directions : ndarray, shape (p, 3)
        Sensor locations (length) and unit measuring axes.
    poles : ndarray of complex, shape (6,)
        Poles of the six rigid-body modes (rad/s).
    shapes : ndarray of complex, shape (p, 6)
        Mode shapes as the sensors read them.
    noise : NoiseLevels
        Frequency, damping and shape levels.
    center_of_gravity : ndarray, shape (3,)
        The estimate's CG (length, the layout's axes).
    inertia_per_mass : ndarray, shape (3, 3)
        The estimate's ``J / m`` (length^2).

    Returns
    -------
    (float, float) or None
        ``r_Q^T Sigma_Q^+ r_Q`` and ``r_P^T Sigma_P^+ r_P``: chi-square-like
        (15 equations each) misfits of the stiffness and damping equations at
        the estimate, each against its own noise covariance; None when the
        noise is zero. The larger one says which part of the data the rigid
        model misses.
    """
    from rigidid.core.estimator import eq18_residuals, prepare

    prep = prepare(positions[None], directions[None], poles[None], shapes[None])
    if not prep.ok[0]:
        return None
    scale = float(prep.scale[0])
    g = (np.asarray(center_of_gravity, dtype=float) - prep.centre[0]) / scale
    j = np.asarray(inertia_per_mass, dtype=float) / scale**2
    params = np.array([j[0, 0], j[1, 1], j[2, 2], j[0, 1], j[0, 2], j[1, 2]])
    d = _residual_responses(positions, directions, poles, shapes, noise, g, params)
    if d is None:
        return None
    r = eq18_residuals(prep.stiffness, prep.damping, g[None], params[None])[0]
    parts = []
    for block in (slice(0, 15), slice(15, 30)):
        cov = d[:, block].T @ d[:, block]
        parts.append(float(r[block] @ pseudo_inverse(cov, symmetric=True)[0] @ r[block]))
    return parts[0], parts[1]


ACCEPTABLE_MISFIT = 4.0
"""Misfit per degree of freedom above which the noise weights are not trusted: the
unweighted (fixed-weight) estimate is reported, with standard errors scaled up."""


@dataclass(frozen=True)
class StandardErrors:
    """Linearised standard errors of an identification, in the units of its figures.

    Attributes
    ----------
    center_of_gravity : ndarray, shape (3,)
        Length.
    inertia : ndarray, shape (3, 3)
        Of the inertia tensor (mass length^2), or of ``J / m`` (length^2) when `per_mass`.
    principal_moments : ndarray, shape (3,)
        Ascending, as `inertia`.
    principal_axes_deg : ndarray, shape (3,)
        Angular standard error of each principal axis (degrees).
    stiffness, damping : ndarray, shape (6, 6)
        Of ``K`` and ``C`` at the CG (or per mass).
    per_mass : bool
        True without a mass.
    noise : NoiseLevels
        The levels propagated.
    misfit : float or None
        Chi-square misfit of eq. (18) in noise units (``None``: not computed).
    misfit_dof : int
        Its degrees of freedom.
    inflation : float
        ``sqrt(max(1, misfit / misfit_dof))``: every standard error is scaled by it,
        so that a misfit above the noise widens the intervals instead of hiding.
    weighted : bool
        Whether the estimate is the noise-weighted one.
    failed : int
        Moved estimates that failed (their responses count as zero).
    linearised : Linearised
        The responses, for the standard error of any other figure (:meth:`std`).
    mass : float or None
        The mass the absolute figures were scaled by.
    """

    center_of_gravity: Array
    inertia: Array
    principal_moments: Array
    principal_axes_deg: Array
    stiffness: Array
    damping: Array
    per_mass: bool
    noise: NoiseLevels
    misfit: float | None
    misfit_dof: int
    inflation: float
    weighted: bool
    failed: int
    linearised: Linearised
    mass: float | None

    def std(self, figure: Callable[[Estimates], Array], value: Array | None = None) -> Array:
        """Standard error of a figure of per-mass estimates, inflated, and scaled by the mass when known.

        Parameters
        ----------
        figure : callable
            As :meth:`Linearised.std`; per-mass quantities (rates per mass, ...).
        value : ndarray, optional
            The figure's per-mass value at the estimate: with a mass, the mass
            noise adds ``value * mass * noise.mass`` in quadrature and the result
            is in absolute units. Without `value`, the figure is taken as
            mass-free (lengths, angles).
        """
        sd = self.inflation * self.linearised.std(figure)
        if value is None or self.mass is None:
            return sd
        result: Array = np.sqrt((self.mass * sd) ** 2 + (np.asarray(value) * self.mass * self.noise.mass) ** 2)
        return result


def _moments(est: Estimates) -> Array:
    j = 0.5 * (est.inertia_per_mass + np.swapaxes(est.inertia_per_mass, 1, 2))
    ok = np.all(np.isfinite(j), axis=(1, 2))
    out = np.full((j.shape[0], 3), np.nan)
    out[ok] = np.linalg.eigvalsh(j[ok])
    return out


def standard_errors(
    positions: Array,
    directions: Array,
    poles: CArray,
    shapes: CArray,
    *,
    inertia_per_mass: Array,
    mass: float | None,
    noise: NoiseLevels,
    weights: Array | None,
    misfit: float | None,
    misfit_dof: int = 21,
    damping_weight: float = DAMPING_WEIGHT,
    center_of_gravity: Array | None = None,
) -> StandardErrors:
    """Linearised standard errors of the kernel's estimate (see :func:`spread`).

    Parameters
    ----------
    positions, directions : ndarray, shape (p, 3)
        Sensor locations (length) and unit measuring axes.
    poles : ndarray of complex, shape (6,)
        Poles of the six rigid-body modes (rad/s).
    shapes : ndarray of complex, shape (p, 6)
        Mode shapes as the sensors read them.
    inertia_per_mass : ndarray, shape (3, 3)
        The estimate's ``J / m`` (for the principal axes).
    mass : float or None
        Mass; None for per-mass standard errors.
    noise : NoiseLevels
        Standard deviations of the measurement errors.
    weights : ndarray, shape (30, 30), or None
        The whitening the estimate was computed with (None: fixed weights).
    misfit : float or None
        Chi-square misfit of the noise-weighted fit, for the inflation.
    misfit_dof : int
        Its degrees of freedom.
    damping_weight : float
        The fixed weight, when `weights` is None.
    center_of_gravity : ndarray, shape (3,), optional
        The estimate's CG, where the moved estimates start (:func:`spread`).

    Returns
    -------
    StandardErrors
    """
    lin = spread(
        positions, directions, poles, shapes, noise, damping_weight=damping_weight, weights=weights,
        start=center_of_gravity,
    )  # fmt: skip
    inflation = 1.0 if misfit is None or misfit_dof <= 0 else float(np.sqrt(max(1.0, misfit / misfit_dof)))
    axes = np.linalg.eigh(0.5 * (inertia_per_mass + inertia_per_mass.T))[1]
    turn = lin.std(principal_axis_deviation(axes))  # (3 axes, 3 components)
    base = lin.base
    out = StandardErrors(
        center_of_gravity=np.zeros(3),
        inertia=np.zeros((3, 3)),
        principal_moments=np.zeros(3),
        principal_axes_deg=np.rad2deg(inflation * np.sqrt(np.sum(turn**2, axis=1))),
        stiffness=np.zeros((6, 6)),
        damping=np.zeros((6, 6)),
        per_mass=mass is None,
        noise=noise,
        misfit=misfit,
        misfit_dof=misfit_dof if misfit is not None else 0,
        inflation=inflation,
        weighted=weights is not None,
        failed=lin.failed,
        linearised=lin,
        mass=mass,
    )
    figures = {
        "inertia": (lambda e: e.inertia_per_mass, base.inertia_per_mass[0]),
        "principal_moments": (_moments, _moments(base)[0]),
        "stiffness": (lambda e: e.stiffness_per_mass, base.stiffness_per_mass[0]),
        "damping": (lambda e: e.damping_per_mass, base.damping_per_mass[0]),
    }
    values = {name: out.std(fn, value) for name, (fn, value) in figures.items()}
    return replace(
        out,
        center_of_gravity=out.std(lambda e: e.center_of_gravity),
        inertia=values["inertia"],
        principal_moments=values["principal_moments"],
        stiffness=values["stiffness"],
        damping=values["damping"],
    )
