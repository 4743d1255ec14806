"""Regenerate this sample: `python samples/frf-uff/make_sample.py`.

One FRF test written twice: as a lab's universal file `test.uff` (datasets 151,
164, 18, 15 and one 58 per response and reference, function type 4, the way
Simcenter Testlab and ME'scope export FRFs: ASCII, complex single precision
``6E13.5``, even frequency spacing, acceleration over force, every node
measuring in its own coordinate system) and as `layout.json` (with its
`references`) + `refs.json` + `frf.csv` in global axes. The body is
`samples/four-mounts/body.json` on its mounts (exact FRFs, no noise).

Precision: dataset 58 keeps 6 significant digits, so the FRF values are rounded
through the same ``E13.5`` text and `frf.csv` holds those rounded values; node
coordinates and the dataset 18 points are round in 6 digits, and the local
systems are quarter turns, so both files hold the same doubles.
"""

import json
from pathlib import Path

import numpy as np

from rigidid import api
from rigidid.core.frf import accelerance
from rigidid.io.atomic import write_text_atomic
from rigidid.io.files import load_body
from rigidid.io.frf import frf_csv_text

HERE = Path(__file__).resolve().parent
BODY = HERE.parent / "four-mounts" / "body.json"

# quarter-turn local systems (columns: the local x, y, z axes in global axes), as Testlab gives each node its own
FLIP_Y = np.array([[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]])  # Testlab's usual: 180 degrees about y
TURN_Z = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # 90 degrees about z
EYE = np.eye(3)
# (node, global position, local system, measured local axes 1..3 signed)
NODES = [
    (11, (0.3, 0.2, 0.15), FLIP_Y, (1, 2, 3)),
    (12, (-0.3, 0.2, -0.15), TURN_Z, (1, 3)),
    (13, (0.3, -0.2, -0.15), EYE, (2, -3)),
    (14, (-0.3, -0.2, 0.15), TURN_Z, (1, 2)),
    (15, (0.0, 0.25, 0.2), EYE, (3,)),
]
# (node, global position, local system, local axis of the force): hammer points, one direction each
REFERENCES = [
    (101, (0.25, 0.22, 0.1), FLIP_Y, -1),  # local -x = global +x
    (102, (-0.25, -0.22, 0.12), TURN_Z, 1),  # local +x = global +y
    (103, (0.05, -0.1, 0.25), EYE, -3),
]
FREQUENCIES = 0.5 * np.arange(1, 301)  # 0.5-150 Hz: rigid modes 8-26 Hz, the mass line above them
AXES = "xyz"


def axis_name(vector: np.ndarray) -> str:
    k = int(np.argmax(np.abs(vector)))
    return ("+" if vector[k] > 0 else "-") + AXES[k]


def e13(x: float) -> str:
    return f"{x:13.5e}"


def round6(x: np.ndarray) -> np.ndarray:
    return np.vectorize(lambda v: float(e13(v)))(x)


def points() -> tuple[list[dict], list[dict], list[tuple[int, int]], list[tuple[int, int]]]:
    """layout.json sensors and references (global axes), and the UFF (node, code) of each."""
    sensors, codes = [], []
    for node, pos, rot, axes in NODES:
        for code in axes:
            sid = str(node) if len(axes) == 1 else f"{node}{'+' if code > 0 else '-'}{AXES[abs(code) - 1]}"
            direction = np.sign(code) * rot[:, abs(code) - 1]
            sensors.append({"id": sid, "position": list(pos), "direction": axis_name(direction)})
            codes.append((node, code))
    refs, ref_codes = [], []
    for node, pos, rot, code in REFERENCES:
        direction = np.sign(code) * rot[:, abs(code) - 1]
        refs.append({"id": str(node), "position": list(pos), "direction": axis_name(direction)})
        ref_codes.append((node, code))
    return sensors, refs, codes, ref_codes


