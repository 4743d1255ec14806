"""Reading rigidid's own files: layout.json, modes.csv, body.json.

Every reader validates once, here, and raises :class:`~rigidid.errors.InputError`
naming the file and the row or field. Writers live in :mod:`rigidid.io.atomic`.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, NamedTuple, TypeVar

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ValidationError

from rigidid.errors import InputError
from rigidid.io.dialect import Dialect, column_key, decimal_point, sniff_dialect
from rigidid.models import BodyFile, LayoutFile, ModeRow, MountEntry, MountsFile

__all__ = [
    "MODES_COLUMNS",
    "ModeTable",
    "ModeValue",
    "layout_arrays",
    "load_body",
    "load_layout",
    "load_modes",
    "load_mounts",
    "mode_table_from_rows",
    "modes_csv_text",
]

MODES_COLUMNS = ("mode", "frequency_hz", "damping_ratio", "sensor", "real", "imag")
_REQUIRED = MODES_COLUMNS[:5]
MODES_OPTIONAL = ("scaling",)
"""Optional ``modes.csv`` columns: ``scaling`` (``modal_a`` for shapes scaled by the force, written by
``rigidid modes --frf``; ``unit_max`` otherwise) is read into ``ModeTable.scaling``; six ``modal_a`` modes
give ``identify`` the measured mass (``scaled_modes``)."""

M = TypeVar("M", bound=BaseModel)
# a plain decimal number: no underscores ("1_0"), no hex, no words but nan/inf (refused by the model)
_NUMBER = re.compile(r"[+-]?((\d+\.?\d*|\.\d+)([eE][+-]?\d+)?|nan|inf|infinity)", re.IGNORECASE)


@dataclass(frozen=True)
class ModeTable:
    """Modal parameters read from ``modes.csv``, ordered like the layout's sensors.

    Attributes
    ----------
    labels : tuple of int
        Mode labels in file order of first appearance.
    frequency_hz, damping_ratio : ndarray, shape (n,)
        Per mode.
    sensor_ids : tuple of str
        The layout's sensor ids, the row order of `shapes`.
    shapes : ndarray of complex, shape (p, n)
        Mode-shape values as each sensor reads them along its own direction.
    """

    labels: tuple[int, ...]
    frequency_hz: NDArray[np.float64]
    damping_ratio: NDArray[np.float64]
    sensor_ids: tuple[str, ...]
    shapes: NDArray[np.complex128]
    scaling: tuple[str, ...] | None = None
    """Per mode, the optional ``scaling`` column of ``modes.csv`` (``modal_a``, ``unit_max``), or None."""

    @classmethod
    def numbered(
        cls,
        frequency_hz: NDArray[np.float64],
        damping_ratio: NDArray[np.float64],
        sensor_ids: Sequence[str],
        shapes: NDArray[np.complex128],
    ) -> ModeTable:
        """A table of estimated or simulated modes, labelled 1, 2, ... in the order given."""
        return cls(tuple(range(1, len(frequency_hz) + 1)), frequency_hz, damping_ratio, tuple(sensor_ids), shapes)

    def subset(self, labels: Sequence[int]) -> ModeTable:
        """The modes with the given labels, in that order."""
        index = [self.labels.index(label) for label in labels]
        return ModeTable(
            tuple(labels),
            self.frequency_hz[index],
            self.damping_ratio[index],
            self.sensor_ids,
            self.shapes[:, index],
            None if self.scaling is None else tuple(self.scaling[i] for i in index),
        )


def _first_error(exc: ValidationError) -> tuple[str, str]:
    """Location and message of the first validation error, in file terms."""
    errors = exc.errors()
    # a misspelt field shows as "unknown" plus "missing": the unknown one explains both
    err = next((e for e in errors if e["type"] == "extra_forbidden"), errors[0])
    loc = ".".join(str(part) for part in err["loc"] if not (isinstance(part, str) and "[" in part))
    loc = loc.replace(".str", "").replace(".tuple", "")
    message = str(err["msg"]).removeprefix("Value error, ")
    if err["type"] == "missing":
        message = "required field is missing"
    elif err["type"] == "extra_forbidden":
        message = "unknown field"
    elif err["type"] in ("literal_error", "enum") and isinstance(err.get("input"), str | int | float):
        message = f"{message}, not {err['input']!r}"
    return loc, message


def _read_text(path: Path, limit: int | None = None) -> str:
    """The file's text (UTF-8, optional BOM), reading at most `limit` bytes (default: no limit)."""
    from rigidid.limits import MAX_CSV_BYTES

    limit = MAX_CSV_BYTES if limit is None else limit
    try:
        with path.open("rb") as fh:
            raw = fh.read(limit + 1)
    except FileNotFoundError:
        raise InputError("file not found", source=str(path)) from None
    except IsADirectoryError:
        raise InputError("is a directory, not a file", source=str(path)) from None
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror or exc}", source=str(path)) from None
    if len(raw) > limit:
        raise InputError(f"larger than the limit of {limit // 2**20} MiB for this kind of file", source=str(path))
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise InputError(f"not UTF-8 text (byte {exc.start})", source=str(path)) from None


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise _DuplicateKey(key)
        out[key] = value
    return out


