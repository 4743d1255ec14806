"""Start-up cost: ``rigidid identify`` on the paper sample against importing its stack.

The stack is ``python -c "import numpy, typer, rich.console, pydantic"``; the commands run
alternately in one loop (so machine load hits all alike); the medians and their ratios are
printed (CPU seconds of each process, which machine load does not inflate as it does wall
time). The target (issue 20) is ``--json -`` within 1.2x of the stack.

Two floors bound what any pydantic boundary can reach: the stack plus validating the
paper's layout with rigidid's own models, and the stack plus the smallest model a layout
can have (units, mass, a list of sensors with id, position and direction), defined and
validated. ``import pydantic`` is lazy (``BaseModel`` loads on first use), so the stack's
figure holds none of the cost of defining and validating a model.

Run: ``python benchmarks/startup.py [--rounds 20]``
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
from pathlib import Path

SAMPLE = Path(__file__).resolve().parent.parent / "samples" / "paper-1994"


# As a user's Python runs: byte code cached (an environment that sets PYTHONDONTWRITEBYTECODE would
# otherwise compile rigidid's modules at every start, while the stack's come compiled from their wheels).
ENV = {key: value for key, value in os.environ.items() if key != "PYTHONDONTWRITEBYTECODE"}


MINIMAL = """
import json, numpy, typer, rich.console, pydantic
from typing import Literal
from pydantic import BaseModel
class Units(BaseModel):
    length: Literal["m", "cm", "mm", "in", "ft"] = "m"
    mass: Literal["kg", "g", "lb"] = "kg"
class Sensor(BaseModel):
    id: str
    position: tuple[float, float, float]
    direction: tuple[float, float, float] | str
class Layout(BaseModel):
    units: Units = Units()
    mass: float | None = None
    sensors: list[Sensor]
Layout.model_validate(json.load(open({layout!r})))
"""
"""The smallest pydantic boundary a layout file can have (the paper's layout validates)."""


def _wall(cmd: list[str]) -> float:
    """CPU seconds (user + system) of one run: steadier than wall time on a busy machine."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=ENV)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=20)
    args = parser.parse_args()
    numpy_cmd = [sys.executable, "-c", "import numpy, typer, rich.console, pydantic"]
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
    layout = SAMPLE / "layout.json"
    floor_cmd = [
        sys.executable,
        "-c",
        "import numpy, typer, rich.console, pydantic; from rigidid.models import LayoutFile; "
        f"LayoutFile.model_validate_json(open({str(layout)!r}).read())",
    ]
    minimal_cmd = [sys.executable, "-c", MINIMAL.format(layout=str(layout))]
    times: dict[str, list[float]] = {"stack": [], "minimal": [], "floor": [], **{k: [] for k in cases}}
    for cmd in (numpy_cmd, minimal_cmd, floor_cmd, *cases.values()):  # warm: byte code written, files in the page cache
        _wall(cmd)
    for _ in range(args.rounds):
        times["stack"].append(_wall(numpy_cmd))
        times["minimal"].append(_wall(minimal_cmd))
        times["floor"].append(_wall(floor_cmd))
        for name, cmd in cases.items():
            times[name].append(_wall(cmd))
    base = statistics.median(times["stack"])
    print(f"{args.rounds} alternating rounds, medians:")
    floor = statistics.median(times["floor"])
    print(f"  import numpy, typer, rich, pydantic {1000 * base:7.1f} ms")
    minimal = statistics.median(times["minimal"])
    print(f"  + the smallest layout model         {1000 * minimal:7.1f} ms   ratio {minimal / base:.2f}")
    print(f"  + the layout validated (pydantic)   {1000 * floor:7.1f} ms   ratio {floor / base:.2f}")
    for name in cases:
        med = statistics.median(times[name])
        print(f"  rigidid identify paper ({name:8s}) {1000 * med:7.1f} ms   ratio {med / base:.2f}")


if __name__ == "__main__":
    main()
