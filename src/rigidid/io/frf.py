"""FRF files: the reference points (``references.json``) and FRFs as CSV.

The CSV has one row per frequency line, response and reference::

    frequency_hz,response,reference,real,imag
    1.0,s1,h1,-0.0012,0.0003

``response`` is a sensor id of the layout, ``reference`` an id of the
references file; values are accelerance (length / s^2 per force unit, i.e. 1 /
mass unit in the layout's units). Every (response, reference) pair must have the
same frequency lines.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rigidid.errors import InputError
from rigidid.io.dialect import plain_number
from rigidid.io.uff_codes import FUNCTION_TYPES
from rigidid.models import LayoutFile, ReferencesFile
from rigidid.units import check_same_units

__all__ = [
    "FRF_COLUMNS",
    "FRF_FORMATS",
    "UffFrfFile",
    "frf_csv_text",
    "frf_format_from",
    "frf_from_datasets",
    "frf_uff_bytes",
    "load_frf_csv",
    "load_frf_uff",
    "load_references",
    "read_frf_uff",
    "reference_arrays",
    "references_from_headers",
]

FRF_COLUMNS = ("frequency_hz", "response", "reference", "real", "imag")


def load_references(path: str | os.PathLike[str]) -> ReferencesFile:
    """Read and validate ``references.json`` (reference ids, positions, force directions).

    Raises
    ------
    InputError
        Unreadable file, invalid JSON, or a field that fails validation (named).
    """
    from rigidid.io.files import load_json_model

    return load_json_model(Path(path), ReferencesFile)


def reference_arrays(refs: ReferencesFile) -> tuple[tuple[str, ...], NDArray[np.float64], NDArray[np.float64]]:
    """Reference ids, positions (q, 3) and unit force directions (q, 3)."""
    ids = tuple(r.id for r in refs.references)
    positions = np.array([r.position for r in refs.references], dtype=float).reshape(-1, 3)
    directions = np.array([r.unit_direction() for r in refs.references], dtype=float).reshape(-1, 3)
    return ids, positions, directions


def _rows(reader: csv.DictReader[str], src: str) -> Any:
    """The rows of a CSV reader; a malformed line (a cell above the field limit...) one InputError naming it."""
    try:
        yield from reader
    except csv.Error as exc:
        raise InputError(f"not valid CSV: {exc}", source=src, location=f"row {reader.line_num}") from None


def load_frf_csv(
    path: str | os.PathLike[str], sensor_ids: Sequence[str], reference_ids: Sequence[str]
) -> tuple[NDArray[np.float64], NDArray[np.complex128]]:
    """Read FRFs from CSV against the layout's sensors and the references.

    Parameters
    ----------
    path : path-like
        The CSV file (columns :data:`FRF_COLUMNS`, in any order, header row first).
    sensor_ids, reference_ids : sequence of str
        Ids of the layout's sensors and of the references; the FRF array
        follows their order.

    Returns
    -------
    frequencies : ndarray, shape (f,)
        Ascending frequency lines (Hz).
    frf : ndarray of complex, shape (p, q, f)

    Raises
    ------
    InputError
        Naming the file and row (or column): missing column, unknown id, a
        value that is not a finite number, a duplicate line, or a (response,
        reference) pair missing or with other frequency lines than the rest.
    """
    src = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise InputError("file not found", source=src) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read: {exc}", source=src) from None
    reader = csv.DictReader(io.StringIO(text))
    try:
        header = [h.strip() for h in (reader.fieldnames or [])]
    except csv.Error as exc:  # a cell above the csv module's field limit, a NUL...
        raise InputError(f"not valid CSV: {exc}", source=src, location="row 1") from None
    missing = [c for c in FRF_COLUMNS if c not in header]
    if missing:
        raise InputError(f"missing column {missing[0]!r} (need {', '.join(FRF_COLUMNS)})", source=src, location="row 1")
    reader.fieldnames = header
    s_index = {s: i for i, s in enumerate(sensor_ids)}
    r_index = {r: j for j, r in enumerate(reference_ids)}
    values: dict[tuple[int, int], dict[float, complex]] = {}
    for n, row in enumerate(_rows(reader, src), start=2):
        if None in row or any(v is None for v in row.values()):
            cells = len(header) + len(row.get(None) or []) - sum(v is None for v in row.values())
            raise InputError(f"{cells} fields, the header has {len(header)}", source=src, location=f"row {n}")
        resp = (row.get("response") or "").strip()
        ref = (row.get("reference") or "").strip()
        if resp not in s_index:
            raise InputError(f"response {resp!r} is not a sensor of the layout", source=src, location=f"row {n}")
        if ref not in r_index:
            raise InputError(f"reference {ref!r} is not in the references file", source=src, location=f"row {n}")
        nums = []
        for col in ("frequency_hz", "real", "imag"):
            try:
                cell = (row.get(col) or "").strip()
                if not plain_number(cell):
                    raise ValueError(cell)
                v = float(cell)
            except ValueError:
                raise InputError(f"{col}: not a number: {row.get(col)!r}", source=src, location=f"row {n}") from None
            if not math.isfinite(v):
                raise InputError(f"{col}: not finite", source=src, location=f"row {n}")
            nums.append(v)
        if not nums[0] > 0.0:
            raise InputError("frequency_hz must be positive", source=src, location=f"row {n}")
        cell = values.setdefault((s_index[resp], r_index[ref]), {})
        if nums[0] in cell:
            raise InputError(f"duplicate line {nums[0]:g} Hz for {resp}/{ref}", source=src, location=f"row {n}")
        cell[nums[0]] = complex(nums[1], nums[2])
    if not values:
        raise InputError("no FRF rows", source=src)
    first = next(iter(values.values()))
    freqs = np.array(sorted(first), dtype=float)
    p, q = len(sensor_ids), len(reference_ids)
    frf = np.zeros((p, q, freqs.size), dtype=complex)
    for i, s in enumerate(sensor_ids):
        for j, r in enumerate(reference_ids):
            pair = values.get((i, j))
            if pair is None:
                raise InputError(f"no FRF for response {s!r} and reference {r!r}", source=src)
            if len(pair) != freqs.size or np.any(np.array(sorted(pair)) != freqs):
                raise InputError(f"FRF {s}/{r} has other frequency lines than the first pair", source=src)
            frf[i, j] = [pair[f] for f in freqs]
    if not np.any(frf):
        raise InputError("every FRF value is zero: no response to fit", source=src)
    return freqs, frf


def frf_csv_text(
    frequencies: NDArray[np.float64],
    frf: NDArray[np.complex128],
    sensor_ids: Sequence[str],
    reference_ids: Sequence[str],
    coherence: NDArray[np.float64] | None = None,
) -> str:
    """FRFs (p, q, f) as the CSV text :func:`load_frf_csv` reads (full precision).

    With `coherence` (p, q, f), a sixth column ``coherence`` (the readers ignore it).
    """
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow([*FRF_COLUMNS, "coherence"] if coherence is not None else FRF_COLUMNS)
    for i, s in enumerate(sensor_ids):
        for j, r in enumerate(reference_ids):
            for k, f in enumerate(frequencies):
                v = frf[i, j, k]
                row = [repr(float(f)), s, r, repr(float(v.real)), repr(float(v.imag))]
                w.writerow(row if coherence is None else [*row, repr(float(coherence[i, j, k]))])
    return out.getvalue()


_ORDINATE_KINDS = {12: "accelerance", 11: "mobility", 8: "receptance", 0: "accelerance", 1: "accelerance"}
"""UFF 58 ordinate specific data type (numerator of an FRF) -> what the FRF is; unknown (0) and
general (1), which some writers use for accelerance, are taken as accelerance."""


def _uff_id(node: int, code: int, ids: Sequence[str]) -> str | None:
    """The id among `ids` of a UFF node and direction: ``"12+z"`` or, else, ``"12"``."""
    axis = ("+" if code > 0 else "-") + "xyz"[abs(code) - 1]
    for candidate in (f"{node}{axis}", str(node)):
        if candidate in ids:
            return candidate
    return None


_ROTATIONS = {4: "x", 5: "y", 6: "z"}


def _check_uff_record(dset: dict[str, Any], src: str, where: str) -> None:
    """Refuse a dataset 58 FRF whose directions are no translation or whose point count is not its values'."""
    for role in ("rsp", "ref"):
        code = int(dset.get(f"{role}_dir", 0))
        name = "response" if role == "rsp" else "reference"
        if abs(code) in _ROTATIONS:
            raise InputError(
                f"{name} direction {code} is a rotation about {_ROTATIONS[abs(code)]}: rigidid reads translations "
                "(+-1, +-2, +-3 for x, y, z)",
                source=src, location=where,
            )  # fmt: skip
        if abs(code) not in (1, 2, 3):
            raise InputError(
                f"{name} direction {code} is not a UFF direction code (+-1, +-2, +-3 for x, y, z)",
                source=src, location=where,
            )  # fmt: skip
    n = int(dset.get("num_pts", -1))
    size = int(np.size(dset.get("data", [])))
    if size != n or n < 1:
        raise InputError(f"{size} values where the header says {dset.get('num_pts')}", source=src, location=where)


