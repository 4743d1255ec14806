"""``rigidid plan``: check a layout (and hammer points, and mounts) before the test; with a body estimate,
predict the precision and suggest sensors to add."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rigidid.api.load import body_from_file, check_uff_options, load_references_for, load_uff, same_units
from rigidid.api.mounts import read_mount_spec
from rigidid.core.simulate import Body
from rigidid.errors import InputError
from rigidid.io import files
from rigidid.models import BodyFile, LayoutFile, MountsFile, ReferencesFile
from rigidid.progress import no_progress
from rigidid.results import PathLike, PlanResult

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

    from rigidid.core.noise import NoiseLevels
    from rigidid.core.plan import Prediction, ReferenceReport, SensorPlan
    from rigidid.progress import ProgressCallback


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
    records: bool = False,
    impacts: Sequence[tuple[Sequence[float], Sequence[float]]] | None = None,
    sample_rate: float | None = None,
    duration: float | None = None,
    record_noise: float | None = None,
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
        predicted precision to first order, from one fit of the body's exact modes
        (:func:`rigidid.core.mounts.predict_mount_model_linearised`; ``draws`` 0)
        in :attr:`PlanResult.mount_prediction`.
    records : bool
        The test will be impact records (``identify --records``): with `body`, predict the
        refit's own sensor budget for it (:func:`predicted_records_budget`), in
        :attr:`PlanResult.records_budget`. Implied by `impacts`, `sample_rate` or `duration`.
    impacts : sequence of (position, direction), optional
        The planned impacts (layout length; force direction), as ``simulate_records``'s; default
        :func:`rigidid.core.plan.default_impacts`.
    sample_rate, duration : float, optional
        Samples per second (default 512) and free decay per record (s, default 8) of the planned records.
    record_noise : float, optional
        Their noise, relative to each channel's RMS over each record's free decay (default 0.01).

    Returns
    -------
    PlanResult

    Raises
    ------
    InputError
        Bad files, units that differ between files, ``add`` > 0 without a body.
    """
    from rigidid.core.noise import DEFAULT_NOISE
    from rigidid.core.plan import check_layout, predict_uncertainty

    if isinstance(layout, LayoutFile):
        lay = layout
    elif Path(layout).suffix.lower() in (".uff", ".unv"):
        lay = load_uff(layout, units=units, geometry=geometry).layout
    else:
        check_uff_options(layout, units, geometry)
        lay = files.load_layout(layout, require_rank=False)
    ids, positions, directions = files.layout_arrays(lay)
    layout_units: dict[str, str] = {"length": lay.units.length, "mass": lay.units.mass}
    report = check_layout(positions, directions, unit=lay.units.length, names=ids)
    split = None
    if mounts is not None:
        from rigidid.core.mounts import split_uniqueness

        where, axes, mount_spec = read_mount_spec(mounts, layout_units)
        mount_groups = [m.group for m in mount_spec.mounts]
        split = split_uniqueness(where, axes, mount_groups)
    planned = records or any(x is not None for x in (impacts, sample_rate, duration, record_noise))
    if body is None:
        if add:
            raise InputError("suggesting sensors needs a body estimate", source="add")
        if planned:
            raise InputError("predicting the records route's sensor budget needs a body estimate", source="records")
        return PlanResult(layout_units, report, references=_plan_references(references, lay, None), mount_split=split)
    spec = body if isinstance(body, BodyFile) else files.load_body(body)
    same_units(spec, lay, None if isinstance(body, BodyFile) else str(body))
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
        from rigidid.core.mounts import predict_mount_model_linearised

        step("predicting the mount model", 0, 1)
        mount_prediction = predict_mount_model_linearised(
            core_body, positions, directions, where, axes, groups=mount_groups, noise=levels
        )
        step("predicting the mount model", 1, 1)
    suggestions = _suggest(core_body, lay, positions, directions, candidates, add, levels, draws, seed, step)
    budget = None if prediction is None else predicted_budget(core_body, lay, positions, directions, prediction)
    records_budget = None if prediction is None or not planned else predicted_records_budget(
        core_body, lay, positions, directions, impacts=impacts, sample_rate=sample_rate, duration=duration,
        noise=record_noise, progress=step,
    )  # fmt: skip
    return PlanResult(
        layout_units, report, prediction, suggestions, checked_refs, split, mount_prediction,
        sensor_budget=None if budget is None else budget[0], tolerances=None if budget is None else budget[1],
        records_budget=None if records_budget is None else records_budget[0],
        records_test=None if records_budget is None else records_budget[1],
    )  # fmt: skip


