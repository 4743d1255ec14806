"""Universal File Format (UFF) input and output, through :mod:`pyuff`.

A thin layer between UFF files and the plain data the rest of rigidid uses:
the ``layout.json`` dictionary, ``modes.csv`` rows and per-impact time
records (see ``FORMATS.md``). Parsing and formatting are pyuff's; this module
maps UFF's numbering (nodes, signed direction codes, unit codes) onto
rigidid's sensors and units, and turns whatever is missing or contradictory
into :class:`~rigidid.errors.InputError` naming the data set.

Datasets used
-------------
=====  ====================================================================
15     nodes, coordinates in their definition system (6 significant digits)
2411   nodes, coordinates in the part (global) system (double precision)
18     coordinate systems (origin, +x point, +xz point; 6 digits)
2420   coordinate systems (axes and origin; double precision)
58     one time record per sensor and impact (``func_type`` 1), or one FRF per
       response and reference (``func_type`` 4; not both in one file)
55     mode shapes at nodes (normal, 2, or complex, 3 and 7)
82     trace lines (written only, for animation)
151    header: the model name becomes the layout's ``name``
164    units
=====  ====================================================================

Other datasets (2412 elements, 2414 analysis results, ...) are not read; a
file without 58 or 55 is refused saying so. A second file can give the
geometry (``geometry=``: its 15, 2411, 18, 2420, 164 and 151).

Conventions
-----------
Sensors
    A sensor is a (node, signed direction) pair of a dataset 58:
    ``rsp_dir`` 1, 2, 3 = +x, +y, +z and -1, -2, -3 = -x, -y, -z, along
    the axes of the node's displacement coordinate system
    (:mod:`rigidid.io.uff_systems`); the layout gets the global direction.
    Rotations (4..6) and scalar records (0) are not accelerometers and are
    refused. The sensors are listed in the order of
    their first record in the file.
Sensor ids
    ``"<node>"`` (``"12"``) when the node carries one sensor, else
    ``"<node><direction>"`` (``"12+x"``, ``"12+y"``, ``"12-z"``). Writing
    reverses this: ids of these two forms keep their node numbers; other ids
    are replaced by node numbers 1, 2, ... given to distinct positions in
    order of first appearance.
Impacts
    Time records (58 with ``func_type`` 1) are grouped into impacts by
    (``load_case_id``, ``ref_node``, ``ref_dir``), in order of first
    appearance; every record of one impact must share one time axis. The
    writer gives impact ``i`` (from 1) load case ``i`` and reference node 0.
Mode shapes
    A 55 gives a 3-vector per node in the node's displacement system; a
    sensor reads its component along the sensor's (local) axis. When the file has no dataset
    58, every node component that is non-zero in some mode becomes a
    sensor along +x, +y or +z (how modal software exports measured DOFs:
    unmeasured components are zero). Complex eigenvalues (analysis types 3
    and 7) are read in the file's unit and sign convention
    (:mod:`rigidid.io.uff_eigen`; the plain pole in rad/s by default);
    normal modes (type 2) give the frequency in Hz and the viscous damping
    ratio.
Units
    Dataset 164's factors (UFF units per SI unit) decide: the length unit
    from the length factor, the mass unit as ``force / (length / s^2)``
    (coherent systems: SI, mm/mN, cm/cN, ft/poundal, or user-defined) or as
    the mass whose weight is the force unit (gravitational systems: ft or in
    with lbf give lb, m or mm with kgf give kg). A unit outside
    m/cm/mm/in/ft and kg/g/lb is an :class:`~rigidid.errors.InputError`.

pyuff pitfalls met here
-----------------------
- Dataset 15 stores coordinates with 6 significant digits, 55 stores shapes,
  frequencies and eigenvalues with 6 (round trips to about 5e-6), and 58
  stores its time step with 6: write time steps that are round in 6 digits
  (1e-3, 5e-4, ...) if the time axis must come back exactly.
- The dataset 15 writer fails on float node numbers: node numbers are ints.
- pyuff replaces NaN samples by zeros when writing: the writers here refuse
  non-finite data instead.
- Binary 58 (the default here) is about 8x faster to read than ASCII and
  exact; some vendor tools read pyuff's binary 58 wrongly (``binary=False``).
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rigidid.errors import InputError, RigididError, RigididWarning
from rigidid.io.atomic import atomic_path
from rigidid.io.uff_codes import (
    AXES,
    CODE_FACTORS,
    FUNCTION_TYPES,
    ID_PATTERN,
    LENGTH_PER_M,
    MASS_PER_KG,
    STANDARD_UNITS,
    dir_code,
)
from rigidid.io.uff_eigen import EigenConvention, eigen_convention, stated_frequency
from rigidid.io.uff_systems import CoordinateSystemError, CoordinateSystems
from rigidid.units import G0

if TYPE_CHECKING:
    from rigidid.core.identify import Identification

__all__ = [
    "UFF_STEP_DIGITS",
    "ModeRow",
    "UffContents",
    "UffRecord",
    "read_uff",
    "uff_function_types",
    "write_uff",
    "write_uff_test",
]

Array = NDArray[np.float64]
CArray = NDArray[np.complex128]

UFF_STEP_DIGITS = 6
"""Significant digits of a dataset 58's time step (``E13.5``, as pyuff writes and most tools do)."""

ModeRow = tuple[int, float, float, str, float, float]
"""One ``modes.csv`` row: ``(mode, frequency_hz, damping_ratio, sensor_id, real, imag)``."""


class UffRecord(NamedTuple):
    """The time records of one impact.

    Attributes
    ----------
    time : ndarray, shape (samples,)
        Uniform time axis (s).
    data : ndarray, shape (samples, k)
        Column ``j``: what sensor ``sensor_ids[j]`` reads (any consistent unit).
    sensor_ids : tuple of str
        The layout sensor of each column.
    """

    time: Array
    data: Array
    sensor_ids: tuple[str, ...]


@dataclass(frozen=True)
class UffContents:
    """What a UFF file says about a test, in rigidid's terms.

    Attributes
    ----------
    layout : dict
        ``layout.json`` content: ``{"name", "units": {"length", "mass"},
        "sensors": [{"id", "position", "direction"}]}`` (no ``mass``: UFF
        does not carry it).
    mode_rows : list of tuple
        ``modes.csv`` rows ``(mode, frequency_hz, damping_ratio, sensor_id,
        real, imag)``, mode by mode, sensors in layout order; empty without
        dataset 55.
    records : list of UffRecord
        One per impact, in file order; empty without time records.
    record_labels : list of str
        Per impact: ``"load case 1"`` or ``"load case 1, reference 3+z"``.
    nodes : dict of int to tuple of float
        Every node's coordinates (length unit).
    references : list of dict
        FRF files: the reference (force) points named by the FRFs' headers,
        ``{"id", "position", "direction"}`` as ``references.json`` has them
        (ids as for sensors), in order of first appearance; empty otherwise.
    frf_sets : list of dict
        FRF files: the datasets 58 of function type 4 and the datasets 164, as
        read (:func:`rigidid.io.frf.frf_from_datasets` turns them into an array).
    """

    layout: dict[str, Any]
    mode_rows: list[ModeRow] = field(default_factory=list)
    records: list[UffRecord] = field(default_factory=list)
    record_labels: list[str] = field(default_factory=list)
    nodes: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    references: list[dict[str, Any]] = field(default_factory=list)
    frf_sets: list[dict[str, Any]] = field(default_factory=list)


