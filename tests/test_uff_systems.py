"""UFF as the tools write it: coordinate systems, geometry in another file, 55 conventions, refusals."""

from __future__ import annotations

import math
import shutil
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import pyuff

from rigidid import api
from rigidid.core.identify import Identification
from rigidid.errors import InputError, RigididWarning
from rigidid.io.uff import read_uff
from rigidid.io.uff_eigen import eigen_convention, stated_frequency

from .conftest import SAMPLES
from .test_uff import mode55, nodes15, record58, units164, write_raw
from .tolerances import UFF_LOCAL_SYSTEMS_REL

DATA = Path(__file__).parent / "data" / "uff"
LOCAL = SAMPLES / "uff-local-systems"
T = 0.001 * np.arange(8)


def _identify(data: api.TestData) -> Identification:
    assert data.modes is not None
    return api.identify(data.layout, data.modes).identification


def _assert_same_body(a: Identification, b: Identification) -> None:
    for name in ("center_of_gravity", "inertia_per_mass", "stiffness_per_mass", "damping_per_mass"):
        x, y = np.asarray(getattr(a, name)), np.asarray(getattr(b, name))
        assert np.max(np.abs(x - y)) <= UFF_LOCAL_SYSTEMS_REL * np.max(np.abs(x)), name


# --------------------------------------------------------------------------- the sample


def test_local_systems_identify_the_same_body_as_global_axes(tmp_path: Path) -> None:
    layout = api.load_layout(LOCAL / "layout.json")
    reference = _identify(api.TestData(layout, api.load_modes(LOCAL / "modes.csv", layout)))
    data = api.load_uff(LOCAL / "test.unv")
    # nothing in the file is in global axes, yet the layout read from it is the global one
    expected = {s.id: s for s in layout.sensors}
    for s in data.layout.sensors:
        np.testing.assert_allclose(s.position, expected[s.id].position, rtol=0, atol=1e-15)
        np.testing.assert_allclose(s.unit_direction(), expected[s.id].unit_direction(), rtol=0, atol=1e-15)
    _assert_same_body(reference, _identify(data))
    api.convert(LOCAL / "test.unv", tmp_path)
    converted = api.load_layout(tmp_path / "layout.json")
    _assert_same_body(reference, _identify(api.TestData(converted, api.load_modes(tmp_path / "modes.csv", converted))))


def test_ignoring_the_systems_would_identify_another_body() -> None:
    """The guard above is not vacuous: the file's raw numbers (global axes assumed) are far off."""
    sets = pyuff.UFF(str(LOCAL / "test.unv")).read_sets()
    layout = api.load_layout(LOCAL / "layout.json")
    raw = {
        int(n): (x, y, z)
        for d in sets
        if d["type"] == 15
        for n, x, y, z in zip(d["node_nums"], d["x"], d["y"], d["z"], strict=True)
    }
    moved = [s for s in layout.sensors if int(s.id.split("+")[0]) in raw]
    assert moved
    assert max(float(np.linalg.norm(np.subtract(raw[int(s.id.split("+")[0])], s.position))) for s in moved) > 0.1


# --------------------------------------------------------------------------- coordinate systems


def system18(num: int, origin: Any, x_point: Any, xz_point: Any, kind: int = 0, ref: int = 0) -> dict[str, Any]:
    return {"type": 18, "cs_num": [num], "cs_type": [kind], "ref_cs_num": [ref], "color": [8], "method": [1],
            "cs_name": [f"CS{num}"], "ref_o": [np.asarray(origin, float)], "x_point": [np.asarray(x_point, float)],
            "xz_point": [np.asarray(xz_point, float)]}  # fmt: skip


def test_testlab_system_1_turns_directions_180_degrees_about_y() -> None:
    """pyuff's public Test.Lab export (geometry) with pyuff's uff55_translation (modes) on its nodes."""
    with _no_warning():
        data = read_uff(DATA / "uff55_translation.uff", geometry=DATA / "testlab_161_164_18_15_82.uff")
    sensors = {s["id"]: s for s in data.layout["sensors"]}
    assert data.layout["units"] == {"length": "m", "mass": "kg"}
    np.testing.assert_allclose(sensors["1+x"]["direction"], [-1.0, 0.0, 0.0], atol=1e-7)  # system 1: x -> -X
    np.testing.assert_allclose(sensors["1+z"]["direction"], [0.0, 0.0, -1.0], atol=1e-7)  # and z -> -Z
    assert sensors["1+y"]["direction"] == "+y"
    np.testing.assert_allclose(sensors["1+x"]["position"], [-2.4, -0.95, 0.0])


