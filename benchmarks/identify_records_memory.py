"""`rigidid identify LAYOUT --records REC` (the default refit): wall time and peak memory (not a test).

For each case (the records ``modes_speed.py --floor ... --keep DIR`` writes, ``.npy`` or CSV), in
fresh processes, interleaved ``--repeat`` times:

- ``identify --records`` as shipped: the record files read block by block and pre-decimated while
  read (``api.load_records_decimated``), the refit on those;
- the same with ``load_records_decimated`` replaced by a whole read at the file's rate (the route
  before this change: the raw records held, the refit decimating them itself).

It prints medians of wall time (start-up included) and peak resident memory (the child's VmHWM),
how the peak grows from the first case to the last (same channels), and the CG, its standard error
and the normalised cost of both routes.

Run: ``python benchmarks/identify_records_memory.py --cases-dir /tmp/cases --cases 8x1000000,8x10000000``
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from modes_speed import CLI_CODE, PEAK_PREAMBLE, _run_peak

WHOLE_CODE = (
    PEAK_PREAMBLE
    + """
import sys
from rigidid import api

def whole(paths, layout, *, keep_values, progress=None):  # the raw records, as before
    records = api.load_records(paths, layout)
    return api.DecimatedRecords(records, 1, [0] * len(records), 0)

api.load_records_decimated = whole
from rigidid.cli import main
sys.argv = ["rigidid", *sys.argv[1:]]
main()
"""
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cases-dir", required=True, help="where modes_speed.py --keep wrote the records")
    parser.add_argument("--cases", default="8x1000000,8x10000000", help="comma-separated CHANNELSxSAMPLES")
    parser.add_argument("--suffix", default=".npy", help="record format: .npy or .csv")
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args()
    folder = Path(args.cases_dir)
    peaks: dict[str, list[float]] = {"pre-decimated": [], "whole": []}
    for case in args.cases.split(","):
        channels, samples = (int(v) for v in case.split("x"))
        record = folder / f"record_{channels}x{samples}{args.suffix}"
        layout = folder / f"layout{channels}.json"
        out = {name: folder / f"identify_{name}.json" for name in peaks}
        commands = {
            "pre-decimated": [sys.executable, "-c", CLI_CODE, "identify", str(layout), "--records", str(record),
                              "--json", str(out["pre-decimated"])],
            "whole": [sys.executable, "-c", WHOLE_CODE, "identify", str(layout), "--records", str(record),
                      "--json", str(out["whole"])],
        }  # fmt: skip
        runs: dict[str, list[tuple[float, float]]] = {name: [] for name in commands}
        for _ in range(args.repeat):
            for name, cmd in commands.items():
                runs[name].append(_run_peak(cmd, folder))
        print(f"\n{channels} channels x {samples} samples ({record.name}); medians of {args.repeat} interleaved runs")
        print(f"{'route':<16} {'wall s':>7} {'peak MB':>8}  CG (m), its std, normalised cost")
        for name, values in runs.items():
            wall = float(np.median([w for w, _ in values]))
            peak = float(np.median([m for _, m in values]))
            peaks[name].append(peak)
            data = json.loads(out[name].read_text())
            crb = data["uncertainty_records_crb"]
            cg = np.round(data["center_of_gravity"], 7).tolist()
            std = np.round(crb["center_of_gravity"]["std"], 8).tolist()
            print(f"{name:<16} {wall:>7.2f} {peak:>8.0f}  {cg} +- {std}, {crb['normalised_cost']:.3f}")
    for name, values in peaks.items():
        if len(values) > 1:
            print(f"peak growth, {name}: {values[0]:.0f} -> {values[-1]:.0f} MB ({values[-1] / values[0]:.2f}x)")


if __name__ == "__main__":
    main()
