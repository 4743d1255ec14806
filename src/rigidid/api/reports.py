"""The HTML report and the PNG figures of an identification (matplotlib is imported only here, on use)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from rigidid.api.records import summed_record_spectrum
from rigidid.models import BodyFile, LayoutFile, ReferencesFile
from rigidid.results import IdentifyResult, PathLike

if TYPE_CHECKING:
    from rigidid.progress import ProgressCallback


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
    png: PathLike | None = None,
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
        blocks (:func:`rigidid.io.records.spectrum.summed_spectrum_streamed`); used instead of `records`.
    png : path-like, optional
        A folder (made if missing) to write the same figures into as PNG files, as
        :func:`report_pngs` does, from the images the page embeds (drawn once).

    Returns
    -------
    str
        One HTML document; it needs no network to open.
    """
    from rigidid.reporting import render_report

    stiffness = None
    if png is not None:
        Path(png).mkdir(parents=True, exist_ok=True)
    if body is not None:
        mounts = [m.position for m in body.mounts]
        stiffness = [np.asarray(m.stiffness, dtype=float) for m in body.mounts]
    if stabilisation is None:
        spectrum = None
    elif spectrum is None and records:
        spectrum = summed_record_spectrum(records)
    return render_report(
        result.identification,
        result.positions,
        result.directions,
        result.sensor_ids,
        result.units,
        mounts=None if mounts is None else [np.asarray(m, dtype=float) for m in mounts],
        stabilisation=stabilisation,
        uncertainty=_intervals_for_report(result),
        test=result.test,
        title=title or result.layout_name or "rigidid report",
        mode_labels=result.modes_used,
        inputs=inputs,
        force_unit=force_unit,
        mount_stiffness=stiffness,
        spectrum=spectrum,
        progress=progress,
        identified_mounts=result.mounts,
        torque_roll_axis=result.torque_roll_axis,
        png=png,
    )


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
    from rigidid.reporting import identified_mount_labels, save_pngs, stiffness_labels

    folder = Path(directory)
    folder.mkdir(parents=True, exist_ok=True)
    mounts, labels = None, []
    if body is not None:
        mounts = [np.asarray(m.position, dtype=float) for m in body.mounts]
        stiffness = [np.asarray(m.stiffness, dtype=float) for m in body.mounts]
        labels = stiffness_labels(stiffness, result.units["length"], result.units["mass"], force_unit)
    if result.mounts is not None:
        mounts = list(result.mounts.positions)
        has_mass = result.identification.mass is not None
        labels = identified_mount_labels(result.mounts, result.units, has_mass=has_mass, force_unit=force_unit)
    roll = result.torque_roll_axis
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
        spectrum=None if stabilisation is None else spectrum or (summed_record_spectrum(records) if records else None),
        progress=progress,
        roll_axis=None if roll is None else roll.direction,
    )


def _intervals_for_report(result: IdentifyResult) -> list[Any]:
    """Every interval the result holds, as the report shows them: Monte Carlo, record segments, the refit's bound."""
    return [x for x in (result.uncertainty, result.record_spread, result.record_bound) if x is not None]


FRF_ROUTES: tuple[str, ...] = ("massline", "residues")
"""The FRF routes :func:`frf_report` can put side by side."""