def predicted_budget(
    body: Body,
    layout: LayoutFile,
    positions: NDArray[np.float64],
    directions: NDArray[np.float64],
    prediction: Prediction,
) -> tuple[dict[str, dict[str, NDArray[np.float64]]], dict[str, float]] | None:
    """The predicted budget of CG, inertia and stiffness: the noise's part beside each sensor tolerance's.

    Parameters
    ----------
    body : Body
        The body estimate (its exact modes are what the sensors would read).
    layout : LayoutFile
        The planned sensors and their ``tolerances`` (defaults for the fields left out,
        :func:`rigidid.api.records.sensor_bounds`).
    positions, directions : ndarray, shape (p, 3)
        The sensors, layout order.
    prediction : Prediction
        The noise's prediction (:func:`rigidid.core.plan.predict_uncertainty`): its standard
        deviations are the ``noise`` part.

    Returns
    -------
    (dict, dict) or None
        Per source (``noise``, :data:`rigidid.core.sensor_budget.SOURCES`, ``combined``) the standard
        deviations ``center_of_gravity`` (3,), ``inertia_tensor`` (3, 3) and ``stiffness_diagonal``
        (6,) in absolute units, and the bounds used; None when the kernel cannot linearise the test.

    Notes
    -----
    The type-B parts are :func:`rigidid.core.sensor_budget.sensor_budget` at the body's exact modes:
    the identification from the modes' propagation. ``identify --records`` reports the refit's own
    (:func:`rigidid.core.timedomain.refine.sensor_terms`), a different estimator's: on four-mounts
    0.25-1.28 of this prediction (``tests/test_clipping.py``); :func:`predicted_records_budget`
    predicts that one. The per-mass parts are scaled by the body's mass.
    """
    import numpy as np

    from rigidid.api.records import sensor_bounds
    from rigidid.core.sensor_budget import sensor_budget
    from rigidid.core.simulate import body_modes

    bounds = sensor_bounds(layout)
    modes = body_modes(body, positions, directions)
    try:
        type_b = sensor_budget(positions, directions, modes.poles, modes.shapes, bounds)
    except ValueError:
        return None
    mass = float(body.mass)
    noise = prediction.uncertainty
    out = {"noise": {"center_of_gravity": np.asarray(noise.center_of_gravity.std, dtype=float),
                     "inertia_tensor": np.asarray(noise.inertia.std, dtype=float),
                     "stiffness_diagonal": np.asarray(noise.stiffness_diagonal.std, dtype=float)}}  # fmt: skip
    for source, parts in type_b.std.items():
        out[source] = {"center_of_gravity": parts["center_of_gravity"],
                       "inertia_tensor": mass * parts["inertia_per_mass"],
                       "stiffness_diagonal": mass * np.diag(parts["stiffness_per_mass"])}  # fmt: skip
    out["combined"] = {key: np.sqrt(sum(part[key] ** 2 for part in out.values())) for key in out["noise"]}
    return out, dict(vars(bounds))


