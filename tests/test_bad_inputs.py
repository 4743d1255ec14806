"""Every bad input file (named by its fault) gives one clear error naming the file and the row or field."""

from __future__ import annotations

import numpy as np
import pytest

from rigidid import api
from rigidid.errors import InputError
from rigidid.io.files import ModeTable

from .conftest import DATA, PAPER

BAD = DATA / "bad"

LAYOUT_FAULTS = {
    "layout_invalid_json.json": "line 2: invalid JSON",
    "layout_unknown_unit.json": "units.length: Input should be",
    "layout_zero_direction.json": "sensors.5.direction: direction is a zero vector",
    "layout_unknown_direction.json": "sensors.5.direction: unknown direction 'up'",
    "layout_duplicate_id.json": "duplicate sensor id '5'",
    "layout_five_sensors.json": "sensors: 5 sensors; at least six are needed",
    "layout_negative_mass.json": "mass: Input should be greater than 0",
    "layout_short_position.json": "sensors.5.position",
    "layout_misspelt_field.json": "sensors.5.postion: unknown field",
    "layout_rank_3.json": "sensors: the sensors see only 3 of the 6 rigid-body motions",
}

MODES_FAULTS = {
    "modes_missing_column.csv": "row 1: missing column 'damping_ratio'",
    "modes_unknown_column.csv": "row 1: missing column 'real'",
    "modes_unknown_sensor.csv": "row 5: sensor '9' is not in the layout",
    "modes_missing_sensor.csv": "mode 1 has no value for sensor '4'",
    "modes_nan.csv": "row 5: real: must be a finite number",
    "modes_not_a_number.csv": "row 5: real: Input should be a valid number",
    "modes_damping_above_one.csv": "row 5: damping_ratio: Input should be less than 1",
    "modes_inconsistent_frequency.csv": "row 5: mode 1: frequency or damping differs from row 2",
    "modes_ragged_row.csv": "row 5: 7 fields, the header has 6",
    "modes_duplicate_sensor.csv": "row 5: mode 1 gives sensor '3' twice",
    "modes_empty.csv": "file is empty",
    "modes_header_only.csv": "no mode rows",
    "modes_all_zero_shape.csv": "mode 2: every shape value is zero",
    "modes_five_modes.csv": "5 modes given; the six rigid-body modes are needed",
}


@pytest.mark.parametrize(("name", "message"), LAYOUT_FAULTS.items())
def test_bad_layout(name: str, message: str) -> None:
    with pytest.raises(InputError) as info:
        api.identify(BAD / name, PAPER / "modes.csv")
    text = str(info.value)
    assert text.startswith(str(BAD / name)), text
    assert message in text, text
    assert "\n" not in text


@pytest.mark.parametrize(("name", "message"), MODES_FAULTS.items())
def test_bad_modes(name: str, message: str) -> None:
    with pytest.raises(InputError) as info:
        api.identify(PAPER / "layout.json", BAD / name)
    text = str(info.value)
    assert text.startswith(str(BAD / name)), text
    assert message in text, text
    assert "\n" not in text


def test_missing_file() -> None:
    with pytest.raises(InputError, match="file not found"):
        api.identify(BAD / "no_such_layout.json", PAPER / "modes.csv")


@pytest.mark.parametrize(
    ("modes", "message"),
    [([1, 2, 3, 4, 5], "give six different mode labels"), ([1, 2, 3, 4, 5, 9], "mode 9 is not in the modes file")],
)
def test_bad_mode_selection(modes: list[int], message: str) -> None:
    with pytest.raises(InputError, match=message):
        api.identify(PAPER / "layout.json", PAPER / "modes.csv", modes_used=modes)


def test_more_modes_than_six_with_six_sensors_asks_for_modes_option() -> None:
    layout = api.load_layout(PAPER / "layout.json")
    table = api.load_modes(PAPER / "modes.csv", layout)
    seven = ModeTable(
        (*table.labels, 7),
        np.append(table.frequency_hz, 20.0),
        np.append(table.damping_ratio, 0.01),
        table.sensor_ids,
        np.hstack([table.shapes, table.shapes[:, :1]]),
    )
    with pytest.raises(InputError, match="`modes_used`"):
        api.identify(layout, seven)
