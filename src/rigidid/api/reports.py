"""The HTML report and the PNG figures of an identification (matplotlib is imported only here, on use)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from rigidid.api.records import summed_record_spectrum
from rigidid.models import BodyFile
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
