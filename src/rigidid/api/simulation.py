"""Forward simulation: the modes, impact records and FRF files of a body on its mounts, written as a test gives them."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rigidid.api.load import body_from_file, same_units
from rigidid.core.simulate import add_noise, body_modes
from rigidid.core.statespace import modal_from_poles
from rigidid.errors import InputError
from rigidid.io import files
from rigidid.io.files import ModeTable
from rigidid.models import BodyFile, LayoutFile
from rigidid.progress import no_progress
from rigidid.results import FrfData, PathLike

if TYPE_CHECKING:
    from rigidid.io.files import ModeTable
    from rigidid.progress import ProgressCallback


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
    same_units(spec, lay, None if isinstance(body, BodyFile) else str(body))
    ids, positions, directions = files.layout_arrays(lay)
    modes = body_modes(body_from_file(spec), positions, directions)
    if frequency_noise or damping_noise or shape_noise:
        try:
            modes = add_noise(modes, frequency=frequency_noise, damping=damping_noise, shape=shape_noise, seed=seed)
            f, z = modal_from_poles(modes.poles)
        except InputError as exc:  # a noisy frequency or damping ratio out of range: the option's fault
            option = "frequency_noise" if frequency_noise else "damping_noise"
            raise InputError(f"too large: a noisy mode is invalid ({exc.message})", source=option) from None
        return ModeTable.numbered(f, z, ids, modes.shapes)
    f, z = modal_from_poles(modes.poles)
    return ModeTable.numbered(f, z, ids, modes.shapes)


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
    same_units(spec, lay, None if isinstance(body, BodyFile) else str(body))
    ids, positions, directions = files.layout_arrays(lay)
    from rigidid.core.plan import default_impacts

    planned = default_impacts(positions) if impacts is None else [
        (np.asarray(p, dtype=float), np.asarray(d, dtype=float)) for p, d in impacts
    ]  # fmt: skip
    for _, direction in planned:
        if not np.any(np.asarray(direction, dtype=float)):
            raise InputError("an impact direction is the zero vector", source="impacts")
    if not (sample_rate > 0 and duration > 0 and pretrigger >= 0):
        raise InputError("sample rate and duration must be positive, pre-trigger zero or positive", source="records")
    from rigidid.limits import check_record_size

    check_record_size(sample_rate, duration, len(ids), len(planned))
    check_record_size(  # the decay fits: a pre-trigger that does not is to blame
        sample_rate, duration + pretrigger, len(ids), len(planned), name="pretrigger", advice="lower the pre-trigger"
    )
    data = impulse_records(
        body_from_file(spec),
        positions,
        directions,
        [(np.asarray(p, dtype=float), np.asarray(d, dtype=float)) for p, d in planned],
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


def write_simulated_frf(
    body: PathLike,
    layout: PathLike,
    references: PathLike | None,
    out: PathLike,
    *,
    noise: float = 0.0,
    seed: int | None = None,
    frf_format: str | None = None,
) -> FrfData:
    """Simulate accelerance FRFs of a body on its mounts and write them as a CSV or UFF 58 file.

    Parameters
    ----------
    body, layout, references : path-like
        ``body.json``, ``layout.json`` and ``references.json`` (the hammer points).
    out : path-like
        The FRF file, written atomically; its format from `frf_format` or its suffix.
    noise : float
        Complex noise relative to each value (0.01 = 1 %).
    seed : int, optional
        Seed of the noise.
    frf_format : str, optional
        ``csv``, ``uff`` (binary 58b) or ``uff-ascii``; default from the suffix.

    Returns
    -------
    FrfData
        The FRFs written. A UFF 58 states its abscissa as a start and a step in 6
        digits: the lines are then a grid those digits state exactly.

    Raises
    ------
    InputError
        No references, a negative noise, bad files (naming the file).
    """
    from rigidid.api.frf import simulate_frf
    from rigidid.io.atomic import write_bytes_atomic, write_text_atomic
    from rigidid.io.frf import frf_csv_text, frf_format_from, frf_uff_bytes, load_references, reference_arrays

    if references is None:
        raise InputError("simulated FRFs need the hammer points (references.json)", source="references")
    if not noise >= 0.0:
        raise InputError(f"must be zero or positive, got {noise}", source="frf_noise")
    fmt = frf_format_from(Path(out), frf_format)
    if fmt == "csv":
        data = simulate_frf(body, layout, references, noise=noise, seed=seed)
        write_text_atomic(out, frf_csv_text(data.frequencies, data.frf, data.sensor_ids, data.reference_ids))
        return data
    lay = files.load_layout(layout, require_rank=False)
    refs = load_references(references)
    default = simulate_frf(body, lay, refs).frequencies  # the default lines (noise does not move them)
    step = float(f"{default[0]:.5e}")
    grid = step * np.arange(1, default.size + 1, dtype=np.float64)
    data = simulate_frf(body, lay, refs, frequencies=grid, noise=noise, seed=seed)
    try:
        content = frf_uff_bytes(
            data.frequencies, data.frf, data.sensor_ids, files.layout_arrays(lay)[2], data.reference_ids,
            reference_arrays(refs)[2], {"length": lay.units.length, "mass": lay.units.mass}, binary=fmt == "uff",
        )  # fmt: skip
    except InputError as exc:
        if exc.source in ("sensors", "references"):
            exc.source = str(layout if exc.source == "sensors" else references)
        raise
    write_bytes_atomic(out, content)
    return data
