"""Impact records: modes estimated from record files (read in row blocks), the output-error refit of the body
on the records, record-spread intervals, the records' spectrum, and :func:`identify_test` /
:func:`identify_records`, what ``rigidid identify`` does with a test's files."""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from rigidid.api import checks
from rigidid.api.identification import identify, suspect_mode, with_warnings
from rigidid.api.load import UFF_SUFFIXES, check_uff_options, input_source, load_layout, load_records, load_test
from rigidid.core.selection import rigid_fit_residuals
from rigidid.errors import InputError
from rigidid.io import files
from rigidid.io.files import ModeTable
from rigidid.models import LayoutFile
from rigidid.results import IdentifyResult, PathLike, TestData, TestRun

if TYPE_CHECKING:
    from rigidid.api.force import ForceOptions
    from rigidid.core.sensor_budget import SensorBounds
    from rigidid.core.timedomain import ModalEstimate
    from rigidid.core.timedomain.chain import ChainModel
    from rigidid.io.files import ModeTable
    from rigidid.progress import ProgressCallback


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
    keep_decays: bool = False,
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
    keep_decays : bool
        For record files read in row blocks: keep, during that one read, the impacts and decays
        the output-error refit needs (:attr:`ModalEstimate.decays
        <rigidid.core.timedomain.estimate.ModalEstimate.decays>`), so that :func:`refine_records`
        need not read the files again.

    Returns
    -------
    modes : ModeTable
        Modes labelled 1..n_modes in ascending frequency; with the layout's ``chain``, the
        shapes with the chain divided out (:func:`chain_corrected`).
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
        return _estimate_streamed(lay, paths, method, n_modes, band, max_order, decimate, progress,
                                  keep_decays=keep_decays)  # fmt: skip
    records_given = bool(arrays)
    arrays += load_records(paths, lay)
    dts = [dt for _, dt in arrays]
    if max(dts) - min(dts) > 1e-9 * max(dts):
        raise InputError(
            f"records have different sample intervals ({min(dts):.6g} to {max(dts):.6g} s)", source="records"
        )
    from rigidid.core.timedomain.clipping import clipped_channels

    ids = tuple(s.id for s in lay.sensors)
    whole = [clipped_channels([data]) for data, _ in arrays]
    starts = [_decay_start(data, dt) if mask.any() else 0 for mask, (data, dt) in zip(whole, arrays, strict=True)]
    in_decay = [clipped_channels([data], [k]) if mask.any() else mask
                for mask, k, (data, _) in zip(whole, starts, arrays, strict=True)]  # fmt: skip
    kept = _unclipped(ids, _pulse_clipped(ids, whole, in_decay))
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
    _warn_hits(result.impacts, [str(p) for p in paths] if not records_given else
               [f"record {k + 1}" for k in range(len(arrays))], dts[0])  # fmt: skip
    table = ModeTable.numbered(result.frequency_hz, result.damping_ratio, [ids[c] for c in columns], result.shapes)
    return chain_corrected(table, lay), result


def _warn_hits(impacts: Sequence[Any], names: Sequence[str], dt: float) -> None:
    """A DoubleHitWarning naming the records where more than one hit was found (none when each has one)."""
    several = [(name, i) for name, i in zip(names, impacts, strict=False) if getattr(i, "hits", 1) > 1]
    if not several:
        return
    import warnings

    from rigidid.errors import DoubleHitWarning

    named = "; ".join(
        f"{name}: {i.hits} hits, the last {(i.start - i.onset) * dt:.3g} s after the first" for name, i in several
    )
    warnings.warn(
        f"double hit: {named}; the free decay is taken after the last hit (the pre-trigger before the first)",
        DoubleHitWarning,
        stacklevel=3,
    )


def _decay_start(data: NDArray[np.float64], dt: float, energy: NDArray[np.float64] | None = None) -> int:
    """The first row of `data`'s free decay (:func:`~rigidid.core.timedomain.preprocess.find_impact`, as the
    estimation finds it); 0 when it finds none (the estimation then says why)."""
    from rigidid.core.timedomain.preprocess import find_impact

    try:
        return int(find_impact(data, dt, energy=energy).start)
    except InputError:
        return 0


