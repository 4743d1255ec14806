"""Test planning: how precise will the result be, and where to add sensors.

Before an impact test, three questions: can this layout see all six
rigid-body motions at all (:func:`rigidid.core.layout_check.check_layout`);
how precisely will the CG and the inertia come out for the noise to expect
(Monte Carlo on simulated modes of a CAD estimate of the body,
:func:`predict_uncertainty`); and which extra sensor helps most
(:func:`suggest_sensors`). Both predictions run the identification kernel
(:func:`rigidid.core.estimator.estimate`) on perturbed copies of the simulated
test (:mod:`rigidid.core.noise`).

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.core import estimator
from rigidid.core.estimator import DAMPING_WEIGHT
from rigidid.core.geometry import (
    layout_condition,
    local_sensor_matrix,
    normalise_directions,
    sensor_matrix,
)
from rigidid.core.layout_check import AXIS_COS, Finding, LayoutReport, check_layout
from rigidid.core.linalg import numerical_rank
from rigidid.core.noise import DEFAULT_NOISE, NoiseLevels, StandardNormals, apply_noise, draw_normals
from rigidid.core.simulate import Body, body_modes
from rigidid.core.uncertainty import Uncertainty, propagate
from rigidid.errors import IllConditionedWarning, InputError, Notice, emit

if TYPE_CHECKING:
    from rigidid.core.sensor_budget import SensorBounds

__all__ = [
    "AXIS_COS",
    "INERTIAL_PARAMETERS",
    "RECORDS_DURATION",
    "RECORDS_NOISE",
    "RECORDS_NOISE_EVALUATIONS",
    "RECORDS_SAMPLE_RATE",
    "RECORDS_TIME_CONSTANTS",
    "RIGID_LOADS",
    "Finding",
    "LayoutReport",
    "PlannedDecays",
    "PredictedFigures",
    "Prediction",
    "RecordsBudget",
    "ReferenceReport",
    "SensorPlan",
    "SuggestedSensor",
    "candidate_grid",
    "check_layout",
    "check_references",
    "default_impacts",
    "planned_decays",
    "predict_records_budget",
    "predict_uncertainty",
    "suggest_sensors",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]
Progress = Callable[[str, float, "float | None"], None]


# --------------------------------------------------------------------------- predicted uncertainty


def _body_length(body: Body) -> float:
    """Characteristic length ``sqrt(trace(J) / (3 m))``: the RMS radius of gyration."""
    return float(np.sqrt(np.trace(body.inertia_tensor) / (3.0 * body.mass)))


def _score(cg_std: Array, moments_rel_std: Array, length: float) -> Array:
    """``|std(CG)| / L + |std(I_k) / I_k|`` along the last axis (NaN/inf propagate)."""
    result: Array = np.linalg.norm(cg_std, axis=-1) / length + np.linalg.norm(moments_rel_std, axis=-1)
    return result


@dataclass(frozen=True)
class PredictedFigures:
    """Predicted precision of a layout for a body.

    Attributes
    ----------
    score : float
        ``|std(CG)|_2 / L + |std(I_k) / I_k|_2``, with ``L = sqrt(trace(J) / (3 m))``
        the body's RMS radius of gyration and ``I_k`` its principal moments:
        the relative error to expect on the CG plus that on the principal
        moments (dimensionless; smaller is better; ``inf`` when the layout
        cannot identify the body).
    center_of_gravity_std : ndarray, shape (3,)
        Standard deviation of each CG coordinate (length).
    principal_moments_std : ndarray, shape (3,)
        Standard deviation of each principal moment, ascending moments (mass length^2).
    principal_moments_rel_std : ndarray, shape (3,)
        The same relative to the moments.
    condition : float
        Condition number of the layout.
    failed : int
        Monte Carlo draws that could not be identified.
    """

    score: float
    center_of_gravity_std: Array
    principal_moments_std: Array
    principal_moments_rel_std: Array
    condition: float
    failed: int


@dataclass(frozen=True)
class Prediction:
    """Result of :func:`predict_uncertainty`.

    Attributes
    ----------
    figures : PredictedFigures
        The summary (standard deviations and score).
    inertia_std : ndarray, shape (3, 3)
        Standard deviation of each inertia tensor entry (mass length^2).
    uncertainty : Uncertainty
        The whole Monte Carlo result; its estimates are the identification of
        the exact simulated modes (the body itself, to rounding).
    """

    figures: PredictedFigures
    inertia_std: Array
    uncertainty: Uncertainty

    @property
    def center_of_gravity_std(self) -> Array:
        """Standard deviation of the CG coordinates (length)."""
        return self.figures.center_of_gravity_std

    @property
    def principal_moments_std(self) -> Array:
        """Standard deviation of the principal moments (mass length^2)."""
        return self.figures.principal_moments_std

    @property
    def score(self) -> float:
        """See :attr:`PredictedFigures.score`."""
        return self.figures.score


def _check_body(body: Body) -> None:
    if not isinstance(body, Body):
        raise InputError("the body must be a rigidid.core.simulate.Body")


def predict_uncertainty(
    body: Body,
    positions: ArrayLike,
    directions: ArrayLike,
    *,
    noise: NoiseLevels = DEFAULT_NOISE,
    draws: int = 1000,
    seed: int | None = 0,
    damping_weight: float = DAMPING_WEIGHT,
    progress: Progress | None = None,
) -> Prediction:
    """Predicted standard deviation of the CG and inertia for a planned test.

    Parameters
    ----------
    body : Body
        Estimate of the body (mass, CG, inertia, mounts), from CAD for example.
    positions : array_like, shape (p, 3)
        Planned sensor locations (length), ``p >= 6``.
    directions : array_like, shape (p, 3)
        Planned measuring axes.
    noise : NoiseLevels
        Measurement noise to expect.
    draws : int
        Monte Carlo draws.
    seed : int, optional
        Seed (fixed by default so that repeated plans agree).
    damping_weight : float
        As in :func:`~rigidid.core.identify.identify`.
    progress : callable, optional
        ``progress(task, done, total)`` as the draws are identified.

    Returns
    -------
    Prediction

    Raises
    ------
    InputError
        Invalid body or arrays.
    IdentificationError
        If the layout cannot identify the body (rank below 6).

    Notes
    -----
    The exact modes of the body as the layout would read them
    (:func:`~rigidid.core.simulate.body_modes`) are perturbed by `noise` and
    identified again (:func:`~rigidid.core.uncertainty.propagate`) with the
    noise-weighted kernel, as ``identify`` will identify the test. The figures
    hold for this body and these mounts: a CAD estimate that is far off (or
    mounts that couple the modes differently) changes them.
    """
    _check_body(body)
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    dirs = normalise_directions(directions)
    modes = body_modes(body, pos, dirs)
    result = propagate(
        pos, dirs, modes.poles, modes.shapes, mass=body.mass, noise=noise, draws=draws, seed=seed,
        damping_weight=damping_weight, progress=progress, weighted=True,
    )  # fmt: skip
    moments = np.linalg.eigvalsh(body.inertia_tensor)
    cg_std = result.center_of_gravity.std
    mom_std = result.principal_moments.std
    rel = mom_std / moments
    figures = PredictedFigures(
        score=float(_score(cg_std, rel, _body_length(body))),
        center_of_gravity_std=cg_std,
        principal_moments_std=mom_std,
        principal_moments_rel_std=rel,
        condition=layout_condition(pos, dirs)[0],
        failed=result.failed,
    )
    return Prediction(figures, result.inertia.std, result)


# --------------------------------------------------------------------------- the records route's budget


RECORDS_TIME_CONSTANTS = 5.0
"""Decay time constants ``1 / (-Re lambda)`` of the slowest-decaying mode kept by :func:`planned_decays`:
the refit's sensor map from the whole decays differs by 1.1e-4 at most on chain_matrix's test (8 time
constants: 3.5e-5, 3: 1.3e-3; ``benchmarks/plan_budget.py --length``): its signatures and Jacobian hold
the decay's energy, ``exp(-10)`` of which lies beyond. The map is computed on that much only."""

