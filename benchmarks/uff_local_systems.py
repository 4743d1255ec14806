"""How closely a UFF test in local coordinate systems identifies the body of the same test in global axes.

Run: `python benchmarks/uff_local_systems.py`. Compares `samples/uff-local-systems/test.unv`
(read directly, and after `convert`) and the same file with its global-coordinate nodes in
dataset 15 (6 digits) instead of 2411 (17 digits) against `layout.json` + `modes.csv` of that sample. Prints the
largest difference of each quantity relative to its largest entry.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pyuff

from rigidid import api
from rigidid.core.identify import Identification

SAMPLE = Path(__file__).resolve().parent.parent / "samples" / "uff-local-systems"
QUANTITIES = ("center_of_gravity", "inertia_per_mass", "stiffness_per_mass", "damping_per_mass")


def _identify(data: api.TestData) -> Identification:
    assert data.modes is not None
    return api.identify(data.layout, data.modes).identification


def main() -> None:
    layout = api.load_layout(SAMPLE / "layout.json")
    reference = _identify(api.TestData(layout, api.load_modes(SAMPLE / "modes.csv", layout)))
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        api.convert(SAMPLE / "test.unv", folder / "converted")
        converted = api.load_layout(folder / "converted" / "layout.json")
        sets = pyuff.UFF(str(SAMPLE / "test.unv")).read_sets()
        for d in sets:
            if d["type"] == 2411:  # the nodes given in global coordinates, now with 6 digits
                d["type"] = 15
                d["def_cs"] = np.zeros(len(d["node_nums"]), dtype=int)
                for key in ("node_nums", "def_cs", "disp_cs", "color"):
                    d[key] = np.asarray(d[key], dtype=int)
        pyuff.UFF(str(folder / "nodes15.unv")).write_sets(sets, mode="overwrite")
        cases = {
            "test.unv": _identify(api.load_uff(SAMPLE / "test.unv")),
            "convert -> identify": _identify(
                api.TestData(converted, api.load_modes(folder / "converted" / "modes.csv", converted))
            ),
            "2411 nodes as 15": _identify(api.load_uff(folder / "nodes15.unv")),
        }
    print(f"{'case':22s}" + "".join(f"{q:>20s}" for q in QUANTITIES))
    for name, result in cases.items():
        row = []
        for q in QUANTITIES:
            a, b = np.asarray(getattr(reference, q)), np.asarray(getattr(result, q))
            row.append(float(np.max(np.abs(a - b)) / np.max(np.abs(a))))
        print(f"{name:22s}" + "".join(f"{v:20.2e}" for v in row))


if __name__ == "__main__":
    main()
