"""Every answer checks itself (issue 22): default standard errors, the misfit's verdict, plausibility."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from rigidid import api
from rigidid.errors import IdentificationError, InputError, ModelMisfitWarning, UnitsWarning
from rigidid.jsonout import result_to_dict
from rigidid.models import BodyFile

from .conftest import SAMPLES

FOUR = SAMPLES / "four-mounts"


def _layout_in(tmp_path: Path, length: str) -> Path:
    data = json.loads((FOUR / "layout.json").read_text())
    data["units"]["length"] = length
    out = tmp_path / "layout.json"
    out.write_text(json.dumps(data))
    return out


def test_standard_errors_are_there_by_default_with_the_json_keys() -> None:
    result = api.with_mounts(api.identify(FOUR / "layout.json", FOUR / "modes.csv"), FOUR / "mounts.json",
                             torque_axis=[1.0, 0.0, 0.0])  # fmt: skip
    err = result_to_dict(result)["standard_errors"]
    assert err["method"] == "linearised" and err["weighted"] is True
    keys = ("center_of_gravity", "inertia_tensor", "principal_moments", "principal_axes_deg", "stiffness_matrix",
            "damping_matrix", "mounts", "torque_roll_axis_deg", "misfit", "inflation")  # fmt: skip
    for key in keys:
        assert key in err, key
    assert len(err["mounts"]) == 4 and all(np.all(np.asarray(m["stiffness"]) > 0.0) for m in err["mounts"])
    assert np.all(np.asarray(err["stiffness_matrix"]) >= 0.0)


def test_a_layout_in_metres_declared_as_millimetres_is_named(tmp_path: Path) -> None:
    with pytest.warns(UnitsWarning, match=r"length unit.*metres declared as mm"):
        api.identify(_layout_in(tmp_path, "mm"), FOUR / "modes.csv")


def test_the_right_units_give_no_units_warning() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        api.identify(FOUR / "layout.json", FOUR / "modes.csv")


def test_noise_far_below_the_misfit_is_an_error(tmp_path: Path) -> None:
    """Shapes 3 % off a rigid body while the user states 1e-6: the model cannot explain the data (exit 1)."""
    from rigidid.core.simulate import add_noise, body_modes
    from rigidid.io.files import ModeTable

    arrays = api.load_arrays(FOUR / "layout.json", FOUR / "modes.csv")
    table = api.load_modes(FOUR / "modes.csv", api.load_layout(FOUR / "layout.json"))
    body = api.body_from_file(BodyFile.model_validate_json((FOUR / "body.json").read_text()))
    noisy = add_noise(body_modes(body, arrays.positions, arrays.directions), shape=0.03,
                      rng=np.random.default_rng(1))  # fmt: skip
    noisy_table = ModeTable(table.labels, table.frequency_hz, table.damping_ratio, table.sensor_ids, noisy.shapes)
    quiet = {"frequency": 1e-7, "damping": 1e-7, "shape": 1e-7}
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        with pytest.raises(IdentificationError, match="cannot explain these modes"):
            api.identify(FOUR / "layout.json", noisy_table, noise=quiet)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        api.identify(FOUR / "layout.json", noisy_table, noise={"frequency": 1e-7, "damping": 1e-7, "shape": 0.01})
    misfit = [str(w.message) for w in seen if w.category is ModelMisfitWarning]
    assert len(misfit) == 1 and "times the noise levels" in misfit[0], [str(w.message) for w in seen]


def test_five_modes_with_mounts_point_to_the_mount_model(tmp_path: Path) -> None:
    table = api.load_modes(FOUR / "modes.csv", api.load_layout(FOUR / "layout.json"))
    five = table.subset(table.labels[:5])
    with pytest.raises(InputError, match="--method mounts"):
        api.identify(FOUR / "layout.json", five, mounts=FOUR / "mounts.json")
