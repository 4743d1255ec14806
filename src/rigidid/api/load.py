"""Loading a test: layout, modes, records, UFF and body files, validated once at this boundary, and the one
check that two files speak the same units (:func:`same_units`)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from rigidid.api.mounts import read_mount_spec
from rigidid.core.simulate import Body, Mount
from rigidid.core.statespace import poles_from_modal
from rigidid.errors import InputError
from rigidid.io import files
from rigidid.io.files import ModeTable
from rigidid.models import BodyFile, LayoutFile, MountsFile, ReferencesFile
from rigidid.results import Arrays, FrfData, PathLike, TestData
from rigidid.units import check_same_units

if TYPE_CHECKING:
    from rigidid.io.files import ModeTable


def load_layout(path: PathLike) -> LayoutFile:
    """Read and validate ``layout.json`` (see :func:`rigidid.io.files.load_layout`)."""
    return files.load_layout(path)


def load_modes(path: PathLike, layout: LayoutFile) -> ModeTable:
    """Read and validate ``modes.csv`` against a layout (see :func:`rigidid.io.files.load_modes`)."""
    return files.load_modes(path, [s.id for s in layout.sensors])


def load_arrays(layout: PathLike, modes: PathLike) -> Arrays:
    """Read ``layout.json`` and ``modes.csv`` into the arrays :mod:`rigidid.core` takes."""
    lay = load_layout(layout)
    table = load_modes(modes, lay)
    ids, positions, directions = files.layout_arrays(lay)
    poles = poles_from_modal(table.frequency_hz, table.damping_ratio)
    return Arrays(ids, positions, directions, table.labels, poles, table.shapes, lay.mass)


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
    _, _, entries = read_mount_spec(mounts, {"length": spec.units.length, "mass": spec.units.mass})
    replaced = []
    for k, m in enumerate(entries.mounts):
        if m.stiffness is None:
            raise InputError("a mount without stiffness cannot be simulated", source=source, location=f"mounts.{k}")
        extra = {} if m.damping is None else {"damping": m.damping}
        replaced.append(MountSpec(position=m.position, stiffness=m.stiffness, **extra))
    if all(m.damping is None for m in entries.mounts):
        raise InputError(
            "no mount has a damping: undamped modes cannot be simulated (they never decay); "
            "give each mount a `damping` (3 values or a 3x3 matrix, mass/s, as in body.json)",
            source=source,
            location="mounts",
        )
    return spec.model_copy(update={"mounts": replaced})


def same_units(other: BodyFile | LayoutFile, layout: LayoutFile, source: str | None) -> None:
    """Refuse a body or layout file whose units differ from the layout's (:func:`rigidid.units.check_same_units`)."""
    check_same_units(other.units, layout.units, source=source)


def load_references_for(references: ReferencesFile | PathLike, layout: LayoutFile) -> ReferencesFile:
    """The reference (hammer) points of a test, in the layout's units."""
    from rigidid.io.frf import load_references

    refs = references if isinstance(references, ReferencesFile) else load_references(references)
    if refs.units is not None:
        source = None if isinstance(references, ReferencesFile) else str(references)
        check_same_units(refs.units, layout.units, source=source)
    return refs


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
        the mode shapes), the modes of dataset 55 if any, and the time records;
        for a file of FRFs (58, function type 4), the FRFs as accelerance and
        the layout's ``references`` from their reference nodes and directions.

    Raises
    ------
    InputError
        Missing or contradictory pieces, naming the dataset and node.
    """
    from pydantic import ValidationError

    from rigidid.io.uff import read_uff

    src = str(path)
    contents = read_uff(path, units=units, geometry=geometry)
    if contents.references:
        contents.layout["references"] = contents.references
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
    frf = None
    if contents.frf_sets:
        from rigidid.io.frf import frf_from_datasets

        ids = tuple(s.id for s in layout.sensors)
        rids = tuple(r.id for r in layout.references or [])
        freqs, h = frf_from_datasets(contents.frf_sets, ids, rids, src)
        frf = FrfData(freqs, h, ids, rids)
    return TestData(layout, modes, records, list(contents.record_labels), frf)


UFF_SUFFIXES = (".uff", ".unv")
"""Suffixes of files read as universal files (geometry, modes and records in one file)."""


def check_uff_options(layout: PathLike, units: dict[str, str] | None, geometry: PathLike | None) -> None:
    """Refuse `units` and `geometry` for a layout that is not UFF: they would be ignored.

    Raises
    ------
    InputError
        Naming the parameter (source ``units`` or ``geometry``).
    """
    if Path(layout).suffix.lower() in UFF_SUFFIXES:
        return
    if geometry is not None:
        raise InputError("a geometry file completes a UFF input; the layout here is not UFF", source="geometry")
    if units is not None:
        raise InputError(f"applies to a UFF input only; {layout} states its own units", source="units")


def load_test(
    layout: PathLike,
    inputs: Sequence[PathLike],
    *,
    records: bool,
    units: dict[str, str] | None = None,
    geometry: PathLike | None = None,
) -> TestData:
    """The layout and its modes or records, from JSON/CSV files or one UFF file (and its geometry file).

    Parameters
    ----------
    layout : path
        ``layout.json``, or a UFF file holding the geometry and the modes or records.
    inputs : sequence of paths
        One ``modes.csv``, or one record file per impact (`records`); none with a UFF `layout`.
    records : bool
        Whether the inputs are impact records rather than modes.
    units, geometry
        As for :func:`load_uff` (UFF input only).
    """
    layout = Path(layout)
    is_uff = layout.suffix.lower() in UFF_SUFFIXES
    check_uff_options(layout, units, geometry)
    if is_uff:
        if inputs:
            raise InputError("with a UFF file, give no other input files", source=str(inputs[0]))
        data = load_uff(layout, units=units, geometry=geometry)
        if records and not data.records:
            if data.frf is not None:
                raise InputError(
                    "the file holds FRFs (datasets 58, function type 4), not time records: without --records, "
                    "`rigidid identify FILE` identifies the body from them",
                    source=str(layout),
                )
            raise InputError("no time records (dataset 58) in the file", source=str(layout))
        if not records and data.modes is None and data.frf is not None:
            raise InputError(
                "the file holds FRFs (datasets 58, function type 4), not modes: `rigidid identify FILE` identifies "
                "the body from them; `rigidid modes FILE --frf FILE` fits their modes",
                source=str(layout),
            )
        if not records and data.modes is None:
            raise InputError("no modes (dataset 55) in the file; with time records pass --records", source=str(layout))
        return data
    lay = load_layout(layout)
    if records:
        if not inputs:
            raise InputError("no records: give one records.csv per impact", source="RECORDS")
        return TestData(lay, None, load_records(inputs, lay), [str(p) for p in inputs])
    if len(inputs) != 1:
        message = "give one modes.csv" if not inputs else "give one modes.csv (several files: records? pass --records)"
        raise InputError(message, source="MODES")
    return TestData(lay, load_modes(inputs[0], lay))


def input_source(layout: PathLike, inputs: Sequence[PathLike] | None) -> str:
    """The file(s) modes or records come from, to name in an error."""
    if Path(layout).suffix.lower() in UFF_SUFFIXES or not inputs:
        return str(layout)
    return ", ".join(str(p) for p in inputs)