def predicted_records_budget(
    body: Body,
    layout: LayoutFile,
    positions: NDArray[np.float64],
    directions: NDArray[np.float64],
    *,
    impacts: Sequence[tuple[Sequence[float], Sequence[float]]] | None = None,
    sample_rate: float | None = None,
    duration: float | None = None,
    noise: float | None = None,
    progress: ProgressCallback | None = None,
) -> tuple[dict[str, dict[str, NDArray[np.float64]]], dict[str, Any]] | None:
    """The sensor budget ``identify --records`` will report for a planned test: the refit's own.

    Parameters
    ----------
    body : Body
        The body estimate.
    layout : LayoutFile
        The planned sensors and their ``tolerances`` (:func:`rigidid.api.records.sensor_bounds`).
    positions, directions : ndarray, shape (p, 3)
        The sensors, layout order.
    impacts : sequence of (position, direction), optional
        The planned impacts (default :func:`rigidid.core.plan.default_impacts`).
    sample_rate, duration : float, optional
        Samples per second (Hz, default 512) and free decay per record (s, default 8).
    noise : float, optional
        The records' noise relative to each channel's RMS over each record's free decay (default 0.01).
    progress : callable, optional
        ``progress(task, done, total)`` around the prediction.

    Returns
    -------
    (dict, dict) or None
        Per source (``noise`` when the refit converged, :data:`rigidid.core.sensor_budget.SOURCES`,
        ``sensors``: the four in quadrature, ``combined``: all in quadrature, with the noise) the standard
        deviations ``center_of_gravity`` (3,), ``inertia_tensor`` (3, 3) and ``stiffness_diagonal`` (6,),
        absolute units; and the test as planned (``impacts``, ``sample_rate_hz``, ``duration_s``,
        ``noise``, the refit's ``fit_decimation`` and ``fit_rows`` per impact, ``rows_used`` by the
        prediction). None when the refit cannot run on such a test.

    Raises
    ------
    InputError
        A bad test: a rate or duration not positive, records too large, a zero impact direction.

    Notes
    -----
    :func:`rigidid.core.plan.predict_records_budget`: the refit's linearisation
    (:func:`rigidid.core.timedomain.refine.sensor_terms`) on the planned records, at the body.
    """
    import numpy as np

    from rigidid.api.records import sensor_bounds
    from rigidid.core.plan import (
        RECORDS_DURATION,
        RECORDS_NOISE,
        RECORDS_SAMPLE_RATE,
        default_impacts,
        predict_records_budget,
    )
    from rigidid.limits import check_number, check_record_size

    sample_rate = RECORDS_SAMPLE_RATE if sample_rate is None else sample_rate
    duration = RECORDS_DURATION if duration is None else duration
    noise = RECORDS_NOISE if noise is None else noise
    for value, name in ((sample_rate, "sample_rate"), (duration, "duration"), (noise, "record_noise")):
        check_number(value, name, positive=True)
    planned = default_impacts(positions) if impacts is None else [
        (np.asarray(p, dtype=float).reshape(3), np.asarray(d, dtype=float).reshape(3)) for p, d in impacts
    ]  # fmt: skip
    if any(not np.any(d) for _, d in planned):
        raise InputError("an impact direction is the zero vector", source="impacts")
    check_record_size(sample_rate, duration, positions.shape[0], len(planned))
    step = progress or no_progress
    step("predicting the records route's sensor budget", 0, 1)
    found = predict_records_budget(
        body, positions, directions, sensor_bounds(layout), planned, sample_rate=sample_rate, duration=duration,
        noise=noise,
    )  # fmt: skip
    step("predicting the records route's sensor budget", 1, 1)
    if found is None:
        return None
    mass = float(body.mass)
    parts_of = ({} if found.noise_std is None else {"noise": found.noise_std}) | found.std
    out = {source: {"center_of_gravity": np.asarray(parts["center_of_gravity"], dtype=float),
                    "inertia_tensor": mass * parts["inertia_per_mass"],
                    "stiffness_diagonal": mass * np.diag(parts["stiffness_per_mass"])}
           for source, parts in parts_of.items()}  # fmt: skip
    keys = out["position"]
    out["sensors"] = {key: np.sqrt(sum(out[s][key] ** 2 for s in found.std)) for key in keys}
    if "noise" in out:
        out["combined"] = {key: np.hypot(out["noise"][key], out["sensors"][key]) for key in keys}
    test = {
        "impacts": [{"position": p.tolist(), "direction": (d / np.linalg.norm(d)).tolist()} for p, d in planned],
        "sample_rate_hz": float(sample_rate), "duration_s": float(duration), "noise": float(noise),
        "fit_decimation": found.factor,
        "fit_rows": found.rows, "rows_used": found.used,
    }  # fmt: skip
    return out, test


def _plan_references(
    references: ReferencesFile | PathLike | None, layout: LayoutFile, body: Body | None
) -> ReferenceReport | None:
    """``plan --references``: the reference set checked against the layout (and the body estimate)."""
    if references is None:
        return None
    from rigidid.core.plan import check_references
    from rigidid.io.frf import reference_arrays

    refs = load_references_for(references, layout)
    ids, positions, directions = files.layout_arrays(layout)
    _, rpos, rdirs = reference_arrays(refs)
    return check_references(positions, directions, rpos, rdirs, body=body, unit=layout.units.length, names=ids)


def _suggest(
    body: Body,
    lay: LayoutFile,
    positions: NDArray[np.float64],
    directions: NDArray[np.float64],
    candidates: LayoutFile | PathLike | None,
    add: int,
    levels: NoiseLevels,
    draws: int,
    seed: int | None,
    step: ProgressCallback,
) -> SensorPlan | None:
    """`add` sensors chosen one at a time among `candidates` (default: a grid around the layout), or None."""
    from rigidid.core.plan import suggest_sensors

    if not add:
        return None
    if add < 0:
        raise InputError(f"must be positive, got {add}", source="add")
    cand_pos = cand_dir = None
    if candidates is not None:
        cand = candidates if isinstance(candidates, LayoutFile) else files.load_layout(candidates, require_rank=False)
        same_units(cand, lay, None if isinstance(candidates, LayoutFile) else str(candidates))
        _, cand_pos, cand_dir = files.layout_arrays(cand)
    step(f"choosing {add} sensors to add", 0, add)
    return suggest_sensors(
        body, positions, directions, cand_pos, cand_dir, add=add, noise=levels, draws=min(draws, 300), seed=seed,
        progress=lambda _, done, total: step(f"choosing {add} sensors to add", done, total),
    )  # fmt: skip
