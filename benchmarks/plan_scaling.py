"""Time and peak memory of ``rigidid plan LAYOUT --body BODY`` as the layout grows (issue 24).

    python benchmarks/plan_scaling.py [--sensors 12 200 1006] [--src DIR]

Each layout has N single-axis sensors at seeded random points of a 600 mm cube, pointing along
+-x, +-y, +-z in turn, with the engine-on-mounts sample's body estimate (1000 Monte Carlo draws,
the default). Each run is a fresh process; prints its wall time, its peak resident memory and the
number of lines it printed. ``--src`` runs another checkout's sources (e.g. ``/work/main/src``)
for a before/after comparison.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BODY = ROOT / "samples" / "engine-on-mounts" / "body.json"


def layout(n: int, path: Path) -> None:
    rng = np.random.default_rng(0)
    axes = ["+x", "+y", "+z", "-x", "-y", "-z"]
    sensors = [
        {"id": f"s{i}", "position": [float(x) for x in rng.uniform(-300.0, 300.0, 3)], "direction": axes[i % 6]}
        for i in range(n)
    ]
    path.write_text(json.dumps({"units": {"length": "mm", "mass": "kg"}, "sensors": sensors}))


def run(n: int, src: Path, folder: Path) -> tuple[float, float, int, int]:
    lay = folder / f"layout{n}.json"
    layout(n, lay)
    env = {**os.environ, "PYTHONPATH": str(src)}
    cmd = [sys.executable, "-m", "rigidid", "plan", str(lay), "--body", str(BODY)]
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    out = proc.stdout.read() if proc.stdout else ""
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    return wall, usage.ru_maxrss / 1024.0, os.waitstatus_to_exitcode(status), len(out.splitlines())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sensors", type=int, nargs="+", default=[12, 200, 1006])
    parser.add_argument("--src", type=Path, default=ROOT / "src")
    args = parser.parse_args()
    print(f"sources: {args.src}")
    print(f"{'sensors':>8} {'wall s':>8} {'peak MB':>8} {'exit':>5} {'lines':>6}")
    with tempfile.TemporaryDirectory() as tmp:
        for n in args.sensors:
            wall, peak, code, lines = run(n, args.src, Path(tmp))
            print(f"{n:>8} {wall:>8.2f} {peak:>8.0f} {code:>5} {lines:>6}")


if __name__ == "__main__":
    main()
