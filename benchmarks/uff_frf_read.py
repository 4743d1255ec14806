"""Time to read a large UFF file of FRFs against a layout (``identify LAYOUT --frf FILE.uff``).

The file: 24 responses (8 nodes x 3 axes) x 6 references (at sensor nodes, the driving points,
so the references come from the FRF headers) x 2,000 lines, written by rigidid's own UFF 58
writer as ASCII 58 and as binary 58b, and as ASCII 58 after a dataset 15 with the nodes (the
references' positions then come from the file's geometry, through ``read_uff``). The timed call
is :func:`rigidid.api.frf.load_frf_test` (layout, FRF file, no references file): the references
from the headers, then the FRFs. Last, how ``identify test.uff`` tells a file of FRFs: the whole
file read (``load_uff``) against the 58s' headers alone (``uff_function_types``, when it exists).

Run::

    PYTHONPATH=src python benchmarks/uff_frf_read.py [--lines 2000] [--repeat 3]

Prints the best of ``--repeat`` CPU times (``time.process_time``: the machine's load counts less) per
format, and the file sizes.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from rigidid.api.frf import load_frf_test
from rigidid.api.load import load_uff
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
    nodes = "".join(
        f"{n:10d}{0:10d}{0:10d}{11:10d}" + "".join(f"{v:13.5e}" for v in lay.sensors[3 * (n - 1)].position) + "\n"
        for n in range(1, 9)
    )
    geometry = f"    -1\n    15\n{nodes}    -1\n".encode()
    with tempfile.TemporaryDirectory() as folder:
        for kind, binary, head in (
            ("ASCII 58", False, b""),
            ("binary 58b", True, b""),
            ("15 + ASCII 58", False, geometry),
        ):
            path = Path(folder) / f"big-{len(head)}-{binary}.uff"
            body = frf_uff_bytes(freq, h, ids, sdirs, refs, rdirs, lay.units.model_dump(), binary=binary)
            path.write_bytes(head + body)
            best = _best(lambda path=path: load_frf_test(lay, path), args.repeat)
            _, got, data = load_frf_test(lay, path)
            assert data.frf.shape == (24, 6, args.lines) and len(got.references) == 6
            size = path.stat().st_size / 2**20
            print(f"{kind:14s} {size:6.1f} MiB  load_frf_test {best:6.2f} s CPU (best of {args.repeat})")
        whole = _best(lambda: load_uff(path, units={"length": "mm", "mass": "kg"}), args.repeat)
        print(f"is it a file of FRFs? {path.name}: load_uff {whole:6.2f} s", end="")
        try:
            from rigidid.io.uff import uff_function_types
        except ImportError:
            print()
            return
        heads = _best(lambda: uff_function_types(path), args.repeat)
        print(f", uff_function_types {heads:6.3f} s")


def _best(call: Callable[[], object], repeat: int) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.process_time()
        call()
        best = min(best, time.process_time() - t0)
    return float(best)


if __name__ == "__main__":
    main()
