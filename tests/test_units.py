"""rigidid.units against factors worked out by hand from the definitions of the units."""

from __future__ import annotations

import pytest

from rigidid.units import FORCE_UNITS, G0, KG_PER_MASS, LBF, default_force_unit, force_factor, force_units


def test_definitions() -> None:
    assert G0 == 9.80665
    assert pytest.approx(4.4482216152605, rel=1e-14) == LBF
    assert KG_PER_MASS["slug"] == pytest.approx(14.593902937206, rel=1e-12)  # lbf s^2 / ft
    assert KG_PER_MASS["t"] == 1000.0
    assert FORCE_UNITS == ("N", "kN", "lbf")


@pytest.mark.parametrize(
    ("length", "mass", "force", "factor"),
    [
        ("m", "kg", "N", 1.0),  # kg/s^2 is N/m
        ("mm", "kg", "N", 1e-3),  # kg mm/s^2 = 1e-3 N
        ("mm", "t", "N", 1.0),  # t mm/s^2 = N: the tonne-mm-s system is coherent
        ("m", "g", "kN", 1e-6),
        ("in", "lb", "lbf", 1.0 / 386.08858267716535),  # g0 in in/s^2 = 9.80665 / 0.0254
        ("ft", "slug", "lbf", 1.0),  # the slug-ft-s system is coherent
        ("in", "slug", "lbf", 1.0 / 12.0),
        ("in", "lb", "N", 0.45359237 * 0.0254),
    ],
)
def test_force_factor(length: str, mass: str, force: str, factor: float) -> None:
    assert force_factor(length, mass, force) == pytest.approx(factor, rel=1e-13)


def test_paper_vertical_stiffness_in_lbf_per_inch() -> None:
    # the figure: 224184 lb/s^2 is about 580.6 lbf/in
    assert 224184.0 * force_factor("in", "lb", "lbf") == pytest.approx(580.65, abs=0.01)


def test_unit_strings_and_defaults() -> None:
    assert default_force_unit("kg") == default_force_unit("t") == default_force_unit("g") == "N"
    assert default_force_unit("lb") == default_force_unit("slug") == "lbf"
    imperial = force_units("in", "lb")
    assert imperial.stiffness == {"translation": "lbf/in", "coupling": "lbf/rad", "rotation": "lbf in/rad"}
    assert imperial.damping["translation"] == "lbf s/in"
    metric = force_units("mm", "kg", "kN")
    assert metric.stiffness["translation"] == "kN/mm"
    assert metric.factor == pytest.approx(1e-6)


def test_unknown_unit_names_the_kind() -> None:
    with pytest.raises(ValueError, match="force unit 'kgf'"):
        force_factor("m", "kg", "kgf")
    with pytest.raises(ValueError, match="mass unit 'oz'"):
        force_factor("m", "oz", "N")
