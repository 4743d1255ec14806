"""Monte Carlo propagation of measurement uncertainty to the identified body.

Every draw perturbs the measured data (natural frequencies, damping ratios,
mode shapes, sensor positions and directions, optionally the mass) by the
stated standard deviations and identifies the body again with exactly the
estimator of :func:`rigidid.core.identify.identify` (``method="structured"``):
eq. (19) of [1] for ``M^-1 K`` and ``M^-1 C``, then the whole of eq. (18)
solved for the CG and ``J / m`` (:func:`rigidid.core.identify.solve_structured`).
All draws are computed together by the identification kernel
(:func:`rigidid.core.estimator.estimate`); the spread of the results over the
draws is the uncertainty. The noise model and the sampling are in
:mod:`rigidid.core.noise`.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core import estimator
from rigidid.core.estimator import DAMPING_WEIGHT, Estimates
from rigidid.core.identify import Identification, identify
from rigidid.core.noise import DEFAULT_NOISE, NoiseLevels, apply_noise, checked_test, draw_normals
from rigidid.errors import IdentificationError, IllConditionedWarning, InputError, Notice, emit

__all__ = [
    "IntervalEstimate",
    "Uncertainty",
    "identify_batch",
    "propagate",
    "summarise",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

_FAILED_WARN_FRACTION = 0.05
"""Fraction of failed draws above which :func:`propagate` warns."""


_VALUES_PER_WINDOW = 250_000
"""Monte Carlo draws times sensors perturbed and identified at once (:func:`propagate`): bounds the memory
of large layouts; below 250 sensors the 1000 default draws are one window."""


def identify_batch(
    positions: ArrayLike,
    directions: ArrayLike,
    poles: ArrayLike,
    shapes: ArrayLike,
    *,
    damping_weight: float = DAMPING_WEIGHT,
    weights: Array | None = None,
    progress: Callable[[str, float, float | None], None] | None = None,
) -> Estimates:
    """Identify many tests at once with the kernel of :func:`rigidid.core.identify.identify`.

    Parameters
    ----------
    positions : array_like, shape (B, p, 3)
        Sensor locations of each test (length).
    directions : array_like, shape (B, p, 3)
        Measuring axes (normalised here; a zero direction fails its test).
    poles : array_like of complex, shape (B, 6)
        Poles of the six rigid-body modes (rad/s), ``Im > 0``.
    shapes : array_like of complex, shape (B, p, 6)
        Mode shapes as the sensors read them.
    damping_weight : float
        As in :func:`~rigidid.core.identify.identify`.
    weights : ndarray, shape (30, 30), optional
        Residual whitening shared by every test (:func:`rigidid.core.estimator.solve_cg`).
    progress : callable, optional
        ``progress(task, done, total)`` as the draws are identified.

    Returns
    -------
    Estimates
        Per-mass results; tests that fail are flagged, never raised.

    Raises
    ------
    InputError
        Arrays of inconsistent shapes.
    IdentificationError
        Fewer than six sensors.

    Notes
    -----
    :func:`rigidid.core.estimator.estimate` on normalised directions: the same
    steps, to rounding, as ``identify(..., method="structured")`` draw by
    draw. Warnings (conditioning, plausibility) are not raised; see
    :attr:`~rigidid.core.estimator.Estimates.plausible`.
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
    return estimator.estimate(pos, dirs, lam, psi, damping_weight=damping_weight, weights=weights, progress=progress)


# --------------------------------------------------------------------------- propagation


@dataclass(frozen=True)
class IntervalEstimate:
    """An estimate with its standard error and 95 % interval (arrays of the quantity's shape).

    Attributes
    ----------
    estimate : ndarray
        From all the data (what :func:`~rigidid.core.identify.identify` returns).
    std : ndarray
        Standard error of the estimate.
    low, high : ndarray
        Bounds of the 95 % interval. How they are found depends on the
        producer: the 2.5 and 97.5 percentiles of the draws for
        :func:`propagate` (Monte Carlo), ``estimate -/+ t std`` with Student's
        ``t`` for :func:`rigidid.core.record_spread.record_spread`.
    """

    estimate: Array
    std: Array
    low: Array
    high: Array


