"""Shared fixtures: data paths come from this file's location, never the working directory."""

from __future__ import annotations

import os
import sys

# One BLAS thread per test process, set before numpy loads OpenBLAS (subprocess tests inherit
# it): on a loaded 2-core machine OpenBLAS's threads spin against each other and the other
# processes; measured there, a 51x51 eigh took 0.15 s with its threads and 0.8 ms with one.
# Run the suite in parallel instead (pytest -n 2, pytest-xdist). An explicit setting wins.
if "numpy" not in sys.modules:
    for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_name, "1")

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


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The tests marked ``slow`` first, each group in its collected order.

    Run in parallel (pytest-xdist), a long test handed out last keeps one worker busy
    after the others have finished; handed out first, the short ones fill in around it.
    """
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)


def refit_with_warnings(layout, records, **options):  # type: ignore[no-untyped-def]
    """The records route on records held in memory, as ``identify --records`` runs it (modes, identification,
    refit with exact sensors stated unless `options` say otherwise), and every warning it gave."""
    import warnings

    from rigidid import api
    from rigidid.core.sensor_budget import SensorBounds

    options.setdefault("tolerances", SensorBounds(0.0, 0.0, 0.0, 0.0))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        modes, estimate = api.estimate_rigid_modes(layout, records)
        start = api.identify(layout, modes)
        result = api.with_refinement(start, records, estimate, **options)
    return result, caught