# --------------------------------------------------------------------------- helpers


def _pyuff() -> Any:
    try:
        import pyuff
    except ImportError:  # pragma: no cover - depends on the environment
        raise RigididError("UFF files need the optional package pyuff (pip install pyuff)") from None
    return pyuff


def _dir_name(code: int) -> str:
    return ("+" if code > 0 else "-") + AXES[abs(code) - 1]


def _axis_direction(value: Any, where: str, source: str | None) -> str:
    """Signed axis name (``"+x"``...) of a layout direction (string or axis-aligned vector)."""
    if isinstance(value, str):
        key = value.strip().lower()
        key = key if key[:1] in "+-" else "+" + key
        if len(key) == 2 and key[1] in AXES:
            return key
        raise InputError(f"unknown direction {value!r}", source=source, location=where)
    v = np.asarray(value, dtype=float).reshape(-1)
    nonzero = np.flatnonzero(v)
    if v.shape != (3,) or not np.all(np.isfinite(v)) or nonzero.size != 1:
        raise InputError(
            f"direction {list(np.atleast_1d(v))} is not along an axis; UFF records only +-x, +-y, +-z",
            source=source,
            location=where,
        )
    i = int(nonzero[0])
    return ("+" if v[i] > 0 else "-") + AXES[i]


def _sensor_ids(sensors: Sequence[tuple[int, int]]) -> list[str]:
    per_node: dict[int, int] = {}
    for node, _ in sensors:
        per_node[node] = per_node.get(node, 0) + 1
    return [str(node) if per_node[node] == 1 else f"{node}{_dir_name(code)}" for node, code in sensors]


def _assign_nodes(positions: Array, sensor_ids: Sequence[str]) -> list[int]:
    """Node number of every sensor: from ids ``"12"``/``"12+z"`` when consistent, else by position."""
    scale = max(1.0, float(np.max(np.abs(positions)))) if positions.size else 1.0
    parsed = [ID_PATTERN.match(sid) for sid in sensor_ids]
    if all(parsed):
        nodes = [int(m.group(1)) for m in parsed if m]
        where: dict[int, Array] = {}
        consistent = all(n > 0 for n in nodes)
        for n, p in zip(nodes, positions, strict=True):
            if n in where and not np.allclose(where[n], p, rtol=0.0, atol=1e-9 * scale):
                consistent = False
            where.setdefault(n, p)
        if consistent:
            return nodes
    numbering: list[tuple[Array, int]] = []
    result = []
    for p in positions:
        for q, n in numbering:
            if np.allclose(q, p, rtol=0.0, atol=1e-9 * scale):
                result.append(n)
                break
        else:
            numbering.append((p, len(numbering) + 1))
            result.append(len(numbering))
    return result


def units_from_164(dset: dict[str, Any], source: str, where: str) -> dict[str, str]:
    """The layout units (``{"length": ..., "mass": ...}``) a dataset 164 states, by its factors or its code."""
    length_f = float(dset.get("length", 0.0))
    force_f = float(dset.get("force", 0.0))
    code = dset.get("units_code")
    if not isinstance(code, int | np.integer) or not 1 <= int(code) <= 10:
        raise InputError(
            f"units code {code} is not a UFF units code (1-8 and 10 name units, 9 is user defined)",
            source=source,
            location=where,
        )
    if not (length_f > 0.0 and force_f > 0.0) and int(code) in CODE_FACTORS:
        length_f, force_f = CODE_FACTORS[int(code)]

    def match(value: float, table: dict[str, float]) -> str | None:
        for name, ref in table.items():
            if value > 0.0 and math.isclose(value, ref, rel_tol=1e-4):
                return name
        return None

    length = match(length_f, LENGTH_PER_M)
    mass = None
    if length is not None and force_f > 0.0:
        mass = match(force_f / length_f, MASS_PER_KG) or match(force_f * G0, MASS_PER_KG)
    if length is None or mass is None:
        raise InputError(
            f"units code {code} (length factor {length_f:.6g}, force factor {force_f:.6g} per SI unit) "
            "is not one of the layout units m/cm/mm/in/ft with kg/g/lb",
            source=source,
            location=where,
        )
    return {"length": length, "mass": mass}


def write_164(units: dict[str, str]) -> dict[str, Any]:
    """The dataset 164 (pyuff's dict) of the layout's units (``{"length": ..., "mass": ...}``)."""
    try:
        length, mass = units["length"], units["mass"]
        length_f, mass_f = LENGTH_PER_M[length], MASS_PER_KG[mass]
    except KeyError as exc:
        raise InputError(f"unknown unit {exc.args[0]!r}; length m/cm/mm/in/ft, mass kg/g/lb", source="units") from None
    if (length, mass) in STANDARD_UNITS:
        code, force_f, text, temp, offset = STANDARD_UNITS[(length, mass)]
    else:  # a coherent user system whose mass unit is the layout's
        code, force_f, text, temp, offset = 9, mass_f * length_f, f"US: {length} {mass} s", 1.0, 273.15
    return {
        "type": 164,
        "units_code": code,
        "units_description": text[:20],
        "temp_mode": 1,
        "length": length_f,
        "force": force_f,
        "temp": temp,
        "temp_offset": offset,
    }


def _write_sets(path: str | os.PathLike[str], datasets: list[dict[str, Any]]) -> None:
    """Write datasets through pyuff to a temporary file beside `path`, then rename it."""
    pyuff = _pyuff()
    p = Path(path)
    with atomic_path(p) as tmp:
        try:
            with warnings.catch_warnings():
                # pyuff's binary 58 writer reopens the file and leaves that handle to the garbage
                # collector (CPython closes it, flushed, when the writer returns): not ours to report
                warnings.simplefilter("ignore", ResourceWarning)
                pyuff.UFF(str(tmp)).write_sets(datasets, mode="overwrite")
        except Exception as exc:  # pyuff raises bare Exception
            raise RigididError(f"{p}: pyuff could not write the file: {exc}") from exc


def _nodes_dataset(nodes: Sequence[int], coords: Array) -> dict[str, Any]:
    n = len(nodes)
    return {
        "type": 15,
        "node_nums": np.asarray(nodes, dtype=int),  # ints: pyuff's 15 writer fails on floats
        "def_cs": np.zeros(n, dtype=int),
        "disp_cs": np.zeros(n, dtype=int),
        "color": np.ones(n, dtype=int),
        "x": coords[:, 0].astype(float),
        "y": coords[:, 1].astype(float),
        "z": coords[:, 2].astype(float),
    }


def _pole_text(pole: complex) -> str:
    f = abs(pole) / (2.0 * math.pi)
    z = -pole.real / abs(pole)
    return f"f = {f:.6g} Hz, damping ratio = {z:.6g}"


