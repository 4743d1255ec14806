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

__all__ = ["FRF_COLUMNS", "frf_csv_text", "load_frf_csv", "load_references", "reference_arrays"]

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