def _uff_units_factor(sets: list[dict[str, Any]], src: str, units: dict[str, str] | None) -> float:
    """Factor from rigidid's accelerance to the file's, from its dataset 164 (1 without one)."""
    from rigidid.io.uff import units_from_164
    from rigidid.io.uff_codes import LENGTH_PER_M, MASS_PER_KG

    found = [d for d in sets if d.get("type") == 164]
    if not found:
        return 1.0
    file_units = units_from_164(found[0], src, "dataset 164")
    if units is not None:
        check_same_units(file_units, units, source=src, location="dataset 164")
    force = float(found[0].get("force", 0.0))
    if not force > 0.0:  # a standard code with zero factors: coherent or gravitational by the code
        from rigidid.io.uff_codes import CODE_FACTORS

        force = CODE_FACTORS.get(int(found[0].get("units_code") or 0), (1.0, 1.0))[1]
    return MASS_PER_KG[file_units["mass"]] * LENGTH_PER_M[file_units["length"]] / force


def _frf_dataset(
    dset: dict[str, Any], where: str, src: str, s_index: dict[str, int], r_index: dict[str, int]
) -> tuple[tuple[int, int], tuple[NDArray[np.float64], NDArray[np.complex128]]]:
    """(sensor, reference) indices and (frequencies, accelerance) of one dataset 58, checked (:func:`load_frf_uff`)."""
    func = int(dset.get("func_type", 0))
    if func == 3:
        raise InputError(
            "function type 3 is a cross spectrum, not an FRF: export H1/H2 FRFs (function type 4)",
            source=src,
            location=where,
        )
    if func != 4:
        name = FUNCTION_TYPES.get(func, "unknown")
        hint = ": time records are read with `--records` (identify, modes)" if func == 1 else ""
        raise InputError(
            f"function type {func} ({name}) is not an FRF (function type 4){hint}", source=src, location=where
        )
    kind = _ORDINATE_KINDS.get(int(dset.get("ordinate_spec_data_type", 12)))
    if kind is None:
        raise InputError(
            f"ordinate type {dset.get('ordinate_spec_data_type')} is not acceleration (12), velocity (11) "
            "or displacement (8)",
            source=src,
            location=where,
        )
    if int(dset.get("rsp_node", 0)) <= 0 or int(dset.get("ref_node", 0)) <= 0:
        raise InputError(
            f"the FRF names no response or reference node (response node {dset.get('rsp_node')}, reference "
            f"node {dset.get('ref_node')}): it carries no geometry; name the nodes in the exporting tool",
            source=src,
            location=where,
        )
    _check_uff_record(dset, src, where)
    rsp = _uff_id(int(dset.get("rsp_node", 0)), int(dset.get("rsp_dir", 0)), list(s_index))
    ref = _uff_id(int(dset.get("ref_node", 0)), int(dset.get("ref_dir", 0)), list(r_index))
    if rsp is None:
        raise InputError(
            f"response node {dset.get('rsp_node')} direction {dset.get('rsp_dir')} is no sensor of the layout",
            source=src,
            location=where,
        )
    if ref is None:
        raise InputError(
            f"reference node {dset.get('ref_node')} direction {dset.get('ref_dir')} is not in the references",
            source=src,
            location=where,
        )
    x = np.asarray(dset["x"], dtype=float)
    data = np.asarray(dset["data"], dtype=complex)
    keep = x > 0.0
    x, data = x[keep], data[keep]
    w = 2.0 * np.pi * x
    if kind == "mobility":
        data = 1j * w * data
    elif kind == "receptance":
        data = -(w**2) * data
    return (s_index[rsp], r_index[ref]), (x, data)