def _modes_dataset(
    mode: int, pole: complex, node_nums: Sequence[int], vectors: CArray, title: str, units: str
) -> dict[str, Any]:
    """Complex 55 (analysis type 3): 3D translations ``vectors`` (nodes, 3) of one mode."""
    return {
        "type": 55,
        "id1": title[:80],
        "id2": _pole_text(pole)[:80],
        "id3": f"pole {pole.real:.6g} {pole.imag:+.6g}j rad/s"[:80],
        "id4": f"units {units}"[:80],
        "id5": "NONE",
        "model_type": 1,
        "analysis_type": 3,
        "data_ch": 2,
        "spec_data_type": 8,
        "load_case": 1,
        "mode_n": int(mode),
        "eig": complex(pole),
        "modal_a": 0j,
        "modal_b": 0j,
        "node_nums": np.asarray(node_nums, dtype=int),
        "r1": np.ascontiguousarray(vectors[:, 0], dtype=complex),
        "r2": np.ascontiguousarray(vectors[:, 1], dtype=complex),
        "r3": np.ascontiguousarray(vectors[:, 2], dtype=complex),
    }


# --------------------------------------------------------------------------- reading


@dataclass
class _Reader:
    source: str
    units: dict[str, str] | None = None
    name: str | None = None
    node_defs: dict[int, list[tuple[tuple[float, float, float], str]]] = field(default_factory=dict)
    node_cs: dict[int, tuple[int, int, str]] = field(default_factory=dict)
    systems: CoordinateSystems = field(default_factory=CoordinateSystems)
    records: list[tuple[dict[str, Any], str]] = field(default_factory=list)
    modes: list[tuple[dict[str, Any], str]] = field(default_factory=list)
    not_read: dict[int, int] = field(default_factory=dict)
    units_where: str = ""
    units_dataset: dict[str, Any] | None = None

    def error(self, message: str, where: str | None = None) -> InputError:
        return InputError(message, source=self.source, location=where)

    def add_nodes(self, dset: dict[str, Any], where: str, kind: int = 15) -> None:
        """Nodes of a 15 (coordinates in the definition system) or 2411 (in the part, global, system)."""
        nums = np.asarray(dset.get("node_nums", []), dtype=float).reshape(-1)
        xyz = np.column_stack([np.asarray(dset.get(k, []), dtype=float).reshape(-1) for k in "xyz"])
        if xyz.shape[0] != nums.shape[0] or not np.all(np.isfinite(xyz)):
            raise self.error("node coordinates are incomplete or not finite", where)
        def_cs = np.asarray(dset.get("def_cs", np.zeros(nums.size)), dtype=int).reshape(-1)
        if kind == 2411:  # field 2 is the export system, a label: 2411 coordinates are in the part system
            def_cs = np.zeros(nums.size, dtype=int)
        disp_cs = np.asarray(dset.get("disp_cs", np.zeros(nums.size)), dtype=int).reshape(-1)
        if def_cs.size != nums.size or disp_cs.size != nums.size:
            raise self.error("node coordinate system numbers are incomplete", where)
        for num, p, dcs, ucs in zip(nums, xyz, def_cs, disp_cs, strict=True):
            if num != round(num) or num <= 0:
                raise self.error(f"node label {num:g} is not a positive integer", where)
            node = int(num)
            cs = (int(dcs), int(ucs), f"{where}, node {node}")
            if node in self.node_cs and self.node_cs[node][:2] != cs[:2]:
                first = self.node_cs[node]
                raise self.error(
                    f"node {node} has definition/displacement systems {cs[0]}/{cs[1]} here and "
                    f"{first[0]}/{first[1]} in {first[2]}",
                    cs[2],
                )
            self.node_cs.setdefault(node, cs)
            self.node_defs.setdefault(node, []).append(((float(p[0]), float(p[1]), float(p[2])), where))

    def add_systems(self, dset: dict[str, Any], kind: int, where: str) -> None:
        try:
            if kind == 18:
                self.systems.add_18(dset, where)
            else:
                self.systems.add_2420(dset, where)
        except CoordinateSystemError as exc:
            raise self.error(str(exc), exc.where) from None

    def set_units(self, dset: dict[str, Any], where: str) -> None:
        units = units_from_164(dset, self.source, where)
        if self.units is not None and units != self.units:
            raise self.error(
                f"units {units['length']}/{units['mass']} contradict {self.units['length']}/{self.units['mass']} "
                f"of {self.units_where}",
                where,
            )
        self.units, self.units_where, self.units_dataset = units, where, dset

    def nodes(self) -> tuple[dict[int, tuple[float, float, float]], dict[int, str]]:
        """Global coordinates of every node, and why a node has none (an unusable definition system)."""
        try:
            self.systems.resolve()
        except CoordinateSystemError as exc:
            raise self.error(str(exc), exc.where) from None
        all_coords = [c for defs in self.node_defs.values() for c, _ in defs]
        scale = max([1.0, *(abs(v) for c in all_coords for v in c)])
        out: dict[int, tuple[float, float, float]] = {}
        why: dict[int, str] = {}
        for node, defs in self.node_defs.items():
            first, first_where = defs[0]
            for coords, where in defs[1:]:
                if not np.allclose(coords, first, rtol=1e-5, atol=1e-9 * scale):
                    raise self.error(
                        f"node {node} has two coordinates: {list(first)} ({first_where}) and {list(coords)}",
                        f"{where}, node {node}",
                    )
            def_cs = self.node_cs.get(node, (0, 0, ""))[0]
            problem = self.systems.check(def_cs, f"node {node} is defined in coordinate system {def_cs}")
            if problem is not None:
                why[node] = problem
                continue
            g = self.systems.to_global(def_cs, np.array(first))
            out[node] = (float(g[0]), float(g[1]), float(g[2]))
        return out, why

    def direction(self, node: int, code: int, where: str) -> str | list[float]:
        """The global measuring direction of signed axis `code` of `node`'s displacement system."""
        disp_cs = self.node_cs.get(node, (0, 0, ""))[1]
        problem = self.systems.check(disp_cs, f"node {node} measures in coordinate system {disp_cs}")
        if problem is not None:
            raise self.error(problem, where)
        v = self.systems.axis(disp_cs, code)
        for i in range(3):  # an axis of the global system stays a name (+x, -z, ...)
            if abs(abs(v[i]) - 1.0) <= 1e-15 and np.count_nonzero(v) == 1:
                return ("+" if v[i] > 0 else "-") + AXES[i]
        return [float(c) for c in v]


def read_all(path: Path) -> list[dict[str, Any]]:
    """Every dataset of a universal file, as pyuff's dicts (binary 58s read by :mod:`rigidid.io.uff_scan`)."""
    pyuff = _pyuff()
    src = str(path)
    if not path.exists():
        raise InputError("file not found", source=src)
    if path.is_dir():
        raise InputError("is a directory, not a file", source=src)
    from rigidid.limits import MAX_UFF_BYTES

    if not path.is_file():
        raise InputError("not a regular file (a device or pipe cannot be read as UFF)", source=src)
    if path.stat().st_size > MAX_UFF_BYTES:
        raise InputError(f"larger than the limit of {MAX_UFF_BYTES // 2**20} MiB for a UFF file", source=src)
    from rigidid.io.uff_scan import BOM, scan

    blocks = scan(path)
    with path.open("rb") as fh:
        bom = fh.read(len(BOM)) == BOM
    if blocks is not None and (bom or any(b.binary58 for b in blocks)):  # pyuff would lose the first dataset
        return _read_binary58(path, blocks)
    if bom:
        raise InputError("starts with a byte-order mark and its datasets are not delimited as UFF wants", source=src)
    try:
        uff = pyuff.UFF(src)
        n = uff.get_n_sets()
        types = [int(t) for t in uff.get_set_types()]
    except Exception as exc:
        raise InputError(f"not a readable UFF file: {exc}", source=src) from None
    if n == 0:
        raise InputError("no UFF datasets found (is it a universal file?)", source=src)
    return _read_sets(uff, types, src)


