"""`rigidid identify LAYOUT --records REC` (the default refit): wall time and peak memory (not a test).

For each case (the records ``modes_speed.py --floor ... --keep DIR`` writes, ``.npy`` or CSV), in
fresh processes, interleaved ``--repeat`` times:

- ``row blocks``: ``identify --records`` as shipped: the modes estimated from the files read block by
  block and decimated as they arrive (as ``rigidid modes``), the refit's impacts, pre-trigger
  statistics and decays at the fit's rate captured in the same read (issue 23; the files read again
  in row blocks, ``api.refine_records``, only when that capture is refused);
- ``whole``: the same with ``api.STREAM_REFIT_VALUES`` raised so far that the refit reads the raw
  records whole (the refit's numbers of a whole read);
- ``before`` (with ``--before-src DIR``, the ``src`` folder of an older checkout, e.g.
  ``git archive <commit> src | tar -x -C DIR``): that version's ``identify --records``;
- ``modes`` (with ``--modes``): ``rigidid modes`` on the same file, the issue's yardstick (the
  refit within 1.5x of its time).

It prints medians of wall time (start-up included), of CPU time (user + system of the child: on a
shared machine the figure to compare) and of peak resident memory (the child's VmHWM), each
route's times over ``modes``'s, how the peak grows from the first case to the last (same
channels), and the CG, its standard error and the normalised cost of every identify route, and the
CG's largest error against the simulated body in its noise standard errors (``sensor_budget.noise``,
the sensors' tolerances aside).

Run: ``python benchmarks/identify_records_memory.py --cases-dir /tmp/cases --cases 8x1000000,8x10000000``
(``--suffix .csv --modes`` for the issue's CSV figures; the records as ``modes_speed.py --keep`` writes them)
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from modes_speed import CLI_CODE, PEAK_PREAMBLE
from records_scenario import CG

WHOLE_CODE = (
    PEAK_PREAMBLE
    + """
import sys
from rigidid import api

api.STREAM_REFIT_VALUES = 10**18  # the refit reads the raw records whole
from rigidid.cli import main
sys.argv = ["rigidid", *sys.argv[1:]]
main()
"""
)


def _run_peak(cmd: list[str], folder: Path, src: str | None) -> tuple[float, float, float]:
    """Wall time (s), CPU time (s, user + system) and peak resident memory (MB, VmHWM) of a child process."""
    peak_file = folder / "peak.txt"
    env = {**os.environ, "RIGIDID_BENCH_PEAK": str(peak_file)}
    if src is not None:
        env["PYTHONPATH"] = src
    used = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    out = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if out.returncode:
        raise SystemExit(f"{' '.join(cmd[3:6])}... failed with exit status {out.returncode}: {out.stderr.strip()}")
    cpu = after.ru_utime + after.ru_stime - used.ru_utime - used.ru_stime
    return wall, cpu, float(peak_file.read_text()) / 1024.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cases-dir", required=True, help="where modes_speed.py --keep wrote the records")
    parser.add_argument("--cases", default="8x1000000,8x10000000", help="comma-separated CHANNELSxSAMPLES")
    parser.add_argument("--suffix", default=".npy", help="record format: .npy or .csv")
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--before-src", help="src folder of an older checkout to measure too")
    parser.add_argument("--routes", default="row blocks,whole", help="comma-separated: row blocks, whole")
    parser.add_argument("--modes", action="store_true", help="also time `rigidid modes` on the same files")
    args = parser.parse_args()
    folder = Path(args.cases_dir)
    names = [r.strip() for r in args.routes.split(",")] + (["before"] if args.before_src else [])
    names += ["modes"] if args.modes else []
    peaks: dict[str, list[float]] = {name: [] for name in names}
    srcs = {name: (args.before_src if name == "before" else None) for name in names}
    for case in args.cases.split(","):
        channels, samples = (int(v) for v in case.split("x"))
        record = folder / f"record_{channels}x{samples}{args.suffix}"
        layout = folder / f"layout{channels}.json"
        out = {name: folder / f"identify_{name.replace(' ', '_')}.json" for name in peaks}
        codes = {"row blocks": CLI_CODE, "whole": WHOLE_CODE, "before": CLI_CODE, "modes": CLI_CODE}
        commands = {
            name: [sys.executable, "-c", codes[name], "identify", str(layout), "--records", str(record),
                   "--json", str(out[name])]
            for name in names
        }  # fmt: skip
        if "modes" in commands:
            commands["modes"] = [sys.executable, "-c", CLI_CODE, "modes", str(layout), str(record),
                                 "-o", str(folder / "modes_out.csv")]  # fmt: skip
        runs: dict[str, list[tuple[float, float, float]]] = {name: [] for name in commands}
        for _ in range(args.repeat):
            for name, cmd in commands.items():
                runs[name].append(_run_peak(cmd, folder, srcs[name]))
        print(f"\n{channels} channels x {samples} samples ({record.name}); medians of {args.repeat} interleaved runs")
        print(f"{'route':<16} {'wall s':>7} {'cpu s':>7} {'peak MB':>8}  x modes (wall, cpu)  CG (m), its std, cost")
        medians = {name: np.median(np.array(values), axis=0) for name, values in runs.items()}
        for name, (wall, cpu, peak) in medians.items():
            peaks[name].append(float(peak))
            ratio = ""
            if "modes" in medians:
                ratio = f"{wall / medians['modes'][0]:.2f}x, {cpu / medians['modes'][1]:.2f}x"
            if name == "modes":
                print(f"{name:<16} {wall:>7.2f} {cpu:>7.2f} {peak:>8.0f}  {ratio}")
                continue
            data = json.loads(out[name].read_text())
            crb = data["uncertainty_records_crb"]
            cg = np.round(data["center_of_gravity"], 7).tolist()
            std = np.round(crb["center_of_gravity"]["std"], 8).tolist()
            cost = crb["normalised_cost"]
            # the CG's error against the simulated body in its noise standard errors (the sensors' budget aside)
            noise = crb.get("sensor_budget", {}).get("noise", {}).get("center_of_gravity")
            err = np.abs(np.subtract(data["center_of_gravity"], CG))
            z = "" if noise is None else f", |error| / noise SE {np.max(err / np.asarray(noise)):.2f}"
            print(f"{name:<16} {wall:>7.2f} {cpu:>7.2f} {peak:>8.0f}  {ratio}  {cg} +- {std}, {cost:.3f}{z}")
    for name, values in peaks.items():
        if len(values) > 1:
            print(f"peak growth, {name}: {values[0]:.0f} -> {values[-1]:.0f} MB ({values[-1] / values[0]:.2f}x)")


if __name__ == "__main__":
    main()