def load_frf_uff(
    path: str | os.PathLike[str],
    sensor_ids: Sequence[str],
    reference_ids: Sequence[str],
    *,
    units: dict[str, str] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.complex128]]:
    """Read FRFs from a universal file (datasets 58, function type 4) as accelerance.

    Parameters
    ----------
    path : path-like
        The UFF file.
    sensor_ids, reference_ids : sequence of str
        Ids of the layout's sensors and of the references: a record's response
        (reference) node ``n`` and direction ``d`` is the id ``"n+x"``-style if
        there is one, else ``"n"``.
    units : dict, optional
        ``{"length", "mass"}`` of the layout: a dataset 164 in the file must
        name the same units.

    Returns
    -------
    frequencies : ndarray, shape (f,)
    frf : ndarray of complex, shape (p, q, f)
        Accelerance; mobility (ordinate type 11) is multiplied by ``i w``,
        receptance (8) by ``-w^2``. With a dataset 164, values per its force
        unit are converted to rigidid's (per mass unit x length / s^2: lbf
        of in/lb and ft/lb files divided out); without, they are taken in
        the layout's units.

    Raises
    ------
    InputError
        Naming the file and dataset: function type 3 (cross spectrum) or
        another non-FRF, an ordinate that is not acceleration, velocity or
        displacement, a node/direction that is no sensor or reference, a
        missing pair, pairs with other frequency lines, or a dataset 164 whose
        units differ from `units`.
    """
    from rigidid.io.uff import read_all

    return frf_from_datasets(read_all(Path(path)), sensor_ids, reference_ids, str(path), units=units)