def uff_function_types(path: str | os.PathLike[str]) -> list[int] | None:
    """The function types of a universal file's datasets 58 (1 time response, 4 FRF...), from their headers only.

    The values are not read: this is how a command tells a file of FRFs from one of records or modes
    before reading it once. None when the file does not follow the UFF layout
    (:func:`rigidid.io.uff_scan.scan`) or a header cannot be read: then read it (:func:`read_uff`).
    """
    from rigidid.io.uff_scan import scan

    try:
        blocks = scan(path)
        if blocks is None:
            return None
        types = []
        with open(path, "rb") as fh:
            for block in blocks:
                if block.kind != 58:
                    continue
                if block.binary58:  # the ID line, ID lines 1-5, then record 6
                    record6 = block.header[6]
                else:  # delimiter, ID line, ID lines 1-5, record 6
                    fh.seek(block.start)
                    record6 = [fh.readline() for _ in range(8)][7]
                types.append(int(record6[:5]))
        return types
    except (OSError, ValueError, IndexError):
        return None


_WANTED = {15, 18, 55, 58, 151, 164, 2411, 2420}


def _read_sets(uff: Any, types: list[int], src: str, ordinals: list[int] | None = None) -> list[dict[str, Any]]:
    """The datasets rigidid reads (others as ``{"type": kind}``).

    `ordinals`: each dataset's number among those of its kind in the original
    file, when `uff` holds only some of them (its own count otherwise), for
    the message naming the one pyuff cannot read.
    """
    out: list[dict[str, Any]] = []
    for i, kind in enumerate(types):
        if kind not in _WANTED:
            out.append({"type": kind})
            continue
        try:
            dset = uff.read_sets(i)
        except Exception as exc:
            count = ordinals[i] if ordinals is not None else types[: i + 1].count(kind)
            raise InputError(f"pyuff cannot read it: {exc}", source=src, location=f"dataset {kind} #{count}") from None
        out.append(dset)
    return out


def _read_binary58(path: Path, blocks: list[Any]) -> list[dict[str, Any]]:
    """A file with binary 58 datasets: those read by :mod:`rigidid.io.uff_scan`, the others by pyuff.

    The other datasets (geometry, units, modes, ASCII 58) are written to a
    temporary file on their own and given to pyuff, so pyuff never reads the
    binary values; the result is in the file's order.
    """
    import tempfile

    from rigidid.io.uff_scan import blocks_text, read_58b

    src = str(path)
    seen: dict[int, int] = {}
    ordinals = []  # each dataset's number among its kind's in the file (binary 58 ones counted too)
    for b in blocks:
        seen[b.kind] = seen.get(b.kind, 0) + 1
        ordinals.append(seen[b.kind])
    others = [b for b in blocks if not b.binary58 and b.kind in _WANTED]
    others_ordinals = [k for b, k in zip(blocks, ordinals, strict=True) if not b.binary58 and b.kind in _WANTED]
    parsed: list[dict[str, Any]] = []
    if others:
        with tempfile.TemporaryDirectory(prefix="rigidid-uff-") as folder:
            part = Path(folder) / "datasets.uff"
            part.write_bytes(blocks_text(path, others))
            try:
                uff = _pyuff().UFF(str(part))
                types = [int(t) for t in uff.get_set_types()]
            except Exception as exc:
                raise InputError(f"not a readable UFF file: {exc}", source=src) from None
            parsed = _read_sets(uff, types, src, others_ordinals if len(types) == len(others) else None)
    queue = iter(parsed)
    out: list[dict[str, Any]] = []
    for block in blocks:
        if block.binary58:
            out.append(read_58b(path, block))
        elif block.kind in _WANTED:
            out.append(next(queue))
        else:
            out.append({"type": block.kind})
    return out


def _time_axis(reader: _Reader, dset: dict[str, Any], where: str) -> tuple[float, float, int]:
    """First time, step and samples of a time record, checked (the values are not read)."""
    n = int(dset.get("num_pts", 0))
    data = dset.get("data")
    size = int(np.size(data)) if data is not None else 0
    if size < 2 or size != n:
        raise reader.error(f"{size} samples where the header says {dset.get('num_pts')}", where)
    if np.iscomplexobj(np.asarray(data)):
        raise reader.error("a time record must be real, this one is complex", where)
    if int(dset.get("abscissa_spacing", 1)) != 1:
        x = np.asarray(dset.get("x"), dtype=float).reshape(-1)
        if x.shape != (n,) or not np.all(np.isfinite(x)):
            raise reader.error("the time axis holds NaN or infinite values", where)
        steps = np.diff(x)
        if np.any(steps <= 0.0) or np.ptp(steps) > 1e-6 * float(np.mean(steps)):
            raise reader.error("the time axis is not uniformly sampled", where)
        return float(x[0]), float(np.mean(steps)), n
    first, step = float(dset.get("abscissa_min", 0.0)), float(dset.get("abscissa_inc", 0.0))
    if not (math.isfinite(first) and math.isfinite(step)):
        raise reader.error("the record holds NaN or infinite values", where)
    if not step > 0.0:
        raise reader.error("the time step is not positive", where)
    return first, step, n


_NOT_READ = {2414: "analysis results", 2412: "elements", 82: "trace lines", 2400: "model header", 1858: "qualifiers"}
_GEOMETRY_TYPES = (15, 18, 151, 164, 2411, 2420)


def _function_type_refusal(reader: _Reader, dset: dict[str, Any], where: str) -> InputError | None:
    """Why a dataset 58 is not read as a time record or an FRF (None when it is one: function type 1 or 4)."""
    func = int(dset.get("func_type", 0))
    if func in (1, 4):
        return None
    node = int(dset.get("rsp_node", 0))
    here = f"{where}, node {node}"
    name = FUNCTION_TYPES.get(func, "unknown")
    return reader.error(
        f"function type {func} ({name}) is not a time record; rigidid reads time responses (function type 1) "
        "and mode shapes (dataset 55)",
        here,
    )


def _read_into(
    reader: _Reader, path: Path, label: str, kinds: tuple[int, ...] | None, sets: Sequence[dict[str, Any]] | None = None
) -> None:
    """Read the datasets of `path` into `reader` (only `kinds` when given); `label` prefixes locations.

    `sets`: the datasets of `path` read already (:func:`read_all`); the file is then not read again.
    """
    counts: dict[int, int] = {}
    for dset in read_all(path) if sets is None else sets:
        kind = int(dset["type"])
        counts[kind] = counts.get(kind, 0) + 1
        where = f"{label}dataset {kind} #{counts[kind]}"
        if kinds is not None and kind not in kinds:
            continue
        if kind in (15, 2411):
            reader.add_nodes(dset, where, kind)
        elif kind in (18, 2420):
            reader.add_systems(dset, kind, where)
        elif kind == 58:
            reader.records.append((dset, where))
        elif kind == 55:
            reader.modes.append((dset, where))
        elif kind == 164:
            reader.set_units(dset, where)
        elif kind == 151 and reader.name is None:
            reader.name = str(dset.get("model_name", "")).strip() or None
        else:
            reader.not_read[kind] = reader.not_read.get(kind, 0) + 1