def frf_report(
    layout: LayoutFile | PathLike,
    frf: PathLike | None = None,
    references: ReferencesFile | PathLike | None = None,
    *,
    method: str = "auto",
    compare: Sequence[str] = FRF_ROUTES,
    mass: float | None = None,
    band: tuple[float, float] | None = None,
    modes: PathLike | None = None,
    modes_used: tuple[int, ...] | None = None,
    title: str | None = None,
    inputs: Sequence[str] = (),
    force_unit: str | None = None,
    progress: ProgressCallback | None = None,
    png: PathLike | None = None,
    units: dict[str, str] | None = None,
    geometry: PathLike | None = None,
) -> str:
    """A self-contained HTML report of the FRF routes (``rigidid report LAYOUT --frf FRF``).

    Parameters
    ----------
    layout, frf, references
        As :func:`rigidid.api.frf.identify_massline`: the references from
        ``references.json``, the layout's ``references`` list or a UFF file's
        FRF headers, which must agree (:func:`rigidid.api.frf.load_frf_test`);
        `layout` may be a UFF file of geometry and FRFs (then `frf` is None).
    method : {"auto", "massline", "residues"}
        The route tabled first, its stiffness and damping (scaled modes) shown.
        ``"auto"``: the one :func:`rigidid.api.frf.identify_frf_auto` chooses,
        with every route it tried listed (the residues route when `modes` is given).
    compare : sequence of str
        Routes to compute from the same FRFs and table beside it (the chosen
        one is always computed; one the data do not allow is listed with why).
    mass, band, modes, modes_used
        As :func:`rigidid.api.frf.identify_massline` (`modes` and `modes_used` serve the residues route).
    title : str, optional
        Heading (default: the layout's name, else "rigidid report").
    inputs : sequence of str
        Input file names, listed under the title.
    force_unit : {"N", "kN", "lbf"}, optional
        Force unit of stiffness and damping.
    progress : callable, optional
        ``progress(task, done, total)`` while the figures are drawn.
    png : path-like, optional
        A folder to write the same figures into as PNG files
        (``<name>.png`` for each name of :data:`rigidid.frf_report.FRF_FIGURE_NAMES` drawn).
    units, geometry
        As for :func:`rigidid.api.load.load_uff` (UFF `layout` only).

    Returns
    -------
    str
        One HTML document (:func:`rigidid.frf_report.render_frf_report`); it needs no network to open.
    """
    from rigidid.api.frf import load_frf_test
    from rigidid.errors import InputError
    from rigidid.frf_report import MeasuredFrfs, frf_figures, render_frf_report
    from rigidid.io import files
    from rigidid.io.frf import reference_arrays
    from rigidid.reporting import png_bytes
    from rigidid.results import TestInfo

    unknown = [m for m in (method, *compare) if m not in (*FRF_ROUTES, "auto") or (m == "auto" and m in compare)]
    if unknown:
        raise InputError(f"FRF routes are auto, {', '.join(FRF_ROUTES)}, not {unknown[0]!r}", source="--method")
    if mass is not None and not mass > 0.0:
        raise InputError(f"mass must be positive, got {mass}", source="--mass")
    lay, refs, test = load_frf_test(layout, frf, references, units=units, geometry=geometry)
    routes = _frf_routes(lay, refs, test, method, compare, mass=mass, band=band, modes=modes, modes_used=modes_used)
    ids, pos, dirs = files.layout_arrays(lay)
    _, rpos, rdirs = reference_arrays(refs)
    data = MeasuredFrfs(test.frequencies, test.frf, pos, dirs, rpos, rdirs, ids, test.reference_ids)
    pngs = {name: png_bytes(fig) for name, fig in frf_figures(data, routes, lay.units.mass, progress).items()}
    if png is not None:
        from rigidid.io.atomic import write_bytes_atomic

        folder = Path(png)
        folder.mkdir(parents=True, exist_ok=True)
        for name, content in pngs.items():
            write_bytes_atomic(folder / f"{name}.png", content)
    return render_frf_report(
        data, routes, title=title or lay.name or "rigidid report", inputs=inputs, force_unit=force_unit,
        test=TestInfo.from_layout(lay), figures=pngs,
    )  # fmt: skip


def _frf_routes(
    lay: LayoutFile,
    refs: ReferencesFile,
    test: Any,
    method: str,
    compare: Sequence[str],
    **given: Any,
) -> list[Any]:
    """The chosen route first, then the others of `compare` the data allow; the chosen one's ``routes`` lists all.

    A compared route the data do not allow (its one-line refusal) is listed in
    the chosen one's ``routes``; its own warnings are not passed on (the
    chosen route's are, as with ``identify --method auto``).
    """
    import dataclasses
    import warnings

    from rigidid.api.frf import frf_auto_routes, identify_frf_route
    from rigidid.errors import IdentificationError
    from rigidid.results import RouteAnswer

    ran: dict[str, Any] = {}  # routes auto already ran: reused, not run again

    def run(name: str) -> Any:
        if name in ran:
            return ran[name]
        modes = given["modes"] if name == "residues" else None
        return identify_frf_route(lay, refs, test, method=name, **{**given, "modes": modes})

    if method == "auto" and given["modes"] is None:
        chosen, *others = frf_auto_routes(lay, refs, test, mass=given["mass"], band=given["band"])
        ran.update((r.route, r) for r in others)
    else:
        chosen = run("residues" if method == "auto" else method)
    answers = list(chosen.routes) or [RouteAnswer(chosen.route, True, "asked for", chosen.massline)]
    out = [chosen]
    for name in dict.fromkeys(compare):
        if name == chosen.route:
            continue
        known = next((a for a in answers if a.route == name), None)
        if known is not None and not known.applies:
            continue
        try:
            with warnings.catch_warnings(record=True):  # only the chosen route's warnings are passed on
                warnings.simplefilter("always")
                other = run(name)
        except IdentificationError as exc:
            if known is None:
                answers.append(RouteAnswer(name, False, str(exc)))
            continue
        if known is None:
            answers.append(RouteAnswer(name, True, "compared", other.massline))
        out.append(other)
    out[0] = dataclasses.replace(chosen, routes=tuple(answers))
    return out
