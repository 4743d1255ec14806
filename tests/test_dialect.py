"""modes.csv as spreadsheets export it: separators, decimal commas, header names with case and units."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np
import pytest

from rigidid import api
from rigidid.errors import InputError
from rigidid.io.dialect import Dialect, column_key, decimal_point, sniff_dialect
from rigidid.io.files import load_modes

from .conftest import SAMPLES

SAMPLE = SAMPLES / "four-mounts"


def _rewrite(header: list[str], delimiter: str, comma: bool, newline: str = "\n", bom: bool = False) -> str:
    """The sample's modes.csv written with another header, separator and decimal mark."""
    rows = list(csv.reader(io.StringIO((SAMPLE / "modes.csv").read_text(encoding="utf-8"))))[1:]
    out = [delimiter.join(header)]
    for row in rows:
        cells = [c.replace(".", ",") if comma and k != 3 else c for k, c in enumerate(row)]
        out.append(delimiter.join(cells))
    return ("\ufeff" if bom else "") + newline.join(out) + newline


@pytest.mark.parametrize(
    ("header", "delimiter", "comma", "newline", "bom"),
    [
        (["Mode", "Frequency (Hz)", "Damping ratio [-]", "Sensor", "Real", "Imag"], ";", True, "\r\n", True),
        (["mode", "Frequency_Hz", "damping_ratio [-]", "sensor", "real", "imag"], ";", False, "\n", False),
        (["MODE", "frequency [Hz]", "Damping_Ratio", "Sensor", "Real", "Imag"], "\t", True, "\n", False),
        (["Mode", "Frequency_Hz", "Damping_ratio", "Sensor", "Real", "Imag"], ",", False, "\r\n", True),
    ],
)
def test_exported_dialects_identify_the_same_body(
    tmp_path: Path, header: list[str], delimiter: str, comma: bool, newline: str, bom: bool
) -> None:
    layout = api.load_layout(SAMPLE / "layout.json")
    plain = api.load_modes(SAMPLE / "modes.csv", layout)
    path = tmp_path / "modes.csv"
    path.write_bytes(_rewrite(header, delimiter, comma, newline, bom).encode("utf-8"))
    exported = api.load_modes(path, layout)
    assert exported.labels == plain.labels
    np.testing.assert_array_equal(exported.frequency_hz, plain.frequency_hz)
    np.testing.assert_array_equal(exported.damping_ratio, plain.damping_ratio)
    np.testing.assert_array_equal(exported.shapes, plain.shapes)
    a = api.identify(layout, plain).identification
    b = api.identify(layout, exported).identification
    np.testing.assert_array_equal(a.center_of_gravity, b.center_of_gravity)
    np.testing.assert_array_equal(a.inertia_per_mass, b.inertia_per_mass)


def test_damping_in_percent_is_not_taken_as_a_ratio(tmp_path: Path) -> None:
    path = tmp_path / "modes.csv"
    path.write_text(_rewrite(["Mode", "Frequency (Hz)", "Damping ratio (%)", "Sensor", "Real", "Imag"], ";", True))
    with pytest.raises(InputError, match="damping_ratio"):
        load_modes(path, [str(i) for i in range(1, 9)])


def test_a_decimal_comma_with_comma_separators_is_not_guessed(tmp_path: Path) -> None:
    path = tmp_path / "modes.csv"
    path.write_text("mode,frequency_hz,damping_ratio,sensor,real,imag\n1,12,5,0,01,1,1,0\n", encoding="utf-8")
    with pytest.raises(InputError, match="row 2"):
        load_modes(path, ["1"])


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("a,b,c\n1.5,2,3\n", Dialect(",", ".")),
        ("a;b;c\n1.5;2;3\n", Dialect(";", ".")),
        ("a;b;c\n1,5;2;3\n", Dialect(";", ",")),
        ("a\tb\tc\n-0,25e-3\t2\t3\n", Dialect("\t", ",")),
        ("a\tb;c\n1,5\t2\n", Dialect("\t", ",")),  # a tab in the header wins over ';'
        ("", Dialect(",", ".")),
    ],
)
def test_sniff_dialect(text: str, expected: Dialect) -> None:
    assert sniff_dialect(text) == expected


def test_decimal_point_and_column_key() -> None:
    comma = Dialect(";", ",")
    assert decimal_point("-0,25", comma) == "-0.25"
    assert decimal_point("1,5e-3", comma) == "1.5e-3"
    assert decimal_point("12+x", comma) == "12+x"
    assert decimal_point("1,2,3", comma) == "1,2,3"  # not a number: left for the validator to name
    assert decimal_point("0,5", Dialect()) == "0,5"
    assert column_key("Frequency (Hz)") == column_key("Frequency_Hz") == column_key("frequency [hz]") == "frequency_hz"
    assert column_key("damping_ratio [-]") == column_key("Damping Ratio") == "damping_ratio"
    assert column_key("Time (s)") == column_key("time [s]") == "time_s"
    assert column_key("Frequency (rad/s)") == "frequency_rad/s"
    assert Dialect(";", ",").describe() == "';' separated, decimal comma"