def frf_from_datasets(
    sets: Sequence[dict[str, Any]],
    sensor_ids: Sequence[str],
    reference_ids: Sequence[str],
    src: str,
    *,
    units: dict[str, str] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.complex128]]:
    """FRFs (p, q, f) as accelerance from the datasets of a universal file (:func:`load_frf_uff`).

    Parameters
    ----------
    sets : sequence of dict
        Datasets as pyuff reads them: every 58 is an FRF; a 164 gives the units.
    sensor_ids, reference_ids : sequence of str
        Ids the records' nodes and directions are matched to (as :func:`load_frf_uff`).
    src : str
        The file, for messages.
    units : dict, optional
        The layout's units: a dataset 164 must name the same.

    Returns
    -------
    frequencies : ndarray, shape (f,)
    frf : ndarray of complex, shape (p, q, f)

    Raises
    ------
    InputError
        As :func:`load_frf_uff`.
    """
    sets = list(sets)
    s_index = {s: i for i, s in enumerate(sensor_ids)}
    r_index = {r: j for j, r in enumerate(reference_ids)}
    found: dict[tuple[int, int], tuple[NDArray[np.float64], NDArray[np.complex128]]] = {}
    n58 = 0
    for dset in sets:
        if dset.get("type") != 58:
            continue
        n58 += 1
        where = f"dataset 58 #{n58}"
        key, frf_pair = _frf_dataset(dset, where, src, s_index, r_index)
        if key in found:
            raise InputError(
                f"a second FRF for response {sensor_ids[key[0]]!r} and reference {reference_ids[key[1]]!r}",
                source=src,
                location=where,
            )
        found[key] = frf_pair
    if not found:
        raise InputError("no FRF (dataset 58, function type 4) in the file", source=src)
    factor = _uff_units_factor(sets, src, units)
    if factor != 1.0:
        found = {key: (x, np.asarray(data / factor, dtype=complex)) for key, (x, data) in found.items()}
    freqs = next(iter(found.values()))[0]
    frf = np.zeros((len(sensor_ids), len(reference_ids), freqs.size), dtype=complex)
    for i, s in enumerate(sensor_ids):
        for j, r in enumerate(reference_ids):
            pair = found.get((i, j))
            if pair is None:
                raise InputError(f"no FRF for response {s!r} and reference {r!r}", source=src)
            if pair[0].shape != freqs.shape or not np.allclose(pair[0], freqs, rtol=1e-9, atol=0.0):
                raise InputError(f"FRF {s}/{r} has other frequency lines than the first pair", source=src)
            frf[i, j] = pair[1]
    if not np.any(frf):
        raise InputError("every FRF value is zero: no response to fit", source=src)
    return freqs, frf


