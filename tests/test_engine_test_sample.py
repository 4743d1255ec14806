"""Issue 25: samples/engine-test, the files of README's examples, recover the body they were made from."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rigidid import api
from rigidid.api import identify_massline
from rigidid.compare import compare_results
from rigidid.jsonout import result_to_dict

from .conftest import SAMPLES

CASE = SAMPLES / "engine-test"
BODY = json.loads((CASE / "body.json").read_text())


def test_modes_give_the_body_and_leave_the_local_mode_out() -> None:
    result = api.identify(CASE / "layout.json", CASE / "modes.csv")
    ident = result.identification
    assert list(result.modes_used) == [1, 2, 3, 5, 6, 7]
    np.testing.assert_allclose(ident.center_of_gravity, BODY["center_of_gravity"], rtol=0, atol=1e-6)
    np.testing.assert_allclose(ident.inertia_tensor, BODY["inertia_tensor"], rtol=0, atol=1e-8 * 7.9e6)
    # the result signed off as reference.json is this one (to the digits of JSON)
    assert compare_results(result_to_dict(result), json.loads((CASE / "reference.json").read_text()), rtol=1e-9).passed


def test_mounts_file_holds_the_rates_the_modes_give() -> None:
    result = api.with_mounts(api.identify(CASE / "layout.json", CASE / "modes.csv"), CASE / "mounts.json")
    mounts = json.loads((CASE / "mounts.json").read_text())["mounts"]
    assert result.mounts is not None
    rates = result.mounts.rates
    for k, mount in enumerate(mounts):
        np.testing.assert_allclose(rates.stiffness[k], mount["stiffness"], rtol=1e-6)
        assert rates.damping is not None
        np.testing.assert_allclose(rates.damping[k], mount["damping"], rtol=1e-6)


@pytest.mark.parametrize("name", ["frf.csv", "frf.uff"])
def test_frfs_measure_the_mass(name: str) -> None:
    found = identify_massline(CASE / "layout.json", CASE / name, CASE / "refs.json")
    assert found.massline.mass == pytest.approx(142.0, rel=1e-9)
    np.testing.assert_allclose(found.massline.center_of_gravity, BODY["center_of_gravity"], atol=1e-6)


def test_uff_with_separate_geometry_is_the_same_test() -> None:
    """Dataset 55 keeps six digits: the CG moves by at most about 1e-6 of the body's size (300 mm)."""
    test = api.load_uff(CASE / "test.unv", geometry=CASE / "geometry.unv")
    assert test.modes is not None
    from_uff = api.identify(test.layout, test.modes)
    assert list(from_uff.modes_used) == [1, 2, 3, 5, 6, 7]
    np.testing.assert_allclose(from_uff.identification.center_of_gravity, BODY["center_of_gravity"], atol=3e-4)
