"""What a report costs: README's four ``rigidid report`` commands, and one report in this process.

The commands run in a copy of ``samples/engine-test`` (so nothing is written into the tree), in
rounds; the median CPU seconds of each process (user + system, which machine load does not inflate
as it does wall time) are printed. Then, in this process, one report of the sample's modes (alone,
with its PNG files, with the mounts and the torque roll axis): the best of a few (issue 20).

The processes run this tree's source (``src``) with its byte code cached, after one warm-up round.

Run: ``PYTHONPATH=src python benchmarks/report_cost.py [--rounds 3]``
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SAMPLE = Path(__file__).resolve().parent.parent / "samples" / "engine-test"
SRC = Path(__file__).resolve().parent.parent / "src"

COMMANDS = {
    "modes --png": ["layout.json", "modes.csv", "-o", "report.html", "--png", "figures/"],
    "modes --mounts --torque-axis": ["layout.json", "modes.csv", "--mounts", "mounts.json", "--torque-axis", "y",
                                     "-o", "report.html"],
    "--records --mounts": ["layout.json", "--records", "hit1.csv", "hit2.csv", "--mounts", "mounts.json",
                           "-o", "report.html"],
    "--frf --references": ["layout.json", "--frf", "frf.csv", "--references", "refs.json", "-o", "frf-report.html"],
}  # fmt: skip


def _cpu_of(args: list[str], folder: Path, env: dict[str, str]) -> float:
    """CPU seconds (user + system) of one ``rigidid report`` process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([sys.executable, "-m", "rigidid", "report", *args], cwd=folder, env=env, check=True,
                   capture_output=True)  # fmt: skip
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def commands(rounds: int) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "engine-test"
        shutil.copytree(SAMPLE, folder)
        # this tree's source, its byte code cached as a user's Python caches it (one warm-up round)
        env = {key: value for key, value in os.environ.items() if key != "PYTHONDONTWRITEBYTECODE"}
        env.update(PYTHONPATH=str(SRC), PYTHONPYCACHEPREFIX=str(Path(tmp) / "pycache"))
        times: dict[str, list[float]] = {name: [] for name in COMMANDS}
        for round_ in range(rounds + 1):
            for name, args in COMMANDS.items():
                cpu = _cpu_of(args, folder, env)
                if round_:
                    times[name].append(cpu)
    print(f"README's report commands, CPU s per process (median of {rounds}):")
    for name, values in times.items():
        print(f"  report {name:<30s} {statistics.median(values):6.2f}")
    print(f"  {'sum':<37s} {sum(statistics.median(v) for v in times.values()):6.2f}")


def figures(repeats: int) -> None:
    import rigidid
    from rigidid import api

    modes = rigidid.identify(SAMPLE / "layout.json", SAMPLE / "modes.csv")
    mounted = api.with_mounts(modes, SAMPLE / "mounts.json", torque_axis=(0.0, 1.0, 0.0))
    rigidid.report(modes)  # imports and font caches once
    best: dict[str, list[float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(repeats):
            for name, call in (
                ("modes", lambda: rigidid.report(modes)),
                ("modes, --png", lambda: rigidid.report(modes, png=Path(tmp) / "png")),
                ("mounts, roll axis", lambda: rigidid.report(mounted)),
            ):
                start = time.process_time()
                call()
                best.setdefault(name, []).append(time.process_time() - start)
    print(f"In-process, CPU s of one report of the sample (best of {repeats}):")
    for name, values in best.items():
        print(f"  {name:<18s} {min(values):6.3f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=3)
    options = parser.parse_args()
    commands(options.rounds)
    figures(options.repeats)


if __name__ == "__main__":
    main()