@dataclass(frozen=True)
class UffFrfFile:
    """A UFF file of FRFs, read once: its datasets and the reference points its FRF headers name.

    Attributes
    ----------
    source : str
        The file, for messages.
    datasets : tuple of dict
        Every dataset as :func:`rigidid.io.uff.read_all` returns them (the
        FRFs, datasets 58, and the units, 164, among them).
    references : ReferencesFile or None
        As :func:`references_from_headers` returns them.
    """

    source: str
    datasets: tuple[dict[str, Any], ...]
    references: ReferencesFile | None

    def frf(
        self, sensor_ids: Sequence[str], reference_ids: Sequence[str], *, units: dict[str, str] | None = None
    ) -> tuple[NDArray[np.float64], NDArray[np.complex128]]:
        """The FRFs (p, q, f) as accelerance against these ids (:func:`frf_from_datasets`; the file is not read)."""
        return frf_from_datasets(self.datasets, sensor_ids, reference_ids, self.source, units=units)


def read_frf_uff(
    path: str | os.PathLike[str], layout: LayoutFile, *, units: dict[str, str] | None = None
) -> UffFrfFile:
    """Read a UFF file of FRFs once: the references its headers name, and the datasets its FRFs come from.

    Parameters
    ----------
    path : path-like
        A UFF file of FRFs (datasets 58, function type 4), ASCII or binary 58b.
    layout : LayoutFile
        The sensors (see :func:`references_from_headers`).
    units : dict, optional
        The layout's units, for a file without dataset 164.

    Returns
    -------
    UffFrfFile
        ``references`` from the headers (or None), and the datasets, from
        which :meth:`UffFrfFile.frf` builds the FRF array for the references
        chosen (:func:`rigidid.api.frf.load_frf_test` checks the headers'
        references against the layout's and ``references.json``).

    Raises
    ------
    InputError
        What :func:`rigidid.io.uff.read_all` raises, and for a file with
        geometry what :func:`rigidid.io.uff.read_uff` raises.
    """
    from rigidid.io.uff import read_all

    sets = tuple(read_all(Path(path)))
    return UffFrfFile(str(path), sets, _header_references(path, sets, layout, units))


def references_from_headers(
    path: str | os.PathLike[str], layout: LayoutFile, *, units: dict[str, str] | None = None
) -> ReferencesFile | None:
    """The reference points a UFF file's FRF headers name (reference node and direction of each dataset 58).

    Parameters
    ----------
    path : path-like
        A UFF file of FRFs (datasets 58, function type 4).
    layout : LayoutFile
        The sensors: a reference node the file gives no coordinates for is
        placed at the layout's sensor of that node number (ids ``"12"`` or
        ``"12+x"``), the driving point of a test.
    units : dict, optional
        The layout's units, for a file without dataset 164.

    Returns
    -------
    ReferencesFile or None
        Ids ``"<node>"`` (one direction at the node) or ``"<node><axis>"``;
        with the file's nodes (15/2411) and coordinate systems (18/2420) the
        positions and directions are read as for sensors
        (:func:`rigidid.io.uff.read_uff`). None when the headers name no
        reference node, or one whose position neither the file nor the layout
        gives. To read the FRFs too, :func:`read_frf_uff` reads the file once.
    """
    return read_frf_uff(path, layout, units=units).references


