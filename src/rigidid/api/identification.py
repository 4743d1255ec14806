"""The modes route: choose the rigid modes, identify (structured, paper or mount model), check the data
and the result, and keep the warnings in the result's diagnostics."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import NDArray

from rigidid.api import checks
from rigidid.api.load import load_layout, load_modes
from rigidid.api.mounts import mount_model
from rigidid.core.identify import Identification, Method
from rigidid.core.identify import identify as identify_core
from rigidid.core.selection import rigid_fit_residuals, select_rigid_modes
from rigidid.core.statespace import poles_from_modal
from rigidid.errors import InputError
from rigidid.io import files
from rigidid.io.files import ModeTable
from rigidid.models import LayoutFile, MountsFile
from rigidid.progress import no_progress
from rigidid.results import IdentifyResult, PathLike, Selection, TestInfo

if TYPE_CHECKING:
    from rigidid.core.frfmodes import ScaledBody
    from rigidid.core.noise import NoiseLevels
    from rigidid.io.files import ModeTable
    from rigidid.progress import ProgressCallback


def _choose_modes(
    modes: ModeTable,
    transformation: NDArray[np.float64],
    wanted: Sequence[int] | None,
    source: str | None,
    fewest: int = 6,
    suggest_mounts: bool = False,
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
        hint = ""
        if n == 5 and fewest == 6 and suggest_mounts:
            hint = "; the mount model fits five (--method mounts, with --mounts)"
        raise InputError(f"{n} modes given; the six rigid-body modes are needed{hint}", source=source)
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
    labels, selection, residuals = _choose_modes(
        table, t, modes_used, source, 5 if method == "mounts" else 6, suggest_mounts=mounts is not None
    )
    used = table.subset(labels)
    notes = _check_data(t, used, ids)
    poles = poles_from_modal(used.frequency_hz, used.damping_ratio)
    body_mass = mass if mass is not None else lay.mass
    fit = errors = None
    if method == "mounts":
        assert mounts is not None
        result, fit, errors = mount_model(positions, directions, poles, used.shapes, body_mass, mounts, lay, noise)
    else:
        levels = checks.noise_levels(noise, positions, directions, used.shapes)
        weighted = levels if method == "structured" else None
        result = identify_core(positions, directions, poles, used.shapes, mass=body_mass, method=method, noise=weighted)
    result = _check_result(result, labels, lay.units.length, notes)
    if method == "structured":
        errors = checks.standard_errors_of(result, positions, directions, poles, used.shapes, levels)
        units = {"length": lay.units.length, "mass": lay.units.mass}
        assumed = positions.shape[0] <= 6 and not (isinstance(noise, Mapping) and "shape" in noise)
        result = checks.checked(
            result, errors, (positions, directions, poles, used.shapes), levels, units, assumed=assumed
        )
    elif method == "paper":
        errors = checks.paper_standard_errors(result, positions, directions, poles, used.shapes, levels)
    intervals = None
    if uncertainty:
        from rigidid.core.uncertainty import propagate

        step = progress or no_progress
        task = f"{uncertainty} Monte Carlo draws"
        step(task, 0, uncertainty)
        intervals = propagate(
            positions, directions, poles, used.shapes, mass=body_mass, noise=levels, draws=uncertainty, seed=seed,
            progress=lambda _, done, total: step(task, done, total), weighted=True,
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
        test=TestInfo.from_layout(lay),
        mount_model=fit,
        scaled=_scaled_body(used, poles, positions, directions),
        standard_errors=errors,
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


def suspect_mode(ident: Identification) -> str:
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
        observability = result.diagnostics.inertia_observability
        cause = (
            "check that these are the six rigid-body modes and that the layout matches the test"
            if observability >= 0.1
            else f"the supports couple rotations to translations only weakly (inertia observability "
            f"{observability:.2g}, typically 0.1-0.3), so noise in the modes can make it so; the mount model "
            "(--method mounts with --mounts) keeps the inertia positive definite, or measure with the supports "
            "further from the CG's height"
        )
        raise IdentificationError(
            f"modes {', '.join(str(m) for m in labels)} determine no rigid body: the inertia tensor they give is "
            f"not positive definite (principal moments per mass {moments} {length}^2); {cause}"
        )
    if not notes:
        return result
    return replace(result, diagnostics=replace(result.diagnostics, warnings=(*result.diagnostics.warnings, *notes)))


def with_warnings(result: IdentifyResult, messages: Sequence[str]) -> IdentifyResult:
    """`result` with `messages` added to its diagnostics' warnings (those not there yet)."""
    diag = result.identification.diagnostics
    new = tuple(m for m in messages if m not in diag.warnings)
    if not new:
        return result
    ident = replace(result.identification, diagnostics=replace(diag, warnings=(*diag.warnings, *new)))
    return replace(result, identification=ident)
