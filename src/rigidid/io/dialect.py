"""CSV dialects as spreadsheets and data recorders write them, and header names as people type them.

Small, file-format-agnostic helpers shared by the CSV readers:

- :func:`sniff_dialect`: the field separator (``,`` ``;`` or tab) from the
  header line, and the decimal mark (``.`` or ``,``) from the data rows;
- :func:`decimal_point`: a number written with a decimal comma, back to a
  point (``"0,39"`` -> ``"0.39"``);
- :func:`column_key`: a header name matched without case, spaces or unit
  suffix (``"Frequency (Hz)"``, ``"Frequency_Hz"``, ``"frequency [hz]"`` ->
  ``"frequency_hz"``; ``"damping_ratio [-]"`` -> ``"damping_ratio"``).

Rules
-----
Separator
    Looked for in the first non-empty line (the header): a tab if it has
    one, else ``;`` if it has one, else ``,``.
Decimal mark
    A comma only when the separator is ``;`` or a tab and some data cell
    (first 50 data lines) is a number written with one comma and no point
    (``-0,5``, ``1,25e-3``); a file whose separator is ``,`` always uses
    ``.``. A file that mixes both marks in numbers is left to the reader's
    number validation (the cell with a point or comma that is not a number
    is reported there).
Units in a header
    A trailing ``(unit)``, ``[unit]`` or ``_unit`` names a unit: the key is
    ``<name>_<unit>`` for a unit, ``<name>`` for a dimensionless one
    (``-``, ``1``, empty). ``"Damping ratio (%)"`` becomes
    ``"damping_ratio_%"``, which no reader accepts: percent is not silently
    taken as a ratio.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = ["Dialect", "column_key", "decimal_point", "sniff_dialect"]

_DECIMAL_COMMA = re.compile(r"^\s*[+-]?(\d+,\d*|,\d+)([eE][+-]?\d+)?\s*$")
_UNIT_SUFFIX = re.compile(r"^(?P<name>.*?)\s*(?:\((?P<p>[^()]*)\)|\[(?P<b>[^\[\]]*)\])\s*$")
_DIMENSIONLESS = {"", "-", "1", "none"}
_SNIFF_LINES = 50


@dataclass(frozen=True)
class Dialect:
    """How a CSV file separates fields and writes its decimal mark.

    Attributes
    ----------
    delimiter : str
        ``","``, ``";"`` or ``"\\t"``.
    decimal : str
        ``"."`` or ``","``.
    """

    delimiter: str = ","
    decimal: str = "."

    def describe(self) -> str:
        """``"';' separated, decimal comma"`` and the like, for messages."""
        sep = {"\t": "tab", ";": "';'", ",": "','"}[self.delimiter]
        mark = "decimal comma" if self.decimal == "," else "decimal point"
        return f"{sep} separated, {mark}"


def sniff_dialect(text: str) -> Dialect:
    """The separator and decimal mark of CSV `text` (rules in the module documentation).

    Parameters
    ----------
    text : str
        The whole file, or at least its header and first data lines (a BOM
        already removed).

    Returns
    -------
    Dialect
    """
    lines = [line for line in text.splitlines() if line.strip()]
    if not lines:
        return Dialect()
    header = lines[0]
    delimiter = "\t" if "\t" in header else ";" if ";" in header else ","
    decimal = "."
    if delimiter != ",":
        for line in lines[1 : 1 + _SNIFF_LINES]:
            if any(_DECIMAL_COMMA.match(cell) for cell in line.split(delimiter)):
                decimal = ","
                break
    return Dialect(delimiter, decimal)


def decimal_point(cell: str, dialect: Dialect) -> str:
    """`cell` with a decimal comma turned into a point when `dialect` uses one and it is a number."""
    if dialect.decimal == "," and _DECIMAL_COMMA.match(cell):
        return cell.replace(",", ".")
    return cell


def column_key(name: str) -> str:
    """A header name as a key: lower case, spaces to ``_``, a unit suffix kept as ``_<unit>``.

    Examples
    --------
    >>> column_key("Frequency (Hz)"), column_key("Frequency_Hz"), column_key(" damping_ratio [-] ")
    ('frequency_hz', 'frequency_hz', 'damping_ratio')
    >>> column_key("Time (s)"), column_key("Damping ratio (%)")
    ('time_s', 'damping_ratio_%')
    """
    text = name.strip().lstrip("\ufeff")
    unit = None
    m = _UNIT_SUFFIX.match(text)
    if m:
        text = m.group("name")
        unit = (m.group("p") if m.group("p") is not None else m.group("b") or "").strip().lower()
    key = re.sub(r"\s+", "_", text.strip().lower())
    if unit is not None and unit not in _DIMENSIONLESS:
        key = key + "_" + re.sub(r"\s+", "", unit)
    return key


def plain_number(text: str) -> bool:
    """Whether a cell may be read as a number: ASCII only, no ``_`` (Python's float reads ``1_0`` as 10
    and full-width or Arabic-Indic digits as numbers; modes.csv and the records refuse them)."""
    return text.isascii() and "_" not in text
