"""The Python API: what the command line does, as functions a notebook can call.

>>> import rigidid
>>> layout = rigidid.load_layout("samples/paper-1994/layout.json")  # doctest: +SKIP
>>> modes = rigidid.load_modes("samples/paper-1994/modes.csv", layout)  # doctest: +SKIP
>>> result = rigidid.identify(layout, modes)  # doctest: +SKIP
>>> result.identification.center_of_gravity  # doctest: +SKIP
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import NDArray

from rigidid.core.identify import Identification, Method
from rigidid.core.identify import identify as identify_core
from rigidid.core.selection import rigid_fit_residuals, select_rigid_modes
from rigidid.core.simulate import Body, Mount, add_noise, body_modes
from rigidid.core.statespace import modal_from_poles, poles_from_modal
from rigidid.errors import InputError
from rigidid.io import files
from rigidid.io.atomic import write_text_atomic
from rigidid.io.files import ModeTable
from rigidid.models import BodyFile, LayoutFile, MountsFile, ReferencesFile
from rigidid.progress import no_progress

if TYPE_CHECKING:
    from rigidid.core.frfmodes import ScaledBody
    from rigidid.core.mounts import MountModel, MountModelPrediction, MountRates, TorqueRollAxis
    from rigidid.core.noise import NoiseLevels
    from rigidid.core.plan import LayoutReport, Prediction, ReferenceReport, SensorPlan
    from rigidid.core.record_spread import RecordSpread
    from rigidid.core.timedomain import ModalEstimate
    from rigidid.core.timedomain.refine import RecordBound
    from rigidid.core.uncertainty import Uncertainty
    from rigidid.progress import ProgressCallback

__all__ = [
    "Arrays",
    "IdentifyResult",
    "PlanResult",
    "TestData",
    "body_from_file",
    "body_with_mounts",
    "convert",
    "estimate_modes",
    "identify",
    "load_arrays",
    "load_layout",
    "load_modes",
    "load_records",
    "load_uff",
    "plan",
    "report",
    "report_pngs",
    "simulate",
    "simulate_records",
    "with_mounts",
    "with_record_spread",
    "with_refinement",
]

PathLike = str | os.PathLike[str]
Selection = Literal["all", "given", "automatic"]


@dataclass(frozen=True)
class IdentifyResult:
    """An identification with the context needed to report it.

    Attributes
    ----------
    identification : Identification
        The numbers (CG, inertia, stiffness, damping, diagnostics).
    units : dict
        ``{"length": ..., "mass": ...}`` of the layout.
    sensor_ids : tuple of str
    positions, directions : ndarray, shape (p, 3)
        The layout (directions as unit vectors).
    modes_used : tuple of int
        Mode labels used, in the order of the identification's modes.
    selection : {"all", "given", "automatic"}
        How the six modes were chosen.
    candidate_residuals : dict or None
        Rigid-body fit residual of every mode given, when chosen automatically.
    poles : ndarray of complex, shape (6,)
        Poles of the modes used (rad/s).
    shapes : ndarray of complex, shape (p, 6)
        Their shapes at the sensors.
    uncertainty : Uncertainty or None
        Monte Carlo intervals, when asked for.
    record_spread : RecordSpread or None
        Data-driven intervals from interleaved segments of the records
        (:func:`with_record_spread`).
    layout_name : str or None
        The layout's ``name``.
    mounts : Mounts or None
        Per-mount rates fitted to the stiffness and damping (:func:`with_mounts`).
    torque_roll_axis : TorqueRollAxis or None
        The rotation under a torque about a given axis (:func:`with_mounts`).
    mount_model : MountModelFit or None
        With ``method="mounts"``: the mount model's fit against the free route.
    record_bound : RecordBound or None
        Cramér-Rao intervals of the output-error refinement on the records
        (:func:`with_refinement`); set when the refinement replaced the
        structured answer.
    scaled : ScaledBody or None
        When the six modes used are scaled to unity modal A (``modes.csv``
        column ``scaling`` ``modal_a``, written by ``rigidid modes --frf``):
        the mass, CG, inertia, stiffness and damping in absolute units from the
        scaled modes (:func:`rigidid.core.frfmodes.body_from_scaled_shapes`).
    """

    identification: Identification
    units: dict[str, str]
    sensor_ids: tuple[str, ...]
    positions: NDArray[np.float64]
    directions: NDArray[np.float64]
    modes_used: tuple[int, ...]
    selection: Selection
    candidate_residuals: dict[int, float] | None = None
    poles: NDArray[np.complex128] | None = None
    shapes: NDArray[np.complex128] | None = None
    uncertainty: Uncertainty | None = None
    record_spread: RecordSpread | None = None
    record_bound: RecordBound | None = None
    layout_name: str | None = None
    mounts: Mounts | None = None
    torque_roll_axis: TorqueRollAxis | None = None
    mount_model: MountModelFit | None = None
    scaled: ScaledBody | None = None


@dataclass(frozen=True)
class MountModelFit:
    """How well the mount model explains the modes, against the free 6x6 matrices.

    Attributes
    ----------
    model : MountModel
        The fit (rates per mass, residual, parameter count).
    free_residual : float or None
        The same eigenproblem residual for the free route (``method="structured"``),
        when six modes allow it.
    free_parameters : int
        Unknowns of the free route: CG, ``J/m``, ``K/m`` and ``C/m`` (51).
    """

    model: MountModel
    residual: float
    free_residual: float | None
    free_parameters: int = 51
    noise: NoiseLevels | None = None

    def _aic(self, residual: float, parameters: int) -> float:
        n = self.model.equations
        return float(n * np.log(max(residual**2, 1e-30)) + 2 * parameters)

    @property
    def aic(self) -> float:
        """Akaike's criterion ``N ln(RSS / N) + 2 P`` of the mount model (RSS floored at 1e-30 N)."""
        return self._aic(self.residual, self.model.parameters)

    @property
    def free_aic(self) -> float | None:
        """Akaike's criterion of the free route on the same equations."""
        return None if self.free_residual is None else self._aic(self.free_residual, self.free_parameters)

    @property
    def adequate(self) -> bool | None:
        """True when the mount model explains the modes as well as the free matrices (lower or equal AIC)."""
        free = self.free_aic
        return None if free is None else bool(self.aic <= free)

    @property
    def verdict(self) -> bool | None:
        """Does the mount model explain the modes: the F test's (:attr:`MountModel.adequate`) when it
        could be made, else :attr:`adequate` (AIC, which flags correct noisy models too often)."""
        return self.adequate if self.model.adequate is None else self.model.adequate


@dataclass(frozen=True)
class Mounts:
    """Per-mount rates of an identification, with the mounts' ids and positions.

    Attributes
    ----------
    ids : tuple of str
        Mount names (``"1"``, ``"2"``... when the file gives none).
    positions : ndarray, shape (n, 3)
        Where they act (length).
    rates : MountRates
        Rates along each mount's axes (force units come from the presentation).
    nominal : ndarray, shape (n, 3) or None
        The file's nominal rates along the same axes, when every mount gives them.
    """

    ids: tuple[str, ...]
    positions: NDArray[np.float64]
    rates: MountRates
    nominal: NDArray[np.float64] | None = None
    groups: tuple[str | None, ...] | None = None


def load_layout(path: PathLike) -> LayoutFile:
    """Read and validate ``layout.json`` (see :func:`rigidid.io.files.load_layout`)."""
    return files.load_layout(path)


def load_modes(path: PathLike, layout: LayoutFile) -> ModeTable:
    """Read and validate ``modes.csv`` against a layout (see :func:`rigidid.io.files.load_modes`)."""
    return files.load_modes(path, [s.id for s in layout.sensors])


@dataclass(frozen=True)
class Arrays:
    """A layout and its modes as the numerical core takes them.

    Attributes
    ----------
    sensor_ids : tuple of str
    positions, directions : ndarray, shape (p, 3)
        Sensor locations (length) and unit measuring axes.
    labels : tuple of int
        Mode labels.
    poles : ndarray of complex, shape (n,)
        One pole per mode (rad/s).
    shapes : ndarray of complex, shape (p, n)
    mass : float or None
    """

    sensor_ids: tuple[str, ...]
    positions: NDArray[np.float64]
    directions: NDArray[np.float64]
    labels: tuple[int, ...]
    poles: NDArray[np.complex128]
    shapes: NDArray[np.complex128]
    mass: float | None


def load_arrays(layout: PathLike, modes: PathLike) -> Arrays:
    """Read ``layout.json`` and ``modes.csv`` into the arrays :mod:`rigidid.core` takes."""
    lay = load_layout(layout)
    table = load_modes(modes, lay)
    ids, positions, directions = files.layout_arrays(lay)
    poles = poles_from_modal(table.frequency_hz, table.damping_ratio)
    return Arrays(ids, positions, directions, table.labels, poles, table.shapes, lay.mass)