def _header_references(
    path: str | os.PathLike[str], sets: Sequence[dict[str, Any]], layout: LayoutFile, units: dict[str, str] | None
) -> ReferencesFile | None:
    """:func:`references_from_headers` from the file's datasets, read already."""
    from rigidid.io.uff import read_uff
    from rigidid.io.uff_codes import ID_PATTERN

    if any(d.get("type") in (15, 2411) for d in sets):
        refs = read_uff(path, units=units, datasets=sets).references
        return ReferencesFile.model_validate({"references": refs}) if refs else None
    points: list[tuple[int, int]] = []
    for d in sets:
        if d.get("type") == 58 and int(d.get("func_type", 0)) == 4:
            key = (int(d.get("ref_node", 0)), int(d.get("ref_dir", 0)))
            if key[0] <= 0 or not 1 <= abs(key[1]) <= 3:
                return None
            if key not in points:
                points.append(key)
    at_node: dict[int, list[float]] = {}
    for sensor in layout.sensors:
        match = ID_PATTERN.match(sensor.id)
        if match is not None:
            at_node.setdefault(int(match.group(1)), list(sensor.position))
    if not points or any(node not in at_node for node, _ in points):
        return None
    count = {node: sum(n == node for n, _ in points) for node, _ in points}
    entries = []
    for node, code in points:
        axis = ("+" if code > 0 else "-") + "xyz"[abs(code) - 1]
        rid = str(node) if count[node] == 1 else f"{node}{axis}"
        entries.append({"id": rid, "position": at_node[node], "direction": axis})
    return ReferencesFile.model_validate({"references": entries})


# --------------------------------------------------------------------------- UFF 58 (function type 4) writer

FRF_FORMATS = ("csv", "uff", "uff-ascii")
"""Formats ``simulate --frf`` writes: CSV (:func:`frf_csv_text`), UFF 58b (binary) or 58 (ASCII)
(:func:`frf_uff_bytes`)."""


def frf_format_from(path: str | os.PathLike[str], given: str | None) -> str:
    """The FRF file format: `given` (one of :data:`FRF_FORMATS`), else from the suffix (``.uff``/``.unv``: ``"uff"``).

    Raises
    ------
    InputError
        `given` is none of :data:`FRF_FORMATS`, or contradicts a UFF suffix
        (``identify --frf`` reads by suffix, so such a file would not read back).
    """
    is_uff = str(path).lower().endswith((".uff", ".unv"))
    if given is None:
        return "uff" if is_uff else "csv"
    fmt = given.strip().lower()
    if fmt not in FRF_FORMATS:
        raise InputError(f"FRF format {given!r}: one of {', '.join(FRF_FORMATS)}", source="frf_format")
    if (fmt == "csv") == is_uff:
        want = ".csv" if fmt == "csv" else ".uff or .unv"
        raise InputError(
            f"{fmt} FRFs in a file named {Path(path).name!r}: FRF files are read by suffix; name it {want}",
            source="frf_format",
        )
    return fmt


