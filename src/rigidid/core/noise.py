"""The measurement-noise model: levels, perturbed copies of a test, defaults from the data.

Used by the Monte Carlo intervals (:mod:`rigidid.core.uncertainty`) and the test
planning predictions (:mod:`rigidid.core.plan`); the statistics of the draws are
theirs, the sampling is here.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.geometry import normalise_directions
from rigidid.core.statespace import modal_from_poles
from rigidid.errors import IdentificationError, InputError

__all__ = [
    "DEFAULT_NOISE",
    "NoiseLevels",
    "Perturbed",
    "StandardNormals",
    "apply_noise",
    "checked_test",
    "draw_normals",
    "estimate_noise",
    "perturb",
    "shape_noise_from_residuals",
    "tilt_directions",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]


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
        return not any(getattr(self, f.name) for f in fields(self))


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
    from rigidid.core.geometry import local_sensor_matrix
    from rigidid.core.selection import project_rigid

    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    dirs = normalise_directions(directions)
    psi = np.asarray(shapes, dtype=complex)
    if psi.ndim != 2 or psi.shape[0] != pos.shape[0] or dirs.shape != pos.shape:
        raise InputError(f"shapes must be (sensors, modes) with {pos.shape[0]} sensors, got {psi.shape}")
    if pos.shape[0] <= 6:
        return base
    _, residual = project_rigid(local_sensor_matrix(pos, dirs), psi)
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
class StandardNormals:
    """Standard normal numbers behind a batch of draws (one stream per quantity and sensor)."""

    frequency: Array  # (B, 6)
    damping: Array  # (B, 6)
    shape: Array  # (B, p, 6, 2)
    position: Array  # (B, p, 3)
    angle: Array  # (B, p, 3)
    mass: Array  # (B,)

    def draws(self, index: slice) -> StandardNormals:
        """The numbers of a window of the draws."""
        return StandardNormals(
            self.frequency[index], self.damping[index], self.shape[index], self.position[index], self.angle[index],
            self.mass[index],
        )  # fmt: skip

    def sensors(self, index: ArrayLike) -> StandardNormals:
        """The numbers of a subset (or reordering) of the sensors."""
        i = np.asarray(index, dtype=np.intp)
        return StandardNormals(
            self.frequency, self.damping, self.shape[:, i], self.position[:, i], self.angle[:, i], self.mass
        )


def draw_normals(rng: np.random.Generator, draws: int, sensors: int) -> StandardNormals:
    return StandardNormals(
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


def apply_noise(
    normals: StandardNormals,
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


def checked_test(
    positions: ArrayLike, directions: ArrayLike, poles: ArrayLike, shapes: ArrayLike
) -> tuple[Array, Array, CArray, CArray]:
    """One test's arrays, validated: positions (p, 3), unit directions (p, 3), six poles, shapes (p, 6)."""
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
    pos, dirs, lam, psi = checked_test(positions, directions, poles, shapes)
    if draws < 1:
        raise InputError(f"the number of draws must be at least 1, got {draws}")
    gen = rng if rng is not None else np.random.default_rng(seed)
    normals = draw_normals(gen, int(draws), pos.shape[0])
    return apply_noise(normals, noise, pos, dirs, lam, psi, mass)
