"""Linearised (delta-method) standard errors of the identification kernel, and its noise weights.

The kernel (:func:`rigidid.core.estimator.estimate`) is a smooth function of the
measured data near a good estimate. Its first-order response to each
independent source of measurement noise is found by central differences: the
data are moved by a small fraction of one standard deviation along each noise
direction, both ways, and identified again as one batch. The standard error of
any figure derived from the estimate (CG, inertia, principal moments and axes,
``K``, ``C``, per-mount rates, a torque roll axis) is then the root sum of
squares of its responses: ``cov = D D^T`` with ``D`` the responses per unit
standard deviation. This costs one batch of ``2 (12 + 72)`` identifications,
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
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from rigidid.core.estimator import DAMPING_WEIGHT, Estimates, estimate
from rigidid.core.noise import NoiseLevels, tilt_directions
from rigidid.core.statespace import modal_from_poles

__all__ = [
    "STEP",
    "Linearised",
    "noise_directions",
    "principal_axis_deviation",
    "residual_weights",
    "spread",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

STEP = 1e-3
"""Central-difference step, in standard deviations of each noise source."""


@dataclass(frozen=True)
class Directions:
    """The data moved by ``+STEP`` and ``-STEP`` standard deviations along each noise direction.

    Attributes
    ----------
    positions, directions : ndarray, shape (2 k, p, 3)
    poles : ndarray of complex, shape (2 k, 6)
    shapes : ndarray of complex, shape (2 k, p, 6)
        Rows ``0..k-1`` moved forwards, ``k..2k-1`` backwards.
    """

    positions: Array
    directions: Array
    poles: CArray
    shapes: CArray


def _poles_from(f: Array, z: Array) -> CArray:
    w = 2.0 * np.pi * f
    result: CArray = w * (-z + 1j * np.sqrt(1.0 - z * z))
    return result


def _shape_moves(positions: Array, directions: Array, shapes: CArray, level: float) -> CArray:
    """Shape moves (12 per mode, 72 in all) carrying the rigid-body part of the shape noise: (72, p, 6)."""
    from rigidid.core.geometry import local_sensor_matrix

    u = np.linalg.svd(local_sensor_matrix(positions, directions), full_matrices=False)[0]  # (p, 6)
    rms = np.sqrt(np.mean(np.abs(shapes) ** 2, axis=0))  # (6,)
    p = positions.shape[0]
    moves = np.zeros((72, p, 6), dtype=complex)
    row = 0
    for k in range(6):
        for part in (1.0, 1j):
            for i in range(6):
                moves[row, :, k] = part * u[:, i] * level * rms[k] / np.sqrt(2.0)
                row += 1
    return moves


def noise_directions(
    positions: Array, directions: Array, poles: CArray, shapes: CArray, noise: NoiseLevels, *, step: float = STEP
) -> Directions:
    """The test's data moved along every noise direction of `noise`, by ``+-step`` standard deviations.

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
        Size of the move in standard deviations.

    Returns
    -------
    Directions
    """
    p = positions.shape[0]
    f, z = modal_from_poles(poles)
    moves_lam: list[CArray] = []
    moves_psi: list[CArray] = []
    moves_pos: list[Array] = []
    moves_dir: list[Array] = []

    def add(
        lam: CArray | None = None, psi: CArray | None = None, pos: Array | None = None, dirs: Array | None = None
    ) -> None:
        moves_lam.append(np.zeros((1, 6), dtype=complex) if lam is None else lam[None] - poles[None])
        moves_psi.append(np.zeros((1, p, 6), dtype=complex) if psi is None else psi[None])
        moves_pos.append(np.zeros((1, p, 3)) if pos is None else pos[None])
        moves_dir.append(np.zeros((1, p, 3)) if dirs is None else dirs[None] - directions[None])

    for k in range(6):
        unit = np.eye(6)[k]
        if noise.frequency > 0.0:
            add(lam=_poles_from(f * (1.0 + step * noise.frequency * unit), z))
        if noise.damping > 0.0 and z[k] > 0.0:
            add(lam=_poles_from(f, np.clip(z * (1.0 + step * noise.damping * unit), 0.0, 0.999)))
    if noise.shape > 0.0:
        for move in _shape_moves(positions, directions, shapes, step * noise.shape):
            add(psi=move)
    if noise.position > 0.0:
        for i in range(p * 3):
            add(pos=(step * noise.position * np.eye(p * 3)[i]).reshape(p, 3))
    if noise.angle_deg > 0.0:
        for i in range(p * 3):
            rot = (np.deg2rad(step * noise.angle_deg) * np.eye(p * 3)[i]).reshape(p, 3)
            add(dirs=tilt_directions(directions, rot))
    d_lam, d_psi = np.concatenate(moves_lam), np.concatenate(moves_psi)
    d_pos, d_dir = np.concatenate(moves_pos), np.concatenate(moves_dir)
    k_all = d_lam.shape[0]
    both = np.concatenate
    return Directions(
        positions=both([positions + d_pos, positions - d_pos]),
        directions=both([directions + d_dir, directions - d_dir]),
        poles=both([poles + d_lam, poles - d_lam]).reshape(2 * k_all, 6),
        shapes=both([shapes + d_psi, shapes - d_psi]),
    )


@dataclass(frozen=True)
class Linearised:
    """The kernel's estimates at the data moved along each noise direction (see :func:`spread`).

    Attributes
    ----------
    base : Estimates
        The estimate from the data as measured (a batch of one).
    moved : Estimates
        ``2 k`` estimates: ``k`` moved forwards, then ``k`` backwards.
    step : float
        The move, in standard deviations.
    noise : NoiseLevels
        The levels the moves were scaled by.
    """

    base: Estimates
    moved: Estimates
    step: float
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
        k = values.shape[0] // 2
        d: Array = (values[:k] - values[k:]) / (2.0 * self.step)
        ok = self.moved.ok[:k] & self.moved.ok[k:]
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
        Central-difference step in standard deviations.

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
    )
    names = ("center_of_gravity", "inertia_per_mass", "stiffness_per_mass", "damping_per_mass", "status")
    base = Estimates(*(getattr(all_est, n)[:1] for n in names))
    rest = Estimates(*(getattr(all_est, n)[1:] for n in names))
    return Linearised(base, rest, step, noise)


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
    found by central differences through
    :func:`rigidid.core.estimator.prepare`. Minimising ``|L r|^2`` over the CG
    and ``J / m`` is then the first-order maximum-likelihood fit of the free
    model (CG, ``J``, symmetric ``K`` and ``C``) to the measured poles and
    rigid-body coordinates: the symmetric parts of ``D Q_g`` and ``D P_g`` are
    free, the antisymmetric parts are the constraints, weighted by their
    covariance (a Sampson-type approximation), and ``|L r|^2`` is chi-square
    with ``30 - 9 = 21`` degrees of freedom when the model and the noise levels
    are right.
    """
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
    k = q.shape[0] // 2
    dq, dp = (q[:k] - q[k:]) / (2.0 * STEP), (p[:k] - p[k:]) / (2.0 * STEP)
    d = eq18_residuals(dq, dp, np.broadcast_to(cg, (k, 3)), np.broadcast_to(inertia_params, (k, 6)))
    ev, vec = np.linalg.eigh(d.T @ d)
    ev = np.maximum(ev, 1e-10 * max(float(ev[-1]), 1e-300))
    result: Array = (vec / np.sqrt(ev)).T
    return result
