"""Frequency response functions of a rigid body on mounts: the forward model with force.

Accelerance (acceleration over force) at ``p`` sensors for forces at ``q``
reference (hammer) points, from the system matrices of eq. (1) of [1]:

``H(w) = -w^2 T (K - w^2 M + i w C)^-1 T_f^T``

with ``T`` the sensor matrix (eq. (3)) and ``T_f`` the same matrix for the
reference points and directions, both about the CG. Elastic modes of the body
can be added modally, and complex noise.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.geometry import sensor_matrix
from rigidid.core.simulate import Body, system_matrices
from rigidid.errors import InputError

__all__ = ["ElasticMode", "accelerance", "random_elastic_modes", "rigid_receptance"]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]


def rigid_receptance(s: ArrayLike, mass: Array, stiffness: Array, damping: Array, loads: Array) -> CArray:
    """Rigid-body coordinates per unit load at each line: ``(s^2 M + s C + K)^-1 F``.

    Eq. (1) of [1] in the Laplace domain, shared by the forward model (:func:`accelerance`),
    the exact support fit and the measured force's model; the accelerance is ``s^2`` times
    it, seen through the sensor matrix.

    Parameters
    ----------
    s : ndarray, shape (f,)
        Laplace variable per line (``i w``; ``i w + a`` behind an exponential window).
    mass, stiffness, damping : ndarray, shape (6, 6)
        ``M``, ``K``, ``C`` in the coordinates of the loads.
    loads : ndarray, shape (6, q)
        Generalised forces, one column per reference (``T_f^T``).

    Returns
    -------
    ndarray of complex, shape (f, 6, q)

    Examples
    --------
    >>> x = rigid_receptance(np.array([2j]), np.eye(6), np.zeros((6, 6)), np.zeros((6, 6)), np.eye(6)[:, :1])
    >>> float(x[0, 0, 0].real), x.shape
    (-0.25, (1, 6, 1))
    """
    sv = np.asarray(s, dtype=np.complex128).reshape(-1)
    z = (sv**2)[:, None, None] * mass[None] + sv[:, None, None] * damping[None] + stiffness[None]
    rhs = np.broadcast_to(np.asarray(loads, dtype=np.complex128), (sv.size, *np.shape(loads)))
    x: CArray = np.asarray(np.linalg.solve(z, rhs), dtype=np.complex128)
    return x


@dataclass(frozen=True)
class ElasticMode:
    """One elastic (flexible) mode of the body, unit modal mass.

    Attributes
    ----------
    frequency : float
        Natural frequency (Hz).
    damping : float
        Viscous damping ratio (fraction of critical, 0.01 = 1 %).
    sensor_shape : ndarray, shape (p,)
        Real mode shape at the sensors, along their directions (1/sqrt(mass)).
    reference_shape : ndarray, shape (q,)
        Real mode shape at the reference points, along the force directions.
    """

    frequency: float
    damping: float
    sensor_shape: Array
    reference_shape: Array


def random_elastic_modes(
    rng: np.random.Generator,
    frequencies: Sequence[float],
    n_sensors: int,
    n_references: int,
    *,
    mass: float,
    damping: float = 0.01,
) -> tuple[ElasticMode, ...]:
    """Elastic modes with random real shapes, of a size comparable to the rigid motion.

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of randomness.
    frequencies : sequence of float
        Natural frequencies (Hz).
    n_sensors, n_references : int
        Number of sensors and of reference points.
    mass : float
        Mass of the body: shapes are drawn with standard deviation ``1/sqrt(mass)``
        so that the elastic residue is of the order of the mass line ``1/mass``.
    damping : float
        Damping ratio of every mode.

    Returns
    -------
    tuple of ElasticMode
    """
    scale = 1.0 / np.sqrt(mass)
    return tuple(
        ElasticMode(
            float(f),
            float(damping),
            scale * rng.standard_normal(n_sensors),
            scale * rng.standard_normal(n_references),
        )
        for f in frequencies
    )


def accelerance(
    body: Body,
    positions: ArrayLike,
    directions: ArrayLike,
    reference_positions: ArrayLike,
    reference_directions: ArrayLike,
    frequencies: ArrayLike,
    *,
    elastic: Sequence[ElasticMode] = (),
    noise: float = 0.0,
    rng: np.random.Generator | None = None,
) -> CArray:
    """Accelerance FRFs of a rigid body on mounts, plus optional elastic modes and noise.

    Parameters
    ----------
    body : Body
        Mass, CG, inertia and mounts.
    positions, directions : array_like, shape (p, 3)
        Sensor locations (length) and unit measuring axes.
    reference_positions, reference_directions : array_like, shape (q, 3)
        Where the force acts (length) and its unit direction.
    frequencies : array_like, shape (f,)
        Frequencies (Hz), positive.
    elastic : sequence of ElasticMode
        Elastic modes added modally:
        ``-w^2 phi_s phi_r^T / (w_n^2 - w^2 + 2 i zeta w_n w)``.
    noise : float
        Standard deviation of complex Gaussian noise relative to each value
        (0.01 = 1 %); real and imaginary parts each get ``noise / sqrt(2)``.
    rng : numpy.random.Generator, optional
        Generator for the noise (required when `noise` > 0).

    Returns
    -------
    ndarray of complex, shape (p, q, f)
        ``H[i, j, k]``: acceleration of sensor ``i`` per unit force at
        reference ``j`` at frequency ``k`` (length / s^2 per force unit,
        i.e. 1 / mass unit).

    Raises
    ------
    InputError
        If shapes disagree, a frequency is not positive, or noise is asked
        without a generator.

    Notes
    -----
    The rigid part is eq. (1) of [1] in the frequency domain. One linear solve
    per frequency (6 x 6), so the cost is negligible next to any fit.
    """
    freq = np.asarray(frequencies, dtype=float).reshape(-1)
    if freq.size == 0 or np.any(freq <= 0.0):
        raise InputError("frequencies must be positive")
    cg = np.asarray(body.center_of_gravity, dtype=float)
    t = sensor_matrix(positions, directions, cg)
    tf = sensor_matrix(reference_positions, reference_directions, cg)
    m, k, c = system_matrices(body)
    w = 2.0 * np.pi * freq
    x = rigid_receptance(1j * w, m, k, c, tf.T)  # (f, 6, q)
    h = -(w**2)[:, None, None] * np.einsum("ia,faj->fij", t, x)
    for mode in elastic:
        phi_s = np.asarray(mode.sensor_shape, dtype=float)
        phi_r = np.asarray(mode.reference_shape, dtype=float)
        if phi_s.shape != (t.shape[0],) or phi_r.shape != (tf.shape[0],):
            raise InputError("elastic mode shapes must have one value per sensor and per reference")
        wn = 2.0 * np.pi * mode.frequency
        denom = wn**2 - w**2 + 2j * mode.damping * wn * w
        h = h + (-(w**2) / denom)[:, None, None] * np.outer(phi_s, phi_r)[None]
    if noise > 0.0:
        if rng is None:
            raise InputError("rng is required when noise > 0")
        e = rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape)
        h = h * (1.0 + noise / np.sqrt(2.0) * e)
    result: CArray = np.ascontiguousarray(np.moveaxis(h, 0, -1))
    return result
