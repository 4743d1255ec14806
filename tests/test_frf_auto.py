"""``--method auto`` on FRFs: the routes the data allow, the plateau band of free-free data, one chosen,
and a warning naming the route to blame when two disagree beyond their intervals."""

from __future__ import annotations

import dataclasses
import warnings
from typing import Any

import numpy as np
import pytest

from rigidid import api
from rigidid.api import frf as api_frf
from rigidid.core.frf import accelerance
from rigidid.core.massline import mass_line
from rigidid.errors import FrfRoutesDisagreeWarning, IdentificationError
from rigidid.io.files import load_body
from rigidid.models import LayoutFile, ReferencesFile
from rigidid.results import FrfData, MassLineResult

from .conftest import SAMPLES

AXES = ["+x", "+y", "+z"]


def _free_free(seed: int = 2, elastic: tuple[Any, ...] = ()) -> tuple[LayoutFile, ReferencesFile, FrfData, Any]:
    """The four-mounts block hung softly (suspension modes 0.25-0.8 Hz), measured 5-40 Hz, 1 % noise."""
    body = api.body_from_file(load_body(SAMPLES / "four-mounts" / "body.json"))
    soft = dataclasses.replace(
        body,
        mounts=tuple(
            dataclasses.replace(m, stiffness=1e-3 * m.stiffness, damping=0.03 * m.damping) for m in body.mounts
        ),
    )
    rng = np.random.default_rng(seed)
    pos, dirs = rng.uniform(-0.3, 0.3, (6, 3)), np.eye(3)[np.arange(6) % 3]
    rpos, rdirs = np.array([[0.3, 0.2, 0.15], [-0.3, 0.2, -0.15], [0.3, -0.2, -0.15]]), np.eye(3)
    f = np.arange(5.0, 40.0, 0.25)
    h = accelerance(soft, pos, dirs, rpos, rdirs, f, elastic=elastic, noise=0.01, rng=rng)
    lay = LayoutFile.model_validate(
        {
            "units": {"length": "m", "mass": "kg"},
            "sensors": [{"id": f"s{i}", "position": list(p), "direction": AXES[i % 3]} for i, p in enumerate(pos)],
        }
    )
    refs = ReferencesFile.model_validate(
        {"references": [{"id": f"r{j}", "position": list(p), "direction": AXES[j]} for j, p in enumerate(rpos)]}
    )
    data = FrfData(f, h, tuple(s.id for s in lay.sensors), tuple(r.id for r in refs.references))
    return lay, refs, data, body


@pytest.fixture(scope="module")
def free_free() -> tuple[LayoutFile, ReferencesFile, FrfData, Any, MassLineResult]:
    """:func:`_free_free` and its answer by ``--method auto`` (run once for the tests that read it)."""
    lay, refs, data, body = _free_free()
    return lay, refs, data, body, api_frf.identify_frf_auto(lay, refs, data)


def test_free_free_data_above_the_suspension_get_the_plateau_band(free_free: tuple[Any, ...]) -> None:
    """No resonance peak: the automatic band refuses; auto finds the plateau and says residues do not apply."""
    lay, refs, data, body, result = free_free
    from rigidid.io.files import layout_arrays

    _, pos, dirs = layout_arrays(lay)
    rpos = np.array([r.position for r in refs.references])
    with pytest.raises(IdentificationError, match="no resonance peak"):
        mass_line(data.frequencies, data.frf, pos, dirs, rpos, np.eye(3))
    routes = {a.route: a for a in result.routes}
    assert not routes["residues"].applies and "no rigid-body peak" in routes["residues"].reason
    assert routes["massline"].applies and result.route == "massline"
    ml = result.massline
    assert ml.band_source == "plateau" and ml.intervals is not None
    assert abs(ml.mass - body.mass) < 4.0 * float(ml.intervals.mass.std)  # observed 0.1 SE
    assert abs(ml.mass / body.mass - 1.0) < 0.015  # observed 0.05 % (SE 0.4 %)
    np.testing.assert_allclose(ml.center_of_gravity, body.center_of_gravity, atol=0.01)  # observed 6e-4 m