def _choose_modes(
    modes: ModeTable,
    transformation: NDArray[np.float64],
    wanted: Sequence[int] | None,
    source: str | None,
    fewest: int = 6,
) -> tuple[tuple[int, ...], Selection, dict[int, float] | None]:
    if wanted is not None:
        labels = tuple(int(m) for m in wanted)
        unknown = [m for m in labels if m not in modes.labels]
        if unknown:
            raise InputError(
                f"mode {unknown[0]} is not in the modes file (it has {list(modes.labels)})", source="modes_used"
            )
        if not fewest <= len(labels) <= 6 or len(set(labels)) != len(labels):
            wanted_text = "six" if fewest == 6 else f"{fewest} or 6"
            raise InputError(f"give {wanted_text} different mode labels, got {list(labels)}", source="modes_used")
        return labels, "given", None
    n = len(modes.labels)
    if n < fewest:
        raise InputError(f"{n} modes given; the six rigid-body modes are needed", source=source)
    if n <= 6:
        return modes.labels, "all", None
    if transformation.shape[0] <= 6:
        raise InputError(
            f"{n} modes given and only {transformation.shape[0]} sensors: with six sensors every shape fits "
            "rigid-body motion, so the rigid modes cannot be chosen; name them (`modes_used`)",
            source=source,
        )
    chosen = tuple(modes.labels[i] for i in select_rigid_modes(transformation, modes.shapes))
    residual = rigid_fit_residuals(transformation, modes.shapes)
    return chosen, "automatic", {label: float(r) for label, r in zip(modes.labels, residual, strict=True)}


def identify(
    layout: LayoutFile | PathLike,
    modes: ModeTable | PathLike,
    *,
    mass: float | None = None,
    modes_used: Sequence[int] | None = None,
    method: Method | Literal["mounts"] = "structured",
    uncertainty: int = 0,
    noise: NoiseLevels | Mapping[str, float] | None = None,
    seed: int | None = 0,
    progress: ProgressCallback | None = None,
    mounts: PathLike | MountsFile | None = None,
) -> IdentifyResult:
    """Identify CG, inertia, stiffness and damping from a layout and its modes.

    Parameters
    ----------
    layout : LayoutFile or path-like
        The sensors (and optionally the mass).
    modes : ModeTable or path-like
        Modal parameters; with more than six modes the six rigid-body modes
        are chosen (see `modes_used`).
    mass : float, optional
        Mass of the body; overrides the layout's ``mass``.
    modes_used : sequence of int, optional
        The six mode labels to use. Without it exactly six modes are used as
        given, or, with more than six modes and more than six sensors, the six
        whose shapes fit rigid-body motion best.
    method : {"structured", "paper", "mounts"}
        See :func:`rigidid.core.identify.identify`; ``"mounts"``: CG, inertia and
        per-mount rates fitted together (:func:`rigidid.core.mounts.identify_mount_model`),
        which needs `mounts` and works with five modes.
    uncertainty : int
        Number of Monte Carlo draws for uncertainty intervals (0: none).
    noise : NoiseLevels or mapping, optional
        Measurement uncertainty to propagate. By default
        :data:`~rigidid.core.noise.DEFAULT_NOISE` with the shape noise
        estimated from the rigid-body fit residuals when there are more than
        six sensors (:func:`~rigidid.core.noise.estimate_noise`); a
        mapping (e.g. ``{"shape": 0.02, "angle_deg": 1.0}``) overrides those
        defaults field by field.
    seed : int, optional
        Seed of the Monte Carlo draws.
    progress : callable, optional
        ``progress(task, done, total)`` around the Monte Carlo draws (total
        unknown while they run).

    Returns
    -------
    IdentifyResult

    Raises
    ------
    InputError
        Bad files or arguments.
    IdentificationError
        Data that determine no rigid body.
    """
    from rigidid.core.geometry import local_sensor_matrix

    if uncertainty and uncertainty < 2:
        raise InputError(f"need at least 2 draws, got {uncertainty}", source="uncertainty")
    lay = layout if isinstance(layout, LayoutFile) else load_layout(layout)
    source = None if isinstance(modes, ModeTable) else str(modes)
    table = modes if isinstance(modes, ModeTable) else load_modes(modes, lay)
    ids, positions, directions = files.layout_arrays(lay)
    if table.sensor_ids != ids:
        raise InputError("the modes' sensors do not match the layout's sensors", source=source)
    t = local_sensor_matrix(positions, directions)
    if method == "mounts" and mounts is None:
        raise InputError("the mount model needs the mounts (a mounts.json or body.json)", source="mounts")
    if method == "mounts" and uncertainty:
        raise InputError("Monte Carlo intervals are computed for the structured method only", source="uncertainty")
    labels, selection, residuals = _choose_modes(table, t, modes_used, source, 5 if method == "mounts" else 6)
    used = table.subset(labels)
    notes = _check_data(t, used, ids)
    poles = poles_from_modal(used.frequency_hz, used.damping_ratio)
    body_mass = mass if mass is not None else lay.mass
    fit = None
    if method == "mounts":
        assert mounts is not None
        result, fit = _mount_model(positions, directions, poles, used.shapes, body_mass, mounts, lay, noise)
    else:
        result = identify_core(positions, directions, poles, used.shapes, mass=body_mass, method=method)
    result = _check_result(result, labels, lay.units.length, notes)
    intervals = None
    if uncertainty:
        from rigidid.core.noise import estimate_noise
        from rigidid.core.uncertainty import propagate

        if isinstance(noise, Mapping) or noise is None:
            levels = replace(estimate_noise(positions, directions, used.shapes), **dict(noise or {}))
        else:
            levels = noise
        step = progress or no_progress
        task = f"{uncertainty} Monte Carlo draws"
        step(task, 0, uncertainty)
        intervals = propagate(
            positions, directions, poles, used.shapes, mass=body_mass, noise=levels, draws=uncertainty, seed=seed,
            progress=lambda _, done, total: step(task, done, total),
        )  # fmt: skip
    return IdentifyResult(
        identification=result,
        units={"length": lay.units.length, "mass": lay.units.mass},
        sensor_ids=ids,
        positions=positions,
        directions=directions,
        modes_used=labels,
        selection=selection,
        candidate_residuals=residuals,
        poles=poles,
        shapes=used.shapes,
        uncertainty=intervals,
        layout_name=lay.name,
        mount_model=fit,
        scaled=_scaled_body(used, poles, positions, directions),
    )


def _scaled_body(
    used: ModeTable, poles: NDArray[np.complex128], positions: NDArray[np.float64], directions: NDArray[np.float64]
) -> ScaledBody | None:
    """The body from six modes scaled to unity modal A by the force (``scaling`` all ``modal_a``), else None."""
    if used.scaling is None or len(used.scaling) != 6 or any(s != "modal_a" for s in used.scaling):
        return None
    from rigidid.core.frfmodes import body_from_scaled_shapes
    from rigidid.errors import IdentificationError, IllConditionedWarning, Notice, emit

    try:
        return body_from_scaled_shapes(poles, used.shapes, positions, directions)
    except IdentificationError as exc:
        emit([Notice(IllConditionedWarning, f"the modal_a scaled modes give no mass: {exc}")])
        return None


def _suspect_mode(ident: Identification) -> str:
    """A sentence naming a used mode that fits rigid motion far worse than the others (an elastic mode?), or ''."""
    from rigidid.core.selection import elastic_suspect

    residual = np.asarray(ident.diagnostics.rigid_fit_residual, dtype=float)
    k = elastic_suspect(residual)
    if k is None:
        return ""
    return (
        f"; the mode at {ident.frequency_hz[k]:.4g} Hz fits rigid-body motion with a residual of "
        f"{residual[k]:.2f} against {float(np.median(np.delete(residual, k))):.2g} for the others: it may be an "
        "elastic mode taken for a rigid one, which makes this answer wrong too; estimate one more mode "
        "(--n-modes 7) and choose the six rigid-body modes (--modes), or end --band below it"
    )


def _check_data(t: NDArray[np.float64], used: ModeTable, ids: tuple[str, ...]) -> list[str]:
    """Refuse modes that are not rigid-body modes; warn of a misfitting sensor or damping in percent."""
    import warnings

    from rigidid.core.checks import nonrigid_modes, percent_damping, sensor_outliers
    from rigidid.errors import DampingUnitWarning, IdentificationError, SensorFitWarning

    if t.shape[0] > 6:
        bad = nonrigid_modes(used.labels, rigid_fit_residuals(t, used.shapes))
        if bad is not None:
            many = len(bad.labels) > 1
            labels = ", ".join(str(label) for label in bad.labels)
            values = ", ".join(f"{r:.2f}" for r in bad.residuals)
            raise IdentificationError(
                f"mode{'s' if many else ''} {labels} {'are' if many else 'is'} not {'' if many else 'a '}rigid-body "
                f"mode{'s' if many else ''}: {'their shapes fit' if many else 'its shape fits'} rigid-body motion "
                f"with a residual of {values} (rigid-body modes fit to about 0.2 or better); choose the six "
                "rigid-body modes with --modes"
            )
    notes: list[str] = []
    for finding in sensor_outliers(t, used.shapes):
        notes.append(
            f"sensor {ids[finding.index]!r} does not move with the others as a rigid body: its readings are "
            f"{100 * finding.misfit:.0f} % (RMS over the modes, of each mode's RMS reading) away from the rigid "
            f"motion of the other sensors (median sensor {100 * finding.typical:.1f} %); check its position, "
            "direction and sign in the layout"
        )
        warnings.warn(notes[-1], SensorFitWarning, stacklevel=3)
    percent = percent_damping(used.damping_ratio)
    if percent is not None:
        shown = ", ".join(f"{z:.3g}" for z in percent.damping_ratio)
        notes.append(
            f"the damping ratios are mostly above 10 % of critical ({shown}); damping_ratio is a fraction "
            "(0.0039 for 0.39 %): were they given in percent?"
        )
        warnings.warn(notes[-1], DampingUnitWarning, stacklevel=3)
    return notes