class _DuplicateKey(Exception):
    pass


def _no_constant(name: str) -> Any:
    raise _BadConstant(name)


class _BadConstant(Exception):
    pass


def _table_hint(text: str) -> str:
    """What a file that is not JSON looks like, when it is one of rigidid's tables (files swapped?)."""
    first = text.lstrip().split("\n", 1)[0].strip().lower()
    if not first or first[0] in "{[":
        return ""
    if "frequency" in first and "mode" in first:
        kind = "a modes table (modes.csv)"
    elif first.startswith("time"):
        kind = "a time record"
    elif any(sep in first for sep in (",", ";", "\t")):
        kind = "a CSV table"
    else:
        return ""
    return f"; this is {kind}, not JSON: the layout (JSON) comes first, then the modes or records (swapped?)"


def _first_odd(data: Any, where: str = "") -> tuple[str, str] | None:
    """Location and fault of the first true/false (rigidid's inputs have none) or too large number."""
    from rigidid.limits import MAX_MAGNITUDE

    if isinstance(data, bool):
        return where or "(top)", "true/false where a number or text is expected"
    if isinstance(data, (int, float)) and not abs(data) <= MAX_MAGNITUDE:
        return where or "(top)", f"must be at most {MAX_MAGNITUDE:g} in magnitude"
    items = data.items() if isinstance(data, dict) else enumerate(data) if isinstance(data, list) else ()
    for key, value in items:
        found = _first_odd(value, f"{where}.{key}" if where else str(key))
        if found:
            return found
    return None


def load_json(path: Path) -> Any:
    """Parse a JSON input strictly: bounded size, no duplicate keys, no NaN/Infinity, no true/false, no deep nesting.

    Raises
    ------
    InputError
        Naming the file and the line or field.
    """
    from rigidid.limits import MAX_JSON_BYTES

    src = str(path)
    text = _read_text(path, MAX_JSON_BYTES)
    try:
        data = json.loads(text, object_pairs_hook=_unique_keys, parse_constant=_no_constant)
    except json.JSONDecodeError as exc:
        raise InputError(
            f"invalid JSON: {exc.msg}" + _table_hint(text), source=src, location=f"line {exc.lineno}"
        ) from None
    except _DuplicateKey as exc:
        raise InputError(f"key {exc.args[0]!r} appears twice in one object", source=src) from None
    except _BadConstant as exc:
        raise InputError(f"{exc.args[0]} is not a number JSON allows", source=src) from None
    except RecursionError:
        raise InputError("nested too deeply to be a rigidid file", source=src) from None
    try:
        odd = _first_odd(data)
    except RecursionError:  # pragma: no cover - json nests less deeply than this walk can
        raise InputError("nested too deeply to be a rigidid file", source=src) from None
    if odd is not None:
        raise InputError(odd[1], source=src, location=odd[0])
    return data


def load_json_model(path: Path, model: type[M]) -> M:
    """Read a JSON file and validate it as `model`; :class:`InputError` names the first invalid field."""
    data = load_json(path)
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        loc, message = _first_error(exc)
        raise InputError(message, source=str(path), location=loc or None) from None


