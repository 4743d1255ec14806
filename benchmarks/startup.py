"""Start-up cost: ``rigidid identify`` on the paper sample against ``python -c "import numpy"``.

Both commands run alternately in one loop (so machine load hits both alike);
the medians and their ratio are printed. The target is a ratio below 2.5.

Run: ``python benchmarks/startup.py [--rounds 20]``
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

SAMPLE = Path(__file__).resolve().parent.parent / "samples" / "paper-1994"


def _wall(cmd: list[str]) -> float:
    start = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=20)
    args = parser.parse_args()
    numpy_cmd = [sys.executable, "-c", "import numpy"]
    cases = {
        "tables": [sys.executable, "-m", "rigidid", "identify", str(SAMPLE / "layout.json"), str(SAMPLE / "modes.csv")],
        "--json -": [
            sys.executable,
            "-m",
            "rigidid",
            "identify",
            str(SAMPLE / "layout.json"),
            str(SAMPLE / "modes.csv"),
            "--json",
            "-",
        ],
    }
    times: dict[str, list[float]] = {"import numpy": [], **{k: [] for k in cases}}
    for _ in range(args.rounds):
        times["import numpy"].append(_wall(numpy_cmd))
        for name, cmd in cases.items():
            times[name].append(_wall(cmd))
    base = statistics.median(times["import numpy"])
    print(f"{args.rounds} alternating rounds, medians:")
    print(f"  python -c 'import numpy'          {1000 * base:7.1f} ms")
    for name in cases:
        med = statistics.median(times[name])
        print(f"  rigidid identify paper ({name:8s}) {1000 * med:7.1f} ms   ratio {med / base:.2f}")


if __name__ == "__main__":
    main()