def _check_result(result: Identification, labels: Sequence[int], length: str, notes: list[str]) -> Identification:
    """Refuse an inertia that is not positive definite; add the data checks' notes to the diagnostics."""
    from rigidid.core.checks import inertia_not_positive
    from rigidid.errors import IdentificationError

    bad = inertia_not_positive(result.inertia_per_mass)
    if bad is not None:
        moments = ", ".join(f"{v:.4g}" for v in bad.principal_moments_per_mass)
        raise IdentificationError(
            f"modes {', '.join(str(m) for m in labels)} determine no rigid body: the inertia tensor they give is "
            f"not positive definite (principal moments per mass {moments} {length}^2); check that these are the "
            "six rigid-body modes and that the layout matches the test"
        )
    if not notes:
        return result
    return replace(result, diagnostics=replace(result.diagnostics, warnings=(*result.diagnostics.warnings, *notes)))


def body_from_file(body: BodyFile) -> Body:
    """The core :class:`~rigidid.core.simulate.Body` of a validated ``body.json``."""
    return Body(
        mass=body.mass,
        center_of_gravity=np.array(body.center_of_gravity, dtype=float),
        inertia_tensor=np.array(body.inertia_tensor, dtype=float),
        mounts=tuple(Mount.from_values(m.position, m.stiffness, m.damping) for m in body.mounts),
    )


def body_with_mounts(body: BodyFile | PathLike, mounts: PathLike | MountsFile) -> BodyFile:
    """`body` with its mounts replaced by those of ``mounts.json`` (each with its ``stiffness``).

    Parameters
    ----------
    body : BodyFile or path-like
        ``body.json``: mass, CG and inertia are kept.
    mounts : path-like or MountsFile
        Positions, ``stiffness`` and optional ``damping`` of every mount (as in
        ``body.json``: three values along the layout's x, y, z or a 3x3 matrix),
        in the body's units.

    Returns
    -------
    BodyFile

    Raises
    ------
    InputError
        A bad file, units that differ from the body's, or a mount without stiffness.
    """
    from rigidid.models import MountSpec

    spec = body if isinstance(body, BodyFile) else files.load_body(body)
    source = None if isinstance(mounts, MountsFile) else str(mounts)
    _, _, entries = _mount_spec(mounts, {"length": spec.units.length, "mass": spec.units.mass})
    replaced = []
    for k, m in enumerate(entries.mounts):
        if m.stiffness is None:
            raise InputError("a mount without stiffness cannot be simulated", source=source, location=f"mounts.{k}")
        extra = {} if m.damping is None else {"damping": m.damping}
        replaced.append(MountSpec(position=m.position, stiffness=m.stiffness, **extra))
    return spec.model_copy(update={"mounts": replaced})


def simulate(
    body: BodyFile | PathLike,
    layout: LayoutFile | PathLike,
    *,
    frequency_noise: float = 0.0,
    damping_noise: float = 0.0,
    shape_noise: float = 0.0,
    seed: int | None = None,
) -> ModeTable:
    """The six rigid-body modes of a body on its mounts, as the layout's sensors read them.

    Parameters
    ----------
    body : BodyFile or path-like
        Mass, CG, inertia tensor and mounts (``body.json``).
    layout : LayoutFile or path-like
        The sensors.
    frequency_noise, damping_noise : float
        Relative standard deviation of Gaussian noise on each natural
        frequency and damping ratio (0.001 = 0.1 %).
    shape_noise : float
        Complex Gaussian noise on the shape values, relative to each mode's
        RMS value.
    seed : int, optional
        Seed of the noise.

    Returns
    -------
    ModeTable
        Modes labelled 1-6 in ascending frequency, shapes scaled to a largest
        value of 1.

    Raises
    ------
    InputError
        Bad files, or units of the body and layout that differ.
    """
    lay = layout if isinstance(layout, LayoutFile) else files.load_layout(layout, require_rank=False)
    spec = body if isinstance(body, BodyFile) else files.load_body(body)
    _same_units(spec, lay, None if isinstance(body, BodyFile) else str(body))
    ids, positions, directions = files.layout_arrays(lay)
    modes = body_modes(body_from_file(spec), positions, directions)
    if frequency_noise or damping_noise or shape_noise:
        modes = add_noise(modes, frequency=frequency_noise, damping=damping_noise, shape=shape_noise, seed=seed)
    f, z = modal_from_poles(modes.poles)
    return ModeTable.numbered(f, z, ids, modes.shapes)


@dataclass(frozen=True)
class PlanResult:
    """A sensor layout checked before the test, with predictions when a body estimate is given.

    Attributes
    ----------
    units : dict
        The layout's units.
    report : LayoutReport
        Rank, condition and findings in words.
    prediction : Prediction or None
        Predicted standard deviations of CG and inertia (needs a body).
    suggestions : SensorPlan or None
        The sensors to add, best first (needs a body and ``add > 0``).
    references : ReferenceReport or None
        Whether the reference (hammer) points of an FRF test excite all six
        rigid-body motions (needs ``references``).
    """

    units: dict[str, str]
    report: LayoutReport
    prediction: Prediction | None = None
    suggestions: SensorPlan | None = None
    references: ReferenceReport | None = None
    mount_split: tuple[int, int, str] | None = None
    mount_prediction: MountModelPrediction | None = None


def plan(
    layout: LayoutFile | PathLike,
    *,
    body: BodyFile | PathLike | None = None,
    candidates: LayoutFile | PathLike | None = None,
    add: int = 0,
    noise: Mapping[str, float] | None = None,
    draws: int = 1000,
    seed: int | None = 0,
    units: dict[str, str] | None = None,
    geometry: PathLike | None = None,
    progress: ProgressCallback | None = None,
    references: ReferencesFile | PathLike | None = None,
    mounts: PathLike | MountsFile | None = None,
) -> PlanResult:
    """Check a sensor layout before the test; predict and improve it with a body estimate.

    Parameters
    ----------
    layout : LayoutFile or path-like
        The planned sensors (any number, rank not required): ``layout.json``
        or a UFF file (its nodes and records give the sensors).
    body : BodyFile or path-like, optional
        An estimate of the body and its mounts (e.g. from CAD), in the layout's units.
    candidates : LayoutFile or path-like, optional
        Possible extra sensors, as a layout file (positions and directions); by
        default a 3 x 3 x 3 grid over the sensors' bounding box, each point tried
        along x, y and z.
    add : int
        How many sensors to suggest, one at a time (greedy).
    noise : mapping, optional
        Overrides of :data:`~rigidid.core.noise.DEFAULT_NOISE`
        (``frequency``, ``damping``, ``shape``, ``position``, ``angle_deg``).
    draws : int
        Monte Carlo draws of each prediction.
    seed : int, optional
        Seed of the draws.
    units : dict, optional
        ``{"length", "mass"}`` of a UFF layout without dataset 164.
    geometry : path-like, optional
        A UFF file completing a UFF layout (see :func:`load_uff`).
    progress : callable, optional
        ``progress(task, done, total)`` around the predictions and the search
        for sensors (total unknown while they run).
    references : ReferencesFile or path-like, optional
        ``references.json`` of an FRF test: checked with
        :func:`rigidid.core.plan.check_references` (about the body's CG and
        with its modes when a body is given).
    mounts : path-like or MountsFile, optional
        ``mounts.json`` (or a ``body.json``): whether this mount layout determines
        every per-mount rate (:func:`rigidid.core.mounts.split_uniqueness`),
        in :attr:`PlanResult.mount_split`; with `body`, also the mount model's
        predicted precision (:func:`rigidid.core.mounts.predict_mount_model`,
        at most 50 draws) in :attr:`PlanResult.mount_prediction`.

    Returns
    -------
    PlanResult

    Raises
    ------
    InputError
        Bad files, units that differ between files, ``add`` > 0 without a body.
    """
    from rigidid.core.noise import DEFAULT_NOISE
    from rigidid.core.plan import check_layout, predict_uncertainty, suggest_sensors

    if isinstance(layout, LayoutFile):
        lay = layout
    elif Path(layout).suffix.lower() in (".uff", ".unv"):
        lay = load_uff(layout, units=units, geometry=geometry).layout
    else:
        lay = files.load_layout(layout, require_rank=False)
    ids, positions, directions = files.layout_arrays(lay)
    layout_units: dict[str, str] = {"length": lay.units.length, "mass": lay.units.mass}
    report = check_layout(positions, directions, unit=lay.units.length, names=ids)
    split = None
    if mounts is not None:
        from rigidid.core.mounts import split_uniqueness

        where, axes, mount_spec = _mount_spec(mounts, layout_units)
        mount_groups = [m.group for m in mount_spec.mounts]
        split = split_uniqueness(where, axes, mount_groups)
    if body is None:
        if add:
            raise InputError("suggesting sensors needs a body estimate", source="add")
        return PlanResult(
            layout_units, report, references=_plan_references(references, lay, None), mount_split=split
        )
    spec = body if isinstance(body, BodyFile) else files.load_body(body)
    _same_units(spec, lay, None if isinstance(body, BodyFile) else str(body))
    core_body = body_from_file(spec)
    checked_refs = _plan_references(references, lay, core_body)
    levels = replace(DEFAULT_NOISE, **dict(noise or {}))
    prediction = None
    step = progress or no_progress
    if report.rank == 6:
        task = f"predicting the uncertainty ({draws} draws)"
        prediction = predict_uncertainty(
            core_body, positions, directions, noise=levels, draws=draws, seed=seed,
            progress=lambda _, done, total: step(task, done, total),
        )  # fmt: skip
    mount_prediction = None
    if mounts is not None and report.rank == 6:
        from rigidid.core.mounts import predict_mount_model

        step("predicting the mount model", 0, 1)
        mount_prediction = predict_mount_model(
            core_body, positions, directions, where, axes, groups=mount_groups, noise=levels, draws=min(draws, 50),
            seed=seed,
        )  # fmt: skip
        step("predicting the mount model", 1, 1)
    suggestions = None
    if add:
        if add < 0:
            raise InputError(f"must be positive, got {add}", source="add")
        cand_pos = cand_dir = None
        if candidates is not None:
            cand = (
                candidates if isinstance(candidates, LayoutFile) else files.load_layout(candidates, require_rank=False)
            )
            _same_units(cand, lay, None if isinstance(candidates, LayoutFile) else str(candidates))
            _, cand_pos, cand_dir = files.layout_arrays(cand)
        step(f"choosing {add} sensors to add", 0, add)
        suggestions = suggest_sensors(
            core_body,
            positions,
            directions,
            cand_pos,
            cand_dir,
            add=add,
            noise=levels,
            draws=min(draws, 300),
            seed=seed,
            progress=lambda _, done, total: step(f"choosing {add} sensors to add", done, total),
        )
    return PlanResult(layout_units, report, prediction, suggestions, checked_refs, split, mount_prediction)