def load_layout(path: str | os.PathLike[str], *, require_rank: bool = True) -> LayoutFile:
    """Read and validate a sensor layout (``layout.json``).

    Parameters
    ----------
    path : path-like
        The file.
    require_rank : bool
        Also require at least six sensors that see all six rigid-body motions
        (true for identification; false to inspect a layout being planned).

    Returns
    -------
    LayoutFile
        The validated layout.

    Raises
    ------
    InputError
        Missing file, invalid JSON, a field that breaks the contract, or a
        layout whose sensors cannot see all six rigid-body motions (rank < 6).
    """
    from rigidid.core.geometry import layout_condition

    p = Path(path)
    layout = load_json_model(p, LayoutFile)
    if not require_rank:
        return layout
    _, positions, directions = layout_arrays(layout)
    if len(layout.sensors) < 6:
        raise InputError(f"{len(layout.sensors)} sensors; at least six are needed", source=str(p), location="sensors")
    _, rank = layout_condition(positions, directions)
    if rank < 6:
        raise InputError(
            f"the sensors see only {rank} of the 6 rigid-body motions (rank {rank} < 6); "
            "add sensors along other axes or away from a common line/point",
            source=str(p),
            location="sensors",
        )
    return layout


def layout_arrays(layout: LayoutFile) -> tuple[tuple[str, ...], NDArray[np.float64], NDArray[np.float64]]:
    """Sensor ids, positions (p, 3) and unit directions (p, 3) of a layout."""
    ids = tuple(s.id for s in layout.sensors)
    positions = np.array([s.position for s in layout.sensors], dtype=float).reshape(-1, 3)
    directions = np.array([s.unit_direction() for s in layout.sensors], dtype=float).reshape(-1, 3)
    return ids, positions, directions


def load_body(path: str | os.PathLike[str]) -> BodyFile:
    """Read and validate a body description (``body.json``) for ``simulate``.

    Raises
    ------
    InputError
        As :func:`load_layout`.
    """
    return load_json_model(Path(path), BodyFile)


def load_mounts(path: str | os.PathLike[str]) -> MountsFile:
    """Read ``mounts.json`` (or a ``body.json``, whose mounts act along the layout's axes).

    Raises
    ------
    InputError
        As :func:`load_layout`.
    """
    p = Path(path)
    data = load_json(p)
    if isinstance(data, dict) and "center_of_gravity" in data:
        body = load_body(p)
        entries = [MountEntry(position=m.position, stiffness=m.stiffness, damping=m.damping) for m in body.mounts]
        return MountsFile(name=body.name, units=body.units, mounts=entries)
    try:
        return MountsFile.model_validate(data)
    except ValidationError as exc:
        loc, message = _first_error(exc)
        raise InputError(message, source=str(p), location=loc or None) from None


def _python_float(text: str) -> float | None:
    try:
        return float(text)
    except ValueError:
        return None


def _csv_rows(reader: Any, src: str) -> Any:
    """The rows of a CSV reader; a malformed line becomes an InputError naming the row."""
    try:
        yield from reader
    except csv.Error as exc:
        raise InputError(f"not valid CSV: {exc}", source=src, location=f"row {reader.line_num}") from None