def read_uff(
    path: str | os.PathLike[str],
    *,
    units: dict[str, str] | None = None,
    geometry: str | os.PathLike[str] | None = None,
    datasets: Sequence[dict[str, Any]] | None = None,
) -> UffContents:
    """Read a test from a universal file: sensors, units, time records and modes.

    Parameters
    ----------
    path : path-like
        The UFF file (ASCII or binary 58).
    units : dict, optional
        ``{"length": ..., "mass": ...}`` to use when neither file has a
        dataset 164 (ignored when one has).
    geometry : path-like, optional
        A second UFF file whose nodes (15/2411), coordinate systems
        (18/2420), units (164) and name (151) complete `path` (how several
        exporters write a test: geometry in one file, modes or records in
        another). Its 55 and 58 datasets are not read.
    datasets : sequence of dict, optional
        The datasets of `path` as :func:`read_all` returned them, when the
        caller has read the file already: it is not read again.

    Returns
    -------
    UffContents
        ``layout`` (``layout.json`` dictionary), ``mode_rows``, ``records``
        (one :class:`UffRecord` per impact), ``record_labels`` and ``nodes``
        (global coordinates). Conventions (sensor ids, coordinate systems,
        grouping into impacts, units, eigenvalues) in the module
        documentation.

    Raises
    ------
    InputError
        Naming the file and the data set (``"dataset 58 #3, node 12"``, the
        count of that type from 1; datasets of the geometry file are prefixed
        with its name) for: a file pyuff cannot read; a node with two
        different coordinates; a node defined or measuring in a coordinate
        system that is missing, cylindrical or spherical; a 58 that is not a
        time response (naming its function type), whose response node has no
        coordinates, whose direction is a rotation or scalar, that repeats a
        sensor of its impact, or whose time axis differs from the rest of its
        impact; a 55 without a positive frequency, with eigenvalues of both
        signs, that is not 3D translations, that repeats a mode number, or
        that lacks a sensor's node; no sensors at all (then, datasets that
        are not read, such as 2414); no dataset 164 and no `units`; unknown
        units.

    Warns
    -----
    RigididWarning
        A 55 that is not a mode (ignored); complex eigenvalues read in a
        convention other than rad/s with a negative real part (naming the
        evidence).
    """
    p = Path(path)
    reader = _Reader(str(p))
    if geometry is not None:
        g = Path(geometry)
        _read_into(reader, g, f"{g.name}: ", _GEOMETRY_TYPES)
    _read_into(reader, p, "", None, datasets)
    nodes, no_position = reader.nodes()

    # sensors from the 58s
    sensors: list[tuple[int, int]] = []
    time_sets: list[tuple[dict[str, Any], str, tuple[int, int]]] = []
    frf_sets: list[tuple[dict[str, Any], str]] = []
    for dset, where in reader.records:
        refusal = _function_type_refusal(reader, dset, where)
        if refusal is not None:
            raise refusal
        node, code = int(dset.get("rsp_node", 0)), int(dset.get("rsp_dir", 0))
        here = f"{where}, node {node}"
        if node <= 0:
            raise reader.error(
                f"the record names no response node (node {node}, direction {code}): it carries no geometry; "
                "rigidid needs the node and direction of every record (name them in the exporting tool)",
                here,
            )
        if not 1 <= abs(code) <= 3:
            what = "a rotation" if 4 <= abs(code) <= 6 else "not a direction"
            raise reader.error(
                f"response direction {code} is {what}; accelerometers read along +-x, +-y, +-z (1..3, -1..-3)", here
            )
        _require_node(reader, node, nodes, no_position, here, "response node")
        if (node, code) not in sensors:
            sensors.append((node, code))
        if int(dset.get("func_type", 0)) == 4:
            frf_sets.append((dset, where))
        else:
            time_sets.append((dset, where, (node, code)))
    references = _frf_references(reader, frf_sets, time_sets, nodes, no_position)
    if not reader.records:
        sensors = _sensors_from_modes(reader, nodes, no_position)
    if not sensors:
        raise reader.error(_no_sensors_message(reader, nodes))
    if reader.units is None:
        if units is None:
            raise reader.error(
                "no units: the file has no dataset 164; give the units (--units LENGTH,MASS, e.g. mm,kg)"
            )
        given = {"length": str(units.get("length")), "mass": str(units.get("mass"))}
        if given["length"] not in LENGTH_PER_M or given["mass"] not in MASS_PER_KG:
            raise InputError(
                f"unknown units {given['length']}/{given['mass']}; length m/cm/mm/in/ft, mass kg/g/lb", source="units"
            )
        reader.units = given
    ids = _sensor_ids(sensors)
    id_of = dict(zip(sensors, ids, strict=True))
    layout: dict[str, Any] = {
        "name": reader.name or p.stem,
        "units": dict(reader.units),
        "sensors": [
            {
                "id": sid,
                "position": list(nodes[node]),
                "direction": reader.direction(node, code, f"{reader.node_cs.get(node, (0, 0, ''))[2]}"),
            }
            for (node, code), sid in zip(sensors, ids, strict=True)
        ],
    }
    records, labels = _group_records(reader, time_sets, id_of)
    rows = _mode_rows(reader, sensors, ids)
    raw = [d for d, _ in frf_sets] + ([reader.units_dataset] if frf_sets and reader.units_dataset else [])
    return UffContents(layout, rows, records, labels, nodes, references, raw)


def _frf_references(
    reader: _Reader,
    frf_sets: list[tuple[dict[str, Any], str]],
    time_sets: list[tuple[dict[str, Any], str, tuple[int, int]]],
    nodes: dict[int, tuple[float, float, float]],
    no_position: dict[int, str],
) -> list[dict[str, Any]]:
    """The reference points the FRFs' headers name (``references.json`` entries), checked.

    Raises
    ------
    InputError
        Time records and FRFs in one file; a reference node that is 0, has no
        coordinates or a direction that is no translation (naming the dataset).
    """
    if frf_sets and time_sets:
        first = int(reader.records[0][0].get("func_type", 0))
        where = next(w for d, w in reader.records if int(d.get("func_type", 0)) != first)
        raise reader.error(
            "time records (function type 1) and FRFs (function type 4) in one file: give them as two files", where
        )
    points: list[tuple[int, int]] = []
    for dset, where in frf_sets:
        node, code = int(dset.get("ref_node", 0)), int(dset.get("ref_dir", 0))
        here = f"{where}, reference node {node}"
        if node <= 0:
            raise reader.error(
                f"the FRF names no reference node (node {node}): it carries no geometry; name the force points "
                "in the exporting tool",
                here,
            )
        if not 1 <= abs(code) <= 3:
            what = "a rotation" if 4 <= abs(code) <= 6 else "not a direction"
            raise reader.error(f"reference direction {code} is {what}; forces act along +-x, +-y, +-z", here)
        _require_node(reader, node, nodes, no_position, here, "reference node")
        if (node, code) not in points:
            points.append((node, code))
    return [
        {
            "id": rid,
            "position": list(nodes[node]),
            "direction": reader.direction(node, code, f"{reader.node_cs.get(node, (0, 0, ''))[2]}"),
        }
        for (node, code), rid in zip(points, _sensor_ids(points), strict=True)
    ]


def _require_node(
    reader: _Reader,
    node: int,
    nodes: dict[int, tuple[float, float, float]],
    no_position: dict[int, str],
    where: str,
    what: str,
) -> None:
    if node in nodes:
        return
    if node in no_position:
        raise reader.error(no_position[node], where)
    raise reader.error(
        f"{what} {node} has no coordinates: no dataset 15 or 2411 defines it "
        "(give the geometry file with --geometry when it is separate)",
        where,
    )