def _plan_references(
    references: ReferencesFile | PathLike | None, layout: LayoutFile, body: Body | None
) -> ReferenceReport | None:
    """``plan --references``: the reference set checked against the layout (and the body estimate)."""
    if references is None:
        return None
    from rigidid.core.plan import check_references
    from rigidid.io.frf import load_references, reference_arrays

    refs = references if isinstance(references, ReferencesFile) else load_references(references)
    if refs.units is not None and refs.units != layout.units:
        source = None if isinstance(references, ReferencesFile) else str(references)
        raise InputError("units differ from the layout's units", source=source, location="units")
    ids, positions, directions = files.layout_arrays(layout)
    _, rpos, rdirs = reference_arrays(refs)
    return check_references(positions, directions, rpos, rdirs, body=body, unit=layout.units.length, names=ids)


def _same_units(other: BodyFile | LayoutFile, layout: LayoutFile, source: str | None) -> None:
    if other.units != layout.units:
        raise InputError(
            f"units ({other.units.length}, {other.units.mass}) differ from layout units "
            f"({layout.units.length}, {layout.units.mass})",
            source=source,
            location="units",
        )


# --------------------------------------------------------------------------- time records, UFF, report


@dataclass(frozen=True)
class TestData:
    """What a test file set provides: the layout, and modes and/or time records.

    Attributes
    ----------
    layout : LayoutFile
    modes : ModeTable or None
    records : list of (ndarray, float)
        Per impact: samples x sensors (layout order) and the sample interval (s).
    record_names : list of str
        Where each record came from.
    """

    layout: LayoutFile
    modes: ModeTable | None = None
    records: list[tuple[NDArray[np.float64], float]] = field(default_factory=list)
    record_names: list[str] = field(default_factory=list)


def load_records(paths: Sequence[PathLike], layout: LayoutFile) -> list[tuple[NDArray[np.float64], float]]:
    """Read impact records (CSV, .npy, .npz, .mat or .h5 files, one per impact), columns in layout order.

    Parameters
    ----------
    paths : sequence of path-like
        One file per impact.
    layout : LayoutFile
        The sensors; every record has one column per sensor id.

    Returns
    -------
    list of (ndarray, float)
        Per record: samples x sensors, and the sample interval (s).

    Raises
    ------
    InputError
        See :func:`rigidid.io.records.read_record`.
    """
    from rigidid.io.records import read_record

    ids = [s.id for s in layout.sensors]
    return [read_record(p, ids) for p in paths]


def load_uff(path: PathLike, *, units: dict[str, str] | None = None, geometry: PathLike | None = None) -> TestData:
    """Read a test from a universal file (datasets 15/2411, 58, 55, 164) through pyuff.

    Parameters
    ----------
    path : path-like
        The ``.uff``/``.unv`` file.
    units : dict, optional
        ``{"length", "mass"}`` when the file has no dataset 164.
    geometry : path-like, optional
        A second UFF file with the nodes (15/2411), coordinate systems
        (18/2420), units (164) and name (151) that `path` lacks.

    Returns
    -------
    TestData
        Layout (sensors from the records' nodes and signed directions, or from
        the mode shapes), the modes of dataset 55 if any, and the time records.

    Raises
    ------
    InputError
        Missing or contradictory pieces, naming the dataset and node.
    """
    from pydantic import ValidationError

    from rigidid.io.uff import read_uff

    src = str(path)
    contents = read_uff(path, units=units, geometry=geometry)
    try:
        layout = LayoutFile.model_validate(contents.layout)
    except ValidationError as exc:
        raise InputError(
            f"the sensors it describes are not a valid layout: {exc.errors()[0]['msg']}", source=src
        ) from None
    modes = None
    if contents.mode_rows:
        values = [files.ModeValue(None, m, f, z, sid, complex(re, im)) for m, f, z, sid, re, im in contents.mode_rows]
        modes = files.mode_table_from_rows(values, tuple(s.id for s in layout.sensors), src)
    records: list[tuple[NDArray[np.float64], float]] = []
    for record in contents.records:
        time = np.asarray(record.time, dtype=float)
        missing = [s.id for s in layout.sensors if s.id not in record.sensor_ids]
        if missing:
            label = contents.record_labels[len(records)] if len(contents.record_labels) > len(records) else "a record"
            raise InputError(f"{label} has no record of sensor {missing[0]}", source=src)
        order = [record.sensor_ids.index(sid) for sid in (s.id for s in layout.sensors)]
        data = np.asarray(record.data, dtype=float)
        if order != list(range(data.shape[1])):  # no copy when the file has the layout's order
            data = data[:, order]
        records.append((data, float(time[1] - time[0])))
    return TestData(layout, modes, records, list(contents.record_labels))


def estimate_modes(
    layout: LayoutFile | PathLike,
    records: Sequence[PathLike] | Sequence[tuple[NDArray[np.float64], float]],
    *,
    method: str | None = None,
    n_modes: int = 6,
    band: tuple[float, float] | None = None,
    max_order: int | None = None,
    decimate: int | None = None,
    progress: ProgressCallback | None = None,
) -> tuple[ModeTable, ModalEstimate]:
    """Modal parameters from impact records (the paper's time-domain step).

    Parameters
    ----------
    layout : LayoutFile or path-like
        The sensors.
    records : sequence of path-like, or of (data, dt)
        One free-decay record per impact: ``records.csv`` files, or arrays
        (samples x sensors in layout order) with their sample interval (s).
    method : {"era", "ar"}, optional
        Estimator (default :data:`rigidid.core.timedomain.DEFAULT_METHOD`).
    n_modes : int
        Number of modes to find (6 for the rigid-body modes; more when elastic
        modes share the band, then :func:`identify` chooses the rigid six).
    band : (float, float), optional
        Frequency band (Hz).
    max_order : int, optional
        Highest model order of the stabilisation sweep.
    decimate : int, optional
        Decimation factor (default chosen from the records' spectrum).
    progress : ProgressCallback, optional
        Progress of the decimation and the model-order sweep.

    Returns
    -------
    modes : ModeTable
        Modes labelled 1..n_modes in ascending frequency.
    estimate : ModalEstimate
        Everything the estimator found, the stabilisation diagram included.

    Raises
    ------
    InputError
        Bad records or records of different sample rates.
    IdentificationError
        Fewer than `n_modes` stable modes.
    """
    from rigidid.core.timedomain import DEFAULT_METHOD
    from rigidid.core.timedomain import estimate_modes as estimate

    lay = layout if isinstance(layout, LayoutFile) else load_layout(layout)
    if not records:
        raise InputError("no records given", source="records")
    arrays: list[tuple[NDArray[np.float64], float]] = []
    paths: list[PathLike] = []
    for item in records:
        if isinstance(item, tuple):
            arrays.append(item)
        else:
            paths.append(item)
    if paths and not arrays:
        return _estimate_streamed(lay, paths, method, n_modes, band, max_order, decimate, progress)
    arrays += load_records(paths, lay)
    dts = [dt for _, dt in arrays]
    if max(dts) - min(dts) > 1e-9 * max(dts):
        raise InputError(
            f"records have different sample intervals ({min(dts):.6g} to {max(dts):.6g} s)", source="records"
        )
    from rigidid.core.timedomain.clipping import clipped_channels

    ids = tuple(s.id for s in lay.sensors)
    kept = _unclipped(ids, [clipped_channels([data]) for data, _ in arrays])
    columns = list(range(len(ids)) if kept is None else kept)
    result = estimate(
        [data[:, columns] for data, _ in arrays],
        dts[0],
        method=method or DEFAULT_METHOD,  # type: ignore[arg-type]
        n_modes=n_modes,
        band=band,
        max_order=max_order,
        decimate=decimate,
        progress=progress,
    )
    if kept is not None:
        result = replace(result, channels=kept)
    table = ModeTable.numbered(result.frequency_hz, result.damping_ratio, [ids[c] for c in columns], result.shapes)
    return table, result