RECORDS_SAMPLE_RATE = 512.0
"""Samples per second (Hz) of a planned records test when none is given (``rigidid simulate``'s default)."""

RECORDS_DURATION = 8.0
"""Free decay per planned record (s) when none is given (``rigidid simulate``'s default)."""

RECORDS_NOISE = 0.01
"""Noise of a planned record relative to each channel's RMS over its free decay, when none is given."""

RECORDS_NOISE_SEED = 20231
"""Seed of the white noise the planned decays carry in :func:`planned_decays`."""

RECORDS_NOISE_EVALUATIONS = 30
"""Residual evaluations of the refit :func:`predict_records_budget` runs from the body estimate on the
planned noisy decays (its noise part is the refit's standard errors at the minimum it reaches: one noise
draw, thousands of residuals per impact and channel). On chain_matrix's test it converges in 5."""


def default_impacts(positions: ArrayLike) -> list[tuple[Array, Array]]:
    """The two impacts a records test gets when none are given (``rigidid simulate``'s and ``plan``'s).

    Parameters
    ----------
    positions : array_like, shape (p, 3)
        The sensors (length).

    Returns
    -------
    list of (ndarray, ndarray)
        At the first sensor along (1, 1, 1) and at the sensor farthest from it along (-1, 1, -1),
        which excite all six modes in general.
    """
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    far = int(np.argmax(np.linalg.norm(pos - pos[0], axis=1)))
    return [(pos[0].copy(), np.array([1.0, 1.0, 1.0])), (pos[far].copy(), np.array([-1.0, 1.0, -1.0]))]


@dataclass(frozen=True)
class PlannedDecays:
    """The decays the refit would fit in a planned records test (:func:`planned_decays`).

    Attributes
    ----------
    data : PreparedDecays
        The decays at the fit's rate (the first :data:`RECORDS_TIME_CONSTANTS` decay time
        constants) and each channel's noise level
        (:class:`rigidid.core.timedomain.refine.PreparedDecays`).
    dt : float
        Sample interval of the planned records (s).
    factor : int
        The refit's decimation (:func:`~rigidid.core.timedomain.refine.fit_factor`).
    rows : int
        Samples per impact (at the fit's rate) the refit would fit (:data:`~rigidid.core.timedomain.refine.MAX_ROWS`).
    """

    data: Any
    dt: float
    factor: int
    rows: int


@dataclass(frozen=True)
class RecordsBudget:
    """The sensor budget ``identify --records`` will report for a planned test (:func:`predict_records_budget`).

    Attributes
    ----------
    std : dict of str to dict of str to ndarray
        Per type-B source (:data:`rigidid.core.sensor_budget.SOURCES`), the refit's std of
        ``center_of_gravity`` (3,), ``inertia_per_mass`` (3, 3), ``stiffness_per_mass`` and
        ``damping_per_mass`` (6, 6), ``frequency_hz`` and ``damping_ratio`` (6,)
        (:attr:`rigidid.core.timedomain.refine.Refinement.sensor_std`), per mass.
    factor : int
        The refit's decimation of the planned records (:func:`~rigidid.core.timedomain.refine.fit_factor`).
    rows : int
        Samples per impact (at the fit's rate) the refit would fit (:data:`~rigidid.core.timedomain.refine.MAX_ROWS`).
    used : int
        Samples per impact the prediction used (at most :data:`RECORDS_TIME_CONSTANTS` of the
        slowest decay).
    noise_std : dict of str to ndarray or None
        The noise's part: the refit's standard errors (:attr:`rigidid.core.timedomain.refine.Refinement.std`,
        same keys, per mass) on the planned records; None when the refit did not converge.
    """

    std: dict[str, dict[str, Array]]
    factor: int
    rows: int
    used: int
    noise_std: dict[str, Array] | None = None