def _no_sensors_message(reader: _Reader, nodes: dict[int, tuple[float, float, float]]) -> str:
    text = "no sensors: the file has no dataset 58 (time records) or 55 (mode shapes)"
    if nodes:
        text += f"; it holds geometry only ({len(nodes)} nodes): give it with --geometry beside a file of "
        text += "modes or records"
    not_read = [f"{kind} ({_NOT_READ[kind]})" for kind in sorted(reader.not_read) if kind in _NOT_READ]
    if 2414 in reader.not_read:
        text += "; dataset 2414 (analysis results) is not read"
    elif not_read:
        text += "; not read: datasets " + ", ".join(not_read)
    return text


def _sensors_from_modes(
    reader: _Reader, nodes: dict[int, tuple[float, float, float]], no_position: dict[int, str]
) -> list[tuple[int, int]]:
    sensors: list[tuple[int, int]] = []
    for dset, where in reader.modes:
        if int(dset.get("analysis_type", 0)) not in (2, 3, 7):
            continue
        columns = [np.asarray(dset.get(f"r{k}", []), dtype=complex).reshape(-1) for k in (1, 2, 3)]
        node_nums = np.asarray(dset.get("node_nums", []), dtype=int).reshape(-1)
        if any(c.shape != node_nums.shape for c in columns):  # a line lost from the node-by-node values
            raise reader.error(
                f"{node_nums.size} nodes but {', '.join(str(c.size) for c in columns)} values per direction "
                "(a damaged or truncated dataset)",
                where,
            )
        vectors = np.column_stack(columns)
        for node, vec in zip(node_nums, vectors, strict=True):
            for axis in range(3):
                key = (int(node), axis + 1)
                if vec[axis] != 0 and key not in sensors:
                    _require_node(reader, key[0], nodes, no_position, f"{where}, node {key[0]}", "node")
                    sensors.append(key)
    # order: node of first appearance, then x, y, z
    first = {node: i for i, (node, _) in reversed(list(enumerate(sensors)))}
    return sorted(sensors, key=lambda s: (first[s[0]], s[1]))


def _group_records(
    reader: _Reader,
    time_sets: list[tuple[dict[str, Any], str, tuple[int, int]]],
    id_of: dict[tuple[int, int], str],
) -> tuple[list[UffRecord], list[str]]:
    """Time records grouped into impacts (load case and reference), each into one array.

    The time axes are compared from the headers first; then each impact's
    array is allocated once and every record's values are copied into its
    column and released (binary 58 values are mapped from the file by
    :mod:`rigidid.io.uff_scan`, not held), so memory is the records once.
    """
    groups: dict[tuple[int, int, int], list[tuple[dict[str, Any], tuple[float, float, int], str, str]]] = {}
    for dset, where, sensor in time_sets:
        key = (int(dset.get("load_case_id", 0)), int(dset.get("ref_node", 0)), int(dset.get("ref_dir", 0)))
        here = f"{where}, node {sensor[0]}"
        groups.setdefault(key, []).append((dset, _time_axis(reader, dset, here), id_of[sensor], here))
    records: list[UffRecord] = []
    labels: list[str] = []
    for (case, ref_node, ref_dir), items in groups.items():
        label = f"load case {case}"
        if ref_node:
            ref = f"{ref_node}{_dir_name(ref_dir)}" if 1 <= abs(ref_dir) <= 3 else f"{ref_node} dir {ref_dir}"
            label += f", reference {ref}"
        (first0, step0, n0), where0 = items[0][1], items[0][3]
        seen: dict[str, str] = {}
        for _, (first, step, n), sid, where in items:
            if sid in seen:
                raise reader.error(f"sensor {sid} appears twice in {label} (also {seen[sid]})", where)
            seen[sid] = where
            last, last0 = first + (n - 1) * step, first0 + (n0 - 1) * step0
            if n != n0 or max(abs(first - first0), abs(last - last0)) > 1e-6 * step0:
                raise reader.error(
                    f"time axis ({n} samples from {first:.6g} s, step {step:.6g} s) differs from "
                    f"{where0} ({n0} samples from {first0:.6g} s, step {step0:.6g} s) of {label}",
                    where,
                )
        data = np.empty((n0, len(items)))
        sources = [item[0]["data"] for item in items]
        if all(isinstance(v, np.memmap) for v in sources):
            _fill_from_file(data, sources)
        else:
            for j, values in enumerate(sources):
                data[:, j] = values
        for item in items:
            item[0]["data"] = None  # file mappings and pyuff's arrays are not held
        from rigidid.core.timedomain.preprocess import column_peaks

        peaks = column_peaks(data)  # NaN and infinities reach the peaks
        if not np.isfinite(peaks).all():
            raise reader.error("the record holds NaN or infinite values", items[int(np.argmin(np.isfinite(peaks)))][3])
        time0: Array = first0 + step0 * np.arange(n0, dtype=float)
        records.append(UffRecord(time0, data, tuple(item[2] for item in items)))
        labels.append(label)
    return records, labels