@contextmanager
def _no_warning() -> Iterator[None]:
    """Fail on any warning inside the block."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


def test_dataset_15_positions_in_a_referenced_system_18(tmp_path: Path) -> None:
    # system 2 is system 1 shifted by +1 along system 1's x, which is global -X
    path = tmp_path / "chain.uff"
    nodes = nodes15([1], [(0.5, 0.0, 0.0)])
    nodes["def_cs"] = np.array([2])
    nodes["disp_cs"] = np.array([2])
    write_raw(
        path,
        [units164(1, 1.0, 1.0), system18(1, (1, 2, 3), (0, 2, 3), (1, 2, 2)),
         system18(2, (1, 0, 0), (2, 0, 0), (1, 0, 1), ref=1), nodes, record58(1, 1, T, T)],
    )  # fmt: skip
    layout = read_uff(path).layout
    np.testing.assert_allclose(layout["sensors"][0]["position"], [1 - 1.5, 2.0, 3.0], atol=1e-12)
    assert layout["sensors"][0]["direction"] == "-x"  # an axis of the global system stays a name


def test_2411_coordinates_are_global_and_2420_rows_are_the_axes(tmp_path: Path) -> None:
    path = tmp_path / "nx.unv"
    c, s = math.cos(0.3), math.sin(0.3)
    axes = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])  # rows: local x, y, z in global axes
    write_raw(
        path,
        [units164(1, 1.0, 1.0),
         {"type": 2420, "Part_UID": 1, "Part_Name": "p", "CS_sys_labels": [7], "CS_types": [0], "CS_colors": [8],
          "CS_names": ["CS7"], "CS_matrices": [np.vstack([axes, [5.0, 6.0, 7.0]])]},
         {"type": 2411, "node_nums": np.array([1]), "def_cs": np.array([7]), "disp_cs": np.array([7]),
          "color": np.array([1]), "x": np.array([0.1]), "y": np.array([0.2]), "z": np.array([0.3])},
         record58(1, 2, T, T)],
    )  # fmt: skip
    sensor = read_uff(path).layout["sensors"][0]
    assert sensor["position"] == [0.1, 0.2, 0.3]
    np.testing.assert_allclose(sensor["direction"], [-s, c, 0.0], atol=1e-15)


@pytest.mark.parametrize(
    ("extra", "def_cs", "message"),
    [
        (
            [system18(3, (0, 0, 0), (1, 0, 0), (1, 0, 1), kind=1)],
            3,
            r"node 1 is defined in coordinate system 3: coordinate system 3 \(dataset 18 #1, coordinate system 3\) "
            r"is cylindrical; only cartesian coordinate systems are supported",
        ),
        ([system18(3, (0, 0, 0), (1, 0, 0), (1, 0, 1), kind=2)], 3, "is spherical; only cartesian"),
        (
            [],
            4,
            r"node 1 is defined in coordinate system 4: coordinate system 4 is not defined \(no dataset 18 or 2420",
        ),
        ([system18(3, (0, 0, 0), (0, 0, 0), (1, 0, 1))], 3, "the \\+x axis point coincides with the origin"),
    ],
)
def test_unusable_systems_are_named(tmp_path: Path, extra: list[dict[str, Any]], def_cs: int, message: str) -> None:
    nodes = nodes15([1], [(0.0, 0.0, 0.0)])
    nodes["def_cs"] = np.array([def_cs])
    path = tmp_path / "bad.uff"
    write_raw(path, [units164(), *extra, nodes, record58(1, 3, T, T)])
    with pytest.raises(InputError, match=message) as info:
        read_uff(path)
    assert info.value.location is not None and ("node 1" in info.value.location or "dataset 18" in info.value.location)


def test_displacement_system_that_is_missing_is_named(tmp_path: Path) -> None:
    nodes = nodes15([1], [(0.0, 0.0, 0.0)])
    nodes["disp_cs"] = np.array([5])
    path = tmp_path / "bad.uff"
    write_raw(path, [units164(), nodes, record58(1, 3, T, T)])
    with pytest.raises(InputError, match="node 1 measures in coordinate system 5: coordinate system 5 is not defined"):
        read_uff(path)


def test_undefined_system_1_is_global(tmp_path: Path) -> None:
    """ArtemiS, permas4edu and others give every node system 1 and define none: I-DEAS's global system."""
    nodes = nodes15([1], [(0.25, 0.0, 0.0)])
    nodes["def_cs"] = np.array([1])
    nodes["disp_cs"] = np.array([1])
    path = tmp_path / "one.uff"
    write_raw(path, [units164(), nodes, record58(1, -3, T, T)])
    sensor = read_uff(path).layout["sensors"][0]
    assert sensor["position"] == [0.25, 0.0, 0.0]
    assert sensor["direction"] == "-z"


# --------------------------------------------------------------------------- geometry in another file, refusals


