"""Regenerate this sample: `python samples/uff-local-systems/make_sample.py`.

One test written twice: in global axes as `layout.json` + `modes.csv`, and as
the universal file `test.unv` whose nodes are defined and measure in local,
rotated and shifted, cartesian coordinate systems (datasets 2420 and 18), the
way Simcenter Testlab writes a test. The body is `samples/four-mounts/body.json`.

Precision: every number both files share is written so that both hold the same
double. Dataset 55 keeps 6 significant digits (``E13.5``), so the eigenvalues
and shape values are rounded to 6 digits first and `modes.csv` holds those
rounded values (frequency and damping ratio computed from the rounded
eigenvalue, written with 17 digits). Node coordinates go in dataset 2411 and the
2420 matrices in ``D25.16`` (17 significant digits); the dataset 18 system is
chosen so that its 6-digit points are exact (a 3-4-5 rotation).
"""

import json
import math
from pathlib import Path

import numpy as np

from rigidid import api
from rigidid.core.simulate import body_modes
from rigidid.io.atomic import write_text_atomic
from rigidid.io.files import load_body

HERE = Path(__file__).resolve().parent
BODY = HERE.parent / "four-mounts" / "body.json"


def rotation(axis: tuple[float, float, float], degrees: float) -> np.ndarray:
    """Rotation matrix (columns: the rotated x, y, z axes) about `axis` by `degrees`."""
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    t = math.radians(degrees)
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + math.sin(t) * k + (1.0 - math.cos(t)) * k @ k


def round6(x: np.ndarray) -> np.ndarray:
    """Round to 6 significant digits as FORMAT E13.5 does (through the same text)."""
    return np.vectorize(lambda v: float(f"{v:13.5e}"))(x)


# (system number, dataset, rotation R whose columns are the local axes in global axes, origin)
SYSTEMS = [
    (1, 2420, rotation((0.0, 1.0, 0.0), 180.0), np.array([0.3, 0.2, 0.15])),  # Test.Lab's usual flip
    (2, 2420, rotation((1.0, 2.0, 3.0), 37.0), np.array([-0.31, 0.17, 0.12])),
    (3, 2420, rotation((-2.0, 0.5, 1.0), 121.0), np.array([-0.25, -0.26, 0.2])),
    (4, 18, np.array([[0.6, -0.8, 0.0], [0.8, 0.6, 0.0], [0.0, 0.0, 1.0]]), np.array([0.25, -0.2, -0.1])),
]
# (node, system, local coordinates (6 significant digits at most: dataset 15 keeps 6), measured local axes,
#  the dataset that gives the node: 15 in its definition system, 2411 in global coordinates)
NODES = [
    (11, 1, (0.0, 0.0, 0.0), (1, 3), 15),
    (12, 2, (0.05, -0.1, 0.02), (1, 2), 15),
    (13, 3, (-0.04, 0.08, 0.1), (2, 3), 2411),
    (14, 4, (0.05, 0.0, 0.25), (1, 3), 15),
    (15, 2, (0.4, 0.35, -0.3), (3,), 2411),
    (16, 3, (0.15, -0.2, 0.3), (1,), 15),
    (17, 1, (0.6, -0.4, 0.3), (2,), 15),
    (18, 4, (0.1, 0.05, -0.05), (1, 2, 3), 2411),
]


