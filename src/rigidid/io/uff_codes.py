"""The codes of universal files: unit systems (dataset 164), function types (dataset 58), node/direction ids.

Shared by the UFF readers and writers (:mod:`rigidid.io.uff`, :mod:`rigidid.io.frf`). The unit
factors are those of :mod:`rigidid.units` (metres per length unit, kilograms per mass unit,
standard gravity, the pound-force), inverted to the UFF convention: a dataset 164 states how
many of its units make one SI unit.
"""

from __future__ import annotations

import re

from rigidid.units import G0, KG_PER_MASS, LB, LBF, M_PER_LENGTH

__all__ = [
    "AXES",
    "CODE_FACTORS",
    "FUNCTION_TYPES",
    "ID_PATTERN",
    "LBF_PER_N",
    "LENGTH_PER_M",
    "MASS_PER_KG",
    "POUNDAL_PER_N",
    "STANDARD_UNITS",
    "dir_code",
]

AXES = "xyz"
"""The global axes, in UFF direction-code order (1, 2, 3)."""

ID_PATTERN = re.compile(r"^\s*(\d+)\s*([+-]?[xyz])?\s*$", re.IGNORECASE)
"""A sensor or reference id a UFF node and direction can carry: ``"12"``, ``"12+x"``, ``"12 -z"``."""

LENGTH_PER_M: dict[str, float] = {unit: 1.0 / M_PER_LENGTH[unit] for unit in ("m", "cm", "mm", "in", "ft")}
"""Length units of a dataset 164 per metre."""

MASS_PER_KG: dict[str, float] = {unit: 1.0 / KG_PER_MASS[unit] for unit in ("kg", "g", "lb")}
"""Mass units a dataset 164 is matched to, per kilogram."""

LBF_PER_N = 1.0 / LBF
"""Pounds-force per newton."""

POUNDAL_PER_N = 1.0 / (LB * M_PER_LENGTH["ft"])
"""Poundals per newton."""

CODE_FACTORS: dict[int, tuple[float, float]] = {
    1: (1.0, 1.0),
    2: (LENGTH_PER_M["ft"], LBF_PER_N),
    3: (1.0, 1.0 / G0),
    4: (LENGTH_PER_M["ft"], POUNDAL_PER_N),
    5: (1000.0, 1000.0),
    6: (100.0, 100.0),
    7: (LENGTH_PER_M["in"], LBF_PER_N),
    8: (1000.0, 1.0 / G0),
}
"""Standard UFF unit codes -> (length, force) factors per SI unit, for files that leave the factors at zero."""

STANDARD_UNITS: dict[tuple[str, str], tuple[int, float, str, float, float]] = {
    ("m", "kg"): (1, 1.0, "SI: meter (newton)", 1.0, 273.15),
    ("ft", "lb"): (2, LBF_PER_N, "BG: foot (pound f)", 1.8, 459.67),
    ("mm", "kg"): (5, 1000.0, "MM: mm (milli newton)", 1.0, 273.15),
    ("cm", "kg"): (6, 100.0, "CM: cm (centi newton)", 1.0, 273.15),
    ("in", "lb"): (7, LBF_PER_N, "IN: inch (pound f)", 1.8, 459.67),
}
"""(length, mass) -> UFF units code, force factor, description, temperature factor and offset."""

FUNCTION_TYPES: dict[int, str] = {
    0: "general or unknown",
    1: "time response",
    2: "auto spectrum",
    3: "cross spectrum",
    4: "frequency response function (FRF)",
    5: "transmissibility",
    6: "coherence",
    7: "auto correlation",
    8: "cross correlation",
    9: "power spectral density (PSD)",
    10: "energy spectral density",
    11: "probability density function",
    12: "spectrum",
    13: "cumulative frequency distribution",
    14: "peaks valley",
    15: "stress/cycles",
    16: "strain/cycles",
    17: "orbit",
    18: "mode indicator function",
    19: "force pattern",
    20: "partial power",
    21: "partial coherence",
    22: "eigenvalue",
    23: "eigenvector",
    24: "shock response spectrum",
    25: "finite impulse response filter",
    26: "multiple coherence",
    27: "order function",
    28: "phase compensation",
}
"""Function type codes of dataset 58 and what they hold."""


def dir_code(direction: str) -> int:
    """The UFF direction code of a signed axis: ``"+x"`` -> 1, ``"-z"`` -> -3."""
    return (AXES.index(direction[1]) + 1) * (1 if direction[0] == "+" else -1)