def _unclipped(ids: Sequence[str], clipped: Sequence[NDArray[np.bool_]]) -> tuple[int, ...] | None:
    """The channels to fit when some record has clipped ones (None: all), with a ClippedChannelWarning naming them.

    Parameters
    ----------
    ids : sequence of str
        The sensors, in record column order.
    clipped : sequence of ndarray of bool
        Per record, :func:`~rigidid.core.timedomain.clipping.clipped_channels`.

    Returns
    -------
    tuple of int or None
        The columns kept; None when none is clipped, or when leaving them out
        would leave fewer than six sensors (then they are kept, and the warning says so).
    """
    import warnings

    from rigidid.errors import ClippedChannelWarning

    flags = np.zeros(len(ids), dtype=bool)
    where: dict[int, list[int]] = {}
    for k, mask in enumerate(clipped):
        if mask is None:
            continue
        flags |= mask
        for c in np.flatnonzero(mask):
            where.setdefault(int(c), []).append(k + 1)
    if not flags.any():
        return None
    named = ", ".join(f"{ids[c]!r} (record {', '.join(map(str, where[c]))})" for c in sorted(where))
    kept = tuple(int(c) for c in np.flatnonzero(~flags))
    if len(kept) < 6:
        warnings.warn(
            f"clipped channels (flat tops at their peak): {named}; kept in the fit, since leaving them out "
            f"leaves {len(kept)} sensors of the 6 needed: the answer is biased by the overload",
            ClippedChannelWarning,
            stacklevel=3,
        )
        return None
    warnings.warn(
        f"clipped channels (flat tops at their peak) left out of the fit: {named}",
        ClippedChannelWarning,
        stacklevel=3,
    )
    return kept


def fitted_layout(layout: LayoutFile, modes: ModeTable) -> LayoutFile:
    """The layout's sensors that `modes` has shapes for (all of them unless channels were left out).

    Parameters
    ----------
    layout : LayoutFile
        The test's layout.
    modes : ModeTable
        Modes estimated from its records (:func:`estimate_modes`).

    Returns
    -------
    LayoutFile
        `layout` itself, or a copy with the sensors left out of the estimate removed.
    """
    if tuple(s.id for s in layout.sensors) == modes.sensor_ids:
        return layout
    keep = set(modes.sensor_ids)
    return layout.model_copy(update={"sensors": [s for s in layout.sensors if s.id in keep]})


def estimate_rigid_modes(
    layout: LayoutFile | PathLike,
    records: Sequence[PathLike] | Sequence[tuple[NDArray[np.float64], float]],
    *,
    method: str | None = None,
    band: tuple[float, float] | None = None,
    max_order: int | None = None,
    decimate: int | None = None,
    progress: ProgressCallback | None = None,
) -> tuple[ModeTable, ModalEstimate]:
    """Six modes from the records, or seven when one of the six looks elastic.

    :func:`estimate_modes` with six modes; when one of them fits rigid-body
    motion far worse than the others (:func:`rigidid.core.selection.elastic_suspect`:
    an elastic mode in the band, taken for a rigid one), the records are
    estimated again for seven modes, and those are returned when the six that
    fit rigid-body motion best leave the suspect out and look rigid;
    :func:`identify` then chooses those six (its automatic selection). Either
    way an :class:`~rigidid.errors.ElasticModeWarning` says what was found and
    done.

    Parameters
    ----------
    layout, records, method, band, max_order, decimate, progress
        As for :func:`estimate_modes`.

    Returns
    -------
    modes : ModeTable
        Six modes, or seven (one elastic).
    estimate : ModalEstimate
        The estimate they came from.

    Notes
    -----
    Needs more than six sensors (with six, every shape fits rigid-body motion
    exactly and nothing is checked). The output-error refinement that follows
    models rigid-body motion only: :func:`with_refinement` subtracts the unused
    mode from the records first.
    """
    import warnings

    from rigidid.core.geometry import local_sensor_matrix
    from rigidid.core.selection import elastic_suspect, separate_elastic
    from rigidid.errors import ClippedChannelWarning, ElasticModeWarning, IdentificationError

    lay = layout if isinstance(layout, LayoutFile) else load_layout(layout)
    options: dict[str, Any] = {
        "method": method, "band": band, "max_order": max_order, "decimate": decimate, "progress": progress
    }  # fmt: skip
    table, estimate = estimate_modes(lay, records, n_modes=6, **options)
    _, positions, directions = files.layout_arrays(fitted_layout(lay, table))
    if positions.shape[0] <= 6:
        return table, estimate
    t = local_sensor_matrix(positions, directions)
    residual = rigid_fit_residuals(t, table.shapes)
    k = elastic_suspect(residual)
    if k is None:
        return table, estimate
    found = (
        f"the mode at {table.frequency_hz[k]:.4g} Hz fits rigid-body motion with a residual of {residual[k]:.2f} "
        f"against {float(np.median(np.delete(residual, k))):.2g} for the others: an elastic mode taken for a rigid one?"
    )
    try:
        with warnings.catch_warnings():  # the clipped channels were named by the first estimation
            warnings.simplefilter("ignore", ClippedChannelWarning)
            table7, estimate7 = estimate_modes(lay, records, n_modes=7, **options)
    except IdentificationError:
        warnings.warn(
            f"{found} The records give no seventh stable mode to replace it; name the six rigid-body modes "
            "(--modes) or end --band below it",
            ElasticModeWarning,
            stacklevel=2,
        )
        return table, estimate
    keep = separate_elastic(t, table7.shapes)
    if keep is None:
        warnings.warn(
            f"{found} Seven modes estimated do not separate six rigid-body modes from it; name the six "
            "(--modes) or end --band below it",
            ElasticModeWarning,
            stacklevel=2,
        )
        return table, estimate
    left_out = int(np.setdiff1d(np.arange(7), keep)[0])
    warnings.warn(
        f"{found} Seven modes were estimated and the six that fit rigid-body motion best are used, leaving out "
        f"the mode at {table7.frequency_hz[left_out]:.4g} Hz",
        ElasticModeWarning,
        stacklevel=2,
    )
    return table7, estimate7


def _estimate_streamed(
    lay: LayoutFile,
    paths: Sequence[PathLike],
    method: str | None,
    n_modes: int,
    band: tuple[float, float] | None,
    max_order: int | None,
    decimate: int | None,
    progress: ProgressCallback | None,
    cascade: bool = True,
) -> tuple[ModeTable, ModalEstimate]:
    """:func:`estimate_modes` on record files read in blocks and decimated as they arrive.

    The first record chooses the pre-decimation factor (:mod:`rigidid.io.streamed_records`)
    or takes the user's `decimate` whole; the others share it. The estimate reports
    the total factor, the impacts in the files' rows.
    """
    from rigidid.core.timedomain import DEFAULT_METHOD, Impact
    from rigidid.core.timedomain import estimate_modes as estimate
    from rigidid.core.timedomain.preprocess import FIR_HALF_LENGTH
    from rigidid.errors import IdentificationError
    from rigidid.io.streamed_records import read_records_streamed

    ids = [s.id for s in lay.sensors]
    f_limit = float(band[1]) if band is not None else None
    # second decimation stage while reading (memory of the decimated record only), unless the user fixed the
    # factor; read_records_streamed reads again without it when all records' content asks another factor
    cascade = cascade and decimate is None
    streamed, content = read_records_streamed(paths, ids, decimate, f_limit, progress, cascade=cascade)
    factor = streamed[0].factor
    dts = [r.dt for r in streamed]
    cascaded = streamed[0].stages[1] > 1
    kept = _unclipped(ids, [r.clipped for r in streamed if r.clipped is not None])
    columns = list(range(len(ids)) if kept is None else kept)
    try:
        result = estimate(
            [r.data[:, columns] for r in streamed],
            dts[0],
            method=method or DEFAULT_METHOD,  # type: ignore[arg-type]
            n_modes=n_modes,
            band=band,
            max_order=max_order,
            # after a second stage the estimation judges the content again at the records' new rate, where
            # its spectrum resolves the modes (at 500 kHz the raw one's bins are 122 Hz wide), and may
            # decimate further; a user's factor was applied whole while reading
            decimate=None if decimate is None else 1,
            progress=progress,
            energies=[r.energy for r in streamed],
            content=None if cascaded else content,
            settle=FIR_HALF_LENGTH if cascaded else 0,
        )
    except IdentificationError:
        if not cascaded:
            raise
        # the smaller factors the estimation retries need the record before the second stage
        del streamed
        return _estimate_streamed(lay, paths, method, n_modes, band, max_order, decimate, progress, cascade=False)
    if factor > 1:
        impacts = tuple(
            Impact(*(r.offset + k * factor for k in (i.onset, i.peak, i.start)))
            for r, i in zip(streamed, result.impacts, strict=False)
        )
        result = replace(result, decimation=result.decimation * factor, impacts=impacts)
    if kept is not None:
        result = replace(result, channels=kept)
    table = ModeTable.numbered(result.frequency_hz, result.damping_ratio, [ids[c] for c in columns], result.shapes)
    return table, result