def planned_decays(
    body: Body,
    positions: ArrayLike,
    directions: ArrayLike,
    impacts: list[tuple[Array, Array]] | None = None,
    *,
    sample_rate: float = RECORDS_SAMPLE_RATE,
    duration: float = RECORDS_DURATION,
    noise: float = RECORDS_NOISE,
) -> PlannedDecays | None:
    """The decays the refit would fit in a planned test, simulated from the body estimate.

    Parameters
    ----------
    body : Body
        The body estimate and its mounts.
    positions, directions : array_like, shape (p, 3)
        The planned sensors (length; axes).
    impacts : list of (ndarray, ndarray), optional
        Where each impact acts and along which direction; :func:`default_impacts` when None.
    sample_rate : float
        Samples per second of the records (Hz).
    duration : float
        Free decay per record (s).
    noise : float
        Noise of each channel relative to its RMS over each record's free decay (``rigidid
        simulate``'s convention), more than 0.

    Returns
    -------
    PlannedDecays or None
        None when the body has not six modes or the records are too short for the refit.

    Notes
    -----
    The records (:func:`rigidid.core.timedomain.simulate.impulse_records`) carry white noise of
    `noise` times each channel's RMS (a fixed seed, :data:`RECORDS_NOISE_SEED`, so that the refit's
    checks see noise); they are decimated and cut as the refit would
    (:func:`~rigidid.core.timedomain.refine.fit_factor` up to the modal estimate's factor for
    content up to the top mode, :func:`~rigidid.core.timedomain.refine.cut_decays`), then kept for
    :data:`RECORDS_TIME_CONSTANTS` decay time constants of the slowest mode.
    """
    from rigidid.core.timedomain.estimate import decimation_factors
    from rigidid.core.timedomain.preprocess import decimate, fir_taps
    from rigidid.core.timedomain.refine import PreparedDecays, cut_decays, fit_factor
    from rigidid.core.timedomain.simulate import impulse_records

    _check_body(body)
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    dirs = normalise_directions(directions)
    poles = body_modes(body, pos, dirs).poles
    if poles.size != 6:
        return None
    planned = impacts if impacts is not None else default_impacts(pos)
    records = impulse_records(
        body, pos, dirs, planned, sample_rate=sample_rate, duration=duration, noise=noise, seed=RECORDS_NOISE_SEED
    )
    dt, p = 1.0 / sample_rate, pos.shape[0]
    # each record's noise is `noise` times its channel's RMS; the refit pools them per channel (the pre-trigger's)
    rms = np.sqrt(np.mean([np.mean(r**2, axis=0) for r in records], axis=0) / (1.0 + noise**2))
    top = float(np.max(np.abs(poles))) / (2.0 * math.pi)
    q = fit_factor([r.shape[0] for r in records], p, decimation_factors(records, dt, None, (0.0, top))[0])
    try:
        decays = cut_decays([decimate(r, q) if q > 1 else r for r in records], p)
    except InputError:
        return None
    rows = decays[0].shape[0]
    slowest = float(np.min(-poles.real))
    used = rows if slowest <= 0.0 else min(rows, max(64, math.ceil(RECORDS_TIME_CONSTANTS / slowest / (q * dt))))
    sigma = noise * rms * (math.sqrt(float(np.sum(fir_taps(q) ** 2))) if q > 1 else 1.0)
    data = PreparedDecays([d[:used] for d in decays], np.where(sigma > 0.0, sigma, 1.0), q * dt, "pretrigger")
    return PlannedDecays(data, dt, q, rows)


def predict_records_budget(
    body: Body,
    positions: ArrayLike,
    directions: ArrayLike,
    bounds: SensorBounds,
    impacts: list[tuple[Array, Array]] | None = None,
    *,
    sample_rate: float = RECORDS_SAMPLE_RATE,
    duration: float = RECORDS_DURATION,
    noise: float = RECORDS_NOISE,
) -> RecordsBudget | None:
    """The refit's sensor budget for a planned impact test, before the test.

    Parameters
    ----------
    body : Body
        The body estimate and its mounts.
    positions, directions : array_like, shape (p, 3)
        The planned sensors (length; axes).
    bounds : SensorBounds
        The stated tolerances (:class:`rigidid.core.sensor_budget.SensorBounds`, layout length).
    impacts, sample_rate, duration, noise
        The planned test (:func:`planned_decays`).

    Returns
    -------
    RecordsBudget or None
        None when the body's model has not six underdamped modes or the records are too short
        for the refit.

    Notes
    -----
    ``identify --records`` reports the output-error refit's own linearisation of each tolerance
    (:func:`rigidid.core.timedomain.refine.sensor_terms`): a sensor error ``x`` moves the body by
    one Gauss-Newton step ``(J^T J)^+ J^T G~ x`` of the refit's model, eq. (19) of [1], whose
    Jacobian ``J`` and sensor signatures ``G~`` depend on the test (impacts, record length and
    rate, the channels' noise levels). Here that same map is built on the planned decays
    (:func:`planned_decays`): the refit (:func:`~rigidid.core.timedomain.refine.refine_prepared`) runs
    from the body estimate (at most :data:`RECORDS_NOISE_EVALUATIONS` evaluations; a noise standard
    error away from it), and its standard errors are the noise's part. The prediction holds for the
    body estimate: identify reports the map at the body it fits, which the sensors' actual errors
    move, and the noise's part for the records' actual noise (``benchmarks/plan_budget.py``).
    """
    from rigidid.core.simulate import system_matrices
    from rigidid.core.timedomain.refine import refine_prepared

    planned = planned_decays(
        body, positions, directions, impacts, sample_rate=sample_rate, duration=duration, noise=noise
    )
    if planned is None:
        return None
    _, k, c = system_matrices(body)
    try:
        refit = refine_prepared(
            planned.data, planned.dt, positions, directions, center_of_gravity=body.center_of_gravity,
            inertia_per_mass=body.inertia_tensor / body.mass, stiffness_per_mass=k / body.mass,
            damping_per_mass=c / body.mass, max_evaluations=RECORDS_NOISE_EVALUATIONS, sensor_bounds=bounds,
        )  # fmt: skip
    except np.linalg.LinAlgError:
        return None
    if refit.sensor_std is None:
        return None
    used = planned.data.decays[0].shape[0]
    return RecordsBudget(refit.sensor_std, planned.factor, planned.rows, used, refit.std if refit.converged else None)


# --------------------------------------------------------------------------- sensor suggestions