def _uff_node_code(sid: str, direction: NDArray[np.float64], what: str) -> tuple[int, int]:
    """UFF node and signed direction code of a sensor or reference id (``"12"``, ``"12+x"``).

    The direction must lie along a global axis (UFF 58 states nothing else
    without a local coordinate system); an axis in the id must be that one.
    """
    from rigidid.io.uff_codes import ID_PATTERN, dir_code

    match = ID_PATTERN.match(sid)
    if match is None or int(match.group(1)) <= 0:
        raise InputError(
            f"{what} id {sid!r} is not a UFF node and direction (ids such as 12 or 12+x are): "
            "rename it or write the FRFs as CSV",
            source=what + "s",
        )
    d = np.asarray(direction, dtype=float).reshape(3)
    along = np.flatnonzero(np.abs(d) > 1e-12)
    if along.size != 1:
        raise InputError(
            f"{what} {sid}: direction ({d[0]:.6g}, {d[1]:.6g}, {d[2]:.6g}) is not along an axis; UFF 58 "
            "records only +-x, +-y, +-z: write the FRFs as CSV",
            source=what + "s",
        )
    axis = ("+" if d[along[0]] > 0 else "-") + "xyz"[along[0]]
    named = match.group(2)
    if named:
        named = named.lower() if named[0] in "+-" else "+" + named.lower()
        if named != axis:
            raise InputError(f"{what} id {sid!r} names the axis {named} but its direction is {axis}", source=what + "s")
    return int(match.group(1)), dir_code(axis)


def _uff_force_factor(units: dict[str, str]) -> tuple[float, dict[str, Any]]:
    """Dataset 164 of the layout's units and the factor from rigidid's accelerance to the file's.

    rigidid's accelerance is length / s^2 per (mass unit x length / s^2); the
    file's is per the force unit of its 164 system (lbf for in/lb and ft/lb, a
    gravitational system). The factor is 1 for coherent systems.
    """
    from rigidid.io.uff import write_164
    from rigidid.io.uff_codes import LENGTH_PER_M, MASS_PER_KG

    dset = write_164(units)
    factor = MASS_PER_KG[units["mass"]] * LENGTH_PER_M[units["length"]] / float(dset["force"])
    return factor, dset


def _d25(value: float) -> str:
    return f"{value:25.16e}".replace("e", "D")


