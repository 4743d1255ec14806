"""Defaults of the record route on regimes they were not tuned on (issue 11)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from rigidid.api import body_from_file
from rigidid.core.identify import identify
from rigidid.core.simulate import body_modes
from rigidid.core.timedomain import estimate_modes, impulse_records
from rigidid.core.timedomain.estimate import block_rows, decimation_factors
from rigidid.io.files import layout_arrays, load_body, load_layout

from ..tolerances import REGIME_CG_ABS_IN, REGIME_DAMPING_REL

ROOT = Path(__file__).resolve().parents[2]
PAPER_LIKE = ROOT / "tests" / "data" / "paper_like_body.json"
PAPER_LAYOUT = ROOT / "samples" / "paper-1994" / "layout.json"
IMPACTS = [
    ((6.75, 1.5, 0.0), (0.3, 0.5, -1.0)),
    ((-8.4, 0.75, -3.25), (1.0, 0.7, 0.2)),
    ((4.5, -4.0, 0.0), (-0.5, 1.0, 0.6)),
]


@pytest.fixture(scope="module")
def paper_like() -> tuple[object, np.ndarray, np.ndarray, list[np.ndarray]]:
    """Six modes 5.4-7.8 Hz, damping 0.11-0.17 %, two pairs 1.5 % apart; 6 sensors, 3 impacts, 256 Hz, 30 s, 3 %."""
    body = body_from_file(load_body(PAPER_LIKE))
    _, pos, dirs = layout_arrays(load_layout(PAPER_LAYOUT))
    records = impulse_records(
        body, pos, dirs, IMPACTS, sample_rate=256.0, duration=30.0, pretrigger=0.1, noise=0.03, seed=1
    )
    estimates = {band: estimate_modes(records, 1.0 / 256.0, band=band) for band in (None, (1.0, 20.0))}
    return body, pos, dirs, estimates


@pytest.mark.parametrize("band", [None, (1.0, 20.0)])
def test_paper_like_regime_works_with_defaults(paper_like, band) -> None:  # type: ignore[no-untyped-def]
    body, pos, dirs, estimates = paper_like
    est = estimates[band]
    truth = body_modes(body, pos, dirs)
    z_true = -truth.poles.real / np.abs(truth.poles)
    assert est.decimation > 1
    np.testing.assert_allclose(est.damping_ratio, z_true, rtol=REGIME_DAMPING_REL)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ident = identify(pos, dirs, est.poles, est.shapes, mass=body.mass)
    assert np.linalg.norm(ident.center_of_gravity - body.center_of_gravity) < REGIME_CG_ABS_IN


def test_band_inside_the_content_changes_nothing(paper_like) -> None:  # type: ignore[no-untyped-def]
    _, _, _, estimates = paper_like
    default, banded = estimates[None], estimates[(1.0, 20.0)]
    np.testing.assert_array_equal(default.poles, banded.poles)
    np.testing.assert_array_equal(default.shapes, banded.shapes)


def test_band_never_decimates_less_than_no_band() -> None:
    decays = [np.zeros((30000, 3))]
    dt = 1.0 / 256.0
    content = (5.0, 8.0)
    assert decimation_factors(decays, dt, None, content)[0] == 4
    assert decimation_factors(decays, dt, (1.0, 20.0), content)[0] == 4
    assert decimation_factors(decays, dt, (1.0, 6.0), content)[0] == 5
    assert decimation_factors(decays, dt, (1.0, 20.0), content)[-1] == 1


def test_block_rows_span_the_lowest_period_within_caps() -> None:
    assert block_rows(48, 6, 6, 10000, 1.0 / 64.0, 5.0) == 26  # two periods of 5 Hz at 64 Hz
    assert block_rows(48, 6, 6, 10000, 1.0 / 64.0, 0.0) == 20  # no frequency: the old minimum
    assert block_rows(48, 12, 6, 10000, 1.0 / 512.0, 0.1) == 32  # capped at 384 rows x channels
    assert block_rows(48, 6, 6, 100, 1.0 / 512.0, 0.1) == 25  # capped at a quarter of the record


def _pole(f: float, z: float) -> complex:
    w = 2 * np.pi * f
    return complex(w * (-z + 1j * np.sqrt(1 - z * z)))


def test_lightly_damped_poles_are_stable_within_the_damping_floor() -> None:
    from rigidid.core.timedomain.stabilisation import Criteria, stabilise

    shape = np.ones((3, 1), dtype=complex)
    # 0.10 % then 0.11 %: 10 % relative, 0.01 % absolute: stable by the floor only
    models = [(n, np.array([_pole(6.0, z)]), shape) for n, z in ((2, 0.0010), (4, 0.0011))]
    assert bool(stabilise(models, (0.0, 50.0), Criteria())[1].stable[0])
    assert not bool(stabilise(models, (0.0, 50.0), Criteria(damping_floor=0.0))[1].stable[0])
    # 2 % then 2.2 %: 10 % relative, 0.2 % absolute: not stable
    models = [(n, np.array([_pole(6.0, z)]), shape) for n, z in ((2, 0.020), (4, 0.022))]
    assert not bool(stabilise(models, (0.0, 50.0), Criteria())[1].stable[0])
