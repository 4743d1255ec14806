"""Regenerate this sample: `python samples/engine-test/make_sample.py`.

One engine test with every file README.md's examples name, all from `body.json` (the
engine of `samples/engine-on-mounts` with its mounts acting along the test's axes):
the layout (four triaxial nodes, ids `<node>+<axis>`, as UFF needs), modes with an
elastic mode among the rigid-body ones (label 4), mounts with rates and damping, a CAD
estimate, impact records (CSV and `.npz`), FRFs for three hammer points (CSV and UFF),
the test as one universal file and as modes plus a separate geometry file, and the
reference result `rigidid compare` checks against.
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

import numpy as np

from rigidid import api
from rigidid.api import simulate_frf
from rigidid.io.atomic import write_bytes_atomic, write_text_atomic
from rigidid.io.files import ModeTable, layout_arrays, modes_csv_text
from rigidid.io.frf import frf_csv_text, frf_uff_bytes, load_references, reference_arrays
from rigidid.io.records import read_record
from rigidid.io.uff import write_uff_test
from rigidid.io.uff_scan import blocks_text, scan
from rigidid.jsonout import result_to_dict

HERE = Path(__file__).resolve().parent
UNITS = {"length": "mm", "mass": "kg"}
NODES = {1: (310.0, 120.0, 260.0), 2: (-290.0, 150.0, 300.0), 3: (20.0, -230.0, 120.0), 4: (-200.0, -60.0, 50.0)}
MOUNTS = [
    ("front", (260.0, 140.0, 60.0), (180000.0, 160000.0, 420000.0), (350.0, 300.0, 600.0)),
    ("rear-left", (-240.0, 160.0, 90.0), (150000.0, 170000.0, 380000.0), (250.0, 400.0, 500.0)),
    ("rear-right", (-40.0, -210.0, 40.0), (210000.0, 140000.0, 360000.0), (450.0, 200.0, 700.0)),
]


def _json(name: str, data: object) -> None:
    write_text_atomic(HERE / name, json.dumps(data, indent=1) + "\n")


def write_inputs() -> None:
    """body.json, cad-estimate.json, layout.json, mounts.json, refs.json."""
    inertia = [[5.2e6, -0.3e6, 0.45e6], [-0.3e6, 7.9e6, 0.2e6], [0.45e6, 0.2e6, 6.4e6]]
    mounts = [{"position": list(p), "stiffness": list(k), "damping": list(c)} for _, p, k, c in MOUNTS]
    body = {"name": "four-cylinder engine on three mounts (synthetic truth)", "units": UNITS, "mass": 142.0,
            "center_of_gravity": [35.0, -12.0, 180.0], "inertia_tensor": inertia, "mounts": mounts}  # fmt: skip
    _json("body.json", body)
    cad = {**body, "name": "the engine as the CAD model has it (no products of inertia, CG 12 mm off)",
           "center_of_gravity": [30.0, -10.0, 170.0],
           "inertia_tensor": [[5.0e6, 0.0, 0.0], [0.0, 7.5e6, 0.0], [0.0, 0.0, 6.0e6]]}  # fmt: skip
    _json("cad-estimate.json", cad)
    sensors = [{"id": f"{n}+{a}", "position": list(p), "direction": f"+{a}"} for n, p in NODES.items() for a in "xyz"]
    test = {"id": "E4-2231-T03", "specimen": "engine E4, s/n 2231, on its three production mounts",
            "date": "2026-11-20", "operator": "A. Tester",
            "notes": "synthetic test of rigidid's samples (truth: body.json)"}  # the report shows it under the title
    _json("layout.json", {"name": "engine test, four triaxial accelerometers", "units": UNITS, "mass": 142.0,
                          "test": test, "sensors": sensors})  # fmt: skip
    _json("mounts.json", {
        "name": "the engine's three mounts: data-sheet rates and damping along the test's axes",
        "units": UNITS,
        "mounts": [{"id": i, "position": list(p), "axes": [[1, 0, 0], [0, 1, 0], [0, 0, 1]],
                    "stiffness": list(k), "damping": list(c)} for i, p, k, c in MOUNTS],
    })  # fmt: skip
    # the hammer at a node; UFF-style ids, as frf.uff needs
    refs = [("1+x", NODES[1], "+x"), ("2+y", NODES[2], "+y"), ("3+z", NODES[3], "+z")]
    _json("refs.json", {"units": UNITS, "references": [
        {"id": i, "position": list(p), "direction": d} for i, p, d in refs]})  # fmt: skip


def write_modes() -> None:
    """modes.csv: the six rigid-body modes and, as mode 4, a local mode at 12.5 Hz no rigid motion explains."""
    rigid = api.simulate(HERE / "body.json", HERE / "layout.json")
    x = np.array([NODES[int(s.split("+")[0])] for s in rigid.sensor_ids])
    local = (x[:, 0] / 300.0) ** 2 - 0.4 + 0.02j  # bending: readings grow with the square of x
    order = [0, 1, 2, 6, 3, 4, 5]
    table = ModeTable(
        labels=(1, 2, 3, 4, 5, 6, 7),
        frequency_hz=np.concatenate([rigid.frequency_hz, [12.5]])[order],
        damping_ratio=np.concatenate([rigid.damping_ratio, [0.015]])[order],
        sensor_ids=rigid.sensor_ids,
        shapes=np.hstack([rigid.shapes, local[:, None]])[:, order],
    )
    write_text_atomic(HERE / "modes.csv", modes_csv_text(table))


def write_records() -> list[tuple[np.ndarray, np.ndarray, list[str]]]:
    """hit1.csv, hit2.csv (and .npz): two impacts, 4 s at 300 Hz, 0.5 % noise."""
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        paths = api.simulate_records(
            HERE / "body.json", HERE / "layout.json", tmp, sample_rate=300.0, duration=4.0, noise=0.005, seed=7
        )
        ids = [s.id for s in api.load_layout(HERE / "layout.json").sensors]
        for k, path in enumerate(paths, start=1):
            text = Path(path).read_text()
            write_text_atomic(HERE / f"hit{k}.csv", text)
            data, dt = read_record(path, ids)
            time = np.arange(data.shape[0]) * dt
            with tempfile.NamedTemporaryFile(suffix=".npz", dir=tmp, delete=False) as fh:
                np.savez_compressed(fh, data=data, channels=np.array(ids), dt=np.float64(dt))
            write_bytes_atomic(HERE / f"hit{k}.npz", Path(fh.name).read_bytes())
            out.append((time, data, ids))
    return out


def write_frfs() -> None:
    """frf.csv and frf.uff: accelerance for the three hammer points, 0.5 to 120 Hz in 0.5 Hz lines."""
    lines = np.arange(1, 241) * 0.5
    frf = simulate_frf(HERE / "body.json", HERE / "layout.json", HERE / "refs.json", frequencies=lines)
    write_text_atomic(HERE / "frf.csv", frf_csv_text(frf.frequencies, frf.frf, frf.sensor_ids, frf.reference_ids))
    layout = api.load_layout(HERE / "layout.json")
    dirs = layout_arrays(layout)[2]
    rdirs = reference_arrays(load_references(HERE / "refs.json"))[2]
    content = frf_uff_bytes(frf.frequencies, frf.frf, frf.sensor_ids, dirs, frf.reference_ids, rdirs, UNITS)
    write_bytes_atomic(HERE / "frf.uff", content)


def write_uff(records: list[tuple[np.ndarray, np.ndarray, list[str]]]) -> None:
    """test.uff (151, 164, 15, 58 records, 55 modes); test.unv (164, 55) with geometry.unv (151, 164, 15)."""
    layout = json.loads((HERE / "layout.json").read_text())
    table = api.load_modes(HERE / "modes.csv", api.load_layout(HERE / "layout.json"))
    rows = [
        (label, float(table.frequency_hz[k]), float(table.damping_ratio[k]), sid, v.real, v.imag)
        for k, label in enumerate(table.labels)
        for sid, v in zip(table.sensor_ids, table.shapes[:, k], strict=True)
    ]
    write_uff_test(HERE / "test.uff", layout, records, mode_rows=rows)
    with tempfile.TemporaryDirectory() as tmp:
        modes_only = Path(tmp) / "modes.unv"
        write_uff_test(modes_only, layout, [], mode_rows=rows, binary=False)
        blocks = scan(modes_only) or []
        geometry = [b for b in blocks if b.kind in (151, 164, 15)]
        test = [b for b in blocks if b.kind in (164, 55)]
        write_bytes_atomic(HERE / "geometry.unv", blocks_text(modes_only, geometry))
        write_bytes_atomic(HERE / "test.unv", blocks_text(modes_only, test))


def main() -> None:
    write_inputs()
    write_modes()
    records = write_records()
    write_frfs()
    write_uff(records)
    result = api.identify(HERE / "layout.json", HERE / "modes.csv")
    _json("reference.json", result_to_dict(result))


if __name__ == "__main__":
    main()