def geometry_text() -> str:
    """Datasets 151, 164 (user defined, SI factors, as Testlab writes), 18 (one system per node) and 15."""
    out = ["    -1", "   151", "frf-uff sample", "NONE", "rigidid make_sample.py", "NONE", "NONE", "NONE", "NONE"]
    out += ["    -1", "    -1", "   164", f"{9:10d}USER_DEFINED"]
    out += ["  1.00000000000000000D+00  1.00000000000000000D+00  1.00000000000000000D+00"]
    out += [" -2.73149999999999960D+02", "    -1", "    -1", "    18"]
    everything = [(n, p, r) for n, p, r, _ in NODES] + [(n, p, r) for n, p, r, _ in REFERENCES]
    for node, pos, rot in everything:
        o = np.array(pos)
        x_point, xz_point = o + rot[:, 0], o + rot[:, 0] + rot[:, 2]
        out += [f"{node:10d}{0:10d}{0:10d}{8:10d}{1:10d}", f"SYS{node}"]
        out += ["".join(e13(v) for v in (*o, *x_point)), "".join(e13(v) for v in xz_point)]
    out += ["    -1", "    -1", "    15"]
    for node, pos, _ in everything:
        out.append(f"{node:10d}{0:10d}{node:10d}{8:10d}" + "".join(e13(v) for v in pos))
    out += ["    -1"]
    return "\n".join(out) + "\n"


def frf_text(h: np.ndarray, codes: list[tuple[int, int]], ref_codes: list[tuple[int, int]]) -> str:
    """One ASCII dataset 58 per response and reference (function type 4, complex single, even spacing)."""
    out = []
    record = 0
    for j, (rnode, rcode) in enumerate(ref_codes):
        for i, (node, code) in enumerate(codes):
            record += 1
            rsp, ref = f"Point{node}:{code:+d}", f"Point{rnode}:{rcode:+d}"
            out += ["    -1", "    58", f"{rsp} / {ref}", "NONE", "26-Nov-26 12:00:00", f"Record {record} of section 1"]
            out += ["H1 : FRF"]
            rsp_field, ref_field = f"{rsp[:10]:<10s}{node:10d}{code:4d}", f"{ref[:10]:<10s}{rnode:10d}{rcode:4d}"
            out += [f"{4:5d}{record:10d}{0:5d}{j + 1:10d} {rsp_field} {ref_field}"]
            step = FREQUENCIES[1] - FREQUENCIES[0]
            out += [f"{5:10d}{FREQUENCIES.size:10d}{1:10d}{e13(FREQUENCIES[0])}{e13(step)}{e13(0.0)}"]
            out += [f"{18:10d}{0:5d}{0:5d}{0:5d} {'Frequency':<20s} {'Hz':<20s}"]
            out += [f"{12:10d}{1:5d}{0:5d}{0:5d} {'Acceleration':<20s} {'m/s^2':<20s}"]
            out += [f"{13:10d}{0:5d}{1:5d}{0:5d} {'Force':<20s} {'N':<20s}"]
            out += [f"{0:10d}{0:5d}{0:5d}{0:5d} {'NONE':<20s} {'NONE':<20s}"]
            values = np.empty(2 * FREQUENCIES.size)
            values[0::2], values[1::2] = h[i, j].real, h[i, j].imag
            out += ["".join(e13(v) for v in values[k : k + 6]) for k in range(0, values.size, 6)]
            out += ["    -1"]
    return "\n".join(out) + "\n"


def main() -> None:
    sensors, refs, codes, ref_codes = points()
    pos = np.array([s["position"] for s in sensors], dtype=float)
    dirs = np.array([[float(s["direction"][0] + "1") * (s["direction"][1] == a) for a in AXES] for s in sensors])
    rpos = np.array([r["position"] for r in refs], dtype=float)
    rdirs = np.array([[float(r["direction"][0] + "1") * (r["direction"][1] == a) for a in AXES] for r in refs])
    body = api.body_from_file(load_body(BODY))
    h = accelerance(body, pos, dirs, rpos, rdirs, FREQUENCIES)
    h = round6(h.real) + 1j * round6(h.imag)
    layout = {"name": "frf-uff sample", "units": {"length": "m", "mass": "kg"}, "sensors": sensors, "references": refs}
    write_text_atomic(HERE / "layout.json", json.dumps(layout, indent=1) + "\n")
    write_text_atomic(HERE / "refs.json", json.dumps({"units": layout["units"], "references": refs}, indent=1) + "\n")
    ids = [s["id"] for s in sensors]
    write_text_atomic(HERE / "frf.csv", frf_csv_text(FREQUENCIES, h, ids, [r["id"] for r in refs]))
    write_text_atomic(HERE / "test.uff", geometry_text() + frf_text(h, codes, ref_codes))


if __name__ == "__main__":
    main()
