"""Time to read a large UFF file of FRFs against a layout (``identify LAYOUT --frf FILE.uff``).

The file: 24 responses (8 nodes x 3 axes) x 6 references (at sensor nodes, the driving points,
so the references come from the FRF headers) x 2,000 lines, written by rigidid's own UFF 58
writer as ASCII 58 and as binary 58b. The timed call is :func:`rigidid.api.frf.load_frf_test`
(layout, FRF file, no references file): the references from the headers, then the FRFs.

Run::

    PYTHONPATH=src python benchmarks/uff_frf_read.py [--lines 2000] [--repeat 3]

Prints the best of ``--repeat`` wall times per format, and the file sizes.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from rigidid.api.frf import load_frf_test
from rigidid.io.frf import frf_uff_bytes
from rigidid.models import LayoutFile


def _layout(nodes: int) -> LayoutFile:
    rng = np.random.default_rng(1)
    sensors = [
        {"id": f"{n}{axis}", "position": [float(v) for v in rng.uniform(-400.0, 400.0, 3)], "direction": axis}
        for n in range(1, nodes + 1)
        for axis in ("+x", "+y", "+z")
    ]
    for s in sensors:  # one position per node
        s["position"] = sensors[3 * (int(s["id"][:-2]) - 1)]["position"]
    return LayoutFile.model_validate({"name": "big", "units": {"length": "mm", "mass": "kg"}, "sensors": sensors})


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lines", type=int, default=2000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    lay = _layout(8)
    ids = [s.id for s in lay.sensors]
    sdirs = np.array([s.unit_direction() for s in lay.sensors])
    refs = ["1+x", "2+y", "3+z", "4+x", "5+y", "6+z"]
    rdirs = np.array([sdirs[ids.index(r)] for r in refs])
    rng = np.random.default_rng(2)
    freq = 1.0 + 0.25 * np.arange(args.lines)
    h = rng.standard_normal((24, 6, args.lines)) + 1j * rng.standard_normal((24, 6, args.lines))
    with tempfile.TemporaryDirectory() as folder:
        for binary in (False, True):
            path = Path(folder) / ("big-58b.uff" if binary else "big-ascii.uff")
            path.write_bytes(frf_uff_bytes(freq, h, ids, sdirs, refs, rdirs, lay.units.model_dump(), binary=binary))
            best = np.inf
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                _, got, data = load_frf_test(lay, path)
                best = min(best, time.perf_counter() - t0)
            assert data.frf.shape == (24, 6, args.lines) and len(got.references) == 6
            kind = "binary 58b" if binary else "ASCII 58 "
            size = path.stat().st_size / 2**20
            print(f"{kind}  {size:6.1f} MiB  load_frf_test {best:6.2f} s (best of {args.repeat})")


if __name__ == "__main__":
    main()