def candidate_grid(positions: ArrayLike, per_axis: int = 3, margin: float = 0.0) -> Array:
    """Candidate sensor positions on a regular grid over the sensors' bounding box.

    Parameters
    ----------
    positions : array_like, shape (p, 3)
        Existing sensor locations (length).
    per_axis : int
        Grid points along each axis (at least 1); an axis along which the
        sensors do not extend gets one point.
    margin : float
        Enlarge the box by this fraction of its extent on each side.

    Returns
    -------
    ndarray, shape (k, 3)
        Grid points, ``k <= per_axis ** 3``.

    Notes
    -----
    The grid knows nothing of the body's surface: points inside the body or
    in the air are candidates too. Pass real mounting points to
    :func:`suggest_sensors` when you have them.
    """
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    if pos.shape[0] == 0 or per_axis < 1:
        raise InputError("candidate_grid needs at least one position and one point per axis")
    lo, hi = pos.min(axis=0), pos.max(axis=0)
    ext = hi - lo
    lo, hi = lo - margin * ext, hi + margin * ext
    tiny = 1e-9 * max(float(ext.max()), 1e-300)
    axes = [np.linspace(lo[a], hi[a], per_axis) if ext[a] > tiny else np.array([lo[a]]) for a in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    result: Array = grid
    return result


@dataclass(frozen=True)
class SuggestedSensor:
    """One step of :func:`suggest_sensors`.

    Attributes
    ----------
    step : int
        1 for the first sensor added, 2 for the next...
    candidate : int
        Index into the candidate list (positions x directions, see
        :attr:`SensorPlan.candidate_positions`).
    position : ndarray, shape (3,)
        Where to put it (length).
    direction : ndarray, shape (3,)
        Its measuring axis (unit).
    figures : PredictedFigures
        Predicted precision of the layout with this sensor and those before it.
    ranking : tuple of (int, float)
        Every candidate tried at this step and its score, best first: the
        :data:`SHORTLIST` judged by the Monte Carlo, then the others by their
        first-order score.
    """

    step: int
    candidate: int
    position: Array
    direction: Array
    figures: PredictedFigures
    ranking: tuple[tuple[int, float], ...]


@dataclass(frozen=True)
class SensorPlan:
    """Result of :func:`suggest_sensors`.

    Attributes
    ----------
    baseline : PredictedFigures
        The layout as given.
    steps : tuple of SuggestedSensor
        The sensors to add, in order.
    candidate_positions, candidate_directions : ndarray, shape (c, 3)
        The candidates tried (positions repeated for the three axes when no
        directions were given).
    noise : NoiseLevels
        Noise assumed.
    draws : int
        Monte Carlo draws per candidate.
    """

    baseline: PredictedFigures
    steps: tuple[SuggestedSensor, ...]
    candidate_positions: Array
    candidate_directions: Array
    noise: NoiseLevels
    draws: int


def _figures_batch(
    body: Body,
    layouts_pos: Array,
    layouts_dir: Array,
    shapes: CArray,
    poles: CArray,
    normals: StandardNormals,
    noise: NoiseLevels,
    damping_weight: float,
) -> list[PredictedFigures]:
    """Predicted figures of several layouts of the same size at once (common random numbers)."""
    n_lay, p = layouts_pos.shape[:2]
    draws = normals.mass.shape[0]
    data = apply_noise(normals, noise, layouts_pos, layouts_dir, poles, shapes, body.mass)
    batch = estimator.estimate(
        data.positions.reshape(-1, p, 3),
        data.directions.reshape(-1, p, 3),
        data.poles.reshape(-1, 6),
        data.shapes.reshape(-1, p, 6),
        damping_weight=damping_weight,
    )
    assert data.mass is not None
    mass = data.mass.reshape(n_lay, draws)
    ok = batch.ok.reshape(n_lay, draws)
    cg = batch.center_of_gravity.reshape(n_lay, draws, 3)
    moments = batch.principal_moments_per_mass.reshape(n_lay, draws, 3) * mass[..., None]
    truth = np.linalg.eigvalsh(body.inertia_tensor)
    length = _body_length(body)
    out = []
    for k in range(n_lay):
        good = ok[k]
        n_ok = int(good.sum())
        cond = layout_condition(layouts_pos[k], layouts_dir[k])[0]
        if n_ok < max(2, int(0.95 * draws)):
            inf3 = np.full(3, np.inf)
            out.append(PredictedFigures(math.inf, inf3, inf3.copy(), inf3.copy(), cond, draws - n_ok))
            continue
        cg_std = cg[k, good].std(axis=0, ddof=1)
        m_std = moments[k, good].std(axis=0, ddof=1)
        rel = m_std / truth
        out.append(PredictedFigures(float(_score(cg_std, rel, length)), cg_std, m_std, rel, cond, draws - n_ok))
    return out


SHORTLIST = 12
"""Candidates per step that :func:`suggest_sensors` judges by its Monte Carlo: the best of the
first-order (delta-method) ranking of all candidates. On the bundled samples' layouts (two steps
each) the Monte Carlo's choice is among the first-order best eight (``benchmarks/plan_speed.py``)."""


def _first_order_scores(
    body: Body, positions: Array, directions: Array, shapes: CArray, poles: CArray, noise: NoiseLevels,
    damping_weight: float,
) -> Array:  # fmt: skip
    """First-order (delta-method) :attr:`PredictedFigures.score` of layouts ``(L, p, 3)``, shapes ``(L, p, 6)``.

    The kernel's response to one standard deviation of each noise source
    (:func:`rigidid.core.linearised.spread`, one Newton step from the exact CG per
    direction, eq. (18) of [1]) at the body's exact modes: about 90 linearised
    identifications per layout against the Monte Carlo's hundreds of full ones, and
    no Monte Carlo error. ``inf`` where the kernel cannot be linearised (rank below 6).
    """
    from rigidid.core.linearised import spread

    truth = np.linalg.eigvalsh(body.inertia_tensor)
    length = _body_length(body)
    start = np.asarray(body.center_of_gravity, dtype=float)
    scores = np.full(positions.shape[0], np.inf)
    for k in range(positions.shape[0]):
        lin = spread(positions[k], directions[k], poles, shapes[k], noise, damping_weight=damping_weight, start=start)
        if not lin.base.ok[0] or lin.failed:
            continue
        cg_std = lin.std(lambda e: e.center_of_gravity)
        moments_std = body.mass * lin.std(lambda e: e.principal_moments_per_mass)
        scores[k] = float(_score(cg_std, moments_std / truth, length))
    return scores


def _layouts(
    base: tuple[Array, Array, CArray],
    candidates: tuple[Array, Array, CArray],
    chosen: list[int],
    extra: NDArray[np.intp],
) -> tuple[Array, Array, CArray]:
    """Layouts ``(L, size, 3)``: the sensors, the `chosen` candidates and each `extra` one; and their shapes."""
    pos, dirs, base_shapes = base
    c_pos, c_dir, cand_shapes = candidates
    p = pos.shape[0]
    size = p + len(chosen) + (1 if extra.size else 0)
    n_lay = max(extra.size, 1)
    lay_pos = np.empty((n_lay, size, 3))
    lay_dir = np.empty((n_lay, size, 3))
    lay_shp = np.empty((n_lay, size, 6), dtype=complex)
    lay_pos[:, :p], lay_dir[:, :p], lay_shp[:, :p] = pos, dirs, base_shapes
    for slot, c in enumerate(chosen):
        lay_pos[:, p + slot], lay_dir[:, p + slot], lay_shp[:, p + slot] = c_pos[c], c_dir[c], cand_shapes[c]
    if extra.size:
        lay_pos[:, -1], lay_dir[:, -1], lay_shp[:, -1] = c_pos[extra], c_dir[extra], cand_shapes[extra]
    return lay_pos, lay_dir, lay_shp


def _judged(
    figures_of: Callable[[NDArray[np.intp]], list[PredictedFigures]],
    remaining: NDArray[np.intp],
    rough: Array | None,
) -> tuple[NDArray[np.intp], list[PredictedFigures], list[tuple[int, float]]]:
    """The candidates the Monte Carlo judges, its figures, and the others with their first-order scores.

    With first-order scores `rough`, the best :data:`SHORTLIST` of `remaining` (in their order), unless
    none of them can be identified: then every candidate, as without.
    """
    if rough is not None:
        by_rough = np.argsort(rough, kind="stable")
        short = remaining[np.sort(by_rough[:SHORTLIST])]
        figs = figures_of(short)
        if np.any(np.isfinite([f.score for f in figs])):
            return short, figs, [(int(remaining[i]), float(rough[i])) for i in by_rough[SHORTLIST:]]
    return remaining, figures_of(remaining), []


def _by_conditioning(positions: Array, directions: Array, c_pos: Array, c_dir: Array) -> NDArray[np.intp]:
    """Candidates ordered by the layout each makes: most independent motions first, then best conditioned."""
    ranks, ratios = [], []
    for where, along in zip(c_pos, c_dir, strict=True):
        lay_p, lay_d = np.vstack([positions, where]), np.vstack([directions, along])
        s = np.linalg.svd(local_sensor_matrix(lay_p, lay_d), compute_uv=False)
        r = int(numerical_rank(s, lay_p.shape[0]))
        ranks.append(r)
        ratios.append(s[r - 1] / s[0] if r else 0.0)
    order: NDArray[np.intp] = np.lexsort((-np.array(ratios), -np.array(ranks)))
    return order


def suggest_sensors(
    body: Body,
    positions: ArrayLike,
    directions: ArrayLike,
    candidates: ArrayLike | None = None,
    candidate_directions: ArrayLike | None = None,
    *,
    add: int = 1,
    noise: NoiseLevels = DEFAULT_NOISE,
    draws: int = 300,
    seed: int | None = 0,
    damping_weight: float = DAMPING_WEIGHT,
    progress: Progress | None = None,
) -> SensorPlan:
    """Greedy choice of sensors to add, each the one that most reduces the predicted uncertainty.

    Parameters
    ----------
    body : Body
        Estimate of the body and its mounts.
    positions : array_like, shape (p, 3)
        Current sensor locations (length); fewer than six is allowed.
    directions : array_like, shape (p, 3)
        Current measuring axes.
    candidates : array_like, shape (k, 3), optional
        Possible new sensor locations; default :func:`candidate_grid` of the
        current positions (27 points).
    candidate_directions : array_like, shape (k, 3), optional
        Measuring axis of each candidate. Without it every candidate position
        is tried along x, y and z.
    add : int
        Number of sensors to add.
    noise : NoiseLevels
        Noise to expect.
    draws : int
        Monte Carlo draws per candidate and step.
    seed : int, optional
        Seed; every candidate is judged on the same random numbers (common
        random numbers), so comparisons are much less noisy than the figures.
    damping_weight : float
        As in :func:`~rigidid.core.identify.identify`.
    progress : callable, optional
        ``progress("choosing sensors", step, add)`` after each step.

    Returns
    -------
    SensorPlan

    Raises
    ------
    InputError
        Invalid body, arrays, or ``add`` larger than the number of candidates.

    Warns
    -----
    IllConditionedWarning
        When no candidate gives a usable layout at some step (it is then
        chosen by condition number).

    Notes
    -----
    The criterion is :attr:`PredictedFigures.score`. Each step ranks every
    remaining candidate by its first-order (delta-method) score, the kernel's
    response to each noise source at the body's exact modes
    (:func:`rigidid.core.linearised.spread`), and judges the best
    :data:`SHORTLIST` of them with the Monte Carlo of
    :func:`~rigidid.core.estimator.estimate` (``SHORTLIST * draws``
    identifications per step instead of ``k * draws``); the first-order score
    runs 1-3 % below the Monte Carlo's and orders near ties differently, the
    short list leaves the choice to the Monte Carlo. When no short-listed
    candidate can be identified, every candidate is judged by the Monte Carlo.
    While the layout cannot identify the body (rank below 6) the candidate
    that gives the best-conditioned layout is taken. Greedy choice is not
    globally optimal; it is a good start for an engineer's judgement.
    """
    _check_body(body)
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    dirs = normalise_directions(directions) if pos.shape[0] else np.zeros((0, 3))
    if dirs.shape != pos.shape:
        raise InputError(f"directions must match positions {pos.shape}, got {dirs.shape}")
    c_pos, c_dir = _sensor_candidates(pos, candidates, candidate_directions)
    if not (1 <= add <= c_pos.shape[0]):
        raise InputError(f"can add between 1 and {c_pos.shape[0]} sensors (the candidates), asked for {add}")
    if not (isinstance(draws, int) and draws >= 2):
        raise InputError(f"draws must be an integer of at least 2, got {draws!r}")
    p = pos.shape[0]
    everything = body_modes(body, np.vstack([pos, c_pos]), np.vstack([dirs, c_dir]))
    base_shapes, cand_shapes = everything.shapes[:p], everything.shapes[p:]
    normals_all = draw_normals(np.random.default_rng(seed), draws, p + add)

    def layouts(chosen: list[int], extra: NDArray[np.intp]) -> tuple[Array, Array, CArray]:
        return _layouts((pos, dirs, base_shapes), (c_pos, c_dir, cand_shapes), chosen, extra)

    def figures_of(chosen: list[int], extra: NDArray[np.intp]) -> list[PredictedFigures]:
        n_extra = len(chosen) + (1 if extra.size else 0)
        size = p + n_extra
        if size < 6:
            return [
                PredictedFigures(math.inf, np.full(3, np.inf), np.full(3, np.inf), np.full(3, np.inf), math.inf, draws)
                for _ in range(max(extra.size, 1))
            ]
        lay_pos, lay_dir, lay_shp = layouts(chosen, extra)
        normals = normals_all.sensors(np.arange(size))
        return _figures_batch(body, lay_pos, lay_dir, lay_shp, everything.poles, normals, noise, damping_weight)

    baseline = figures_of([], np.zeros(0, dtype=np.intp))[0]
    notices: list[Notice] = []
    chosen: list[int] = []
    steps: list[SuggestedSensor] = []
    for step in range(1, add + 1):
        remaining = np.array([c for c in range(c_pos.shape[0]) if c not in chosen], dtype=np.intp)
        rough = None
        if p + step >= 6 and remaining.size > SHORTLIST:
            lay_pos, lay_dir, lay_shp = layouts(chosen, remaining)
            rough = _first_order_scores(body, lay_pos, lay_dir, lay_shp, everything.poles, noise, damping_weight)
        remaining, figs, rest = _judged(lambda extra: figures_of(chosen, extra), remaining, rough)
        scores = np.array([f.score for f in figs])
        if np.all(~np.isfinite(scores)):
            # cannot identify yet: take the best-conditioned (rank first) layout
            base_pos, base_dir = np.vstack([pos, c_pos[chosen]]), np.vstack([dirs, c_dir[chosen]])
            order = _by_conditioning(base_pos, base_dir, c_pos[remaining], c_dir[remaining])
            if p + step >= 6:
                notices.append(
                    Notice(
                        IllConditionedWarning,
                        f"step {step}: no candidate gives a layout that identifies the body; chose by conditioning",
                    )
                )
        else:
            order = np.argsort(scores, kind="stable")
        best = int(order[0])
        c_best = int(remaining[best])
        chosen.append(c_best)
        ranking = tuple((int(remaining[i]), float(scores[i])) for i in order) + tuple(rest)
        steps.append(SuggestedSensor(step, c_best, c_pos[c_best].copy(), c_dir[c_best].copy(), figs[best], ranking))
        if progress is not None:
            progress("choosing sensors", step, add)
    emit(notices)
    return SensorPlan(baseline, tuple(steps), c_pos, c_dir, noise, draws)


# --------------------------------------------------------------------------- reference (hammer) points


RIGID_LOADS = ("force along x", "force along y", "force along z", "moment about x", "moment about y", "moment about z")
"""The six generalised loads on a rigid body, in the order of its coordinates."""

INERTIAL_PARAMETERS = (
    "the mass",
    "the CG along x",
    "the CG along y",
    "the CG along z",
    "the inertia about x",
    "the inertia about y",
    "the inertia about z",
    "the product of inertia xy",
    "the product of inertia xz",
    "the product of inertia yz",
)
"""The ten inertial parameters the mass line determines, in the order of :func:`check_references`."""

REFERENCE_CONDITION_LIMIT = 1.0e3
"""Largest condition number of the references' map onto the ten inertial parameters that is
accepted. Measured on the three samples' layouts: three references at corners along x, y and
z give 3.9-10; three whose lines of action pass near the sensors' centroid give 20 to 6e3;
two references or three along one axis give rank 9 (structurally: see :func:`check_references`)."""

PARTICIPATION_MIN = 0.01
"""A rigid-body mode counts as excited when some reference puts at least this fraction of its
generalised force into it (``|psi_k^T g_j| / sqrt(g_j^T M^-1 g_j)``, mass-normalised ``psi``)."""


@dataclass(frozen=True)
class ReferenceReport:
    """Whether a set of reference (hammer) points drives all six rigid-body motions.

    Attributes
    ----------
    references : int
        Number of references.
    point : ndarray, shape (3,)
        The point loads are taken about: the body's CG when a body is given,
        else the centroid of the sensors (length).
    load_rank : int
        Rank of the references' generalised forces ``T_f^T`` (6 x q): at most
        ``min(q, 6)``.
    coverage : ndarray, shape (6,)
        Per load of :data:`RIGID_LOADS`, the norm of its row of ``T_f^T``
        (moments divided by the characteristic length) over the largest.
    weakest_load : str
        The load of :data:`RIGID_LOADS` with the least coverage.
    rank : int
        How many of the ten inertial parameters the mass line determines
        (rank of the map, 10 needed).
    condition : float
        Condition number of that map (dimensionless; ``inf`` when rank < 10).
    weakest_parameter : str
        The parameter of :data:`INERTIAL_PARAMETERS` the references determine worst.
    participation : ndarray or None, shape (6,)
        Per rigid-body mode on the mounts (ascending frequency), the largest
        fraction of a reference's generalised force going into it; ``None``
        without a body with mounts.
    mode_frequencies : ndarray or None, shape (6,)
        Undamped frequencies of those modes (Hz).
    ok : bool
        Rank 10, condition at most :data:`REFERENCE_CONDITION_LIMIT`, and (with
        a body) every mode excited (:data:`PARTICIPATION_MIN`).
    statement : str
        The verdict in words, naming what is missing.
    suggestion : str
        The reference to add (one at a time, the one giving the highest rank
        and then the lowest condition; more than one, at most three, while
        the set is not yet accepted), in words.
    suggested_position, suggested_direction : ndarray, shape (3,)
        The first reference to add (length; unit vector along an axis).
    suggested_condition : float
        The condition with the suggested references added.
    """

    references: int
    point: Array
    load_rank: int
    coverage: Array
    weakest_load: str
    rank: int
    condition: float
    weakest_parameter: str
    participation: Array | None
    mode_frequencies: Array | None
    ok: bool
    statement: str
    suggestion: str
    suggested_position: Array
    suggested_direction: Array
    suggested_condition: float


def _mass_matrix_about(body: Body, point: Array) -> Array:
    """6x6 rigid-body mass matrix about `point`: ``[[m I, -m S(g)], [m S(g), J_g + m (|g|^2 I - g g^T)]]``."""
    from rigidid.core.geometry import skew

    g = np.asarray(body.center_of_gravity, dtype=float) - point
    m = body.mass
    out = np.zeros((6, 6))
    out[:3, :3] = m * np.eye(3)
    out[:3, 3:] = -m * skew(g)
    out[3:, :3] = m * skew(g)
    out[3:, 3:] = np.asarray(body.inertia_tensor, dtype=float) + m * (float(g @ g) * np.eye(3) - np.outer(g, g))
    return out


def _parameter_map(mass_matrix: Array, loads: Array) -> Array:
    """``D`` (6 q x 10): ``vec(M(theta) X)`` per inertial parameter, ``X = M0^-1 G`` the rigid accelerations.

    ``theta = (m, m g_x, m g_y, m g_z, J_xx, J_yy, J_zz, J_xy, J_xz, J_yz)`` (``J`` about the point), in
    which ``M`` is linear; the mass line gives ``X``, and ``M(theta) X = G`` is what determines ``theta``.
    """
    from rigidid.core.geometry import skew

    x = np.linalg.solve(mass_matrix, loads)
    basis = np.zeros((10, 6, 6))
    basis[0, :3, :3] = np.eye(3)
    for k in range(3):
        e = np.zeros(3)
        e[k] = 1.0
        basis[1 + k, :3, 3:] = -skew(e)
        basis[1 + k, 3:, :3] = skew(e)
    for n, (a, b) in enumerate(((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))):
        basis[4 + n, 3 + a, 3 + b] = basis[4 + n, 3 + b, 3 + a] = 1.0
    d: Array = np.einsum("kab,bj->ajk", basis, x).reshape(-1, 10)
    return d


def _condition(d: Array) -> tuple[int, float, Array]:
    s, vt = np.linalg.svd(d, full_matrices=True)[1:]
    rank = int(numerical_rank(s, d.shape[0]))
    cond = float(s[0] / s[-1]) if rank == d.shape[1] else math.inf
    return rank, cond, vt[-1]


def check_references(
    positions: ArrayLike,
    directions: ArrayLike,
    reference_positions: ArrayLike,
    reference_directions: ArrayLike,
    *,
    body: Body | None = None,
    unit: str = "",
    names: tuple[str, ...] | None = None,
) -> ReferenceReport:
    """Whether reference (hammer) points excite all six rigid-body motions, and what to add.

    Parameters
    ----------
    positions, directions : array_like, shape (p, 3)
        The sensors (length; unit axes): candidate places for a new reference.
    reference_positions, reference_directions : array_like, shape (q, 3)
        Where the force acts and its unit direction.
    body : Body, optional
        An estimate of the body (and mounts): the loads are taken about its CG,
        its mass matrix maps them to accelerations, and with mounts each
        rigid-body mode's participation is given. Without, a nominal body
        (CG at the sensors' centroid, isotropic inertia of their spread).
    unit : str
        Length unit, for the messages.
    names : tuple of str, optional
        Sensor ids, for the suggestion.

    Returns
    -------
    ReferenceReport

    Raises
    ------
    InputError
        Shapes that disagree, or no reference.

    Notes
    -----
    A reference ``j`` applies the generalised force ``g_j = (d_j, r_j x d_j)``
    (a row of ``T_f``, eq. (3) of [1] for the reference point); the body
    answers with the rigid accelerations ``x_j = M^-1 g_j``, which the mass
    line measures (``T M^-1 T_f^T``). The ten inertial parameters ``theta``
    follow from ``M(theta) x_j = g_j``, linear in ``theta``: the references
    determine them when that 6 q x 10 map has rank 10, and its condition
    number (lengths scaled by the sensors' RMS radius, masses by the body's)
    says how well. One reference cannot (6 equations). Two cannot either:
    an inertia ``e e^T`` about ``e = alpha_1 x alpha_2`` (normal to both
    angular accelerations they cause) changes no equation, so rank 9 at
    most. Forces that never give a moment about an axis leave the inertia
    about it free.
    """
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    dirs = normalise_directions(np.asarray(directions, dtype=float).reshape(-1, 3))
    rpos = np.asarray(reference_positions, dtype=float).reshape(-1, 3)
    rdirs = normalise_directions(np.asarray(reference_directions, dtype=float).reshape(-1, 3))
    if rpos.shape[0] == 0 or rpos.shape != rdirs.shape:
        raise InputError("need one position and one direction per reference, at least one reference")
    if pos.shape != dirs.shape:
        raise InputError("need one direction per sensor")
    point = pos.mean(axis=0) if body is None else np.asarray(body.center_of_gravity, dtype=float)
    spread = np.vstack([pos, rpos]) - point
    length = float(np.sqrt(np.mean(np.sum(spread**2, axis=1)))) or 1.0
    if body is None:
        mass0 = np.diag([1.0, 1.0, 1.0, length**2, length**2, length**2])
        scale_m = 1.0
    else:
        _check_body(body)
        mass0 = _mass_matrix_about(body, point)
        scale_m = body.mass
    # dimensionless: lengths / L, masses / m
    sdiag = np.array([1.0, 1.0, 1.0, length, length, length])
    mass_s = mass0 / scale_m / np.outer(sdiag, sdiag)

    def loads_of(p: Array, d: Array) -> Array:
        g: Array = sensor_matrix(p, d, point).T / sdiag[:, None]
        return g

    loads = loads_of(rpos, rdirs)
    rank, cond, weak = _condition(_parameter_map(mass_s, loads))
    rows = np.linalg.norm(loads, axis=1)
    coverage = rows / rows.max()
    weakest_load = RIGID_LOADS[int(np.argmin(coverage))]
    weakest_parameter = INERTIAL_PARAMETERS[int(np.argmax(np.abs(weak)))]
    load_rank = int(numerical_rank(np.linalg.svd(loads.T, compute_uv=False), loads.shape[1]))

    places = np.vstack([pos, rpos])
    chosen, best_rank, best_cond = _references_to_add(places, loads, mass_s, loads_of, rank, cond)
    suggestion = _suggestion_text(places, pos.shape[0], chosen, best_rank, best_cond, names, unit)
    add_pos = places[chosen[0][0]].copy()
    add_dir = np.eye(3)[chosen[0][1]]

    participation, frequencies = _participation(body, rpos, rdirs)

    ok = _accepted(rank, cond)
    excited = participation is None or bool(np.all(participation >= PARTICIPATION_MIN))
    q = rpos.shape[0]
    statement = _reference_statement(q, rank, cond, ok, coverage, weakest_load, weakest_parameter)
    statement += _participation_text(participation, frequencies)
    return ReferenceReport(
        references=q,
        point=point,
        load_rank=load_rank,
        coverage=coverage,
        weakest_load=weakest_load,
        rank=rank,
        condition=cond,
        weakest_parameter=weakest_parameter,
        participation=participation,
        mode_frequencies=frequencies,
        ok=ok and excited,
        statement=statement,
        suggestion=suggestion,
        suggested_position=add_pos,
        suggested_direction=add_dir,
        suggested_condition=best_cond,
    )


def _accepted(rank: int, condition: float) -> bool:
    """Whether a set of references with this rank and condition is accepted (:data:`REFERENCE_CONDITION_LIMIT`)."""
    return rank == 10 and condition <= REFERENCE_CONDITION_LIMIT


def _mass_normal_modes(stiffness: Array, mass: Array) -> tuple[Array | None, Array]:
    """Undamped modes ``K psi = w^2 M psi``, ``psi^T M psi = I`` (Cholesky of ``M``); ``None`` if ``K`` is zero."""
    if not np.any(stiffness):
        return None, np.zeros((6, 6))
    chol = np.linalg.cholesky(mass)
    a = np.linalg.solve(chol, np.linalg.solve(chol, stiffness).T).T  # L^-1 K L^-T
    eigvals, vecs = np.linalg.eigh(0.5 * (a + a.T))
    psi: Array = np.linalg.solve(chol.T, vecs)
    return eigvals, psi


def _references_to_add(
    places: Array,
    loads: Array,
    mass_s: Array,
    loads_of: Callable[[Array, Array], Array],
    rank: int,
    cond: float,
) -> tuple[list[tuple[int, int]], int, float]:
    """The references to add, one at a time (at most three), and the rank and condition they reach.

    Each candidate is a place (a sensor's or a reference's) along x, y or z; the one giving the highest
    rank of the inertial-parameter map, then the lowest condition, is taken.
    """
    chosen: list[tuple[int, int]] = []
    current = loads
    best_rank, best_cond = rank, cond
    while len(chosen) < 3:
        best = (-1, math.inf, 0, 0)
        for i, place in enumerate(places):
            for axis in range(3):
                extra = loads_of(place[None], np.eye(3)[axis][None])
                r, c = _condition(_parameter_map(mass_s, np.hstack([current, extra])))[:2]
                if r > best[0] or (r == best[0] and c < best[1]):
                    best = (r, c, i, axis)
        chosen.append((best[2], best[3]))
        current = np.hstack([current, loads_of(places[best[2]][None], np.eye(3)[best[3]][None])])
        best_rank, best_cond = best[0], best[1]
        if _accepted(best_rank, best_cond) or _accepted(rank, cond):
            break
    return chosen, int(best_rank), float(best_cond)


def _participation(body: Body | None, rpos: Array, rdirs: Array) -> tuple[Array | None, Array | None]:
    """Each rigid-body mode's largest participation in the references' loads, and the modes' frequencies (Hz).

    None, None without a body on mounts (or when its modes cannot be computed).
    """
    if body is None or not body.mounts:
        return None, None
    from rigidid.core.simulate import system_matrices

    m_cg, k_cg, _ = system_matrices(body)
    eigvals, psi = _mass_normal_modes(k_cg, m_cg)
    if eigvals is None:
        return None, None
    g_cg = sensor_matrix(rpos, rdirs, np.asarray(body.center_of_gravity, dtype=float)).T  # (6, q)
    norms = np.sqrt(np.einsum("aj,aj->j", g_cg, np.linalg.solve(m_cg, g_cg)))
    participation: Array = np.max(np.abs(psi.T @ g_cg) / norms, axis=1)
    frequencies: Array = np.sqrt(np.clip(eigvals, 0.0, None)) / (2.0 * np.pi)
    return participation, frequencies


def _reference_statement(
    q: int, rank: int, cond: float, ok: bool, coverage: Array, weakest_load: str, weakest_parameter: str
) -> str:
    """What the references determine, and the load they miss or give least of."""
    subject = "the reference" if q == 1 else f"the {q} references"
    absent = [name for name, v in zip(RIGID_LOADS, coverage, strict=True) if v < 1e-9]
    if absent:
        listed = absent[0] if len(absent) == 1 else ", a ".join(absent[:-1]) + " or a " + absent[-1]
        missing = f"no reference gives a {listed}"
    else:
        missing = f"the weakest load is the {weakest_load} ({coverage.min():.0%} of the strongest)"
    if q == 2 and rank < 10:
        missing += (
            "; two references never determine the inertia about the axis normal to the two rotations "
            "they cause: a third is needed"
        )
    if ok:
        return (
            f"{subject} determine{'s' if q == 1 else ''} mass, CG and inertia from the mass line "
            f"(condition {cond:.3g}); {missing}"
        )
    if rank < 10:
        return f"{subject} leave{'s' if q == 1 else ''} {weakest_parameter} undetermined (rank {rank} of 10); {missing}"
    return (
        f"{subject} determine{'s' if q == 1 else ''} {weakest_parameter} poorly (condition {cond:.3g} > "
        f"{REFERENCE_CONDITION_LIMIT:g}); {missing}"
    )


def _sensor_candidates(
    positions: Array, candidates: ArrayLike | None, candidate_directions: ArrayLike | None
) -> tuple[Array, Array]:
    """Candidate sensors (positions, unit directions): each candidate place along x, y and z unless directed."""
    cand = candidate_grid(positions) if candidates is None else np.asarray(candidates, dtype=float).reshape(-1, 3)
    if candidate_directions is None:
        return np.repeat(cand, 3, axis=0), np.tile(np.eye(3), (cand.shape[0], 1))
    c_dir = normalise_directions(candidate_directions)
    if c_dir.shape != cand.shape:
        raise InputError(f"candidate directions must match candidates {cand.shape}, got {c_dir.shape}")
    return cand, c_dir


def _suggestion_text(
    places: Array,
    sensors: int,
    chosen: list[tuple[int, int]],
    rank: int,
    cond: float,
    names: tuple[str, ...] | None,
    unit: str,
) -> str:
    """The references to add, in words: where (a sensor's or a reference's place), along which axis."""
    labels = list(names or [f"#{i + 1}" for i in range(sensors)])
    labels += [f"reference #{j + 1}" for j in range(places.shape[0] - sensors)]
    unit_text = " " + unit if unit else ""
    parts = []
    for i, axis in chosen:
        where = f"sensor {labels[i]}" if i < sensors else labels[i]
        coords = ", ".join(f"{v:.4g}" for v in places[i])
        parts.append(f"along +{'xyz'[axis]} at {where} ({coords}{unit_text})")
    return f"add a reference {' and one '.join(parts)}: " + (
        f"condition {cond:.3g}" if rank == 10 else f"rank {rank} of 10"
    )


def _participation_text(participation: Array | None, frequencies: Array | None) -> str:
    """Whether the references excite every rigid-body mode (empty without a body on mounts)."""
    if participation is None or frequencies is None:
        return ""
    k = int(np.argmin(participation))
    if participation[k] < PARTICIPATION_MIN:
        return (
            f"; rigid-body mode {k + 1} ({frequencies[k]:.3g} Hz) is not excited "
            f"(participation {participation[k]:.1%} < {PARTICIPATION_MIN:.0%})"
        )
    return f"; every rigid-body mode is excited (least: mode {k + 1}, {participation[k]:.0%})"
