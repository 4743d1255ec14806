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
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from rigidid.errors import InputError
from rigidid.models import ReferencesFile

__all__ = ["FRF_COLUMNS", "frf_csv_text", "load_frf_csv", "load_frf_uff", "load_references", "reference_arrays"]

FRF_COLUMNS = ("frequency_hz", "response", "reference", "real", "imag")


def load_references(path: str | os.PathLike[str]) -> ReferencesFile:
    """Read and validate ``references.json`` (reference ids, positions, force directions).

    Raises
    ------
    InputError
        Unreadable file, invalid JSON, or a field that fails validation (named).
    """
    from rigidid.io.files import _load_json_model

    return _load_json_model(Path(path), ReferencesFile)


def reference_arrays(refs: ReferencesFile) -> tuple[tuple[str, ...], NDArray[np.float64], NDArray[np.float64]]:
    """Reference ids, positions (q, 3) and unit force directions (q, 3)."""
    ids = tuple(r.id for r in refs.references)
    positions = np.array([r.position for r in refs.references], dtype=float).reshape(-1, 3)
    directions = np.array([r.unit_direction() for r in refs.references], dtype=float).reshape(-1, 3)
    return ids, positions, directions


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
    header = [h.strip() for h in (reader.fieldnames or [])]
    missing = [c for c in FRF_COLUMNS if c not in header]
    if missing:
        raise InputError(f"missing column {missing[0]!r} (need {', '.join(FRF_COLUMNS)})", source=src, location="row 1")
    reader.fieldnames = header
    s_index = {s: i for i, s in enumerate(sensor_ids)}
    r_index = {r: j for j, r in enumerate(reference_ids)}
    values: dict[tuple[int, int], dict[float, complex]] = {}
    for n, row in enumerate(reader, start=2):
        resp = (row.get("response") or "").strip()
        ref = (row.get("reference") or "").strip()
        if resp not in s_index:
            raise InputError(f"response {resp!r} is not a sensor of the layout", source=src, location=f"row {n}")
        if ref not in r_index:
            raise InputError(f"reference {ref!r} is not in the references file", source=src, location=f"row {n}")
        nums = []
        for col in ("frequency_hz", "real", "imag"):
            try:
                v = float((row.get(col) or "").strip())
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
    return freqs, frf


def frf_csv_text(
    frequencies: NDArray[np.float64],
    frf: NDArray[np.complex128],
    sensor_ids: Sequence[str],
    reference_ids: Sequence[str],
) -> str:
    """FRFs (p, q, f) as the CSV text :func:`load_frf_csv` reads (full precision)."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(FRF_COLUMNS)
    for i, s in enumerate(sensor_ids):
        for j, r in enumerate(reference_ids):
            for k, f in enumerate(frequencies):
                v = frf[i, j, k]
                w.writerow([repr(float(f)), s, r, repr(float(v.real)), repr(float(v.imag))])
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


def load_frf_uff(
    path: str | os.PathLike[str], sensor_ids: Sequence[str], reference_ids: Sequence[str]
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

    Returns
    -------
    frequencies : ndarray, shape (f,)
    frf : ndarray of complex, shape (p, q, f)
        Accelerance; mobility (ordinate type 11) is multiplied by ``i w``,
        receptance (8) by ``-w^2``; values are taken in the layout's units.

    Raises
    ------
    InputError
        Naming the file and dataset: function type 3 (cross spectrum) or
        another non-FRF, an ordinate that is not acceleration, velocity or
        displacement, a node/direction that is no sensor or reference, a
        missing pair, or pairs with other frequency lines.
    """
    from rigidid.io.uff import _read_all

    src = str(path)
    sets = _read_all(Path(path))
    s_index = {s: i for i, s in enumerate(sensor_ids)}
    r_index = {r: j for j, r in enumerate(reference_ids)}
    found: dict[tuple[int, int], tuple[NDArray[np.float64], NDArray[np.complex128]]] = {}
    n58 = 0
    for dset in sets:
        if dset.get("type") != 58:
            continue
        n58 += 1
        where = f"dataset 58 #{n58}"
        func = int(dset.get("func_type", 0))
        if func == 3:
            raise InputError(
                "function type 3 is a cross spectrum, not an FRF: export H1/H2 FRFs (function type 4)",
                source=src,
                location=where,
            )
        if func != 4:
            raise InputError(f"function type {func} is not an FRF (function type 4)", source=src, location=where)
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
        found[(s_index[rsp], r_index[ref])] = (x, data)
    if not found:
        raise InputError("no FRF (dataset 58, function type 4) in the file", source=src)
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
    return freqs, frf