def report(
    result: IdentifyResult,
    *,
    mounts: Sequence[Sequence[float]] | None = None,
    stabilisation: Sequence[Any] | None = None,
    title: str | None = None,
    inputs: Sequence[str] = (),
    force_unit: str | None = None,
    body: BodyFile | None = None,
    records: Sequence[tuple[NDArray[np.float64], float]] | None = None,
    progress: ProgressCallback | None = None,
    spectrum: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
) -> str:
    """A self-contained HTML report of an identification (tables and pictures).

    Parameters
    ----------
    result : IdentifyResult
    mounts : sequence of (3,) positions, optional
        Mount positions to draw (e.g. from a body estimate).
    stabilisation : sequence, optional
        The stabilisation diagram of :func:`estimate_modes` (``estimate.diagram``).
    title : str, optional
        Heading of the document (default: the layout's name, else "rigidid report").
    inputs : sequence of str
        Input file names, listed under the title.
    force_unit : {"N", "kN", "lbf"}, optional
        Force unit of stiffness and damping (see :mod:`rigidid.units`).
    body : BodyFile, optional
        A body description whose mounts (positions and stiffness) to draw.
    records : sequence of (ndarray, float), optional
        The impact records, whose summed spectrum goes behind the stabilisation diagram.
    progress : callable, optional
        ``progress(task, done, total)`` while the figures are drawn.
    spectrum : (ndarray, ndarray), optional
        That summed spectrum computed already (frequency in Hz, power), e.g. from record files read in row
        blocks (:func:`rigidid.io.streamed_spectrum.summed_spectrum_streamed`); used instead of `records`.

    Returns
    -------
    str
        One HTML document; it needs no network to open.
    """
    from rigidid.reporting import render_report

    stiffness = None
    if body is not None:
        mounts = [m.position for m in body.mounts]
        stiffness = [np.asarray(m.stiffness, dtype=float) for m in body.mounts]
    if stabilisation is None:
        spectrum = None
    elif spectrum is None and records:
        spectrum = _spectrum(records)
    identified, roll = _report_mounts(result, force_unit)
    return render_report(
        result.identification,
        result.positions,
        result.directions,
        result.sensor_ids,
        result.units,
        mounts=None if mounts is None else [np.asarray(m, dtype=float) for m in mounts],
        stabilisation=stabilisation,
        uncertainty=_intervals_for_report(result),
        title=title or result.layout_name or "rigidid report",
        mode_labels=result.modes_used,
        inputs=inputs,
        force_unit=force_unit,
        mount_stiffness=stiffness,
        spectrum=spectrum,
        progress=progress,
        identified_mounts=identified,
        torque_roll_axis=roll,
    )


def _report_mounts(result: IdentifyResult, force_unit: str | None) -> tuple[dict[str, Any] | None, Any]:
    """The identified mounts and the torque roll axis as the report takes them (the result JSON's forms)."""
    from rigidid.jsonout import mounts_to_dict, result_to_dict

    identified = None if result.mounts is None else mounts_to_dict(result, force_unit)
    roll = None if result.torque_roll_axis is None else result_to_dict(result, force_unit)["torque_roll_axis"]
    return identified, roll


