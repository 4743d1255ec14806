"""Every answer checks itself (issue 22): default standard errors, the misfit's verdict, plausibility."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from rigidid import api
from rigidid.errors import (
    IdentificationError,
    InputError,
    ModelMisfitWarning,
    UnitsWarning,
)
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
        api.identify(FOUR / "layout.json", noisy_table, noise={"frequency": 1e-7, "damping": 1e-7, "shape": 0.003})
    misfit = [str(w.message) for w in seen if w.category is ModelMisfitWarning]
    assert len(misfit) == 1 and "times the noise levels" in misfit[0], [str(w.message) for w in seen]


def test_five_modes_with_mounts_point_to_the_mount_model(tmp_path: Path) -> None:
    table = api.load_modes(FOUR / "modes.csv", api.load_layout(FOUR / "layout.json"))
    five = table.subset(table.labels[:5])
    with pytest.raises(InputError, match="--method mounts"):
        api.identify(FOUR / "layout.json", five, mounts=FOUR / "mounts.json")


def _four_mounts_with_hose(tmp_path: Path, hose: float) -> Path:
    """modes.csv of the four-mounts body with an extra support (a hose) that mounts.json does not list."""
    from rigidid.core.simulate import Mount, add_noise, body_modes
    from rigidid.io.files import ModeTable

    arrays = api.load_arrays(FOUR / "layout.json", FOUR / "modes.csv")
    body = api.body_from_file(BodyFile.model_validate_json((FOUR / "body.json").read_text()))
    if hose > 0.0:
        from dataclasses import replace

        extra = Mount.from_values([0.0, 0.3, 0.2], [hose, hose, hose], [0.0, 0.0, 0.0])
        body = replace(body, mounts=(*body.mounts, extra))
    modes = add_noise(body_modes(body, arrays.positions, arrays.directions), shape=0.002, frequency=2e-4,
                      damping=0.01, rng=np.random.default_rng(3))  # fmt: skip
    f, z = np.abs(modes.poles) / (2 * np.pi), -modes.poles.real / np.abs(modes.poles)
    return ModeTable(tuple(range(1, 7)), f, z, arrays.sensor_ids, modes.shapes)  # type: ignore[return-value]


@pytest.mark.parametrize("hose", [0.0, 2e4])
def test_a_support_missing_from_mounts_json_is_named(tmp_path: Path, hose: float) -> None:
    """A hose at 10-20 % of a mount's rates, not in mounts.json: named; without it, no such warning."""
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        result = api.identify(FOUR / "layout.json", _four_mounts_with_hose(tmp_path, hose))  # type: ignore[arg-type]
        out = api.with_mounts(result, FOUR / "mounts.json")
    named = [str(w.message) for w in seen if "support missing from mounts.json" in str(w.message)]
    assert len(named) == (1 if hose else 0), [str(w.message) for w in seen]
    assert out.mounts is not None and out.mounts.stiffness_std is not None


def test_the_papers_negative_damping_is_explained_by_its_standard_error() -> None:
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        api.identify(SAMPLES / "paper-1994" / "layout.json", SAMPLES / "paper-1994" / "modes.csv")
    texts = [str(w.message) for w in seen]
    assert any("within" in t and "standard errors of zero" in t for t in texts), texts
