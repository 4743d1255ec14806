"""`rigidid modes` on binary UFF 58 records: wall time and peak memory, native reader against pyuff (not a test).

Each case takes the record ``modes_speed.py --floor`` writes (``record_<C>x<N>.npy`` with its
``layout<C>.json`` in ``--cases-dir``; written there by ``modes_speed.py --floor ... --keep DIR``),
writes it as a universal file with ``write_uff_test`` (15, 151, 164 and one binary 58 of
float64 values per channel; sensor directions rounded to the nearest axis, since UFF holds no
others: the estimation does not use the geometry), then times in fresh processes

- ``rigidid modes FILE.uff`` as shipped (binary 58 values located by ``rigidid.io.uff_scan``
  and copied into the record block by block),
- the same with ``uff_scan.scan`` replaced by one that declines, so pyuff reads the whole
  file (the reader before this change), and
- ``rigidid modes LAYOUT record.npy`` for reference (the streamed binary route),

interleaved, ``--repeat`` times; it prints medians of wall time (start-up included) and peak
resident memory (the child's VmHWM), and the largest difference between the modes the two UFF
readers give (the records read are equal; the rest is floating-point order in BLAS).

Run: ``python benchmarks/uff_records_speed.py --cases-dir /tmp/cases --cases 8x1000000,32x1000000``
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from modes_speed import CLI_CODE, PEAK_PREAMBLE, _run_peak

PYUFF_CODE = (
    PEAK_PREAMBLE
    + """
import sys
import rigidid.io.uff_scan as uff_scan
uff_scan.scan = lambda path: None  # the reader falls back to pyuff for the whole file
from rigidid.cli import main
sys.argv = ["rigidid", *sys.argv[1:]]
main()
"""
)


def _uff_case(folder: Path, channels: int, samples: int) -> tuple[Path, Path, Path]:
    from rigidid.io.uff import write_uff_test

    npy, layout = folder / f"record_{channels}x{samples}.npy", folder / f"layout{channels}.json"
    if not (npy.exists() and layout.exists()):
        raise SystemExit(f"{npy} or {layout} missing: run modes_speed.py --floor {channels}x{samples} --keep {folder}")
    uff = folder / f"record_{channels}x{samples}.uff"
    if not uff.exists():
        lay = json.loads(layout.read_text())
        for sensor in lay["sensors"]:  # UFF directions lie along axes: the largest component's
            d = np.asarray(sensor["direction"], dtype=float)
            k = int(np.argmax(np.abs(d)))
            sensor["direction"] = [float(np.sign(d[k])) if i == k else 0.0 for i in range(3)]
        table = np.load(npy, mmap_mode="r")
        ids = [s["id"] for s in lay["sensors"]]
        write_uff_test(uff, lay, [(np.asarray(table[:, 0]), np.asarray(table[:, 1:]), ids)])
    return uff, npy, layout


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cases-dir", required=True, help="where modes_speed.py --keep wrote the records")
    parser.add_argument("--cases", default="8x1000000,32x1000000", help="comma-separated CHANNELSxSAMPLES")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    folder = Path(args.cases_dir)
    for case in args.cases.split(","):
        channels, samples = (int(v) for v in case.split("x"))
        t0 = time.perf_counter()
        uff, npy, layout = _uff_case(folder, channels, samples)
        print(f"\n{channels} channels x {samples} samples: UFF {uff.stat().st_size / 1e6:.0f} MB "
              f"(ready in {time.perf_counter() - t0:.0f} s); medians of {args.repeat} interleaved runs")  # fmt: skip
        commands = {
            "rigidid modes UFF (native 58b)": [sys.executable, "-c", CLI_CODE, "modes", str(uff), "-o",
                                               str(folder / "u1.csv")],
            "rigidid modes UFF (pyuff, before)": [sys.executable, "-c", PYUFF_CODE, "modes", str(uff), "-o",
                                                  str(folder / "u2.csv")],
            "rigidid modes .npy": [sys.executable, "-c", CLI_CODE, "modes", str(layout), str(npy), "-o",
                                   str(folder / "u3.csv")],
        }  # fmt: skip
        runs: dict[str, list[tuple[float, float]]] = {name: [] for name in commands}
        for _ in range(args.repeat):
            for name, cmd in commands.items():
                runs[name].append(_run_peak(cmd, folder))
        print(f"{'contender':<36} {'wall s':>7} {'peak MB':>8}")
        for name, values in runs.items():
            wall = float(np.median([w for w, _ in values]))
            peak = float(np.median([m for _, m in values]))
            print(f"{name:<36} {wall:>7.2f} {peak:>8.0f}")
        a, b = (np.loadtxt(folder / f"u{k}.csv", delimiter=",", skiprows=1, usecols=(1, 2, 4, 5)) for k in (1, 2))
        print(f"UFF modes (frequency, damping, shapes) with the native reader and the pyuff-read ones: largest "
              f"difference {np.max(np.abs(a - b)):.1e}")  # fmt: skip


if __name__ == "__main__":
    main()