def test_geometry_from_another_file_through_the_cli(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from rigidid.cli import app

    out = tmp_path / "out"
    result = CliRunner().invoke(
        app, ["convert", str(DATA / "uff55_translation.uff"), "--geometry", str(DATA / "testlab_161_164_18_15_82.uff"),
              "-o", str(out)],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert (out / "layout.json").is_file() and (out / "modes.csv").is_file()
    alone = CliRunner().invoke(app, ["convert", str(DATA / "uff55_translation.uff"), "-o", str(tmp_path / "no")])
    assert alone.exit_code == 2
    assert "dataset 55 #1, node 1: node 1 has no coordinates" in alone.output
    assert "--geometry" in alone.output
    assert not (tmp_path / "no").exists()


def test_plan_takes_units_and_geometry(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from rigidid.cli import app

    path = tmp_path / "nounits.uff"
    write_raw(path, [nodes15([1, 2], [(0, 0, 0), (1, 0, 0)]), record58(1, 3, T, T), record58(2, 3, T, T)])
    refused = CliRunner().invoke(app, ["plan", str(path)])
    assert refused.exit_code == 2 and "--units" in refused.output
    given = CliRunner().invoke(app, ["plan", str(path), "--units", "mm,kg"])
    assert given.exit_code in (0, 1), given.output  # a two-sensor layout is checked (and found short)
    assert "no units" not in given.output


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("testlab_161_164_18_15_82.uff", r"no sensors: .*geometry only \(36 nodes\).*--geometry"),
        ("nx_2411_2414_excerpt.unv", r"no sensors: .*dataset 2414 \(analysis results\) is not read"),
        ("non_ascii_header_frf.uff", r"dataset 58 #1, node 0: the record names no response node .* no geometry"),
        ("catman_time_history.uff", r"dataset 58 #1, node 0: the record names no response node .* no geometry"),
    ],
)
def test_real_exports_are_refused_with_what_is_missing(tmp_path: Path, name: str, message: str) -> None:
    path = tmp_path / name
    shutil.copy(DATA / name, path)
    with pytest.raises(InputError, match=message):
        read_uff(path)


def test_the_sensors_error_comes_before_the_units_error(tmp_path: Path) -> None:
    path = tmp_path / "geometry.uff"
    write_raw(path, [nodes15([1], [(0, 0, 0)])])
    with pytest.raises(InputError, match="no sensors"):
        read_uff(path)


# --------------------------------------------------------------------------- dataset 55 conventions


def _modes_file(tmp_path: Path, eigs: list[complex], modal_a: list[complex] | None = None, id2: str = "NONE") -> Path:
    path = tmp_path / "modes.uff"
    sets: list[dict[str, Any]] = [units164(1, 1.0, 1.0), nodes15([1], [(0, 0, 0)])]
    for k, eig in enumerate(eigs):
        d = mode55(k + 1, [1], np.ones((1, 3)), eig=eig)
        d["id2"] = id2 if k == 0 else "NONE"
        if modal_a is not None:
            d["modal_a"] = modal_a[k]
        sets.append(d)
    write_raw(path, sets)
    return path


def test_eigenvalues_in_hz_with_positive_real_part_are_read_from_modal_a(tmp_path: Path) -> None:
    """The convention of permas4edu example 019: Re > 0, Im = damped frequency in Hz, modal A = 4 pi i Im."""
    eigs = [0.0395661 + 19.6208j, 0.273499 + 110.944j]
    path = _modes_file(tmp_path, eigs, [4 * math.pi * 19.6208j, 4 * math.pi * 110.944j])
    with pytest.warns(RigididWarning, match=r"positive real part .* eigenvalues are in Hz"):
        rows = read_uff(path).mode_rows
    f = {r[0]: r[1] for r in rows}
    z = {r[0]: r[2] for r in rows}
    assert f[1] == pytest.approx(abs(eigs[0]), rel=1e-9)
    assert z[1] == pytest.approx(eigs[0].real / abs(eigs[0]), rel=1e-9)


def test_eigenvalues_in_rad_per_s_checked_against_the_stated_frequency(tmp_path: Path) -> None:
    pole = -0.5 + 2 * math.pi * 10.0j
    path = _modes_file(tmp_path, [pole], id2=f"f = {abs(pole) / (2 * math.pi):.6g} Hz, damping 0.8 %")
    with _no_warning():
        rows = read_uff(path).mode_rows
    assert rows[0][1] == pytest.approx(abs(pole) / (2 * math.pi), rel=1e-6)


def test_stated_frequency_that_says_hz_wins_over_the_default(tmp_path: Path) -> None:
    path = _modes_file(tmp_path, [-0.01 + 12.5j], id2="Mode 1 at 12.5 Hz")
    with pytest.warns(RigididWarning, match=r"eigenvalues are in Hz .*stated 12.5 Hz"):
        rows = read_uff(path).mode_rows
    assert rows[0][1] == pytest.approx(abs(-0.01 + 12.5j), rel=1e-9)


def test_eigenvalues_of_both_signs_are_refused(tmp_path: Path) -> None:
    path = _modes_file(tmp_path, [-0.2 + 40j, 0.3 + 50j])
    with pytest.raises(
        InputError, match=r"real parts have both signs \(dataset 55 #1, mode 1: negative, dataset 55 #2"
    ):
        read_uff(path)


def test_convention_units() -> None:
    assert stated_frequency(["NONE", "f = 1.5E+01 Hz"]) == 15.0
    assert stated_frequency(["mode 3", "12 kHz"]) is None  # kHz is not Hz
    e = -1 + 10j
    with pytest.raises(ValueError, match="units contradict"):
        eigen_convention([("a", e, 0j, abs(e) / (2 * math.pi)), ("b", e, 0j, abs(e))])
    plain = eigen_convention([("a", -1 + 10j, 20j, None)])
    assert (plain.flip_sign, plain.scale, plain.note) == (False, 1.0, "")