def test_two_routes_apart_beyond_their_intervals_are_warned_about_naming_the_one_to_blame(
    monkeypatch: pytest.MonkeyPatch, free_free: tuple[Any, ...]
) -> None:
    lay, refs, data, _, real = free_free
    ml = real.massline
    assert ml.intervals is not None
    std = float(ml.intervals.mass.std)
    bad = dataclasses.replace(ml, mass=ml.mass + 10.0 * std, misfit_noise_units=1.4)  # explained, but off
    good = dataclasses.replace(ml, misfit_noise_units=1.0)

    def fake(*args: Any, method: str, **kwargs: Any) -> MassLineResult:
        return dataclasses.replace(real, massline=bad if method == "residues" else good, route=method)

    monkeypatch.setattr(api_frf, "_identify_route", fake)
    monkeypatch.setattr("rigidid.core.frfband.plateau_band", lambda f, h: None)
    with pytest.warns(FrfRoutesDisagreeWarning, match=r"residues and massline disagree .* the mass .* blame residues"):
        result = api_frf.identify_frf_auto(lay, refs, data)
    assert [a.applies for a in result.routes] == [True, True]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        same = dataclasses.replace(ml, mass=ml.mass + 0.5 * std)  # within the intervals: no warning
        monkeypatch.setattr(
            api_frf,
            "_identify_route",
            lambda *a, method, **k: dataclasses.replace(
                real, massline=same if method == "residues" else ml, route=method
            ),
        )
        api_frf.identify_frf_auto(lay, refs, data)


def test_an_elastic_mode_just_above_the_band_is_warned_about() -> None:
    """The mounted block measured to 100 Hz with an elastic mode at 105 Hz: the FRFs rise at the top of the band
    (the routes' upper residual cannot follow so near a mode); without it they are flat there and nothing is said
    (pytest runs with warnings as errors)."""
    from rigidid.core.frf import ElasticMode
    from rigidid.errors import ElasticNearBandWarning

    body = api.body_from_file(load_body(SAMPLES / "four-mounts" / "body.json"))
    rng = np.random.default_rng(4)
    pos, dirs = rng.uniform(-0.3, 0.3, (6, 3)), np.eye(3)[np.arange(6) % 3]
    rpos, rdirs = np.array([[0.3, 0.2, 0.15], [-0.3, 0.2, -0.15], [0.3, -0.2, -0.15]]), np.eye(3)
    f = np.arange(2.0, 100.0, 0.25)
    lay = LayoutFile.model_validate(
        {
            "units": {"length": "m", "mass": "kg"},
            "sensors": [{"id": f"s{i}", "position": list(p), "direction": AXES[i % 3]} for i, p in enumerate(pos)],
        }
    )
    refs = ReferencesFile.model_validate(
        {"references": [{"id": f"r{j}", "position": list(p), "direction": AXES[j]} for j, p in enumerate(rpos)]}
    )
    mode = ElasticMode(105.0, 0.01, 0.1 * rng.standard_normal(6), 0.1 * rng.standard_normal(3))
    for elastic in ((), (mode,)):
        h = accelerance(body, pos, dirs, rpos, rdirs, f, elastic=elastic, noise=0.003, rng=rng)
        data = FrfData(f, h, tuple(s.id for s in lay.sensors), tuple(r.id for r in refs.references))
        if elastic:
            with pytest.warns(ElasticNearBandWarning, match="rise towards the top of the band"):
                api_frf.identify_frf_auto(lay, refs, data)
        else:
            api_frf.identify_frf_auto(lay, refs, data)


def test_the_plateau_stops_clear_of_an_elastic_peak() -> None:
    """Free-free with an elastic mode at 30 Hz in the 5-40 Hz band: the plateau ends at half its peak."""
    from rigidid.core.frf import ElasticMode

    rng = np.random.default_rng(9)
    mode = ElasticMode(30.0, 0.01, 0.2 * rng.standard_normal(6), 0.2 * rng.standard_normal(3))
    lay, refs, data, body = _free_free(elastic=(mode,))
    result = api_frf.identify_frf_auto(lay, refs, data)
    ml = result.massline
    assert ml.band_source == "plateau" and ml.band[1] <= 15.0 and ml.intervals is not None
    assert abs(ml.mass - body.mass) < 4.0 * float(ml.intervals.mass.std)
    assert abs(ml.mass / body.mass - 1.0) < 0.1  # observed 3.4 %, within its interval (the mode is near)