def load_modes(path: str | os.PathLike[str], sensor_ids: Sequence[str]) -> ModeTable:
    """Read and validate ``modes.csv`` against the layout's sensor ids.

    Parameters
    ----------
    path : path-like
        The file.
    sensor_ids : sequence of str
        The layout's sensor ids; every mode must give each exactly once.

    Returns
    -------
    ModeTable

    Notes
    -----
    Dialects (:mod:`rigidid.io.dialect`): fields separated by ``,``, ``;``
    or tabs; decimal commas with ``;`` or tabs; header names without case,
    spaces or unit suffix (``Mode;Frequency (Hz);Damping ratio [-];...``);
    a UTF-8 byte order mark and CRLF line ends.

    Raises
    ------
    InputError
        Naming the file and the row (line number, header = 1) for: a missing
        or unknown column, a bad value (not a number, NaN, frequency <= 0,
        damping outside [0, 1)), an unknown sensor, a sensor given twice in a
        mode, frequency or damping differing between rows of one mode, a mode
        missing a sensor, or no rows at all.
    """
    p = Path(path)
    src = str(p)
    text = _read_text(p)
    dialect = sniff_dialect(text)
    reader = _csv_rows(csv.reader(io.StringIO(text), delimiter=dialect.delimiter), src)
    if text.lstrip().startswith(("{", "[")):
        raise InputError(
            "this is a JSON file, not a modes table (mode, frequency_hz, ...): the layout comes first, "
            "then the modes (swapped?)",
            source=src,
        )
    columns = _modes_header(next(reader, None), src)
    rows: list[ModeValue] = []
    scalings: dict[int, str] = {}
    for line, row in enumerate(reader, start=2):
        if not row or all(not cell.strip() for cell in row):
            continue
        where = f"row {line}"
        if len(row) != len(columns):
            raise InputError(f"{len(row)} fields, the header has {len(columns)}", source=src, location=where)
        record: dict[str, Any] = {c: _modes_cell(c, v, dialect) for c, v in zip(columns, row, strict=True)}
        scale = record.pop("scaling", None)
        _check_number_cells(record, src, where)
        try:
            parsed = ModeRow.model_validate(record)
        except ValidationError as exc:
            loc, message = _first_error(exc)
            raise InputError(message, source=src, location=f"{where}: {loc}") from None
        value = complex(parsed.real, parsed.imag)
        rows.append(ModeValue(where, parsed.mode, parsed.frequency_hz, parsed.damping_ratio, parsed.sensor, value))
        if scale is not None:
            if scale not in ("modal_a", "unit_max"):
                raise InputError(
                    f"scaling must be modal_a or unit_max, got {scale[:40]!r}", source=src, location=f"{where}: scaling"
                )
            if scalings.setdefault(parsed.mode, scale) != scale:
                raise InputError(
                    f"scaling differs between rows of mode {parsed.mode}", source=src, location=f"{where}: scaling"
                )
    table = mode_table_from_rows(rows, sensor_ids, src)
    if "scaling" not in columns:
        return table
    return replace(table, scaling=tuple(scalings[label] for label in table.labels))


class ModeValue(NamedTuple):
    """One validated mode-shape value, with where it was read (``"row 5"``, ``"dataset 55 #3"``)."""

    where: str | None
    mode: int
    frequency_hz: float
    damping_ratio: float
    sensor: str
    value: complex


def _modes_header(header: list[str] | None, src: str) -> list[str]:
    """The modes table's columns from its header row, checked: required, known, each once."""
    if header is None:
        raise InputError("file is empty", source=src)
    if header and column_key(header[0]).startswith("time"):
        raise InputError(
            "this is a time record (its first column is time), not a modes table: give records as "
            "`records` (modes are estimated from them first)",
            source=src,
            location="row 1",
        )
    columns = _modes_columns(header)
    for name in _REQUIRED:
        if name not in columns:
            raise InputError(
                f"missing column {name!r}; expected {', '.join(MODES_COLUMNS)}", source=src, location="row 1"
            )
    for name in columns:
        if name not in MODES_COLUMNS and name not in MODES_OPTIONAL:
            raise InputError(
                f"unknown column {name!r}; expected {', '.join(MODES_COLUMNS)}", source=src, location="row 1"
            )
    if len(set(columns)) != len(columns):
        raise InputError("a column appears twice", source=src, location="row 1")
    return columns


def _check_number_cells(record: dict[str, Any], src: str, where: str) -> None:
    """The numeric cells of a modes row: not empty, plain decimal numbers, within the magnitude limit."""
    from rigidid.limits import MAX_MAGNITUDE

    for name in ("mode", "frequency_hz", "damping_ratio", "real", "imag"):
        cell = record.get(name)
        if cell is None:
            continue
        if cell == "":
            raise InputError("empty cell", source=src, location=f"{where}: {name}")
        if not _NUMBER.fullmatch(cell):
            if _python_float(cell) is None:
                continue  # not a number at all: the model says so
            raise InputError(f"{cell[:40]!r} is not a plain decimal number", source=src, location=f"{where}: {name}")
        if math.isfinite(float(cell)) and abs(float(cell)) > MAX_MAGNITUDE:
            raise InputError(f"must be at most {MAX_MAGNITUDE:g} in magnitude", source=src, location=f"{where}: {name}")


