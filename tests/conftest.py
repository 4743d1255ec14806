"""Shared fixtures: data paths come from this file's location, never the working directory."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = ROOT / "samples"
DATA = Path(__file__).resolve().parent / "data"
PAPER = SAMPLES / "paper-1994"


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261121)


@pytest.fixture(scope="session")
def paper_arrays() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Positions, unit directions, poles and raw shapes of the paper sample."""
    from rigidid import api
    from rigidid.core.statespace import poles_from_modal
    from rigidid.io.files import layout_arrays

    layout = api.load_layout(PAPER / "layout.json")
    modes = api.load_modes(PAPER / "modes.csv", layout)
    _, positions, directions = layout_arrays(layout)
    return positions, directions, poles_from_modal(modes.frequency_hz, modes.damping_ratio), modes.shapes