def _pulse_clipped(
    ids: Sequence[str], whole: Sequence[NDArray[np.bool_]], in_decay: Sequence[NDArray[np.bool_]]
) -> list[NDArray[np.bool_]]:
    """`in_decay` (per record, the channels clipped in the free decay), with a ClippedChannelWarning naming
    those clipped only before it (`whole`: anywhere), during the hammer's pulse: they are kept in the fit.

    The acceleration peaks during the pulse; an overload there leaves the free decay the fit reads as the
    sensor gave it (chain_matrix's clip80 cell: every flat top within the 3 ms pulse). Leaving such a channel
    out cost the sensors' correction its redundancy (10 sensors to 8: the inertia's noise std 3-5 times).
    """
    anywhere = np.zeros(len(ids), dtype=bool)
    for mask in in_decay:
        anywhere |= mask
    where: dict[int, list[int]] = {}
    for k, (w, d) in enumerate(zip(whole, in_decay, strict=True)):
        for c in np.flatnonzero(w & ~d & ~anywhere):
            where.setdefault(int(c), []).append(k + 1)
    if where:
        from rigidid.errors import ClippedChannelWarning

        named = ", ".join(f"{ids[c]!r} (record {', '.join(map(str, where[c]))})" for c in sorted(where))
        warnings.warn(
            f"channels clipped during the impact only (flat tops before the free decay), kept in the fit: {named}",
            ClippedChannelWarning,
            stacklevel=4,
        )
    return list(in_decay)


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
    keep_decays: bool = False,
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
    layout, records, method, band, max_order, decimate, progress, keep_decays
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
    from rigidid.errors import (
        ClippedChannelWarning,
        DoubleHitWarning,
        ElasticModeWarning,
        IdentificationError,
        OffsetDriftWarning,
    )

    lay = layout if isinstance(layout, LayoutFile) else load_layout(layout)
    options: dict[str, Any] = {
        "method": method, "band": band, "max_order": max_order, "decimate": decimate, "progress": progress,
        "keep_decays": keep_decays,
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
            for repeated in (ClippedChannelWarning, OffsetDriftWarning, DoubleHitWarning):
                warnings.simplefilter("ignore", repeated)
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
    keep_decays: bool = False,
) -> tuple[ModeTable, ModalEstimate]:
    """:func:`estimate_modes` on record files read in blocks and decimated as they arrive (with
    `keep_decays`, the refit's impacts and decays kept on the way).

    The first record chooses the pre-decimation factor (:mod:`rigidid.io.records.streamed`)
    or takes the user's `decimate` whole; the others share it. The estimate reports
    the total factor, the impacts in the files' rows.
    """
    from rigidid.core.timedomain import DEFAULT_METHOD, Impact
    from rigidid.core.timedomain import estimate_modes as estimate
    from rigidid.core.timedomain.preprocess import FIR_HALF_LENGTH
    from rigidid.errors import IdentificationError
    from rigidid.io.records.streamed import read_records_streamed

    ids = [s.id for s in lay.sensors]
    f_limit = float(band[1]) if band is not None else None
    # second decimation stage while reading (memory of the decimated record only), unless the user fixed the
    # factor; read_records_streamed reads again without it when all records' content asks another factor
    cascade = cascade and decimate is None
    streamed, content = read_records_streamed(paths, ids, decimate, f_limit, progress, cascade=cascade,
                                              capture=keep_decays)  # fmt: skip
    factor = streamed[0].factor
    dts = [r.dt for r in streamed]
    cascaded = streamed[0].stages[1] > 1
    whole = [r.clipped for r in streamed if r.clipped is not None]
    in_decay = [
        r.clipped if not r.clipped.any() or r.clip_last is None
        else r.clipped & (r.clip_last >= r.offset + _decay_start(r.data, r.dt, r.energy) * r.factor)
        for r in streamed if r.clipped is not None
    ]  # fmt: skip
    kept = _unclipped(ids, _pulse_clipped(ids, whole, in_decay))
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
        return _estimate_streamed(lay, paths, method, n_modes, band, max_order, decimate, progress, cascade=False,
                                  keep_decays=keep_decays)  # fmt: skip
    if factor > 1:
        impacts = tuple(
            Impact(r.offset + i.onset * factor, r.offset + i.peak * factor, r.offset + i.start * factor, i.hits)
            for r, i in zip(streamed, result.impacts, strict=False)
        )
        result = replace(result, decimation=result.decimation * factor, impacts=impacts)
    if kept is not None:
        result = replace(result, channels=kept)
    _warn_hits(result.impacts, [str(p) for p in paths], dts[0] / factor)
    if any(r.trend is not None for r in streamed):
        result = replace(result, trends=tuple(r.trend for r in streamed))
    elif all(r.captured is not None for r in streamed):  # the refit's reading, done on the way
        result = replace(result, decays=tuple(r.captured for r in streamed))
    table = ModeTable.numbered(result.frequency_hz, result.damping_ratio, [ids[c] for c in columns], result.shapes)
    return chain_corrected(table, lay), result


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
    tolerances: SensorBounds | None = None,
    chain: ChainModel | None = None,
    estimate_delays: bool = False,
    estimate_sensors: bool | None = None,
    estimate_highpass: bool | None = None,
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
    tolerances : SensorBounds, optional
        The sensors' error bounds (type B), propagated into the intervals with the
        noise (the refit's own linearisation, :func:`rigidid.core.timedomain.refine.sensor_terms`); default
        :func:`sensor_bounds` of a layout without ``tolerances``.
    chain : ChainModel, optional
        The channels' acquisition chain in layout order (:func:`chain_model`), modelled in the refit.
    estimate_delays : bool
        Fit each channel's delay relative to the first (``--estimate-delays``).
    estimate_sensors : bool or None
        Estimate each sensor's gain, axis and position errors with the body, the
        tolerances as their prior (:class:`rigidid.core.timedomain.refine.SensorCorrection`);
        a sensor whose estimate is beyond 3 times its tolerance is named
        (:func:`implausible_sensors`). None (the default): when the sensor test flags sensor errors that
        move the body (:mod:`rigidid.core.timedomain.sensor_test`), through the chain, delays or hum when
        they are modelled (not with the noise from the residual: no pre-trigger); False: never (the plain
        refit).
    estimate_highpass : bool or None
        Without a high-pass in `chain`: model an AC coupling, one first-order high-pass common to the channels,
        at the corner the score test of the refit's residual finds (:mod:`rigidid.core.timedomain.coupling`).
        None (the default): when the test flags it (``--estimate-highpass``); False: tested, never modelled
        (``--no-estimate-highpass``); True: always modelled.

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
    bounds = tolerances if tolerances is not None else sensor_bounds(None, result.units["length"])
    return _refit(
        result,
        lambda delays: refine_body(
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
            drift=estimate.trends is not None,
            chain=_kept(chain, estimate.channels),
            estimate_delays=delays,
            sensor_bounds=bounds,
            estimate_sensors=estimate_sensors,
            estimate_highpass=estimate_highpass,
        ),
        progress,
        bounds,
        _kept_ids(result, estimate.channels),
        delays=estimate_delays,
    )


def _kept(chain: ChainModel | None, channels: Sequence[int] | None) -> ChainModel | None:
    """The chains of the channels fitted (the clipped ones left out)."""
    return chain if chain is None or channels is None else chain.columns(channels)


def _kept_ids(result: IdentifyResult, channels: Sequence[int] | None) -> tuple[str, ...]:
    """The fitted channels' ids (`result`'s are the layout's sensors it used)."""
    ids = result.sensor_ids
    return ids if channels is None or len(ids) == len(channels) else tuple(ids[c] for c in channels)


def chain_model(layout: LayoutFile) -> ChainModel | None:
    """The layout's ``chain`` as each sensor's chain, in layout order (None: no chain, or nothing to model).

    Parameters
    ----------
    layout : LayoutFile

    Returns
    -------
    ChainModel or None
        Per sensor, the global fields overridden by its ``chain.sensors`` entry field by field.
    """
    from rigidid.core.timedomain.chain import AntiAlias, ChainModel, ChannelChain

    block = layout.chain
    if block is None:
        return None
    channels = []
    for sensor in layout.sensors:
        over = (block.sensors or {}).get(sensor.id)

        def pick(name: str, over: Any = over) -> Any:
            value = getattr(over, name) if over is not None else None
            return value if value is not None else getattr(block, name)

        aa = pick("antialias")
        channels.append(
            ChannelChain(
                highpass_hz=pick("highpass_hz") or 0.0,
                highpass_order=pick("highpass_order") or 1,
                antialias=None if aa is None else AntiAlias(aa.type, aa.order, aa.corner_hz),
                delay=pick("delay_s") or 0.0,
            )
        )
    model = ChainModel(tuple(channels))
    return None if model.identity else model


def _refit(
    result: IdentifyResult,
    fit: Any,
    progress: ProgressCallback | None,
    tolerances: SensorBounds | None = None,
    ids: Sequence[str] = (),
    delays: bool = False,
) -> IdentifyResult:
    """Run `fit` (a refinement on the records: ``fit(delays)``, the channels' delays estimated or not) and
    accept it, or keep `result` with a RefinementWarning.

    A plain refit (`delays` False) that is not kept and whose residual's score test names a skew (a channel's
    delay step beyond :data:`_SKEW_Z` standard errors) is fitted again with the delays estimated
    (``--estimate-delays``, eq. (19) with a delay per channel); that refit is kept when its own misfit test
    keeps it (:func:`refit_verdict`), the skew's fitted delays named in a ChainWarning. With the sensors'
    errors estimated, the score (with the sensors freed too) is always given, and a skew it names is refitted
    whatever the verdict: the correction would otherwise take the skew for sensor errors, and the misfit test
    budgeted for the tolerances may accept that. The same when the correction was made and dropped by its
    after-check (the plain refit kept, the corrected fit's score with it).
    """
    refinement = _run_fit(result, fit, delays)
    if progress is not None:
        progress("refit", 1, 1)
    if refinement is None:
        return result
    late = _late_channels(refinement, ids)
    test = refinement.sensor_test  # a correction made, or dropped by its after-check: a skew taken for sensor errors
    corrected = refinement.sensor_correction is not None or (test is not None and not test.explains)
    if late and not delays and (corrected or not refit_verdict(refinement)[0]):
        return _refit_skewed(result, fit, refinement, tolerances, (ids, late))
    _warn_delays(refinement, ids, refinement.frequency_hz, late)
    return _accept_refinement(result, refinement, tolerances, ids)


def _run_fit(result: IdentifyResult, fit: Any, delays: bool, why: str = "", keep_plain: bool = False) -> Any:
    """``fit(delays)``, or None with a RefinementWarning (`why` before its reason) when it fails: the answer from
    the modes kept, or with `keep_plain` the plain refit (a skew's refit that failed after a plain one passed)."""
    import warnings

    from rigidid.errors import RefinementWarning

    try:
        return fit(delays)
    except (np.linalg.LinAlgError, InputError, ValueError) as exc:
        kept = "kept the refit without them" if keep_plain else "kept the answer from the modes"
        warnings.warn(
            f"{why}refinement on the records failed ({exc}); {kept}"
            + ("" if keep_plain else suspect_mode(result.identification)),
            RefinementWarning,
            stacklevel=4,
        )
        return None


def _refit_skewed(
    result: IdentifyResult,
    fit: Any,
    plain: Any,
    tolerances: SensorBounds | None,
    named: tuple[Sequence[str], list[tuple[int, str]]],
) -> IdentifyResult:
    """The refit with the channels' delays estimated, after the plain refit `plain` was rejected and its score
    test named the channels `named[1]` late (index, text); kept if its misfit test keeps it, else `result`
    with both refits' reasons.

    Its sensor budget is the refit's own, with the delays in its model (:func:`_accept_refinement`,
    :func:`rigidid.core.timedomain.refine.sensor_terms`), as --estimate-delays reports it.
    """
    import warnings

    from rigidid.errors import ChainWarning, RefinementWarning

    ids, late = named
    where = _skew_where(late, ids)
    plain_kept, first = refit_verdict(plain)
    why = (
        f"the refit's residual named a skew on {where}, and with the channels' delays estimated the "
        if plain_kept
        else f"the plain refit was rejected ({first}); with the channels' delays estimated (a skew on {where}), "
    )
    skewed = _run_fit(result, fit, True, why, keep_plain=plain_kept)
    if skewed is None:
        _warn_delays(plain, ids, plain.frequency_hz, late)
        return _accept_refinement(result, plain, tolerances, ids) if plain_kept else result
    keep, reason = refit_verdict(skewed)
    if keep and not _confirmed(skewed, late):  # the score's skew not in the fit: a misfit the score read as one
        if plain_kept:
            warnings.warn(
                f"the refit's residual named a skew on {where}, but refitted with the channels' delays estimated "
                f"no named channel's delay is beyond {_SKEW_Z:g} standard errors: kept the refit without them",
                ChainWarning,
                stacklevel=3,
            )
            _warn_delays(plain, ids, plain.frequency_hz, [])
            return _accept_refinement(result, plain, tolerances, ids)
        keep, reason = False, f"no named channel's fitted delay is beyond {_SKEW_Z:g} standard errors"
    if not keep:
        _warn_delays(plain, ids, plain.frequency_hz, late)
        warnings.warn(
            f"{first}; refitted with the channels' delays estimated (the residual shows a skew on {where}): "
            f"{reason}" + suspect_mode(result.identification),
            RefinementWarning,
            stacklevel=3,
        )
        return result
    fitted = [
        f"{ids[i]} {skewed.delays[i]:.3g} s (std {skewed.delays_std[i]:.2g} s)"
        for i, _ in late
        if skewed.delays is not None and i < len(skewed.delays)
    ]
    warnings.warn(
        f"the refit's residual showed a delay on channel(s) {where}: refitted with the channels' delays "
        f"estimated and kept that refit (fitted delay {', '.join(fitted)}); state the chain's delays in the "
        "layout's chain block",
        ChainWarning,
        stacklevel=3,
    )
    _warn_delays(skewed, ids, skewed.frequency_hz, [])
    return _accept_refinement(result, skewed, tolerances, ids)


_SKEW_Z = 5.0  # a delay step this many standard errors from zero: an unmodelled skew


def _confirmed(skewed: Any, late: list[tuple[int, str]]) -> bool:
    """Whether the refit with the delays fitted (`skewed`) finds a delay beyond :data:`_SKEW_Z` standard errors on
    a channel the score named (`late`, :func:`_late_channels`): a real skew does (a sample's skew at 2048 Hz: z
    about 200), a misfit of sensor errors the score reads as a phase need not (chain_regimes.py's
    compact-damp8-r1024, seed 800: scores z 5-10, fitted delays within 2 standard errors)."""
    if skewed.delays is None or skewed.delays_std is None:
        return False
    return any(abs(skewed.delays[i]) > _SKEW_Z * skewed.delays_std[i] for i, _ in late if i < len(skewed.delays))


def _late_channels(refinement: Any, ids: Sequence[str]) -> list[tuple[int, str]]:
    """The channels (index, text) whose delay step in `refinement`'s score test is beyond :data:`_SKEW_Z`."""
    if refinement.delay_score is None:
        return []
    step, z = refinement.delay_score
    return [(i, f"{name} ({d:.3g} s, z = {zz:.1f})") for i, (name, d, zz) in enumerate(zip(ids, step, z, strict=False))
            if abs(zz) > _SKEW_Z]  # fmt: skip


def _skew_where(late: list[tuple[int, str]], ids: Sequence[str]) -> str:
    """The late channels' texts (:func:`_late_channels`) and the channel their delays are relative to."""
    return ", ".join(text for _, text in late) + " relative to " + (ids[0] if ids else "the first channel")


def _warn_delays(refinement: Any, ids: Sequence[str], frequency_hz: Any, late: list[tuple[int, str]]) -> None:
    """ChainWarnings: an estimated delay beyond a quarter period of the top mode, an AC coupling the refit found and
    modelled (:mod:`rigidid.core.timedomain.coupling`), or an unmodelled skew's score (the channels `late`,
    :func:`_late_channels`); a HumWarning naming the mains hum the refit modelled."""
    import warnings

    from rigidid.errors import ChainWarning

    if refinement.delays is not None:
        quarter = 0.25 / float(np.max(frequency_hz))
        for name, d, sd in zip(ids, refinement.delays, refinement.delays_std, strict=False):
            if abs(d) > quarter:
                warnings.warn(
                    f"channel {name}: estimated delay {d:.3g} s (std {sd:.2g} s) is beyond a quarter period of the "
                    f"top mode ({quarter:.3g} s): implausible for a skew (a wrong sign or sensor?)",
                    ChainWarning,
                    stacklevel=3,
                )
    if refinement.hum:
        from rigidid.errors import HumWarning

        warnings.warn(
            "mains hum in the records at "
            + ", ".join(f"{hz:g} Hz (amplitude {amp:.3g} noise std, z = {z:.0f})" for hz, z, amp in refinement.hum)
            + ": modelled in the refit as a sinusoid per channel and impact",
            HumWarning,
            stacklevel=3,
        )
    found = refinement.coupling
    if found is not None and (found.modelled or found.flagged):
        score = f"score {found.statistic:.0f} on {found.dof} degrees of freedom, p = {found.p_value:.2g}"
        what = (
            f"showed an AC coupling nobody stated (a decay e^(-2 pi f t) on every channel after each impact, {score}): "
            f"modelled a first-order high-pass at {found.corner_hz:.3g} Hz (std {found.corner_std_hz:.2g} Hz) on "
            "every channel"
            if found.modelled
            else f"shows an AC coupling nobody stated (a decay e^(-2 pi f t) on every channel after each impact, "
            f"{score}, corner {found.corner_hz:.3g} Hz): not modelled (--no-estimate-highpass)"
        )
        warnings.warn(
            f"the refit's residual {what}; state the sensors' highpass_hz in the layout's chain block",
            ChainWarning,
            stacklevel=3,
        )
    if late:
        warnings.warn(
            "the refit's residual shows a delay (a phase growing with frequency) on channel(s) "
            + _skew_where(late, ids)
            + ": state the chain's delays in the layout's chain block or use --estimate-delays",
            ChainWarning,
            stacklevel=3,
        )


def sensor_bounds(layout: LayoutFile | None, length: str = "m") -> SensorBounds:
    """The sensors' error bounds: the layout's ``tolerances``, each field left out from the defaults.

    Parameters
    ----------
    layout : LayoutFile or None
        The layout (its ``tolerances`` and length unit); None: the defaults.
    length : str
        The length unit when `layout` is None.

    Returns
    -------
    SensorBounds
        :data:`rigidid.core.sensor_budget.DEFAULT_BOUNDS` (position converted to
        the layout's length unit) overridden field by field.
    """
    from rigidid.core.sensor_budget import DEFAULT_BOUNDS
    from rigidid.core.sensor_budget import SensorBounds as Bounds
    from rigidid.units import M_PER_LENGTH

    unit = layout.units.length if layout is not None else length
    values = {
        "sensitivity": DEFAULT_BOUNDS.sensitivity,
        "orientation_deg": DEFAULT_BOUNDS.orientation_deg,
        "transverse": DEFAULT_BOUNDS.transverse,
        "position": DEFAULT_BOUNDS.position / M_PER_LENGTH[unit],
    }
    given = layout.tolerances if layout is not None else None
    if given is not None:
        values.update({k: v for k, v in given.model_dump().items() if v is not None})
    return Bounds(**values)


def _sensor_std(result: IdentifyResult, bounds: SensorBounds) -> dict[str, dict[str, NDArray[np.float64]]] | None:
    """Each type-B source's std of the body at the modes used (None when the kernel cannot linearise them)."""
    from rigidid.core.sensor_budget import sensor_budget

    if result.poles is None or result.shapes is None:
        return None
    try:
        budget = sensor_budget(result.positions, result.directions, result.poles, result.shapes, bounds)
    except ValueError:
        return None
    return budget.std


def _accept_refinement(
    result: IdentifyResult, refinement: Any, tolerances: SensorBounds | None = None, ids: Sequence[str] = ()
) -> IdentifyResult:
    """`result` with the refinement's body and bound when its misfit test accepts it (:func:`refit_verdict`)."""
    import warnings

    from rigidid.core.timedomain.refine import record_bound
    from rigidid.errors import RefinementWarning

    ident = result.identification
    keep, reason = refit_verdict(refinement)
    if reason:
        warnings.warn(reason + ("" if keep else suspect_mode(ident)), RefinementWarning, stacklevel=2)
    if not keep:
        return result
    refined = replace(
        ident,
        center_of_gravity=refinement.center_of_gravity,
        inertia_per_mass=refinement.inertia_per_mass,
        stiffness_per_mass=refinement.stiffness_per_mass,
        damping_per_mass=refinement.damping_per_mass,
    )
    bounds = tolerances if tolerances is not None else sensor_bounds(None, result.units["length"])
    if refinement.sensor_correction is not None:
        implausible_sensors(refinement.sensor_correction, bounds, result.sensor_ids)
    # the refit's own linearisation (sensor_terms, its chain, delays and hum included): the refit weighs the
    # channels by their noise, the kernel does not, so their errors are different combinations of the same
    # sensor errors; the kernel's budget (what plan predicts) only when the refit has none
    # (benchmarks/sensor_sensitivity.py; with fitted delays the kernel's was too wide: chain_matrix "all").
    sensor_std = refinement.sensor_std
    if sensor_std is None:
        sensor_std = _sensor_std(result, bounds)
    bound = record_bound(refinement, ident.mass, sensor_std, dict(vars(bounds)) if sensor_std is not None else None)
    if refinement.delays is not None:
        pairs = zip(ids, refinement.delays, refinement.delays_std, strict=False)
        bound = replace(bound, delays={name: (float(d), float(sd)) for name, d, sd in pairs})
    if refinement.hum:
        bound = replace(bound, hum_hz=tuple(hz for hz, _, _ in refinement.hum))
    if refinement.sensor_correction is not None:
        named = ids if ids else result.sensor_ids
        bound = replace(bound, sensor_correction=refinement.sensor_correction, corrected_sensors=tuple(named))
    return replace(result, identification=refined, record_bound=bound, standard_errors=None)


def implausible_sensors(correction: Any, bounds: SensorBounds, ids: Sequence[str]) -> list[str]:
    """Name, in a :class:`~rigidid.errors.SensorCorrectionWarning`, each sensor whose estimated error is implausible.

    Parameters
    ----------
    correction : SensorCorrection
        The sensors' errors estimated with the body
        (:class:`rigidid.core.timedomain.refine.SensorCorrection`).
    bounds : SensorBounds
        The stated tolerances.
    ids : sequence of str
        The sensors' ids, in the correction's order.

    Returns
    -------
    list of str
        The ids named: a determined gain beyond 3 times the sensitivity tolerance, a determined
        tilt beyond 3 times the orientation and transverse tolerances together, or a determined
        shift beyond 3 times the position tolerance along an axis.
    """
    from rigidid.errors import SensorCorrectionWarning

    x, ok = correction.value, correction.determined
    tilt_bound = math.radians(bounds.orientation_deg) + bounds.transverse
    named = []
    for i, sid in enumerate(ids):
        parts = []
        if ok[0, i] and bounds.sensitivity > 0.0 and abs(x[0, i]) > 3.0 * bounds.sensitivity:
            parts.append(f"gain {100 * x[0, i]:+.3g} % (tolerance {100 * bounds.sensitivity:g} %)")
        if ok[1:3, i].all() and tilt_bound > 0.0 and math.hypot(x[1, i], x[2, i]) > 3.0 * tilt_bound:
            parts.append(f"axis off by {math.degrees(math.hypot(x[1, i], x[2, i])):.3g} degrees")
        if ok[3:, i].any() and bounds.position > 0.0 and np.max(np.abs(x[3:, i][ok[3:, i]])) > 3.0 * bounds.position:
            parts.append(f"position off by {np.max(np.abs(x[3:, i][ok[3:, i]])):.3g} (tolerance {bounds.position:g})")
        if parts:
            named.append(sid)
            warnings.warn(
                f"sensor {sid}: the records say its " + ", ".join(parts) + ", beyond 3 times its stated tolerance: "
                "check its calibration, mounting and position",
                SensorCorrectionWarning,
                stacklevel=3,
            )
    return named


def refit_verdict(refinement: Any) -> tuple[bool, str]:
    """Whether to keep a refit, and why (empty: accepted as it is).

    Parameters
    ----------
    refinement : Refinement
        The refit (:func:`rigidid.core.timedomain.refine.refine_prepared`).

    Returns
    -------
    keep : bool
        Use the refit's answer (False: the answer from the modes).
    reason : str
        The warning to give; empty when the refit is accepted.

    Notes
    -----
    With a pre-trigger, the refit's residual is tested against it
    (:func:`rigidid.core.timedomain.acceptance.misfit_test`, false-alarm rate
    :data:`~rigidid.core.timedomain.acceptance.FALSE_ALARM`). Accepted: kept as it is.
    Not accepted but within twice the noise's variance (normalised cost below 2): the
    model misses something systematic (the chain, the sensors), yet the refit still uses
    the whole records; its answer is kept, named, with its standard errors as they are.
    They already hold the misfit: the sandwich
    (:func:`rigidid.core.timedomain.intervals.parameter_covariance`) takes each impact's
    and channel's level ``v_ic`` from the fit's own residual, which is ``R_ic`` times the
    pre-trigger's when the residual exceeds the noise ``R_ic`` times. That is the Birge
    ratio's scaling, per impact and channel; scaling the standard errors again by the
    square root of the pooled ratio counted it twice (the intervals' variance ``R^2``
    times the noise's: on the chain matrix's ``aa`` cell, whose filtered noise is 1.25 times
    denser in the fit's band than the pre-trigger's level taken as white, the true spread was
    0.84 of the reported std, 1.03 without the second scaling; ``benchmarks/refit_width.py``).
    Beyond: the answer from the modes, with the reason. Without a pre-trigger (no test
    possible) the normalised cost must be below 2.
    """
    from rigidid.core.timedomain.refine import good_fit

    test = refinement.misfit
    cost = refinement.normalised_cost
    if test is not None and test.accepted:
        return True, ""
    if test is None:
        if good_fit(refinement):
            return True, ""
        return False, (
            f"refinement on the records ended at a normalised cost of {cost:.3g} (about 1 at a good fit): "
            "a local minimum or a model that does not fit the records; kept the answer from the modes"
        )
    why = (
        f"the refit's residual is {test.ratio:.3g} times the pre-trigger's noise variance (misfit test p = "
        f"{test.p_value:.2g}, false-alarm rate {test.false_alarm:g}): the rigid-body model misses part of the "
        "records (the acquisition chain, sensor errors, an unmodelled mode, or a local minimum)"
    )
    if good_fit(refinement):
        return True, f"{why}; kept the refit, its noise standard errors from its residual's level"
    return False, f"{why}; normalised cost {cost:.3g}: kept the answer from the modes"


STREAM_REFIT_VALUES = 16 * 150_000


def refine_records(
    result: IdentifyResult,
    paths: Sequence[PathLike],
    layout: LayoutFile | PathLike,
    estimate: ModalEstimate,
    *,
    progress: ProgressCallback | None = None,
    stream_above: int | None = None,
    estimate_delays: bool = False,
    estimate_sensors: bool | None = None,
    estimate_highpass: bool | None = None,
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
        (:func:`rigidid.io.records.refit.read_prepared_decays`: the pre-trigger
        statistics and the decays at the fit's rate, nothing else held);
        smaller ones are read whole.
    estimate_delays : bool
        Fit each channel's delay (:func:`with_refinement`); the layout's ``chain`` is modelled.
    estimate_sensors, estimate_highpass : bool or None
        As for :func:`with_refinement`.

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
    (:func:`rigidid.io.records.refit.locate_impacts`) holding the rows around
    `estimate`'s impacts. The records are read whole when that pass cannot
    prove its impacts, and when `result` leaves out a mode of `estimate` (an
    elastic one, subtracted from the raw records). The refit's decimation is
    the smallest up to `estimate`'s factor that fits its row budget, so it may
    differ from a whole-record estimation's when that budget binds (and, for a
    CSV whose rows are estimated from its size, by up to a tenth). That pass
    also reads the decays (:func:`rigidid.io.records.refit.locate_and_read`): each
    file is read once for the refit, rarely twice.

    When `estimate` carries the decays its own reading captured
    (:attr:`~rigidid.core.timedomain.estimate.ModalEstimate.decays`, what
    :func:`identify_test` asks for when a refit follows), the files are not read again:
    :func:`rigidid.core.timedomain.streaming.captured_decays` accepts them (the impacts
    proved on the raw rows, the fit's factor at most the estimate's) or the pass above runs.
    """

    import warnings

    from rigidid.core.timedomain.refine import columns_of, refine_prepared
    from rigidid.errors import OffsetDriftWarning
    from rigidid.io.records import layout_ids, open_source

    lay = layout if isinstance(layout, LayoutFile) else load_layout(layout)
    ids = [s.id for s in lay.sensors]
    unused = any(k + 1 not in result.modes_used for k in range(estimate.poles.size))
    size = 0
    if not unused:
        size = sum(open_source(Path(p), layout_ids(ids, str(p)), None).rows for p in paths) * len(ids)
    dt = estimate.sample_interval / max(1, estimate.decimation)
    impacts, read = None, None
    if not unused and size > (STREAM_REFIT_VALUES if stream_above is None else stream_above):
        from rigidid.core.timedomain.preprocess import FIR_HALF_LENGTH
        from rigidid.io.records.refit import locate_and_read

        reach = (2 * FIR_HALF_LENGTH + 2) * max(1, estimate.decimation) + round(0.005 / dt) + 2
        located = _captured(estimate, len(ids), dt, reach)
        if located is None:
            located = locate_and_read(paths, ids, dt, estimate.impacts, reach, factor=estimate.decimation,
                                      progress=progress, trends=estimate.trends)  # fmt: skip
        impacts, read = (None, None) if located is None else located
    if impacts is None or read is None:
        # read whole; the impacts where the raw records put them (as their estimation would)
        from rigidid.core.timedomain.preprocess import find_impact

        with warnings.catch_warnings():  # named when the records were read for the estimation
            warnings.simplefilter("ignore", OffsetDriftWarning)
            raw = load_records(paths, lay)
        found = tuple(find_impact(data, step) for data, step in raw)
        return with_refinement(
            result, raw, replace(estimate, impacts=found), progress=progress, tolerances=sensor_bounds(lay),
            chain=chain_model(lay), estimate_delays=estimate_delays, estimate_sensors=estimate_sensors,
            estimate_highpass=estimate_highpass,
        )  # fmt: skip
    estimate = replace(estimate, impacts=tuple(impacts))
    ident = result.identification
    if progress is not None:
        progress("refit", 0, 1)

    held: list[Any] = []  # the decays, read once for both refits (a skew's second one: _refit)

    def fit(delays: bool) -> Any:
        if not held:  # the decays, read with the impacts when they could be (io.records.refit.locate_and_read)
            data = read()
            held.append(data if estimate.channels is None else columns_of(data, estimate.channels))  # clipped out
        data = held[0]
        return refine_prepared(
            data, dt, result.positions, result.directions, center_of_gravity=ident.center_of_gravity,
            inertia_per_mass=ident.inertia_per_mass, stiffness_per_mass=ident.stiffness_per_mass,
            damping_per_mass=ident.damping_per_mass, drift=estimate.trends is not None, sensor_bounds=bounds,
            chain=_kept(chain_model(lay), estimate.channels), estimate_delays=delays,
            estimate_sensors=estimate_sensors, estimate_highpass=estimate_highpass,
        )  # fmt: skip

    bounds = sensor_bounds(lay)
    return _refit(result, fit, progress, bounds, _kept_ids(result, estimate.channels), delays=estimate_delays)


def _captured(estimate: ModalEstimate, channels: int, dt: float, reach: int) -> tuple[list[Any], Any] | None:
    """The impacts and ``read()`` of the decays the modes' reading captured (None: read the files again)."""
    if estimate.decays is None or estimate.trends is not None:
        return None
    from rigidid.core.timedomain.streaming import captured_decays, prepared_from

    found = captured_decays(estimate.decays, channels, estimate.decimation, estimate.impacts, reach)
    if found is None:
        return None
    impacts, passes, q = found
    return impacts, lambda: prepared_from(passes, channels, dt, q)


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
        (:func:`rigidid.io.records.spectrum.summed_spectrum_streamed`); the
        records read whole when one is shorter than a Welch segment (4096 rows).
    """
    from rigidid.io.records import layout_ids, open_source
    from rigidid.io.records.spectrum import summed_spectrum_streamed

    lay = layout if isinstance(layout, LayoutFile) else load_layout(layout)
    ids = [s.id for s in lay.sensors]
    sources = [open_source(Path(p), layout_ids(ids, str(p)), None) for p in paths]
    if not sources:
        return None
    if min(s.rows for s in sources) < 2 * 4096:  # short records (rows told by the header or the size): read whole
        del sources
        return summed_record_spectrum(load_records(paths, lay))
    dt = _source_dt(sources[0])
    del sources
    return summed_spectrum_streamed(paths, ids, dt, progress=progress)


def _source_dt(source: Any) -> float:
    """The sample interval of a row-block source: its own, or from the first block's time column."""
    if source.dt:
        return float(source.dt)
    t, _ = next(iter(source.blocks))
    return float(t[1] - t[0])


def summed_record_spectrum(
    records: Sequence[tuple[NDArray[np.float64], float]],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    from rigidid.core.spectrum import summed_spectrum

    return summed_spectrum([data for data, _ in records], records[0][1])


@dataclass(frozen=True)
class ModalOptions:
    """How modes are estimated from impact records (the ``modes`` command's and ``identify --records``' options).

    Attributes
    ----------
    method : str or None
        Estimation method of :mod:`rigidid.core.timedomain` (None: its default).
    n_modes : int
        Modes to estimate.
    band : (float, float) or None
        Frequency band in Hz.
    max_order : int or None
        Highest model order of the stabilisation sweep.
    decimate : int or None
        Decimation factor (None: from the records' content).
    """

    method: str | None = None
    n_modes: int = 6
    band: tuple[float, float] | None = None
    max_order: int | None = None
    decimate: int | None = None


def _refuse_record_options(modal: ModalOptions | None, refine: bool) -> None:
    """Options of the records route given with modes: refused, naming the first, rather than ignored."""
    given = modal or ModalOptions()
    default = ModalOptions()
    names = {"method": "modal_method", "n_modes": "n_modes", "band": "band", "max_order": "max_order",
             "decimate": "decimate"}  # fmt: skip
    for field, name in names.items():
        if getattr(given, field) != getattr(default, field):
            raise InputError("applies to impact records only (`records`); the input here is modes", source=name)
    if not refine:
        raise InputError("the refit runs on impact records only (`records`); the input here is modes", source="refine")


def estimate_test_modes(
    data: TestData,
    modal: ModalOptions,
    *,
    paths: Sequence[PathLike] | None = None,
    rigid_six: bool = False,
    progress: ProgressCallback | None = None,
    keep_decays: bool = False,
) -> tuple[ModeTable, ModalEstimate]:
    """Modes from a test's records, or from record files read in row blocks (`paths`).

    With `rigid_six` and six modes asked, seven are estimated when one of six looks elastic and the
    rigid six are returned (:func:`estimate_rigid_modes`); otherwise :func:`estimate_modes`. With
    `keep_decays`, the files' one read also keeps what the refit needs (:func:`estimate_modes`).
    """
    from rigidid.core.timedomain import METHODS

    if modal.method is not None and modal.method not in METHODS:
        raise InputError(f"unknown method {modal.method!r}; choose {' or '.join(METHODS)}", source="modal_method")
    source: Sequence[PathLike] | Sequence[tuple[NDArray[np.float64], float]] = paths or data.records
    options = {"method": modal.method, "band": modal.band, "max_order": modal.max_order, "decimate": modal.decimate,
               "keep_decays": keep_decays}  # fmt: skip
    if rigid_six and modal.n_modes == 6:
        return estimate_rigid_modes(data.layout, source, progress=progress, **options)  # type: ignore[arg-type]
    return estimate_modes(data.layout, source, n_modes=modal.n_modes, progress=progress, **options)  # type: ignore[arg-type]


def identify_test(
    layout: PathLike,
    inputs: Sequence[PathLike] | None,
    *,
    records: bool = False,
    modal: ModalOptions | None = None,
    units: dict[str, str] | None = None,
    geometry: PathLike | None = None,
    refine: bool = True,
    resample: int = 0,
    spectrum: bool = False,
    progress: ProgressCallback | None = None,
    force: ForceOptions | None = None,
    estimate_delays: bool = False,
    estimate_sensors: bool | None = None,
    estimate_highpass: bool | None = None,
    **identify_options: Any,
) -> TestRun:
    """Load a test, estimate its modes from the records if asked, identify: what ``rigidid identify`` does.

    Record files (not UFF) are read in row blocks and decimated as they arrive unless `resample` needs the
    samples themselves; the output-error refit (`refine`, structured method) and the summed spectrum
    (`spectrum`, for the report) read the files again in row blocks, so memory stays bounded.

    Parameters
    ----------
    layout, inputs, units, geometry
        As for :func:`rigidid.api.load.load_test`.
    records : bool
        The inputs are impact records (one file per impact).
    modal : ModalOptions, optional
        How modes are estimated from the records.
    refine : bool
        Refit the body to the records (output error) after the identification from modes.
    resample : int
        Intervals from this many interleaved segments of the records (0: none).
    spectrum : bool
        Also return the records' summed spectrum.
    progress : callable, optional
        Progress callback (:mod:`rigidid.progress`).
    force : ForceOptions, optional
        Measure the mass with the records' force channel (:mod:`rigidid.api.force`); also when
        the layout has a ``force`` block. The body is identified per unit mass, then scaled by it.
    estimate_delays : bool
        The refit fits each channel's delay relative to the first (``--estimate-delays``); the layout's
        ``chain`` is modelled in any case.
    estimate_sensors : bool or None
        In the refit, estimate each sensor's errors with the body (:func:`with_refinement`; None: when
        the sensor test flags them).
    estimate_highpass : bool or None
        In the refit, model an AC coupling nobody stated (:func:`with_refinement`; None: when its score test
        flags it).
    **identify_options
        Passed to :func:`rigidid.api.identification.identify` (`mass`, `modes_used`, `method`, `uncertainty`,
        `noise`, `seed`, `mounts`).

    Returns
    -------
    TestRun
    """
    with _force_column_expected(layout, force):
        return _identify_test(
            layout, inputs, records=records, modal=modal, units=units, geometry=geometry, refine=refine,
            resample=resample, spectrum=spectrum, progress=progress, force=force, estimate_delays=estimate_delays,
            estimate_sensors=estimate_sensors, estimate_highpass=estimate_highpass,
            **identify_options,
        )  # fmt: skip


@contextmanager
def _force_column_expected(layout: PathLike, force: ForceOptions | None) -> Iterator[None]:
    """A context in which the force column used is not warned about as a column left out."""
    import re

    from rigidid.errors import NonSensorColumnWarning

    column = force.column if force is not None else None
    if column is None and Path(layout).suffix.lower() == ".json":
        try:
            block = load_layout(layout).force
        except InputError:  # the workflow raises it, in its place
            block = None
        column = block.column if block is not None else None
    if column is None:
        yield
        return
    with warnings.catch_warnings():
        warnings.filterwarnings(
            "ignore", message=rf".*columns {re.escape(repr(column))} are not sensors", category=NonSensorColumnWarning
        )
        yield


def _identify_test(
    layout: PathLike,
    inputs: Sequence[PathLike] | None,
    *,
    records: bool,
    modal: ModalOptions | None,
    units: dict[str, str] | None,
    geometry: PathLike | None,
    refine: bool,
    resample: int,
    spectrum: bool,
    progress: ProgressCallback | None,
    force: ForceOptions | None,
    estimate_delays: bool = False,
    estimate_sensors: bool | None = None,
    estimate_highpass: bool | None = None,
    **identify_options: Any,
) -> TestRun:
    """:func:`identify_test`'s work."""
    from rigidid.errors import ClippedChannelWarning, ElasticModeWarning, RefinementWarning, named_source, noted

    modal = modal or ModalOptions()
    method = identify_options.get("method", "structured")
    src = input_source(layout, inputs)
    check_uff_options(layout, units, geometry)
    if not records:
        _refuse_record_options(modal, refine)
    files_in = records and bool(inputs) and Path(layout).suffix.lower() not in UFF_SUFFIXES and geometry is None
    streamed = files_in and not resample
    data = (
        TestData(load_layout(layout))
        if streamed
        else load_test(layout, inputs or [], records=records, units=units, geometry=geometry)
    )
    _check_segments(data, resample)  # before any estimation: blame the option, not the records
    force, data, mass_given = _force_setup(force, data, records, streamed, identify_options, inputs or [])
    paths = list(inputs or []) if streamed else None
    notes: list[str] = []  # the record route's warnings, kept in the result's diagnostics too
    estimate = None
    modes = data.modes
    with named_source(src), noted(notes, ElasticModeWarning, ClippedChannelWarning):
        if records:
            rigid_six = identify_options.get("modes_used") is None
            modes, estimate = estimate_test_modes(data, modal, paths=paths, rigid_six=rigid_six, progress=progress,
                                                  keep_decays=refine and method == "structured")  # fmt: skip
    assert modes is not None
    summed = None
    if spectrum and paths:  # after the estimation, which checked the files
        with named_source(src):
            summed = records_spectrum(paths, data.layout)
    refining = refine and estimate is not None and method == "structured"
    held: list[warnings.WarningMessage] = []
    try:
        with named_source(src), warnings.catch_warnings(record=True) as held:
            warnings.simplefilter("always")
            # without the channels left out of the estimate (clipped)
            result = identify(fitted_layout(data.layout, modes), modes, progress=progress, **identify_options)
    except BaseException:  # the warnings first, then the error they led to
        checks.pass_on(held)
        raise
    if not refining:
        checks.pass_on(held)
    else:
        assert estimate is not None
        try:
            with named_source(src), noted(notes, RefinementWarning):
                result = _refit_test(result, data, paths, estimate, progress, estimate_delays,
                                     (estimate_sensors, estimate_highpass))  # fmt: skip
        except BaseException:
            checks.pass_on(held)
            raise
        result = checks.about_the_answer(result, held, replaced=result.record_bound is not None)
    if force is not None and paths is not None:
        result = _with_force(result, paths, data.layout.model_copy(update={"mass": mass_given}), force, src)
    result = with_warnings(result, notes)
    if resample:
        result = _resampled(result, data, records, modal, resample, len(modes.labels))
    return TestRun(result, estimate, None if streamed else data.records, summed)


def _refit_test(
    result: IdentifyResult,
    data: TestData,
    paths: list[PathLike] | None,
    estimate: ModalEstimate,
    progress: ProgressCallback | None,
    estimate_delays: bool,
    estimating: tuple[bool | None, bool | None],
) -> IdentifyResult:
    """The refit on the test's records: read in row blocks from `paths`, else on the records held; `estimating` is
    ``(estimate_sensors, estimate_highpass)``."""
    sensors, highpass = estimating
    if paths is not None:
        return refine_records(
            result, paths, data.layout, estimate, progress=progress, estimate_delays=estimate_delays,
            estimate_sensors=sensors, estimate_highpass=highpass,
        )  # fmt: skip
    return with_refinement(
        result, data.records, estimate, progress=progress, tolerances=sensor_bounds(data.layout),
        chain=chain_model(data.layout), estimate_delays=estimate_delays, estimate_sensors=sensors,
        estimate_highpass=highpass,
    )  # fmt: skip


def chain_corrected(modes: ModeTable, layout: LayoutFile) -> ModeTable:
    """`modes` estimated from records with the layout's chain divided out of the shapes (``phi_ck / H_c(s_k)``).

    Parameters
    ----------
    modes : ModeTable
        Modes from the records (ERA or AR): each shape value is the mode's contribution
        through the channel's chain (:mod:`rigidid.core.timedomain.chain`).
    layout : LayoutFile
        Its ``chain`` (none: `modes` returned as they are).

    Returns
    -------
    ModeTable
    """
    chain = chain_model(layout)
    if chain is None or modes.frequency_hz.size == 0:
        return modes
    index = {s.id: k for k, s in enumerate(layout.sensors)}
    kept = chain.columns([index[name] for name in modes.sensor_ids])
    w = 2.0 * np.pi * np.asarray(modes.frequency_hz, dtype=float)
    zeta = np.asarray(modes.damping_ratio, dtype=float)
    poles = -zeta * w + 1j * w * np.sqrt(np.maximum(1.0 - zeta**2, 0.0))
    return replace(modes, shapes=kept.correct_shapes(poles, modes.shapes))


def _resampled(
    result: IdentifyResult, data: TestData, records: bool, modal: ModalOptions, resample: int, n_modes: int
) -> IdentifyResult:
    """`result` with the record-spread intervals of :func:`with_record_spread`."""
    if not records:
        raise InputError("data-driven intervals need impact records (--records)", source="segments")
    options = {"method": modal.method, "band": modal.band, "max_order": modal.max_order}
    return with_record_spread(
        result, data.records, segments=resample, n_modes=n_modes,
        estimate_options={k: v for k, v in options.items() if v is not None},
    )  # fmt: skip


def _force_setup(
    force: ForceOptions | None,
    data: TestData,
    records: bool,
    streamed: bool,
    options: dict[str, Any],
    paths: Sequence[PathLike],
) -> tuple[ForceOptions | None, TestData, float | None]:
    """Whether the force is used (`force`, or the layout's ``force`` block) and, if so, the test without its mass.

    The records are then identified per unit mass (the ``mass`` option taken out of `options`);
    the given mass is returned to be reported beside the measured one.
    """
    if force is None and (data.layout.force is None or not records):  # the layout's block applies to records
        return None, data, None
    from rigidid.api.force import ForceOptions as Options
    from rigidid.api.force import check_force

    force = force or Options()
    if not (records and streamed):
        raise InputError("a measured force needs record files (--records, not UFF or --resample)", source="force")
    check_force(data.layout, force, paths)
    given = options.pop("mass", None)
    given = given if given is not None else data.layout.mass
    return force, replace(data, layout=data.layout.model_copy(update={"mass": None})), given


def _with_force(
    result: IdentifyResult, paths: Sequence[PathLike], layout: LayoutFile, force: ForceOptions, src: str
) -> IdentifyResult:
    """`result` scaled by the mass the force measures; the H1 FRFs written when asked."""
    from rigidid.api.force import measure_mass, with_measured_mass
    from rigidid.errors import named_source

    with named_source(src):
        measured, frf = measure_mass(result, paths, layout, force, sensor_bounds(layout))
    if force.frf_out is not None:
        from rigidid.api.force import write_frf

        write_frf(force.frf_out, frf, result, layout, force)
    return with_measured_mass(result, measured, layout.mass)


def _check_segments(data: TestData, resample: int) -> None:
    """Refuse `resample` segments that would leave fewer than 16 samples of the shortest record each."""
    if not (resample and data.records):
        return
    shortest = min(values.shape[0] for values, _ in data.records)
    if resample * 16 > shortest:
        raise InputError(
            f"{resample} segments of records of {shortest} samples leave fewer than 16 samples each; "
            f"the limit here is {shortest // 16}",
            source="segments",
        )


def identify_records(
    layout: PathLike, records: Sequence[PathLike], *, modal: ModalOptions | None = None, **options: Any
) -> TestRun:
    """What ``rigidid identify LAYOUT --records FILES`` does: modes from the records, identification, refit.

    Parameters as for :func:`identify_test` (`records` is true here).

    Examples
    --------
    >>> from rigidid.api import identify_records
    >>> run = identify_records("layout.json", ["hit1.csv", "hit2.csv"])  # doctest: +SKIP
    >>> run.result.identification.center_of_gravity  # doctest: +SKIP
    """
    return identify_test(layout, records, records=True, modal=modal, **options)


def estimate_records_modes(
    layout: PathLike,
    records: Sequence[PathLike],
    modal: ModalOptions | None = None,
    *,
    units: dict[str, str] | None = None,
    geometry: PathLike | None = None,
    progress: ProgressCallback | None = None,
) -> tuple[ModeTable, ModalEstimate]:
    """What ``rigidid modes LAYOUT RECORDS`` does: the modes of a test's record files (or one UFF file).

    Record files are read in row blocks and decimated as they arrive; with six modes asked, seven are
    estimated when one of six looks elastic and the rigid six returned (:func:`estimate_test_modes`).
    """
    from rigidid.errors import named_source

    check_uff_options(layout, units, geometry)
    streamed = bool(records) and Path(layout).suffix.lower() not in UFF_SUFFIXES and geometry is None
    data = (
        TestData(load_layout(layout))
        if streamed
        else load_test(layout, records, records=True, units=units, geometry=geometry)
    )
    with named_source(input_source(layout, records)):
        return estimate_test_modes(
            data, modal or ModalOptions(), paths=list(records) if streamed else None, rigid_six=True, progress=progress
        )