def _diagonals(matrices: Array) -> Array:
    result: Array = np.diagonal(matrices, axis1=1, axis2=2)
    return result


def _percentile_interval(estimate: Array, samples: Array) -> IntervalEstimate:
    if samples.shape[0] == 0:
        nan = np.full(estimate.shape, np.nan)
        return IntervalEstimate(estimate, nan, nan.copy(), nan.copy())
    std = samples.std(axis=0, ddof=1) if samples.shape[0] > 1 else np.zeros(estimate.shape)
    low, high = np.percentile(samples, [2.5, 97.5], axis=0)
    return IntervalEstimate(np.asarray(estimate, dtype=float), std, low, high)


@dataclass(frozen=True)
class Uncertainty:
    """Uncertainty of every identified quantity, from :func:`propagate`.

    Attributes
    ----------
    center_of_gravity : IntervalEstimate
        Shape (3,), length.
    inertia : IntervalEstimate
        Shape (3, 3): the inertia tensor about the CG (mass length^2), or
        ``J / m`` (length^2) when `per_mass`.
    principal_moments : IntervalEstimate
        Shape (3,), ascending; same units as `inertia`.
    stiffness_diagonal : IntervalEstimate
        Shape (6,): diagonal of the support stiffness at the CG, x, y, z, rx,
        ry, rz (mass/s^2 and mass length^2/s^2), or per mass when `per_mass`.
    damping_diagonal : IntervalEstimate
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

    center_of_gravity: IntervalEstimate
    inertia: IntervalEstimate
    principal_moments: IntervalEstimate
    stiffness_diagonal: IntervalEstimate
    damping_diagonal: IntervalEstimate
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
    progress: Callable[[str, float, float | None], None] | None = None,
    weighted: bool = False,
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
    progress : callable, optional
        ``progress(task, done, total)`` as the draws are identified.
    weighted : bool
        Identify the estimate and every draw with the noise-weighted kernel
        (``identify(..., noise=noise)``), the draws with the estimate's weights.

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
    again (:func:`~rigidid.core.noise.perturb`, :func:`identify_batch`); the
    spread of the draws around the estimate stands for the spread of the estimate around the truth
    (parametric bootstrap). The 95 % interval is the 2.5-97.5 percentile range
    of the draws; it covers the truth about 95 % of the time when the noise
    levels are right and the estimator is close to linear over the spread
    (checked by simulation in ``tests/core/test_uncertainty.py``). With large
    noise the estimator is biased and nonlinear and the intervals lose
    coverage. Errors not in the noise model (flexible modes, a wrong mode
    chosen, mass-loaded sensors) are not covered. Only the structured method
    is propagated. The estimate itself comes from
    :func:`~rigidid.core.identify.identify` with ``warn=False`` (call it
    directly to see its warnings).

    Examples
    --------
    The body of :func:`rigidid.core.identify.identify`'s example, with 1 % noise
    on the shapes: the 95 % interval of each CG coordinate holds the estimate.

    >>> from rigidid.core.noise import NoiseLevels
    >>> from rigidid.core.simulate import Body, Mount, body_modes
    >>> mounts = [Mount.from_values(p, (8e4, 9e4, 2e5), (40.0, 50.0, 90.0))
    ...           for p in ([0.3, 0.2, -0.3], [-0.3, 0.2, 0.2], [0.3, -0.25, 0.1], [-0.3, -0.2, -0.2])]
    >>> body = Body(mass=60.0, center_of_gravity=np.array([0.02, -0.01, 0.1]),
    ...             inertia_tensor=np.diag([2.0, 3.0, 4.0]), mounts=mounts)
    >>> pos = np.array([[x, y, z] for x in (0.4, -0.4) for y in (0.3, -0.3) for z in (0.2, -0.2)])
    >>> dirs = np.eye(3)[[0, 1, 2, 0, 1, 2, 0, 1]]
    >>> modes = body_modes(body, pos, dirs)
    >>> result = propagate(pos, dirs, modes.poles, modes.shapes, mass=60.0,
    ...                    noise=NoiseLevels(shape=0.01), draws=200, seed=1)
    >>> cg = result.center_of_gravity
    >>> bool(np.all((cg.low < cg.estimate) & (cg.estimate < cg.high))), result.failed
    (True, 0)
    """
    pos, dirs, lam, psi = checked_test(positions, directions, poles, shapes)
    if not (isinstance(draws, int | np.integer) and draws >= 1):
        raise InputError(f"the number of draws must be a positive integer, got {draws!r}", source="draws")
    base = identify(
        pos, dirs, lam, psi, mass=mass, method="structured", damping_weight=damping_weight, warn=False,
        noise=noise if weighted else None,
    )  # fmt: skip
    normals = draw_normals(np.random.default_rng(seed), int(draws), pos.shape[0])
    window = max(1, _VALUES_PER_WINDOW // pos.shape[0])  # the perturbed copies of many sensors, a window at a time
    parts, masses = [], []
    for start in range(0, int(draws), window):
        part = normals.draws(slice(start, start + window))
        data = apply_noise(part, noise, pos, dirs, lam, psi, mass)
        step = None if progress is None else _offset(progress, start, int(draws))
        estimates = identify_batch(
            data.positions, data.directions, data.poles, data.shapes, damping_weight=damping_weight,
            weights=base.diagnostics.residual_weights, progress=step,
        )  # fmt: skip
        parts.append(estimates)
        masses.append(data.mass)
    batch = parts[0] if len(parts) == 1 else estimator.concatenate(parts)
    masses_all = None if mass is None else np.concatenate([m for m in masses if m is not None])
    return summarise(base_estimate(base), batch, masses_all, noise=noise, seed=seed)


def _offset(
    progress: Callable[[str, float, float | None], None], start: int, total: int
) -> Callable[[str, float, float | None], None]:
    """`progress` of one window of draws, counted among all `total` draws."""
    return lambda task, done, _: progress(task, start + done, total)


def base_estimate(result: Identification) -> dict[str, Array]:
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
    batch: Estimates,
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
    batch : Estimates
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
        emit(
            [
                Notice(
                    IllConditionedWarning,
                    f"{failed} of {draws} Monte Carlo draws failed; the intervals (from the others) understate "
                    "the uncertainty",
                )
            ]
        )
    per_mass = mass is None
    m_est = 1.0 if per_mass else float(estimate["mass"])
    m_draw = np.ones(n_ok) if mass is None else np.asarray(mass, dtype=float)[ok]
    return Uncertainty(
        center_of_gravity=_percentile_interval(estimate["center_of_gravity"], batch.center_of_gravity[ok]),
        inertia=_percentile_interval(m_est * estimate["inertia"], m_draw[:, None, None] * batch.inertia_per_mass[ok]),
        principal_moments=_percentile_interval(
            m_est * estimate["principal_moments"], m_draw[:, None] * batch.principal_moments_per_mass[ok]
        ),
        stiffness_diagonal=_percentile_interval(
            m_est * estimate["stiffness_diagonal"], m_draw[:, None] * _diagonals(batch.stiffness_per_mass)[ok]
        ),
        damping_diagonal=_percentile_interval(
            m_est * estimate["damping_diagonal"], m_draw[:, None] * _diagonals(batch.damping_per_mass)[ok]
        ),
        per_mass=per_mass,
        noise=noise,
        draws=draws,
        failed=failed,
        implausible=int(np.sum(ok & ~batch.plausible)),
        seed=seed,
    )