def _fill_from_file(data: Array, maps: list[np.memmap[Any, Any]]) -> None:
    """Copy file-mapped columns into `data` a block of rows at a time, read from the file, not the mapping.

    Each block (about 1 MB) is read from every column's place in the file
    into a channels-by-rows buffer, then written into `data`'s rows in order;
    the mappings are never touched, so the file does not count in the
    process's memory.
    """
    rows = max(1, (1 << 17) // max(1, data.shape[1]))
    columns = np.empty((data.shape[1], rows))
    with open(maps[0].filename, "rb") as fh:  # type: ignore[arg-type]
        for lo in range(0, data.shape[0], rows):
            hi = min(data.shape[0], lo + rows)
            for j, values in enumerate(maps):
                fh.seek(values.offset + lo * values.itemsize)
                columns[j, : hi - lo] = np.fromfile(fh, dtype=values.dtype, count=hi - lo)
            data[lo:hi] = columns[:, : hi - lo].T  # rows written in order: the new array is touched once


def _convention(reader: _Reader) -> EigenConvention:
    """The eigenvalue convention of the file's complex modes (:mod:`rigidid.io.uff_eigen`)."""
    evidence = []
    for dset, where in reader.modes:
        if int(dset.get("analysis_type", 0)) in (3, 7):
            ids = [str(dset.get(f"id{k}", "")) for k in range(1, 6)]
            evidence.append(
                (
                    f"{where}, mode {int(dset.get('mode_n', 0))}",
                    complex(dset.get("eig", 0.0)),
                    complex(dset.get("modal_a", 0.0)),
                    stated_frequency(ids),
                )
            )
    try:
        convention = eigen_convention(evidence)
    except ValueError as exc:
        raise reader.error(str(exc), "dataset 55") from None
    if convention.note:
        warnings.warn(f"{reader.source}: {convention.note}", RigididWarning, stacklevel=4)
    return convention


def _mode_rows(reader: _Reader, sensors: list[tuple[int, int]], ids: list[str]) -> list[ModeRow]:
    rows: list[ModeRow] = []
    seen: dict[int, str] = {}
    convention = _convention(reader) if reader.modes else EigenConvention(False, 1.0, "")
    for dset, where in reader.modes:
        analysis = int(dset.get("analysis_type", 0))
        if analysis not in (2, 3, 7):
            warnings.warn(
                f"{reader.source}: {where}: analysis type {analysis} is not a mode; ignored",
                RigididWarning,
                stacklevel=3,
            )
            continue
        mode = int(dset.get("mode_n", 0))
        here = f"{where}, mode {mode}"
        if mode in seen:
            raise reader.error(f"mode {mode} appears twice (also {seen[mode]})", here)
        seen[mode] = where
        if int(dset.get("data_ch", 0)) not in (2, 3):
            raise reader.error(f"data characteristic {dset.get('data_ch')} is not a vector of translations", here)
        if analysis == 2:
            f = float(dset.get("freq", 0.0))
            z = float(dset.get("modal_damp_vis", 0.0))
        else:
            pole = convention.pole(complex(dset.get("eig", 0.0)))
            f = abs(pole) / (2.0 * math.pi)
            z = -pole.real / abs(pole) if abs(pole) > 0.0 else 0.0
        if not (math.isfinite(f) and f > 0.0):
            raise reader.error("the mode has no frequency (zero or missing eigenvalue/frequency)", here)
        if not (math.isfinite(z) and 0.0 <= z < 1.0):
            raise reader.error(f"damping ratio {z:.6g} is outside [0, 1)", here)
        node_nums = [int(n) for n in np.asarray(dset.get("node_nums", []), dtype=int)]
        vectors = np.column_stack([np.asarray(dset.get(f"r{k}", []), dtype=complex).reshape(-1) for k in (1, 2, 3)])
        if not np.all(np.isfinite(vectors)):
            raise reader.error("the shape holds NaN or infinite values", here)
        index = {n: i for i, n in enumerate(node_nums)}
        for (node, code), sid in zip(sensors, ids, strict=True):
            if node not in index:
                raise reader.error(f"no value at node {node} (sensor {sid})", f"{here}, node {node}")
            value = complex(vectors[index[node], abs(code) - 1]) * (1 if code > 0 else -1)
            rows.append((mode, f, z, sid, value.real, value.imag))
    return rows


# --------------------------------------------------------------------------- writing


def _layout_sensors(layout: dict[str, Any]) -> tuple[list[str], Array, list[str]]:
    try:
        sensors = list(layout["sensors"])
        ids = [str(s["id"]) for s in sensors]
        positions = np.array([s["position"] for s in sensors], dtype=float).reshape(-1, 3)
        directions = [
            _axis_direction(s["direction"], f"sensors.{i}.direction", "layout") for i, s in enumerate(sensors)
        ]
    except (KeyError, TypeError, ValueError) as exc:
        if isinstance(exc, InputError):
            raise
        raise InputError(f"not a layout dictionary: {exc}", source="layout") from None
    if len(set(ids)) != len(ids):
        raise InputError("sensor ids are not unique", source="layout", location="sensors")
    if not np.all(np.isfinite(positions)):
        raise InputError("positions must be finite", source="layout", location="sensors")
    return ids, positions, directions


def write_uff_test(
    path: str | os.PathLike[str],
    layout: dict[str, Any],
    records: Sequence[tuple[ArrayLike, ArrayLike, Sequence[str]]],
    *,
    mode_rows: Sequence[ModeRow] | None = None,
    binary: bool = True,
) -> dict[str, int]:
    """Write a test as a universal file: 151, 164, 15, 58 per sensor and impact, 55 per mode.

    Parameters
    ----------
    path : path-like
        The file to write (atomically: a temporary file, then renamed).
    layout : dict
        ``layout.json`` content; directions must lie along an axis (``"+x"``
        ... or an axis vector): UFF has no other measuring directions.
    records : sequence of (time, data, sensor_ids)
        Per impact: ``time`` (samples,) uniform in s, ``data`` (samples, k)
        and the k layout sensor ids of its columns. Impact ``i`` is written
        as load case ``i + 1`` with reference node 0.
    mode_rows : sequence of tuple, optional
        ``(mode, frequency_hz, damping_ratio, sensor_id, real, imag)`` rows
        (as ``modes.csv``); written as complex 55 datasets (pole from
        frequency and damping), a sensor's value placed in its node's axis
        component with the sensor's sign.
    binary : bool
        Binary 58 (exact, fast) or ASCII (12 significant digits).

    Returns
    -------
    dict of str to int
        The node number of each sensor id.

    Raises
    ------
    InputError
        A direction off the axes, two sensors on one node and axis, an
        unknown sensor id, a non-uniform or non-finite record, or modes that
        do not give every sensor once.
    """
    ids, positions, directions = _layout_sensors(layout)
    node_list = _assign_nodes(positions, ids)
    node_of = dict(zip(ids, node_list, strict=True))
    codes = {sid: dir_code(d) for sid, d in zip(ids, directions, strict=True)}
    axis_owner: dict[tuple[int, int], str] = {}
    for sid in ids:
        key = (node_of[sid], abs(codes[sid]))
        if key in axis_owner:
            raise InputError(
                f"sensors {axis_owner[key]} and {sid} share node {key[0]} and axis {AXES[key[1] - 1]}",
                source="layout",
            )
        axis_owner[key] = sid
    units = dict(layout.get("units", {}))
    datasets: list[dict[str, Any]] = [
        {
            "type": 151,
            "model_name": str(layout.get("name") or "rigidid test")[:80],
            "description": "rigidid test data",
            "db_app": "rigidid",
            "program": "rigidid",
        },
        write_164(units),
    ]
    unique: dict[int, Array] = {}
    for sid, p in zip(ids, positions, strict=True):
        unique.setdefault(node_of[sid], p)
    datasets.append(_nodes_dataset(list(unique), np.array(list(unique.values()))))
    for i, (time, data, sensor_ids) in enumerate(records):
        datasets.extend(_record_datasets(i, time, data, sensor_ids, node_of, codes, binary))
    if mode_rows:
        datasets.extend(_measured_modes(mode_rows, ids, node_of, codes, list(unique), units))
    _write_sets(path, datasets)
    return node_of


def _record_datasets(
    i: int,
    time: ArrayLike,
    data: ArrayLike,
    sensor_ids: Sequence[str],
    node_of: dict[str, int],
    codes: dict[str, int],
    binary: bool,
) -> list[dict[str, Any]]:
    """Impact `i`'s records as datasets 58, one per sensor (checked: shape, finite, uniform time)."""
    out: list[dict[str, Any]] = []
    where = f"records[{i}]"
    t = np.asarray(time, dtype=float).reshape(-1)
    d = np.asarray(data, dtype=float)
    d = d.reshape(-1, 1) if d.ndim == 1 else d
    sids = [str(s) for s in sensor_ids]
    if d.shape != (t.size, len(sids)) or t.size < 2:
        raise InputError(f"data shape {d.shape} does not match {t.size} samples x {len(sids)} sensors", source=where)
    step = np.diff(t)
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(d))):
        raise InputError("time and data must be finite", source=where)
    if np.any(step <= 0.0) or np.ptp(step) > 1e-9 * abs(float(np.mean(step))):
        raise InputError("the time axis is not uniformly sampled", source=where)
    for j, sid in enumerate(sids):
        if sid not in node_of:
            raise InputError(f"sensor {sid!r} is not in the layout", source=where)
        out.append(
            {
                "type": 58,
                "binary": int(binary),
                "id1": f"impact {i + 1}, sensor {sid}"[:80],
                "id2": "rigidid",
                "func_type": 1,
                "load_case_id": i + 1,
                "rsp_node": node_of[sid],
                "rsp_dir": codes[sid],
                "ref_node": 0,
                "ref_dir": 0,
                "abscissa_spacing": 1,
                "abscissa_spec_data_type": 17,
                "abscissa_axis_lab": "Time",
                "abscissa_axis_units_lab": "s",
                "ordinate_spec_data_type": 12,
                "orddenom_spec_data_type": 0,
                "ordinate_axis_lab": "Acceleration",
                "x": t.copy(),
                "data": np.ascontiguousarray(d[:, j]),
            }
        )
    return out