def _spectrum(records: Sequence[tuple[NDArray[np.float64], float]]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    from rigidid.core.spectrum import summed_spectrum

    return summed_spectrum([data for data, _ in records], records[0][1])


def report_pngs(
    result: IdentifyResult,
    directory: PathLike,
    *,
    stabilisation: Sequence[Any] | None = None,
    force_unit: str | None = None,
    body: BodyFile | None = None,
    records: Sequence[tuple[NDArray[np.float64], float]] | None = None,
    progress: ProgressCallback | None = None,
    spectrum: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
) -> list[Path]:
    """The figures of :func:`report` as PNG files in `directory` (see :func:`rigidid.reporting.save_pngs`).

    Parameters are those of :func:`report`; returns the paths written.
    """
    from rigidid.reporting import _mount_labels, identified_mount_labels, save_pngs

    folder = Path(directory)
    folder.mkdir(parents=True, exist_ok=True)
    mounts, labels = None, []
    if body is not None:
        mounts = [np.asarray(m.position, dtype=float) for m in body.mounts]
        stiffness = [np.asarray(m.stiffness, dtype=float) for m in body.mounts]
        labels = _mount_labels(stiffness, result.units["length"], result.units["mass"], force_unit)
    identified, roll = _report_mounts(result, force_unit)
    if identified is not None:
        mounts = [np.asarray(m["position"], dtype=float) for m in identified["mounts"]]
        labels = identified_mount_labels(identified)
    return save_pngs(
        folder,
        result.identification,
        result.positions,
        result.directions,
        result.sensor_ids,
        result.units,
        mounts=mounts,
        stabilisation=stabilisation,
        mode_labels=result.modes_used,
        mount_labels=labels,
        spectrum=None if stabilisation is None else spectrum or (_spectrum(records) if records else None),
        progress=progress,
        roll_axis=None if roll is None else roll["direction"],
    )


def _intervals_for_report(result: IdentifyResult) -> dict[str, Any] | None:
    """The Monte Carlo intervals, else the data-driven ones, as the report takes them."""
    from rigidid.jsonout import record_spread_to_dict, uncertainty_to_dict

    if result.uncertainty is not None:
        return uncertainty_to_dict(result.uncertainty)
    if result.record_spread is not None:
        return record_spread_to_dict(result.record_spread)
    return None


def convert(
    path: PathLike,
    directory: PathLike,
    *,
    units: dict[str, str] | None = None,
    geometry: PathLike | None = None,
    records_format: str = "csv",
) -> list[Path]:
    """Turn a universal file into ``layout.json``, ``modes.csv`` and ``record-<k>.csv`` files.

    Parameters
    ----------
    path : path-like
        The ``.uff``/``.unv`` file (see :func:`load_uff`).
    directory : path-like
        Folder to write into (created if needed).
    units : dict, optional
        ``{"length", "mass"}`` when the file has no dataset 164.
    geometry : path-like, optional
        A UFF file completing `path` (see :func:`load_uff`).
    records_format : {"csv", "npz", "mat", "h5", "wav"}
        File format of the records (``record-<k>.<format>``; layouts in ``docs/FORMATS.md``).

    Returns
    -------
    list of Path
        The files written (atomically) in `directory`.
    """
    import json

    if records_format not in ("csv", "npz", "mat", "h5", "wav"):
        raise InputError(f"records format {records_format!r}: one of csv, npz, mat, h5, wav", source="records_format")
    from rigidid.io.atomic import check_folder, transaction
    from rigidid.io.records import write_record

    check_folder(directory)
    data = load_uff(path, units=units, geometry=geometry)
    with transaction() as outs:  # all files or none
        folder = outs.folder(directory)
        written = [folder / "layout.json"]
        write_text_atomic(written[0], json.dumps(data.layout.model_dump(exclude_none=True), indent=2) + "\n")
        if data.modes is not None:
            written.append(folder / "modes.csv")
            # 17 digits: the numbers the UFF file holds, unrounded (identify on the converted files
            # then matches identify on the UFF file to rounding)
            write_text_atomic(written[-1], files.modes_csv_text(data.modes, digits=17))
        ids = [s.id for s in data.layout.sensors]
        for k, (values, dt) in enumerate(data.records, start=1):
            written.append(folder / f"record-{k}.{records_format}")
            if records_format == "csv":
                write_record(written[-1], np.arange(values.shape[0]) * dt, values, ids)
            else:
                from rigidid.io.binary_records import write_binary

                write_binary(written[-1], np.arange(values.shape[0]) * dt, values, ids)
    return written


def simulate_records(
    body: BodyFile | PathLike,
    layout: LayoutFile | PathLike,
    directory: PathLike,
    *,
    impacts: Sequence[tuple[Sequence[float], Sequence[float]]] | None = None,
    sample_rate: float = 512.0,
    duration: float = 8.0,
    pretrigger: float = 0.1,
    noise: float = 0.0,
    seed: int | None = None,
    progress: ProgressCallback | None = None,
) -> list[Path]:
    """Write impulse-response records of a body on its mounts, one ``record-<k>.csv`` per impact.

    Parameters
    ----------
    body, layout : model or path-like
        The body (``body.json``) and the sensors (``layout.json``), same units.
    directory : path-like
        Folder to write into (created if needed).
    impacts : sequence of (position, direction), optional
        Where each unit impulse acts and along which direction. Default: two
        impacts, at the first sensor along (1, 1, 1) and at the sensor
        farthest from it along (-1, 1, -1), which excite all six modes in
        general.
    sample_rate, duration, pretrigger : float
        Samples per second; free decay and pre-trigger lengths (s).
    noise : float
        Gaussian noise relative to each channel's RMS.
    seed : int, optional
    progress : callable, optional
        ``progress(task, done, total)`` while the records are computed and written.

    Returns
    -------
    list of Path
        The files written.
    """
    from rigidid.core.timedomain import impulse_records, record_time
    from rigidid.io.records import write_record

    lay = layout if isinstance(layout, LayoutFile) else files.load_layout(layout, require_rank=False)
    spec = body if isinstance(body, BodyFile) else files.load_body(body)
    _same_units(spec, lay, None if isinstance(body, BodyFile) else str(body))
    ids, positions, directions = files.layout_arrays(lay)
    if impacts is None:
        far = int(np.argmax(np.linalg.norm(positions - positions[0], axis=1)))
        impacts = [(positions[0], (1.0, 1.0, 1.0)), (positions[far], (-1.0, 1.0, -1.0))]
    for _, direction in impacts:
        if not np.any(np.asarray(direction, dtype=float)):
            raise InputError("an impact direction is the zero vector", source="impacts")
    if not (sample_rate > 0 and duration > 0 and pretrigger >= 0):
        raise InputError("sample rate and duration must be positive, pre-trigger zero or positive", source="records")
    from rigidid.limits import check_record_size

    check_record_size(sample_rate, duration + pretrigger, len(ids), len(impacts))
    data = impulse_records(
        body_from_file(spec),
        positions,
        directions,
        [(np.asarray(p, dtype=float), np.asarray(d, dtype=float)) for p, d in impacts],
        sample_rate=sample_rate,
        duration=duration,
        pretrigger=pretrigger,
        noise=noise,
        seed=seed,
        progress=progress,
    )
    from rigidid.io.atomic import transaction

    step = progress or no_progress
    with transaction() as outs:  # all records or none
        folder = outs.folder(directory)
        written = []
        for k, values in enumerate(data, start=1):
            step("writing records", k - 1, len(data))
            written.append(folder / f"record-{k}.csv")
            write_record(written[-1], record_time(values.shape[0], sample_rate, pretrigger), values, ids)
        step("writing records", len(data), len(data))
    return written


def _mount_spec(
    mounts: PathLike | MountsFile, units: Mapping[str, str]
) -> tuple[NDArray[np.float64], NDArray[np.float64], MountsFile]:
    """Positions and axes (columns) of the mounts, checked against the layout's units."""
    spec = mounts if isinstance(mounts, MountsFile) else files.load_mounts(mounts)
    source = None if isinstance(mounts, MountsFile) else str(mounts)
    if (spec.units.length, spec.units.mass) != (units["length"], units["mass"]):
        raise InputError(
            f"units ({spec.units.length}, {spec.units.mass}) differ from the layout's "
            f"({units['length']}, {units['mass']})",
            source=source,
            location="units",
        )
    positions = np.array([m.position for m in spec.mounts], dtype=float)
    axes = np.stack([np.eye(3) if m.axes is None else np.asarray(m.axes, dtype=float).T for m in spec.mounts])
    return positions, axes, spec


def _mount_model(
    positions: NDArray[np.float64],
    directions: NDArray[np.float64],
    poles: NDArray[np.complex128],
    shapes: NDArray[np.complex128],
    mass: float | None,
    mounts: PathLike | MountsFile,
    layout: LayoutFile,
    noise: NoiseLevels | Mapping[str, float] | None = None,
) -> tuple[Identification, MountModelFit]:
    """The mount model, started from the free route when six modes allow it, and the comparison with it.

    The output residuals are weighted by `noise` (default: ``estimate_noise``, the shape noise from the
    rigid-body fit, with any overrides of a mapping), as the Monte Carlo intervals are.
    """
    from rigidid.core.geometry import layout_frame
    from rigidid.core.mounts import eigen_residual, identify_mount_model
    from rigidid.core.noise import NoiseLevels, estimate_noise
    from rigidid.errors import IdentificationError

    where, axes, spec = _mount_spec(mounts, {"length": layout.units.length, "mass": layout.units.mass})
    groups = [m.group for m in spec.mounts]
    if isinstance(noise, NoiseLevels):
        levels = noise
    else:
        levels = replace(estimate_noise(positions, directions, shapes), **dict(noise or {}))
    free = None
    if poles.size == 6:
        try:
            free = identify_core(positions, directions, poles, shapes, mass=mass, warn=False)
        except IdentificationError:
            free = None
    start = None if free is None else (free.center_of_gravity, free.inertia_per_mass)
    ident, model = identify_mount_model(
        positions, directions, poles, shapes, where, axes, mass=mass, start=start, groups=groups, noise=levels
    )
    length = layout_frame(positions).scale
    residual = eigen_residual(
        poles, ident.mode_shapes_cg, ident.inertia_per_mass, ident.stiffness_per_mass, ident.damping_per_mass, length
    )
    free_residual = None
    if free is not None:
        free_residual = eigen_residual(
            poles, free.mode_shapes_cg, free.inertia_per_mass, free.stiffness_per_mass, free.damping_per_mass, length
        )
    return ident, MountModelFit(model, residual, free_residual, noise=levels)


def with_mounts(
    result: IdentifyResult, mounts: PathLike | MountsFile | None = None, *, torque_axis: Sequence[float] | None = None
) -> IdentifyResult:
    """Add per-mount rates (from ``mounts.json`` or a ``body.json``) and the torque roll axis.

    Parameters
    ----------
    result : IdentifyResult
        An identification with a mass (rates in force units) or without (per mass).
    mounts : path-like or MountsFile, optional
        Mount positions and optional principal axes, in the layout's units.
    torque_axis : sequence of 3 floats, optional
        Direction of a torque (for an engine, the crankshaft) for the torque roll axis.

    Returns
    -------
    IdentifyResult
        `result` with :attr:`IdentifyResult.mounts` and/or
        :attr:`IdentifyResult.torque_roll_axis` set.

    Raises
    ------
    InputError
        A bad file, units that differ from the layout's, or a zero torque axis.
    """
    from rigidid.core.mounts import mount_rates, torque_roll_axis

    ident = result.identification
    out = result
    if mounts is not None:
        positions, axes, spec = _mount_spec(mounts, result.units)
        scale = 1.0 if ident.mass is None else ident.mass
        groups = tuple(m.group for m in spec.mounts)
        rates = mount_rates(
            scale * ident.stiffness_per_mass, ident.center_of_gravity, positions, axes, scale * ident.damping_per_mass,
            groups=groups,
        )  # fmt: skip
        nominal = None
        if all(m.stiffness is not None for m in spec.mounts):
            nominal = np.array([
                np.diag(rates.axes[k].T @ np.asarray(m.stiffness, dtype=float) @ rates.axes[k])
                for k, m in enumerate(spec.mounts)
            ])  # fmt: skip
        ids = tuple(m.id or str(k + 1) for k, m in enumerate(spec.mounts))
        out = replace(out, mounts=Mounts(ids, positions, rates, nominal, groups))
    if torque_axis is not None:
        out = replace(out, torque_roll_axis=torque_roll_axis(ident.inertia_per_mass, torque_axis))
    return out


def with_warnings(result: IdentifyResult, messages: Sequence[str]) -> IdentifyResult:
    """`result` with `messages` added to its diagnostics' warnings (those not there yet)."""
    diag = result.identification.diagnostics
    new = tuple(m for m in messages if m not in diag.warnings)
    if not new:
        return result
    ident = replace(result.identification, diagnostics=replace(diag, warnings=(*diag.warnings, *new)))
    return replace(result, identification=ident)


def with_record_spread(
    result: IdentifyResult,
    records: Sequence[tuple[NDArray[np.float64], float]],
    *,
    segments: int = 8,
    n_modes: int = 6,
    estimate_options: Mapping[str, Any] | None = None,
) -> IdentifyResult:
    """Add data-driven intervals: re-identify on interleaved segments of the records.

    Parameters
    ----------
    result : IdentifyResult
        The identification from all the records.
    records : sequence of (ndarray, float)
        The records it came from (samples x sensors in layout order, sample interval).
    segments : int
        Number of interleaved segments ``K`` (the sample rate over ``K`` must
        stay above twice the highest mode; 8 when the records allow it).
    n_modes : int
        Modes estimated per segment.
    estimate_options : mapping, optional
        ``method``, ``band``, ``max_order`` for the estimator.

    Returns
    -------
    IdentifyResult
        `result` with ``record_spread`` set (see
        :func:`rigidid.core.record_spread.record_spread`).
    """
    from rigidid.core.record_spread import record_spread

    spread = record_spread(
        [data for data, _ in records],
        records[0][1],
        result.positions,
        result.directions,
        result.identification,
        segments=segments,
        mass=result.identification.mass,
        n_modes=n_modes,
        estimate_options=dict(estimate_options or {}),
    )
    return replace(result, record_spread=spread)


def with_refinement(
    result: IdentifyResult,
    records: Sequence[tuple[NDArray[np.float64], float]],
    estimate: ModalEstimate,
    *,
    progress: ProgressCallback | None = None,
) -> IdentifyResult:
    """Refine the body on the records by output error (maximum likelihood), started from `result`.

    Parameters
    ----------
    result : IdentifyResult
        The structured identification from the records' estimated modes.
    records : sequence of (ndarray, float)
        The records (samples x sensors in layout order, sample interval).
    estimate : ModalEstimate
        The modal estimate the modes came from (impacts found, decimation).
    progress : ProgressCallback, optional
        Called with ``("refit", done, total)``.

    Returns
    -------
    IdentifyResult
        With CG, inertia, stiffness and damping from the refinement and
        ``record_bound`` (Cramér-Rao intervals) set; or `result` unchanged,
        with a :class:`~rigidid.errors.RefinementWarning`, when the fit fails
        or its normalised cost says it is not at the global minimum.

    Notes
    -----
    The refit models the six rigid-body modes only: modes of `estimate` that
    `result` did not use (an elastic mode left out, see :func:`estimate_rigid_modes`)
    are subtracted from the records first
    (:func:`rigidid.core.timedomain.nuisance.subtract_modes`).
    """

    from rigidid.core.timedomain.refine import refine_body

    ident = result.identification
    if progress is not None:
        progress("refit", 0, 1)
    arrays = [data if estimate.channels is None else data[:, list(estimate.channels)] for data, _ in records]
    unused = [k + 1 not in result.modes_used for k in range(estimate.poles.size)]
    if any(unused):  # modes estimated but not used (elastic): out of the records the rigid-body model is fitted to
        from rigidid.core.timedomain.nuisance import subtract_modes

        arrays = subtract_modes(
            arrays, records[0][1], [impact.start for impact in estimate.impacts], estimate.poles, unused
        )
    return _refit(
        result,
        lambda: refine_body(
            arrays,
            records[0][1],
            result.positions,
            result.directions,
            starts=[impact.start for impact in estimate.impacts],
            onsets=[impact.onset for impact in estimate.impacts],
            decimation=estimate.decimation,
            center_of_gravity=ident.center_of_gravity,
            inertia_per_mass=ident.inertia_per_mass,
            stiffness_per_mass=ident.stiffness_per_mass,
            damping_per_mass=ident.damping_per_mass,
        ),
        progress,
    )


def _refit(result: IdentifyResult, fit: Any, progress: ProgressCallback | None) -> IdentifyResult:
    """Run `fit` (a refinement on the records) and accept it, or keep `result` with a RefinementWarning."""
    import warnings

    from rigidid.errors import RefinementWarning

    try:
        refinement = fit()
    except (np.linalg.LinAlgError, InputError, ValueError) as exc:
        warnings.warn(
            f"refinement on the records failed ({exc}); kept the answer from the modes"
            + _suspect_mode(result.identification),
            RefinementWarning,
            stacklevel=3,
        )
        return result
    finally:
        if progress is not None:
            progress("refit", 1, 1)
    return _accept_refinement(result, refinement)


def _accept_refinement(result: IdentifyResult, refinement: Any) -> IdentifyResult:
    """`result` with the refinement's body and bound, or unchanged with a warning when the fit is bad."""
    import warnings

    from rigidid.core.timedomain.refine import good_fit, record_bound
    from rigidid.errors import RefinementWarning

    ident = result.identification
    if not good_fit(refinement):
        warnings.warn(
            f"refinement on the records ended at a normalised cost of {refinement.normalised_cost:.3g} "
            "(about 1 at a good fit): a local minimum or a model that does not fit the records; "
            "kept the answer from the modes" + _suspect_mode(ident),
            RefinementWarning,
            stacklevel=2,
        )
        return result
    refined = replace(
        ident,
        center_of_gravity=refinement.center_of_gravity,
        inertia_per_mass=refinement.inertia_per_mass,
        stiffness_per_mass=refinement.stiffness_per_mass,
        damping_per_mass=refinement.damping_per_mass,
    )
    return replace(result, identification=refined, record_bound=record_bound(refinement, ident.mass))


STREAM_REFIT_VALUES = 16 * 150_000
"""Raw values (samples x sensors, all records) above which :func:`refine_records` reads
the record files in row blocks instead of whole (16 times the refit's row budget)."""


def refine_records(
    result: IdentifyResult,
    paths: Sequence[PathLike],
    layout: LayoutFile | PathLike,
    estimate: ModalEstimate,
    *,
    progress: ProgressCallback | None = None,
    stream_above: int | None = None,
) -> IdentifyResult:
    """:func:`with_refinement` on record files, whose memory does not grow with the records' length.

    Parameters
    ----------
    result : IdentifyResult
        The structured identification from the records' estimated modes.
    paths : sequence of path-like
        The record files `estimate` came from (one per impact).
    layout : LayoutFile or path-like
        The sensors.
    estimate : ModalEstimate
        The modal estimate, its impacts in the files' rows and its total
        decimation (as :func:`estimate_modes` gives for record files).
    progress : ProgressCallback, optional
        Reading and ``("refit", done, total)``.
    stream_above : int, optional
        Records of more raw values than this (default :data:`STREAM_REFIT_VALUES`) (samples x sensors, all files,
        as their headers or sizes tell) are read in row blocks
        (:func:`rigidid.io.refit_records.read_prepared_decays`: the pre-trigger
        statistics and the decays at the fit's rate, nothing else held);
        smaller ones are read whole.

    Returns
    -------
    IdentifyResult
        As :func:`with_refinement`: the same answer whichever way the files
        were read (to the order of floating-point sums).

    Notes
    -----
    The impacts are located again on the raw records
    (:func:`~rigidid.core.timedomain.preprocess.find_impact`, as an estimation
    on the whole records would: `estimate`'s, from records decimated while
    read, are only as fine as that factor), by one more pass in row blocks
    (:func:`rigidid.io.refit_records.locate_impacts`) holding the rows around
    `estimate`'s impacts. The records are read whole when that pass cannot
    prove its impacts, and when `result` leaves out a mode of `estimate` (an
    elastic one, subtracted from the raw records). The refit's decimation is
    the smallest up to `estimate`'s factor that fits its row budget, so it may
    differ from a whole-record estimation's when that budget binds.
    """

    from rigidid.core.timedomain.refine import columns_of, refine_prepared
    from rigidid.io.records import layout_ids
    from rigidid.io.streamed_records import open_source

    lay = layout if isinstance(layout, LayoutFile) else load_layout(layout)
    ids = [s.id for s in lay.sensors]
    unused = any(k + 1 not in result.modes_used for k in range(estimate.poles.size))
    size = 0
    if not unused:
        size = sum(open_source(Path(p), layout_ids(ids, str(p)), None).rows for p in paths) * len(ids)
    dt = estimate.sample_interval / max(1, estimate.decimation)
    impacts = None
    if not unused and size > (STREAM_REFIT_VALUES if stream_above is None else stream_above):
        from rigidid.core.timedomain.preprocess import FIR_HALF_LENGTH
        from rigidid.io.refit_records import locate_impacts

        reach = (2 * FIR_HALF_LENGTH + 2) * max(1, estimate.decimation) + round(0.005 / dt) + 2
        impacts = locate_impacts(paths, ids, dt, estimate.impacts, reach, progress=progress)
    if impacts is None:  # read whole; the impacts where the raw records put them (as their estimation would)
        from rigidid.core.timedomain.preprocess import find_impact

        raw = load_records(paths, lay)
        found = tuple(find_impact(data, step) for data, step in raw)
        return with_refinement(result, raw, replace(estimate, impacts=found), progress=progress)
    estimate = replace(estimate, impacts=tuple(impacts))
    from rigidid.io.refit_records import read_prepared_decays

    ident = result.identification
    if progress is not None:
        progress("refit", 0, 1)
    def fit() -> Any:
        data = read_prepared_decays(
            paths, ids, dt, starts=[i.start for i in estimate.impacts], onsets=[i.onset for i in estimate.impacts],
            factor=estimate.decimation, progress=progress,
        )  # fmt: skip
        if estimate.channels is not None:  # clipped channels left out
            data = columns_of(data, estimate.channels)
        return refine_prepared(
            data, dt, result.positions, result.directions, center_of_gravity=ident.center_of_gravity,
            inertia_per_mass=ident.inertia_per_mass, stiffness_per_mass=ident.stiffness_per_mass,
            damping_per_mass=ident.damping_per_mass,
        )  # fmt: skip

    return _refit(result, fit, progress)


def records_spectrum(
    paths: Sequence[PathLike], layout: LayoutFile | PathLike, *, progress: ProgressCallback | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """The report's summed spectrum of record files (:func:`report`'s `spectrum`), read in row blocks.

    Parameters
    ----------
    paths : sequence of path-like
        The record files (one per impact), checked already (read by the estimation).
    layout : LayoutFile or path-like
        The sensors.
    progress : ProgressCallback, optional
        Reading progress.

    Returns
    -------
    (ndarray, ndarray) or None
        Frequency (Hz) and summed power spectral density, as
        :func:`rigidid.core.spectrum.summed_spectrum` gives on the whole records
        (:func:`rigidid.io.streamed_spectrum.summed_spectrum_streamed`); the
        records read whole when one is shorter than a Welch segment (4096 rows).
    """
    from rigidid.io.records import layout_ids
    from rigidid.io.streamed_records import open_source
    from rigidid.io.streamed_spectrum import summed_spectrum_streamed

    lay = layout if isinstance(layout, LayoutFile) else load_layout(layout)
    ids = [s.id for s in lay.sensors]
    sources = [open_source(Path(p), layout_ids(ids, str(p)), None) for p in paths]
    if not sources:
        return None
    if min(s.rows for s in sources) < 2 * 4096:  # short records (rows told by the header or the size): read whole
        del sources
        return _spectrum(load_records(paths, lay))
    dt = _source_dt(sources[0])
    del sources
    return summed_spectrum_streamed(paths, ids, dt, progress=progress)


def _source_dt(source: Any) -> float:
    """The sample interval of a row-block source: its own, or from the first block's time column."""
    if source.dt:
        return float(source.dt)
    t, _ = next(iter(source.blocks))
    return float(t[1] - t[0])
