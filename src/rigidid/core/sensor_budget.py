"""Type-B uncertainty of an identified body from the sensors' tolerances (issue 23).

Calibration laboratories state an accelerometer's error sources beside the noise:
its sensitivity (calibration and temperature), the orientation of its axis as
mounted, its transverse sensitivity and the position of its seismic centre. None
is random between impacts, so no amount of averaging removes them; each shifts
every mode shape the sensor reads the same way. Their effect on the body is
propagated here by linearisation of the identification kernel
(:func:`rigidid.core.estimator.estimate`, eqs. (3), (18), (19) of [1]):

- a sensitivity error ``delta`` scales the sensor's readings: ``psi_i (1 + delta)``;
- an axis tilted by ``epsilon`` (radians) towards a unit vector ``e`` normal to
  the stated axis ``d_i`` reads ``(d_i + epsilon e) . u``: to first order the
  estimate moves as when the layout stated ``d_i - epsilon e`` for exact readings;
- a transverse sensitivity ``tau`` along an unknown direction normal to the
  axis acts as a tilt of ``tau`` towards it;
- a position error ``delta p`` acts as the layout stating ``p_i - delta p``.

Each derivative is a central difference over a batch of perturbed tests (one call
of the kernel for all sensors and sources). The variance of a result from one
source is ``sum_i sum_a (d result / d x_ia)^2 u_a^2`` over sensors ``i`` and
the source's axes ``a`` (one for sensitivity, two normal to the axis for
orientation and transverse sensitivity, three for position), ``u`` the standard
uncertainty; sources and sensors are independent.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
.. [2] JCGM 100:2008 (GUM), sections 4.3 (type-B evaluation; a bound ``a`` of a
   rectangular distribution gives ``u = a / sqrt(3)``) and 5.1 (law of
   propagation of uncertainty).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.estimator import estimate
from rigidid.core.geometry import frame_arrays, normalise_directions

__all__ = [
    "DEFAULT_BOUNDS",
    "SOURCES",
    "SensorBounds",
    "SensorBudget",
    "SensorJacobians",
    "axis_normals",
    "sensor_budget",
    "sensor_jacobians",
]

Array = NDArray[np.float64]

SOURCES = ("sensitivity", "orientation", "transverse", "position")
"""The type-B sources, in the order of :attr:`SensorBudget.std`."""


@dataclass(frozen=True)
class SensorBounds:
    """Bounds of the sensors' errors (half-widths of rectangular distributions, GUM 4.3.7).

    Attributes
    ----------
    sensitivity : float
        Relative sensitivity error (0.02: +-2 %).
    orientation_deg : float
        Tilt of the measuring axis about each of the two axes normal to it (degrees).
    transverse : float
        Largest transverse sensitivity (relative to the axial one).
    position : float
        Position error along each axis (length, the layout's unit).
    """

    sensitivity: float
    orientation_deg: float
    transverse: float
    position: float

    def standard(self) -> dict[str, float]:
        """Standard uncertainty per axis of each source (``u = a / sqrt 3``; transverse: ``a / sqrt 6``).

        Returns
        -------
        dict of str to float
            Keys :data:`SOURCES`: sensitivity (relative), orientation and
            transverse (radians, per normal axis), position (length, per axis).

        Notes
        -----
        The transverse sensitivity is a magnitude up to the bound in a direction
        uniform about the axis: per normal axis ``E[(tau cos phi)^2] = a^2 / 6``.
        """
        root3 = math.sqrt(3.0)
        return {
            "sensitivity": self.sensitivity / root3,
            "orientation": math.radians(self.orientation_deg) / root3,
            "transverse": self.transverse / math.sqrt(6.0),
            "position": self.position / root3,
        }

    def moments(self) -> dict[str, tuple[float, float]]:
        """Variance and variance of the square of each source's error per axis.

        Returns
        -------
        dict of str to (float, float)
            Keys :data:`SOURCES`: ``(E x^2, Var x^2)`` of one axis's error ``x``
            (units as :meth:`standard`).

        Notes
        -----
        Rectangular on ``[-a, a]`` (sensitivity, orientation, position):
        ``E x^2 = a^2 / 3``, ``E x^4 = a^4 / 5``. Transverse, a magnitude
        ``tau`` rectangular on ``[0, a]`` along a uniform direction, per normal
        axis ``x = tau cos phi``: ``E x^2 = a^2 / 6``, ``E x^4 = 3 a^4 / 40``.
        They give the spread of the misfit the errors leave
        (:func:`rigidid.core.timedomain.acceptance.budgeted_misfit_test`).
        """
        out = {}
        for source, a in (("sensitivity", self.sensitivity), ("orientation", math.radians(self.orientation_deg)),
                          ("position", self.position)):  # fmt: skip
            out[source] = (a**2 / 3.0, a**4 / 5.0 - a**4 / 9.0)
        t = self.transverse
        out["transverse"] = (t**2 / 6.0, 3.0 * t**4 / 40.0 - t**4 / 36.0)
        return {source: out[source] for source in SOURCES}


DEFAULT_BOUNDS = SensorBounds(sensitivity=0.02, orientation_deg=2.0, transverse=0.05, position=0.002)
"""Typical of piezoelectric (IEPE) accelerometers, length in metres: sensitivity within +-2 %
of a calibration certificate (back-to-back comparison, ISO 16063-21, expanded uncertainties of
1-2 %, plus drift and temperature); transverse sensitivity at most 5 % (the bound data sheets
of general-purpose single-axis accelerometers state); axis within 2 degrees of the stated one
(hand-mounted on a surface that is not machined); seismic centre within 2 mm of the stated point
(a 10-15 mm housing measured to its mounting face)."""


@dataclass(frozen=True)
class SensorBudget:
    """Standard deviations of the identified body from each sensor error source.

    Attributes
    ----------
    std : dict of str to dict of str to ndarray
        ``std[source][quantity]``: source one of :data:`SOURCES`, quantity one of
        ``"center_of_gravity"`` (3,), ``"inertia_per_mass"`` (3, 3),
        ``"stiffness_per_mass"`` and ``"damping_per_mass"`` (6, 6).
    total : dict of str to ndarray
        The sources combined (root sum of squares), same quantities.
    """

    std: dict[str, dict[str, Array]]
    total: dict[str, Array]


_SHAPES = {"center_of_gravity": (3,), "inertia_per_mass": (3, 3), "stiffness_per_mass": (6, 6),
           "damping_per_mass": (6, 6)}  # fmt: skip


def axis_normals(d: Array) -> tuple[Array, Array]:
    """Two unit vectors normal to each unit row of `d` and to each other.

    Parameters
    ----------
    d : ndarray, shape (p, 3)
        Unit measuring axes.

    Returns
    -------
    e1, e2 : ndarray, shape (p, 3)
        ``e1`` normal to ``d`` (from the x axis, or the y axis when ``d`` is near x), ``e2 = d x e1``.
    """
    helper = np.where(np.abs(d[:, [0]]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    e1 = np.cross(d, helper)
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    return e1, np.cross(d, e1)


def _flat(est: object) -> Array:
    parts = [np.asarray(getattr(est, name)).reshape(np.asarray(getattr(est, name)).shape[0], -1) for name in _SHAPES]
    return np.concatenate(parts, axis=1)


@dataclass(frozen=True)
class SensorJacobians:
    """Derivatives of the identified body with respect to the stated sensors.

    Attributes
    ----------
    value : ndarray, shape (n,)
        The estimate, flattened: CG (3), J/m (9), K/m (36), C/m (36).
    sensitivity : ndarray, shape (p, n)
        Per sensor, the derivative with respect to a relative change of its readings.
    orientation : ndarray, shape (p, 2, n)
        Per sensor, with respect to its stated axis turned (radians) towards
        ``normals[0][i]`` and ``normals[1][i]``.
    position : ndarray, shape (p, 3, n)
        Per sensor, with respect to its stated position along x, y, z (per length).
    normals : (ndarray, ndarray), shape (p, 3) each
        The two unit vectors normal to each stated axis.
    """

    value: Array
    sensitivity: Array
    orientation: Array
    position: Array
    normals: tuple[Array, Array]


def sensor_jacobians(
    positions: ArrayLike, directions: ArrayLike, poles: ArrayLike, shapes: ArrayLike
) -> SensorJacobians:
    """Central-difference derivatives of the kernel's estimate with respect to every sensor's gain, axis and position.

    Parameters
    ----------
    positions : array_like, shape (p, 3)
        Sensor positions as the layout states them (length).
    directions : array_like, shape (p, 3)
        Measuring axes as stated (normalised here).
    poles : array_like of complex, shape (6,)
        The rigid-body poles (rad/s).
    shapes : array_like of complex, shape (p, 6)
        The mode shapes as the sensors read them.

    Returns
    -------
    SensorJacobians

    Raises
    ------
    ValueError
        When the kernel cannot identify the unperturbed test.

    Notes
    -----
    One batch of ``1 + 12 p`` tests through :func:`rigidid.core.estimator.estimate`;
    steps of 1e-5 (relative, radians, and of the sensors' RMS radius).
    """
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    dirs = normalise_directions(directions)
    lam = np.asarray(poles, dtype=complex).ravel()
    psi = np.asarray(shapes, dtype=complex).reshape(pos.shape[0], -1)
    p = pos.shape[0]
    _, radius = frame_arrays(pos)
    e1, e2 = axis_normals(dirs)
    h_rel, h_len = 1e-5, 1e-5 * float(radius)
    batch = 1 + 12 * p  # per sensor: gain, two tilts, three shifts, each both ways
    bp, bd = np.repeat(pos[None], batch, axis=0), np.repeat(dirs[None], batch, axis=0)
    bs = np.repeat(psi[None], batch, axis=0)
    for i in range(p):
        row = 1 + 12 * i
        for sign, k in ((1.0, row), (-1.0, row + 1)):
            bs[k, i] *= 1.0 + sign * h_rel
            for a, e in enumerate((e1[i], e2[i])):
                bd[k + 2 + 2 * a, i] = normalise_directions((dirs[i] + sign * h_rel * e)[None])[0]
            for axis in range(3):
                bp[k + 6 + 2 * axis, i, axis] += sign * h_len
    est = estimate(bp, bd, np.repeat(lam[None], batch, axis=0), bs)
    if not est.ok[0]:
        raise ValueError("the test cannot be identified: no sensor derivatives")
    values = _flat(est)
    first = values[1:].reshape(p, 6, 2, -1)  # (sensor, perturbation, sign, output)
    slope = (first[:, :, 0] - first[:, :, 1]) / 2.0
    return SensorJacobians(values[0], slope[:, 0] / h_rel, slope[:, 1:3] / h_rel, slope[:, 3:6] / h_len, (e1, e2))


def sensor_budget(
    positions: ArrayLike, directions: ArrayLike, poles: ArrayLike, shapes: ArrayLike, bounds: SensorBounds
) -> SensorBudget:
    """Type-B standard deviations of CG, J/m, K/m and C/m from the sensors' tolerances.

    Parameters
    ----------
    positions, directions, poles, shapes
        As for :func:`sensor_jacobians`.
    bounds : SensorBounds
        Error bounds (position in the layout's length unit).

    Returns
    -------
    SensorBudget
        Per source and combined.

    Raises
    ------
    ValueError
        When the kernel cannot identify the unperturbed test.

    Notes
    -----
    First order (GUM 5.1.2 of [2]): valid while the errors move the estimate
    little against its size.
    """
    jac = sensor_jacobians(positions, directions, poles, shapes)
    u = bounds.standard()
    var = {
        "sensitivity": np.sum(jac.sensitivity**2, axis=0) * u["sensitivity"] ** 2,
        "orientation": np.sum(jac.orientation**2, axis=(0, 1)) * u["orientation"] ** 2,
        "transverse": np.sum(jac.orientation**2, axis=(0, 1)) * u["transverse"] ** 2,  # acts as a tilt
        "position": np.sum(jac.position**2, axis=(0, 1)) * u["position"] ** 2,
    }
    std = {source: _unflat(np.sqrt(v)) for source, v in var.items()}
    return SensorBudget(std, _unflat(np.sqrt(sum(var.values()))))


def _unflat(flat: Array) -> dict[str, Array]:
    out: dict[str, Array] = {}
    start = 0
    for name, shape in _SHAPES.items():
        size = int(np.prod(shape))
        out[name] = flat[start : start + size].reshape(shape)
        start += size
    return out