def _measured_modes(
    mode_rows: Sequence[ModeRow],
    ids: list[str],
    node_of: dict[str, int],
    codes: dict[str, int],
    nodes: list[int],
    units: dict[str, str],
) -> list[dict[str, Any]]:
    from rigidid.core.statespace import poles_from_modal

    per_mode: dict[int, tuple[float, float, dict[str, complex]]] = {}
    for k, row in enumerate(mode_rows):
        mode, f, z, sid, re_, im_ = row
        if sid not in node_of:
            raise InputError(f"sensor {sid!r} is not in the layout", source="mode_rows", location=f"row {k}")
        entry = per_mode.setdefault(int(mode), (float(f), float(z), {}))
        entry[2][sid] = complex(re_, im_)
    out = []
    row_of = {n: i for i, n in enumerate(nodes)}
    for mode, (f, z, values) in per_mode.items():
        missing = [sid for sid in ids if sid not in values]
        if missing:
            raise InputError(f"mode {mode} has no value for sensor {missing[0]!r}", source="mode_rows")
        vectors = np.zeros((len(nodes), 3), dtype=complex)
        for sid, value in values.items():
            code = codes[sid]
            vectors[row_of[node_of[sid]], abs(code) - 1] = value * (1 if code > 0 else -1)
        pole = complex(poles_from_modal([f], [z])[0])
        out.append(_modes_dataset(mode, pole, nodes, vectors, f"measured mode {mode}", _units_text(units)))
    return out


def _units_text(units: dict[str, str]) -> str:
    return f"{units.get('length', '?')}, {units.get('mass', '?')}, s"


def write_uff(
    path: str | os.PathLike[str],
    layout_positions: ArrayLike,
    directions: ArrayLike,
    sensor_ids: Sequence[str],
    identification: Identification,
    units: dict[str, str],
) -> dict[str, int]:
    """Write the identified rigid-body modes as a universal file other tools can animate.

    Parameters
    ----------
    path : path-like
        The file (written atomically).
    layout_positions : array_like, shape (p, 3)
        Sensor positions (length unit).
    directions : array_like, shape (p, 3)
        Measuring axes (checked for shape only: the modes are written as the
        full 3D motion of each node, whatever its sensors read).
    sensor_ids : sequence of str
        Layout ids, numbered into nodes as :func:`write_uff_test` does.
    identification : Identification
        The result; its model modes
        (:meth:`~rigidid.core.identify.Identification.model_modes`) are
        written.
    units : dict
        ``{"length": ..., "mass": ...}`` of the layout (dataset 164).

    Returns
    -------
    dict of str to int
        Node numbers: every sensor id, and ``"CG"``, ``"axis 1"``,
        ``"axis 2"``, ``"axis 3"`` for the marker nodes.

    Notes
    -----
    Datasets written: 151 (header), 164 (units), 15 (one node per distinct
    sensor position, a node at the CG and one at the tip of each principal
    axis, numbered from the next multiple of 1000 above the sensor nodes;
    axis length half the largest sensor distance from the CG), 82 (a closed
    outline through the sensor nodes, :func:`rigidid.core.geometry.sensor_outline`,
    and a line from the CG along each principal axis), and 55 (the six model
    modes, complex, analysis type 3: 3D translation of every node; pole in
    rad/s; frequency and damping ratio in ID line 2), each mode scaled so
    that its largest sensor-node translation is ``1 + 0j``.
    """
    from rigidid.core.geometry import sensor_outline

    pos = np.asarray(layout_positions, dtype=float).reshape(-1, 3)
    dirs = np.asarray(directions, dtype=float)
    sids = [str(s) for s in sensor_ids]
    if dirs.shape != pos.shape or len(sids) != pos.shape[0] or len(set(sids)) != len(sids):
        raise InputError(
            f"positions {pos.shape}, directions {dirs.shape} and {len(sids)} unique sensor ids do not match"
        )
    node_list = _assign_nodes(pos, sids)
    unique: dict[int, Array] = {}
    for n, p in zip(node_list, pos, strict=True):
        unique.setdefault(n, p)
    sensor_nodes = list(unique)
    sensor_xyz = np.array(list(unique.values()))
    g = np.asarray(identification.center_of_gravity, dtype=float)
    axes = identification.principal_axes
    length = 0.5 * float(np.max(np.linalg.norm(sensor_xyz - g, axis=1)))
    length = length if length > 0.0 else 1.0
    base = (max(sensor_nodes) // 1000 + 1) * 1000
    marker_nodes = [base, base + 1, base + 2, base + 3]
    marker_xyz = np.vstack([g, g + length * axes.T])
    all_nodes = sensor_nodes + marker_nodes
    all_xyz = np.vstack([sensor_xyz, marker_xyz])

    datasets: list[dict[str, Any]] = [
        {
            "type": 151,
            "model_name": "rigidid identified rigid body",
            "description": f"rigid-body modes of the identified model; nodes >= {base}: CG and principal axes",
            "db_app": "rigidid",
            "program": "rigidid",
        },
        write_164(units),
        _nodes_dataset(all_nodes, all_xyz),
    ]
    outline = [sensor_nodes[i] for i in sensor_outline(sensor_xyz)]
    if len(outline) > 1:
        datasets.append(
            {"type": 82, "trace_num": 1, "color": 8, "id": "sensor frame", "nodes": np.array(outline, dtype=int)}
        )
    for k in range(3):
        datasets.append(
            {
                "type": 82,
                "trace_num": 2 + k,
                "color": 2 + k,
                "id": f"principal axis {k + 1}",
                "nodes": np.array([base, base + 1 + k], dtype=int),
            }
        )
    poles, shapes = identification.model_modes()
    from rigidid.core.geometry import skew

    for k in range(poles.shape[0]):
        phi = shapes[:, k]
        # translation of a point r: x + theta x (r - g) = x - S(r - g) theta
        vectors = np.array([phi[:3] - skew(r - g) @ phi[3:] for r in all_xyz])
        sensor_part = vectors[: len(sensor_nodes)]
        peak = sensor_part.reshape(-1)[np.argmax(np.abs(sensor_part).reshape(-1))]
        vectors = vectors / peak if abs(peak) > 0.0 else vectors
        datasets.append(
            _modes_dataset(
                k + 1, complex(poles[k]), all_nodes, vectors, f"rigidid rigid-body mode {k + 1}", _units_text(units)
            )
        )
    _write_sets(path, datasets)
    node_of = {sid: n for sid, n in zip(sids, node_list, strict=True)}
    node_of.update({"CG": base, "axis 1": base + 1, "axis 2": base + 2, "axis 3": base + 3})
    return node_of