def frf_uff_bytes(
    frequencies: NDArray[np.float64],
    frf: NDArray[np.complex128],
    sensor_ids: Sequence[str],
    sensor_directions: NDArray[np.float64],
    reference_ids: Sequence[str],
    reference_directions: NDArray[np.float64],
    units: dict[str, str],
    *,
    binary: bool = True,
    name: str = "rigidid simulate",
) -> bytes:
    """FRFs (p, q, f) as a universal file: dataset 164 and one dataset 58 (function type 4) per pair.

    Parameters
    ----------
    frequencies : ndarray, shape (f,)
        Frequency lines (Hz), ascending and positive.
    frf : ndarray of complex, shape (p, q, f)
        Accelerance in the layout's units (1 / mass unit).
    sensor_ids, reference_ids : sequence of str
        Ids of the form ``"12"`` or ``"12+x"``: the node number and, if given,
        the direction code of the record's response (reference).
    sensor_directions, reference_directions : ndarray, shape (p, 3) and (q, 3)
        Unit directions; the code of an id without an axis comes from them
        (they must then lie along a global axis).
    units : dict
        ``{"length", "mass"}`` of the layout: written as dataset 164; values
        are converted to its force unit (lbf for in/lb and ft/lb).
    binary : bool
        Binary 58b (default; double precision, abscissa stored per line, exact)
        or ASCII 58 (``4E20.12``; the abscissa is written as start and
        increment in 6 significant digits, so only a grid whose step has 6
        digits comes back exactly).
    name : str
        First ID line of each record.

    Returns
    -------
    bytes
        The file's content (write it with :func:`rigidid.io.atomic.write_bytes_atomic`).

    Raises
    ------
    InputError
        An id that is no UFF node, an id without axis whose direction is
        oblique, a unit UFF cannot state, non-finite values, or frequencies
        that are not positive and ascending.

    Notes
    -----
    Records: ordinate data type 6 (complex double); abscissa 18 (frequency,
    Hz); ordinate 12 (acceleration, length exponent 1); denominator 13
    (excitation force, force exponent 1). Load case = reference number (from 1).
    """
    freq = np.asarray(frequencies, dtype=float).reshape(-1)
    h = np.asarray(frf, dtype=complex)
    p, q = len(sensor_ids), len(reference_ids)
    if h.shape != (p, q, freq.size):
        raise InputError(f"FRF array of shape {h.shape}, expected {(p, q, freq.size)}", source="frf")
    if freq.size < 2 or not np.all(np.isfinite(freq)) or freq[0] <= 0.0 or np.any(np.diff(freq) <= 0.0):
        raise InputError("frequencies must be at least two positive, ascending lines", source="frequencies")
    if not np.all(np.isfinite(h)):
        raise InputError("FRF values must be finite", source="frf")
    rsp = [_uff_node_code(s, d, "sensor") for s, d in zip(sensor_ids, np.asarray(sensor_directions), strict=True)]
    ref = [
        _uff_node_code(r, d, "reference") for r, d in zip(reference_ids, np.asarray(reference_directions), strict=True)
    ]
    factor, u164 = _uff_force_factor(units)
    step = float(freq[1] - freq[0])
    even = not binary and bool(np.allclose(np.diff(freq), step, rtol=1e-9, atol=0.0))
    length = units["length"]
    force = "N" if u164["units_code"] == 1 else str(u164["units_description"]).split("(")[-1].rstrip(")").strip()
    out = bytearray()
    out += b"    -1\n   164" + b" " * 74 + b"\n"
    out += f"{u164['units_code']:10d}{u164['units_description'][:20]:<20s}{u164['temp_mode']:10d}\n".encode()
    out += (_d25(u164["length"]) + _d25(u164["force"]) + _d25(u164["temp"]) + "\n").encode()
    out += (_d25(u164["temp_offset"]) + "\n    -1\n").encode()
    record = 0
    for j in range(q):
        for i in range(p):
            record += 1
            values = h[i, j] * factor
            if binary:
                data = np.empty(3 * freq.size)
                data[0::3], data[1::3], data[2::3] = freq, values.real, values.imag
                body = data.astype("<f8").tobytes()
                out += f"    -1\n    58b{1:6d}{2:6d}{11:12d}{len(body):12d}{0:6d}{0:6d}{0:12d}{0:12d}\n".encode()
            else:
                out += b"    -1\n    58" + b" " * 74 + b"\n"
            head = [
                f"{name[:80]:<80s}",
                f"{f'{sensor_ids[i]} / {reference_ids[j]}'[:80]:<80s}",
                f"{'NONE':<80s}",
                f"{'NONE':<80s}",
                f"{'NONE':<80s}",
                f"{4:5d}{record:10d}{0:5d}{j + 1:10d} {'NONE':<10s}{rsp[i][0]:10d}{rsp[i][1]:4d}"
                f" {'NONE':<10s}{ref[j][0]:10d}{ref[j][1]:4d}",
                f"{6:10d}{freq.size:10d}{int(even):10d}"
                f"{freq[0] if even else 0.0:13.5e}{step if even else 0.0:13.5e}{0.0:13.5e}",
                f"{18:10d}{0:5d}{0:5d}{0:5d} {'Frequency':<20s} {'Hz':<20s}",
                f"{12:10d}{1:5d}{0:5d}{0:5d} {'Acceleration':<20s} {f'{length}/s^2':<20s}",
                f"{13:10d}{0:5d}{1:5d}{0:5d} {'Force':<20s} {force[:20]:<20s}",
                f"{0:10d}{0:5d}{0:5d}{0:5d} {'NONE':<20s} {'NONE':<20s}",
            ]
            out += ("\n".join(head) + "\n").encode()
            if binary:
                out += body + b"    -1\n"
                continue
            if even:
                data = np.empty(2 * freq.size)
                data[0::2], data[1::2] = values.real, values.imag
                lines = ["".join(f"{v:20.12e}" for v in data[k : k + 4]) for k in range(0, data.size, 4)]
            else:
                lines = [f"{f:13.5e}{v.real:20.12e}{v.imag:20.12e}" for f, v in zip(freq, values, strict=True)]
            out += ("\n".join(lines) + "\n    -1\n").encode()
    return bytes(out)
