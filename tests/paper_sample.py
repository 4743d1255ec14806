"""The 1994 paper's test (``samples/paper-1994``) as plain data, for the UFF and report tests."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rigidid.api import load_arrays
from rigidid.core.identify import Identification, identify
from rigidid.errors import PhysicalPlausibilityWarning

PAPER = Path(__file__).resolve().parent.parent / "samples" / "paper-1994"
AXES = {"+x": (1, 0, 0), "-x": (-1, 0, 0), "+y": (0, 1, 0), "-y": (0, -1, 0), "+z": (0, 0, 1), "-z": (0, 0, -1)}
UNITS = {"length": "in", "mass": "lb"}
MASS = 136.0


def paper_layout() -> dict[str, Any]:
    """``layout.json`` of the paper (with ``mass``)."""
    layout: dict[str, Any] = json.loads((PAPER / "layout.json").read_text(encoding="utf-8"))
    return layout


def layout_arrays(layout: dict[str, Any]) -> tuple[list[str], np.ndarray, np.ndarray]:
    """Sensor ids, positions (p, 3) and unit directions (p, 3) of a layout with axis directions."""
    ids = [s["id"] for s in layout["sensors"]]
    positions = np.array([s["position"] for s in layout["sensors"]], dtype=float)
    directions = np.array([AXES[s["direction"]] for s in layout["sensors"]], dtype=float)
    return ids, positions, directions


def paper_modes(ids: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Poles (6,) and raw shapes (p, 6) of the paper sample, rows in the order of `ids`."""
    case = load_arrays(PAPER / "layout.json", PAPER / "modes.csv")
    order = [case.sensor_ids.index(sid) for sid in ids]
    return case.poles, case.shapes[order]


def paper_identification() -> tuple[Identification, list[str], np.ndarray, np.ndarray]:
    """The paper sample identified (structured method); its damping matrix is known to be indefinite."""
    ids, positions, directions = layout_arrays(paper_layout())
    poles, shapes = paper_modes(ids)
    with pytest.warns(PhysicalPlausibilityWarning, match="damping matrix"):
        ident = identify(positions, directions, poles, shapes, mass=MASS)
    return ident, ids, positions, directions
