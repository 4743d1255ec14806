"""Simulated impact records: exact free decays of a rigid body on mounts.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core.geometry import normalise_directions, sensor_matrix
from rigidid.core.simulate import Body, system_matrices
from rigidid.core.statespace import state_matrix
from rigidid.errors import InputError
from rigidid.progress import ProgressCallback, no_progress

__all__ = ["impulse_records", "record_time"]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

_CHUNK = 1 << 15


def record_time(n_samples: int, sample_rate: float, pretrigger: float = 0.0) -> Array:
    """Time stamps of a simulated record, the impulse at ``t = 0``.

    Parameters
    ----------
    n_samples : int
        Length of the record.
    sample_rate : float
        Samples per second (Hz).
    pretrigger : float
        Pre-trigger duration (s), as given to :func:`impulse_records`.

    Returns
    -------
    ndarray, shape (n_samples,)
        ``(k - round(pretrigger * sample_rate)) / sample_rate`` (s).
    """
    n_pre = round(pretrigger * sample_rate)
    result: Array = (np.arange(n_samples) - n_pre) / sample_rate
    return result


def impulse_records(
    body: Body,
    positions: ArrayLike,
    directions: ArrayLike,
    impacts: Sequence[tuple[ArrayLike, ArrayLike]],
    *,
    sample_rate: float,
    duration: float,
    pretrigger: float = 0.0,
    noise: float = 0.0,
    seed: int | None = None,
    progress: ProgressCallback | None = None,
) -> list[Array]:
    """Sensor accelerations after a unit impulse at each impact, exact.

    Parameters
    ----------
    body : Body
        Mass, CG, inertia and mounts.
    positions : array_like, shape (p, 3)
        Sensor locations (length).
    directions : array_like, shape (p, 3)
        Measuring axes (normalised here).
    impacts : sequence of (position, direction)
        One record per impact: where the unit impulse acts (length, shape (3,))
        and along which direction (shape (3,), normalised here). The impulse
        is 1 force-unit second.
    sample_rate : float
        Samples per second (Hz).
    duration : float
        Length of the free decay after the impulse (s): ``round(duration *
        sample_rate)`` samples, the first at the impulse instant.
    pretrigger : float
        Length of the record before the impulse (s): ``round(pretrigger *
        sample_rate)`` samples of zero (plus noise) come first.
    noise : float
        Standard deviation of Gaussian noise added to each channel, relative
        to the RMS value of that channel's clean decay (0.01 = 1 %).
    seed : int, optional
        Seed of the noise generator (one generator for all records, drawn in
        impact order).
    progress : callable, optional
        ``progress(task, done, total)``, called with the samples computed
        across all impacts (see :mod:`rigidid.progress`).

    Returns
    -------
    list of ndarray, shape (n_pre + n_decay, p)
        Per impact, acceleration read by each sensor along its own direction
        (length / s^2), samples by sensors.

    Raises
    ------
    InputError
        For a non-positive sample rate or duration, negative pre-trigger or
        noise, a zero impact direction, or a body whose state matrix has no
        complete set of eigenvectors.

    Notes
    -----
    With state ``z = [v; x]`` of the CG (velocity and displacement, six each),
    ``z' = A z`` with ``A = [[-M^-1 C, -M^-1 K], [I, 0]]`` (matrices of
    :func:`rigidid.core.simulate.system_matrices`). The impulse sets
    ``v(0+) = M^-1 [f; (r_f - g) x f]``; thereafter the sensors read
    ``T [-M^-1 C, -M^-1 K] z(t)`` with ``T`` the sensor matrix at the CG, and
    ``z(t) = V exp(Lambda t) V^-1 z(0+)`` is evaluated exactly from the
    eigendecomposition of ``A``. The impulsive part of the acceleration at
    ``t = 0`` (a Dirac pulse) is not representable by samples and is left out;
    the first sample is the limit ``t -> 0+``.
    """
    if not (np.isfinite(sample_rate) and sample_rate > 0.0):
        raise InputError(f"sample rate must be positive, got {sample_rate}")
    if not (np.isfinite(duration) and duration > 0.0):
        raise InputError(f"duration must be positive, got {duration}")
    if not (np.isfinite(pretrigger) and pretrigger >= 0.0):
        raise InputError(f"pre-trigger must be zero or positive, got {pretrigger}")
    if not (np.isfinite(noise) and noise >= 0.0):
        raise InputError(f"noise must be zero or positive, got {noise}")
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    dirs = normalise_directions(directions)
    if dirs.shape != pos.shape:
        raise InputError(f"{pos.shape[0]} sensor positions but {dirs.shape[0]} directions")

    m, k, c = system_matrices(body)
    try:
        a = state_matrix(m, k, c)
    except np.linalg.LinAlgError as exc:
        raise InputError("the mass matrix is singular") from exc
    out = a[:6]
    mu, vec = np.linalg.eig(a)
    if np.linalg.cond(vec) > 1e10:
        raise InputError("the state matrix of the body has no complete set of eigenvectors")
    g = np.asarray(body.center_of_gravity, dtype=float)
    t_sensor = sensor_matrix(pos, dirs, g)
    output = t_sensor @ out @ vec

    n_pre = round(pretrigger * sample_rate)
    n_decay = round(duration * sample_rate)
    if n_decay < 1:
        raise InputError("duration is shorter than one sample")
    rng = np.random.default_rng(seed)
    step = progress or no_progress
    total = float(n_decay * len(impacts))
    records: list[Array] = []
    for i, (where, along) in enumerate(impacts):
        r_f = np.asarray(where, dtype=float).reshape(3)
        f = np.asarray(along, dtype=float).reshape(3)
        norm = float(np.linalg.norm(f))
        if not (np.isfinite(norm) and norm > 0.0) or not np.all(np.isfinite(r_f)):
            raise InputError(
                "impact position and direction must be finite, the direction non-zero", location=f"impact {i + 1}"
            )
        f = f / norm
        force = np.concatenate([f, np.cross(r_f - g, f)])
        z0 = np.concatenate([np.linalg.solve(m, force), np.zeros(6)])
        b = np.linalg.solve(vec, z0.astype(complex))
        weights = output * b
        record = np.zeros((n_pre + n_decay, pos.shape[0]))
        for start in range(0, n_decay, _CHUNK):
            stop = min(start + _CHUNK, n_decay)
            t = np.arange(start, stop) / sample_rate
            record[n_pre + start : n_pre + stop] = (np.exp(np.outer(t, mu)) @ weights.T).real
            step("simulating impulse responses", float(i * n_decay + stop), total)
        if noise > 0.0:
            rms = np.sqrt(np.mean(record[n_pre:] ** 2, axis=0))
            record += rng.standard_normal(record.shape) * (noise * rms)
        records.append(record)
    return records