def main() -> None:
    rot = {num: r for num, _, r, _ in SYSTEMS}
    orig = {num: o for num, _, _, o in SYSTEMS}
    sensors = []  # (id, node, system, axis, global position, global direction)
    for node, cs, pos, axes, _ in NODES:
        for axis in axes:
            sid = f"{node}{'+' + 'xyz'[axis - 1]}" if len(axes) > 1 else str(node)
            sensors.append((sid, node, cs, axis, orig[cs] + rot[cs] @ np.array(pos), rot[cs][:, axis - 1]))
    positions = np.array([s[4] for s in sensors])
    directions = np.array([s[5] for s in sensors])
    body = api.body_from_file(load_body(BODY))
    modes = body_modes(body, positions, directions)
    poles = round6(modes.poles.real) + 1j * round6(modes.poles.imag)
    shapes = round6(modes.shapes.real) + 1j * round6(modes.shapes.imag)

    layout = {
        "name": "four-mounts block, sensors in local coordinate systems",
        "units": {"length": "m", "mass": "kg"},
        "mass": 40.0,
        "sensors": [
            {"id": sid, "position": [float(v) for v in p], "direction": [float(v) for v in d]}
            for sid, _, _, _, p, d in sensors
        ],
    }
    write_text_atomic(HERE / "layout.json", json.dumps(layout, indent=2) + "\n")
    lines = ["mode,frequency_hz,damping_ratio,sensor,real,imag"]
    for k, pole in enumerate(poles):
        f, z = abs(pole) / (2.0 * math.pi), -pole.real / abs(pole)
        for j, (sid, *_rest) in enumerate(sensors):
            lines.append(
                f"{k + 1},{float(f)!r},{float(z)!r},{sid},{float(shapes[j, k].real)!r},{float(shapes[j, k].imag)!r}"
            )
    write_text_atomic(HERE / "modes.csv", "\n".join(lines) + "\n")

    import pyuff

    node_nums = [n for n, *_ in NODES]
    sets: list[dict] = [
        {"type": 151, "model_name": "four-mounts local systems", "description": "rigidid sample",
         "db_app": "rigidid", "program": "make_sample.py"},
        {"type": 164, "units_code": 1, "units_description": "SI", "temp_mode": 1, "length": 1.0, "force": 1.0,
         "temp": 1.0, "temp_offset": 273.15},
        {"type": 2420, "Part_UID": 1, "Part_Name": "block", "CS_sys_labels": [s[0] for s in SYSTEMS if s[1] == 2420],
         "CS_types": [0] * 3, "CS_colors": [8] * 3, "CS_names": ["CS1", "CS2", "CS3"],
         "CS_matrices": [np.vstack([r.T, o]) for _, kind, r, o in SYSTEMS if kind == 2420]},
        {"type": 18, "cs_num": [4], "cs_type": [0], "ref_cs_num": [0], "color": [8], "method": [1],
         "cs_name": ["CS4"], "ref_o": [orig[4]], "x_point": [orig[4] + 5.0 * rot[4][:, 0]],
         "xz_point": [orig[4] + 2.0 * rot[4][:, 2]]},
    ]  # fmt: skip
    for kind in (15, 2411):
        chosen = [(n, cs, np.array(pos)) for n, cs, pos, _, k in NODES if k == kind]
        xyz = np.array([p if kind == 15 else orig[cs] + rot[cs] @ p for _, cs, p in chosen])
        sets.append(
            {"type": kind, "node_nums": np.array([n for n, _, _ in chosen]),
             "def_cs": np.array([cs for _, cs, _ in chosen]), "disp_cs": np.array([cs for _, cs, _ in chosen]),
             "color": np.ones(len(chosen), dtype=int), "x": xyz[:, 0], "y": xyz[:, 1], "z": xyz[:, 2]}
        )  # fmt: skip
    row = {n: i for i, n in enumerate(node_nums)}
    for k, pole in enumerate(poles):
        vec = np.zeros((len(NODES), 3), dtype=complex)
        for j, (_, node, _, axis, _, _) in enumerate(sensors):
            vec[row[node], axis - 1] = shapes[j, k]
        sets.append(
            {
                "type": 55,
                "id1": f"mode {k + 1}",
                "id2": "NONE",
                "id3": "NONE",
                "id4": "NONE",
                "id5": "NONE",
                "model_type": 1,
                "analysis_type": 3,
                "data_ch": 2,
                "spec_data_type": 8,
                "load_case": 1,
                "mode_n": k + 1,
                "eig": complex(pole),
                "modal_a": 0j,
                "modal_b": 0j,
                "node_nums": np.array(node_nums),
                "r1": vec[:, 0],
                "r2": vec[:, 1],
                "r3": vec[:, 2],
            }
        )
    pyuff.UFF(str(HERE / "test.unv")).write_sets(sets, mode="overwrite")


if __name__ == "__main__":
    main()