def mode_table_from_rows(rows: Sequence[ModeValue], sensor_ids: Sequence[str], source: str | None) -> ModeTable:
    """Assemble validated mode-shape values into a :class:`ModeTable`, every reader's last step.

    Parameters
    ----------
    rows : sequence of ModeValue
        One value per mode and sensor, in file order.
    sensor_ids : sequence of str
        The layout's sensor ids; every mode must give each exactly once.
    source : str or None
        The file, for the error messages.

    Returns
    -------
    ModeTable
        Modes in order of first appearance, rows in the layout's order.

    Raises
    ------
    InputError
        An unknown sensor, a sensor given twice in a mode, frequency or
        damping differing between values of one mode (relative 1e-6), a mode
        missing a sensor, a mode whose values are all zero, or no values.
    """
    index = {sid: i for i, sid in enumerate(sensor_ids)}
    labels: list[int] = []
    freq: dict[int, tuple[float, float, str | None]] = {}
    values: dict[int, dict[str, complex]] = {}
    for row in rows:
        if row.sensor not in index:
            raise InputError(f"sensor {row.sensor!r} is not in the layout", source=source, location=row.where)
        mode = row.mode
        if mode not in freq:
            labels.append(mode)
            freq[mode] = (row.frequency_hz, row.damping_ratio, row.where)
            values[mode] = {}
        else:
            f0, z0, first = freq[mode]
            if not (np.isclose(f0, row.frequency_hz, rtol=1e-6) and np.isclose(z0, row.damping_ratio, rtol=1e-6)):
                raise InputError(
                    f"mode {mode}: frequency or damping differs from {first or 'its first value'}",
                    source=source,
                    location=row.where,
                )
        if row.sensor in values[mode]:
            raise InputError(f"mode {mode} gives sensor {row.sensor!r} twice", source=source, location=row.where)
        values[mode][row.sensor] = row.value
    if not labels:
        raise InputError("no mode rows", source=source)
    shapes = np.zeros((len(sensor_ids), len(labels)), dtype=complex)
    for k, mode in enumerate(labels):
        missing = [sid for sid in sensor_ids if sid not in values[mode]]
        if missing:
            raise InputError(f"mode {mode} has no value for sensor {missing[0]!r}", source=source)
        shapes[:, k] = [values[mode][sid] for sid in sensor_ids]
        if not np.any(shapes[:, k]):
            raise InputError(f"mode {mode}: every shape value is zero", source=source)
    return ModeTable(
        tuple(labels),
        np.array([freq[m][0] for m in labels]),
        np.array([freq[m][1] for m in labels]),
        tuple(sensor_ids),
        shapes,
    )


def _modes_columns(header: Sequence[str]) -> list[str]:
    """Header names as ``modes.csv`` column names: without case, spaces or unit suffix (``Frequency (Hz)``)."""
    return [column_key(c) for c in header]


def _modes_cell(column: str, cell: str, dialect: Dialect) -> str:
    """A cell, stripped; a number's decimal comma made a point when the file writes decimal commas."""
    return cell.strip() if column == "sensor" else decimal_point(cell.strip(), dialect)


def modes_csv_text(table: ModeTable, digits: int = 10, scaling: Sequence[str] | None = None) -> str:
    """``modes.csv`` text of a mode table (values with `digits` significant digits).

    With `scaling` (one word per mode, e.g. ``modal_a``), an optional last column
    ``scaling`` says how each mode's shape is scaled.
    """
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(MODES_COLUMNS + (("scaling",) if scaling is not None else ()))
    fmt = f"{{:.{digits}g}}"
    for name, values in (
        ("frequency_hz", table.frequency_hz),
        ("damping_ratio", table.damping_ratio),
        ("shapes", table.shapes),
    ):
        if not np.all(np.isfinite(values)):
            raise InputError(f"{name} holds NaN or infinite values; nothing written (inputs or options too large?)")
    for k, label in enumerate(table.labels):
        f, z = fmt.format(table.frequency_hz[k]), fmt.format(table.damping_ratio[k])
        for i, sid in enumerate(table.sensor_ids):
            v = table.shapes[i, k]
            extra = [scaling[k]] if scaling is not None else []
            writer.writerow([label, f, z, sid, fmt.format(v.real), fmt.format(v.imag), *extra])
    return out.getvalue()
