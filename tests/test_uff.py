"""UFF input and output through pyuff: round trips, identification from UFF data, bad files."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rigidid.core.geometry import skew
from rigidid.core.identify import identify
from rigidid.core.simulate import Body, Mount, body_modes
from rigidid.core.statespace import modal_from_poles, poles_from_modal
from rigidid.errors import InputError
from rigidid.io.uff import UffContents, read_uff, write_uff, write_uff_test

from .paper_sample import layout_arrays, paper_identification, paper_layout

pyuff = pytest.importorskip("pyuff")


def paper_layout_without_mass() -> dict[str, Any]:
    layout = paper_layout()
    del layout["mass"]  # UFF does not carry the mass
    return layout


def mode_arrays(contents: UffContents, ids: list[str]) -> tuple[list[int], np.ndarray, np.ndarray, np.ndarray]:
    labels = sorted({row[0] for row in contents.mode_rows})
    freq = np.zeros(len(labels))
    damp = np.zeros(len(labels))
    shapes = np.zeros((len(ids), len(labels)), dtype=complex)
    for mode, f, z, sid, re, im in contents.mode_rows:
        k = labels.index(mode)
        freq[k], damp[k] = f, z
        shapes[ids.index(sid), k] = complex(re, im)
    return labels, freq, damp, shapes


def mixed_layout() -> dict[str, Any]:
    """A triaxial node, uniaxial nodes with signed directions, inches and pounds."""
    return {
        "name": "bracket test",
        "units": {"length": "in", "mass": "lb"},
        "sensors": [
            {"id": "12+x", "position": [1.25, -3.5, 0.75], "direction": "+x"},
            {"id": "12-y", "position": [1.25, -3.5, 0.75], "direction": "-y"},
            {"id": "12+z", "position": [1.25, -3.5, 0.75], "direction": "+z"},
            {"id": "3", "position": [-6.5, 2.0, 0.0], "direction": "-z"},
            {"id": "7", "position": [4.0, 5.5, -1.5], "direction": "+y"},
            {"id": "9", "position": [-2.0, -4.0, 2.25], "direction": "-x"},
        ],
    }


def simulated_records(ids: list[str], seed: int = 0) -> list[tuple[np.ndarray, np.ndarray, list[str]]]:
    rng = np.random.default_rng(seed)
    t1 = 0.001 * np.arange(1500)
    t2 = -0.05 + 0.0005 * np.arange(900)
    return [
        (t1, rng.standard_normal((t1.size, len(ids))), ids),
        (t2, rng.standard_normal((t2.size, 3)), [ids[4], ids[0], ids[3]]),
    ]


def write_raw(path: Path, datasets: list[dict[str, Any]]) -> None:
    """Write datasets with pyuff directly (to build files rigidid would not write)."""
    pyuff.UFF(str(path)).write_sets(datasets, mode="overwrite")


def nodes15(nums: list[int], xyz: list[tuple[float, float, float]]) -> dict[str, Any]:
    a = np.array(xyz, dtype=float)
    n = len(nums)
    return {
        "type": 15,
        "node_nums": np.array(nums, dtype=int),
        "def_cs": np.zeros(n, dtype=int),
        "disp_cs": np.zeros(n, dtype=int),
        "color": np.ones(n, dtype=int),
        "x": a[:, 0],
        "y": a[:, 1],
        "z": a[:, 2],
    }


def units164(code: int = 7, length: float = 39.37007874015748, force: float = 0.22480894309971047) -> dict[str, Any]:
    return {"type": 164, "units_code": code, "units_description": "test", "temp_mode": 1, "length": length,
            "force": force, "temp": 1.8, "temp_offset": 459.67}  # fmt: skip


def record58(node: int, direction: int, t: np.ndarray, y: np.ndarray, case: int = 1, func: int = 1) -> dict[str, Any]:
    return {
        "type": 58,
        "binary": 0,
        "func_type": func,
        "load_case_id": case,
        "rsp_node": node,
        "rsp_dir": direction,
        "ref_node": 0,
        "ref_dir": 0,
        "abscissa_spacing": 1,
        "orddenom_spec_data_type": 0,
        "x": t,
        "data": y,
    }


def mode55(mode: int, nodes: list[int], vectors: np.ndarray, eig: complex = -0.2 + 40.0j) -> dict[str, Any]:
    return {
        "type": 55,
        "analysis_type": 3,
        "data_ch": 2,
        "spec_data_type": 8,
        "load_case": 1,
        "mode_n": mode,
        "eig": eig,
        "modal_a": 0j,
        "modal_b": 0j,
        "node_nums": np.array(nodes, dtype=int),
        "r1": vectors[:, 0].astype(complex),
        "r2": vectors[:, 1].astype(complex),
        "r3": vectors[:, 2].astype(complex),
    }


# --------------------------------------------------------------------------- round trips


@pytest.mark.parametrize("binary", [True, False])
def test_simulated_test_round_trips(tmp_path: Path, binary: bool) -> None:
    layout = mixed_layout()
    ids = [s["id"] for s in layout["sensors"]]
    records = simulated_records(ids)
    path = tmp_path / "test.uff"
    nodes = write_uff_test(path, layout, records, binary=binary)
    assert nodes == {"12+x": 12, "12-y": 12, "12+z": 12, "3": 3, "7": 7, "9": 9}

    back = read_uff(path)
    assert back.layout == layout  # ids, positions, signed directions, units lb/in, name
    assert back.mode_rows == []
    assert back.record_labels == ["load case 1", "load case 2"]
    assert len(back.records) == 2
    for (t, data, sids), got in zip(records, back.records, strict=True):
        assert got.sensor_ids == tuple(sids)
        np.testing.assert_allclose(got.time, t, rtol=0.0, atol=1e-12)
        if binary:
            np.testing.assert_array_equal(got.data, data)
        else:  # ASCII doubles: 12 significant digits
            np.testing.assert_allclose(got.data, data, rtol=1e-10, atol=1e-11)
    assert back.nodes[12] == (1.25, -3.5, 0.75)


def test_paper_layout_round_trips_with_its_ids(tmp_path: Path) -> None:
    layout = paper_layout_without_mass()
    ids = [s["id"] for s in layout["sensors"]]
    t = 0.001 * np.arange(100)
    write_uff_test(tmp_path / "p.uff", layout, [(t, np.ones((100, 6)), ids)])
    assert read_uff(tmp_path / "p.uff").layout == layout


def test_free_text_ids_become_node_numbers(tmp_path: Path) -> None:
    layout = mixed_layout()
    for sensor, name in zip(layout["sensors"], ["a", "b", "c", "front", "rear", "top"], strict=True):
        sensor["id"] = name
    t = 0.001 * np.arange(10)
    nodes = write_uff_test(
        tmp_path / "f.uff", layout, [(t, np.zeros((10, 6)), ["a", "b", "c", "front", "rear", "top"])]
    )
    # one node per distinct position, numbered in order of appearance
    assert nodes == {"a": 1, "b": 1, "c": 1, "front": 2, "rear": 3, "top": 4}
    back = read_uff(tmp_path / "f.uff")
    assert [s["id"] for s in back.layout["sensors"]] == ["1+x", "1-y", "1+z", "2", "3", "4"]
    assert [s["direction"] for s in back.layout["sensors"]] == [s["direction"] for s in layout["sensors"]]


@pytest.mark.parametrize("length", ["m", "cm", "mm", "in", "ft"])
@pytest.mark.parametrize("mass", ["kg", "g", "lb"])
def test_every_layout_unit_round_trips(tmp_path: Path, length: str, mass: str) -> None:
    layout = mixed_layout()
    layout["units"] = {"length": length, "mass": mass}
    t = 0.001 * np.arange(10)
    write_uff_test(tmp_path / "u.uff", layout, [(t, np.zeros((10, 1)), ["3"])])
    assert read_uff(tmp_path / "u.uff").layout["units"] == {"length": length, "mass": mass}


@pytest.mark.parametrize(
    ("code", "length", "force", "expected"),
    [
        (1, 1.0, 1.0, {"length": "m", "mass": "kg"}),  # SI
        (2, 3.28083989501312, 0.224808943099710, {"length": "ft", "mass": "lb"}),  # BG: ft, lbf
        (3, 1.0, 1.0 / 9.80665, {"length": "m", "mass": "kg"}),  # MG: m, kgf
        (4, 3.28083989501312, 7.23301385120989, {"length": "ft", "mass": "lb"}),  # BA: ft, poundal
        (5, 1000.0, 1000.0, {"length": "mm", "mass": "kg"}),  # MM: mm, mN
        (6, 100.0, 100.0, {"length": "cm", "mass": "kg"}),  # CM: cm, cN
        (7, 39.3700787401575, 0.224808943099710, {"length": "in", "mass": "lb"}),  # IN: in, lbf
        (8, 1000.0, 1.0 / 9.80665, {"length": "mm", "mass": "kg"}),  # GM: mm, kgf
        (7, 0.0, 0.0, {"length": "in", "mass": "lb"}),  # factors left at zero: the code decides
        (9, 1000.0, 1.0e6, {"length": "mm", "mass": "g"}),  # user defined, coherent: uN / (mm/s^2) = g
    ],
)
def test_standard_unit_codes(tmp_path: Path, code: int, length: float, force: float, expected: dict[str, str]) -> None:
    t = 0.001 * np.arange(4)
    path = tmp_path / "c.uff"
    write_raw(path, [units164(code, length, force), nodes15([1], [(0.0, 0.0, 0.0)]), record58(1, 3, t, t)])
    assert read_uff(path).layout["units"] == expected


def test_identified_modes_round_trip_through_dataset_55(tmp_path: Path) -> None:
    ident, ids, pos, dirs = paper_identification()
    path = tmp_path / "identified.uff"
    nodes = write_uff(path, pos, dirs, ids, ident, {"length": "in", "mass": "lb"})
    assert nodes["CG"] == 1000 and [nodes[f"axis {k}"] for k in (1, 2, 3)] == [1001, 1002, 1003]

    back = read_uff(path)
    assert back.layout["units"] == {"length": "in", "mass": "lb"}
    g = ident.center_of_gravity
    np.testing.assert_allclose(back.nodes[1000], g, atol=5e-5)
    length = np.array(back.nodes[1001]) - np.array(back.nodes[1000])
    np.testing.assert_allclose(length / np.linalg.norm(length), ident.principal_axes[:, 0], atol=1e-4)

    # no dataset 58: every non-zero node component is a sensor; compare with the model's motion
    poles, shapes = ident.model_modes()
    per_mode = {row[0]: (row[1], row[2]) for row in back.mode_rows}
    assert list(per_mode) == [1, 2, 3, 4, 5, 6]
    freq, damp = np.array(list(per_mode.values())).T
    np.testing.assert_allclose(poles_from_modal(freq, damp), poles, rtol=1e-5)
    node_numbers = [1, 2, 3, 4, 5, 6, 1000, 1001, 1002, 1003]
    points = np.array([back.nodes[n] for n in node_numbers])
    for k in range(6):
        expected = np.array([shapes[:3, k] - skew(r - g) @ shapes[3:, k] for r in points])
        expected = expected / expected[:6].reshape(-1)[np.argmax(np.abs(expected[:6]).reshape(-1))]
        got = np.zeros((len(node_numbers), 3), dtype=complex)
        for mode, _, _, sid, re, im in back.mode_rows:
            if mode == k + 1:
                node, axis = int(sid[:-2]), "xyz".index(sid[-1])
                got[node_numbers.index(node), axis] = complex(re, im)
        np.testing.assert_allclose(got, expected, atol=1e-5)

    # the trace lines other tools draw: the sensor outline and the three principal axes
    raw = pyuff.UFF(str(path))
    lines = [raw.read_sets(i) for i, kind in enumerate(raw.get_set_types()) if kind == 82]
    assert [line["id"] for line in lines] == [
        "sensor frame",
        "principal axis 1",
        "principal axis 2",
        "principal axis 3",
    ]
    outline = lines[0]["nodes"].astype(int).tolist()
    assert outline[0] == outline[-1] and sorted(outline[:-1]) == [1, 2, 3, 4, 5, 6]
    assert lines[1]["nodes"].astype(int).tolist() == [1000, 1001]


# three mounts nearly symmetric about the CG: the inertia is only weakly observable (a warning)
@pytest.mark.filterwarnings("ignore::rigidid.errors.IllConditionedWarning")
def test_identification_from_uff_equals_identification_from_arrays(tmp_path: Path) -> None:
    layout = mixed_layout()
    ids, pos, dirs = layout_arrays(layout)
    mounts = (
        Mount.from_values((6.0, 0.0, -4.0), (3000.0, 3500.0, 9000.0), (3.0, 2.0, 9.0)),
        Mount.from_values((-4.0, 6.0, -4.5), (2500.0, 3000.0, 8000.0), (1.0, 4.0, 7.0)),
        Mount.from_values((-3.0, -6.5, -3.5), (3500.0, 2000.0, 9500.0), (2.0, 3.0, 12.0)),
    )
    inertia = np.array([[2650.0, 40.0, -90.0], [40.0, 3090.0, 25.0], [-90.0, 25.0, 5440.0]])
    body = Body(136.0, np.array([0.3, -0.2, -1.4]), inertia, mounts)
    modes = body_modes(body, pos, dirs)
    f, z = modal_from_poles(modes.poles)
    rows = [
        (k + 1, float(f[k]), float(z[k]), ids[i], float(modes.shapes[i, k].real), float(modes.shapes[i, k].imag))
        for k in range(6)
        for i in range(len(ids))
    ]
    t = 0.001 * np.arange(400)
    response = np.real(modes.shapes @ np.exp(np.outer(modes.poles, t))).T
    path = tmp_path / "simulated.uff"
    write_uff_test(path, layout, [(t, response, ids)], mode_rows=rows)

    back = read_uff(path)
    assert back.layout == layout
    ids2, pos2, dirs2 = layout_arrays(back.layout)
    labels, freq, damp, shapes = mode_arrays(back, ids2)
    assert labels == [1, 2, 3, 4, 5, 6]
    np.testing.assert_allclose(shapes, modes.shapes, atol=5e-6)  # 6 significant digits in a 55
    np.testing.assert_allclose(back.records[0].data, response)

    direct = identify(pos, dirs, modes.poles, modes.shapes, mass=body.mass)
    via_uff = identify(pos2, dirs2, poles_from_modal(freq, damp), shapes, mass=body.mass)
    np.testing.assert_allclose(direct.center_of_gravity, body.center_of_gravity, atol=1e-8)
    np.testing.assert_allclose(via_uff.center_of_gravity, direct.center_of_gravity, atol=1e-4)
    for a, b in (
        (via_uff.inertia_per_mass, direct.inertia_per_mass),
        (via_uff.stiffness_per_mass, direct.stiffness_per_mass),
        (via_uff.damping_per_mass, direct.damping_per_mass),
    ):
        assert np.max(np.abs(a - b)) <= 1e-4 * np.max(np.abs(b))


def test_modes_without_time_records_define_sensors_from_nonzero_components(tmp_path: Path) -> None:
    path = tmp_path / "modes_only.uff"
    vectors = np.array([[0.0, 0.0, 1.0], [0.5, -0.25j, 0.0]])
    write_raw(path, [units164(), nodes15([4, 8], [(1.0, 2.0, 3.0), (4.0, 5.0, 6.0)]), mode55(2, [4, 8], vectors)])
    back = read_uff(path)
    assert [s["id"] for s in back.layout["sensors"]] == ["4", "8+x", "8+y"]
    assert [s["direction"] for s in back.layout["sensors"]] == ["+z", "+x", "+y"]
    f = abs(-0.2 + 40j) / (2 * math.pi)
    assert back.mode_rows == [
        (2, pytest.approx(f), pytest.approx(0.2 / abs(-0.2 + 40j)), "4", 1.0, 0.0),
        (2, pytest.approx(f), pytest.approx(0.2 / abs(-0.2 + 40j)), "8+x", 0.5, 0.0),
        (2, pytest.approx(f), pytest.approx(0.2 / abs(-0.2 + 40j)), "8+y", 0.0, -0.25),
    ]


def test_signed_directions_read_mode_components_with_their_sign(tmp_path: Path) -> None:
    t = 0.001 * np.arange(4)
    path = tmp_path / "signs.uff"
    vectors = np.array([[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]])
    write_raw(path, [units164(), nodes15([1, 2], [(0, 0, 0), (1, 0, 0)]), record58(1, -2, t, t), record58(2, 3, t, t),
                     mode55(1, [1, 2], vectors)])  # fmt: skip
    rows = read_uff(path).mode_rows
    assert [(r[3], r[4]) for r in rows] == [("1", -0.2), ("2", 0.6)]


def test_nodes_from_dataset_2411_and_units_given_by_caller(tmp_path: Path) -> None:
    t = 0.001 * np.arange(4)
    path = tmp_path / "n2411.uff"
    nodes = {"type": 2411, "node_nums": np.array([5]), "def_cs": np.array([0]), "disp_cs": np.array([0]),
             "color": np.array([1]), "x": np.array([0.123456789012]), "y": np.array([1.0]),
             "z": np.array([2.0])}  # fmt: skip
    write_raw(path, [nodes, record58(5, 1, t, t)])
    with pytest.raises(InputError, match="no dataset 164; give the units"):
        read_uff(path)
    with pytest.raises(InputError, match="unknown units furlong/g"):
        read_uff(path, units={"length": "furlong", "mass": "g"})
    back = read_uff(path, units={"length": "mm", "mass": "g"})
    assert back.layout["units"] == {"length": "mm", "mass": "g"}
    assert back.layout["sensors"] == [{"id": "5", "position": [0.123456789012, 1.0, 2.0], "direction": "+x"}]


def test_records_group_by_load_case_and_reference(tmp_path: Path) -> None:
    t = 0.001 * np.arange(4)
    path = tmp_path / "groups.uff"
    a = record58(1, 3, t, t)
    b = record58(2, 3, t, 2 * t)
    c = record58(1, 3, t, 3 * t)
    c["ref_node"], c["ref_dir"] = 2, -3
    write_raw(path, [units164(), nodes15([1, 2], [(0, 0, 0), (1, 0, 0)]), a, b, c])
    back = read_uff(path)
    assert back.record_labels == ["load case 1", "load case 1, reference 2-z"]
    assert back.records[0].sensor_ids == ("1", "2")
    np.testing.assert_allclose(back.records[0].data, np.column_stack([t, 2 * t]), rtol=1e-11)
    np.testing.assert_allclose(back.records[1].data, 3 * t[:, None], rtol=1e-11)


@pytest.mark.parametrize(
    ("func", "message"),
    [
        (4, r"dataset 58 #2: time records \(function type 1\) and FRFs \(function type 4\) in one file"),
        (9, r"dataset 58 #2, node 2: function type 9 \(power spectral density \(PSD\)\) is not a time record"),
        (3, r"function type 3 \(cross spectrum\) is not a time record"),
    ],
)
def test_a_58_that_is_not_a_time_record_is_refused_by_its_function_type(
    tmp_path: Path, func: int, message: str
) -> None:
    t = 0.001 * np.arange(4)
    path = tmp_path / "frf.uff"
    other = record58(2, 1, t, t + 1j * t, func=func)
    write_raw(path, [units164(), nodes15([1, 2], [(0, 0, 0), (1, 0, 0)]), record58(1, 3, t, t), other])
    with pytest.raises(InputError, match=message):
        read_uff(path)


# --------------------------------------------------------------------------- bad files


def bad_file(tmp_path: Path, datasets: list[dict[str, Any]]) -> Path:
    path = tmp_path / "bad.uff"
    write_raw(path, datasets)
    return path


T = 0.001 * np.arange(8)


@pytest.mark.parametrize(
    ("datasets", "location", "message"),
    [
        (
            [units164(), nodes15([1], [(0, 0, 0)]), record58(1, 3, T, T), record58(12, 3, T, T)],
            "dataset 58 #2, node 12",
            "response node 12 has no coordinates",
        ),
        (
            [units164(), nodes15([1, 2], [(0, 0, 0), (1, 0, 0)]), nodes15([2], [(1, 0, 0.5)]), record58(1, 3, T, T)],
            "dataset 15 #2, node 2",
            "node 2 has two coordinates",
        ),
        (
            [units164(), nodes15([1, 2], [(0, 0, 0), (1, 0, 0)]), record58(1, 3, T, T), record58(2, 3, T + 0.5, T)],
            "dataset 58 #2, node 2",
            "time axis .* differs from dataset 58 #1",
        ),
        (
            [units164(), nodes15([1, 2], [(0, 0, 0), (1, 0, 0)]), record58(1, 3, T, T), record58(2, 3, T[:5], T[:5])],
            "dataset 58 #2, node 2",
            "time axis",
        ),
        (
            [units164(), nodes15([1], [(0, 0, 0)]), record58(1, 3, T, T), mode55(1, [1], np.ones((1, 3)), eig=0j)],
            "dataset 55 #1, mode 1",
            "the mode has no frequency",
        ),
        (
            [units164(), nodes15([1], [(0, 0, 0)]), record58(1, 5, T, T)],
            "dataset 58 #1, node 1",
            "response direction 5 is a rotation",
        ),
        (
            [units164(), nodes15([1], [(0, 0, 0)]), record58(1, 0, T, T)],
            "dataset 58 #1, node 1",
            "response direction 0 is not a direction",
        ),
        (
            [units164(), nodes15([1], [(0, 0, 0)]), record58(1, 3, T, T), record58(1, 3, T, T)],
            "dataset 58 #2, node 1",
            "sensor 1 appears twice in load case 1",
        ),
        (
            [
                units164(),
                nodes15([1, 2], [(0, 0, 0), (1, 0, 0)]),
                record58(1, 3, T, T),
                record58(2, 3, T, T),
                mode55(1, [1], np.ones((1, 3))),
            ],
            "dataset 55 #1, mode 1, node 2",
            "no value at node 2",
        ),
        (
            [
                units164(),
                nodes15([1], [(0, 0, 0)]),
                record58(1, 3, T, T),
                mode55(3, [1], np.ones((1, 3))),
                mode55(3, [1], np.ones((1, 3))),
            ],
            "dataset 55 #2, mode 3",
            "mode 3 appears twice",
        ),
        (
            [units164(), units164(1, 1.0, 1.0), nodes15([1], [(0, 0, 0)]), record58(1, 3, T, T)],
            "dataset 164 #2",
            "units m/kg contradict in/lb of dataset 164 #1",
        ),
        (
            [units164(9, 2.0, 3.0), nodes15([1], [(0, 0, 0)]), record58(1, 3, T, T)],
            "dataset 164 #1",
            "units code 9 .* is not one of the layout units",
        ),
        (
            [units164(7, 39.37007874015748, 1.0), nodes15([1], [(0, 0, 0)]), record58(1, 3, T, T)],
            "dataset 164 #1",
            "is not one of the layout units",
        ),
        (
            [units164(), nodes15([1], [(0, 0, 0)])],
            None,
            "no sensors",
        ),
    ],
)
def test_missing_or_contradictory_pieces(
    tmp_path: Path, datasets: list[dict[str, Any]], location: str | None, message: str
) -> None:
    path = bad_file(tmp_path, datasets)
    with pytest.raises(InputError, match=message) as info:
        read_uff(path)
    assert info.value.source == str(path)
    assert info.value.location == location


def test_unreadable_files(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="file not found"):
        read_uff(tmp_path / "missing.uff")
    text = tmp_path / "notes.txt"
    text.write_text("just some text\n", encoding="utf-8")
    with pytest.raises(InputError, match="no UFF datasets"):
        read_uff(text)
    broken = tmp_path / "broken.uff"
    broken.write_text("    -1\n    15\n         1  garbage\n    -1\n", encoding="utf-8")
    with pytest.raises(InputError, match="pyuff cannot read it") as info:
        read_uff(broken)
    assert info.value.location == "dataset 15 #1"


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda lay, rec: lay["sensors"][3].update(direction=[0.0, 0.6, 0.8]), "not along an axis"),
        (lambda lay, rec: lay["sensors"][4].update(position=[1.25, -3.5, 0.75], id="12+y"), "share node 12 and axis y"),
        (lambda lay, rec: rec[0][1].__setitem__((3, 2), np.nan), "finite"),
        (lambda lay, rec: rec[0][0].__setitem__(5, 0.0051), "not uniformly sampled"),
        (lambda lay, rec: rec[0][2].__setitem__(0, "nope"), "sensor 'nope' is not in the layout"),
    ],
)
def test_writer_refuses_what_uff_cannot_hold(tmp_path: Path, change: Any, message: str) -> None:
    layout = mixed_layout()
    ids = [s["id"] for s in layout["sensors"]]
    t = 0.001 * np.arange(10)
    records = [(t.copy(), np.zeros((10, 6)), list(ids))]
    change(layout, records)
    path = tmp_path / "out.uff"
    with pytest.raises(InputError, match=message):
        write_uff_test(path, layout, records)
    assert not path.exists()
    assert list(tmp_path.iterdir()) == []  # no temporary file left behind


def test_written_file_gets_the_usual_permissions(tmp_path: Path) -> None:
    import os

    layout = mixed_layout()
    mask = os.umask(0o022)
    try:
        write_uff_test(tmp_path / "p.uff", layout, [])
    finally:
        os.umask(mask)
    assert (tmp_path / "p.uff").stat().st_mode & 0o777 == 0o644
