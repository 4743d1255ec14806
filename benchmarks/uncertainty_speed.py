"""Speed of the Monte Carlo uncertainty propagation (not a test; prints figures).

Scenario: the paper's sample (six accelerometers, the six modes of its Table 2
as raw sensor readings, 136 lb), every kind of noise switched on: 0.1 % on
frequencies, 5 % on damping ratios, 1 % complex on shapes, 0.02 in on sensor
positions, 1 degree on sensor directions. Target: 10 000 draws in under 5 s on
a 2-core machine (numpy's batched linear algebra, one process).

Run: ``python benchmarks/uncertainty_speed.py [--draws 10000] [--repeat 3] [--seed 1]``
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np

from rigidid.api import load_arrays
from rigidid.core.noise import NoiseLevels
from rigidid.core.uncertainty import propagate
from rigidid.jsonout import noise_to_dict

PAPER = Path(__file__).resolve().parent.parent / "samples" / "paper-1994"
NOISE = NoiseLevels(frequency=0.001, damping=0.05, shape=0.01, position=0.02, angle_deg=1.0)


def paper_sample() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """Positions (in), directions, poles (rad/s), raw shapes and mass (lb) of the paper's test."""
    case = load_arrays(PAPER / "layout.json", PAPER / "modes.csv")
    assert case.mass is not None
    return case.positions, case.directions, case.poles, case.shapes, case.mass


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--draws", type=int, default=10_000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    pos, dirs, poles, shapes, mass = paper_sample()
    times = []
    result = None
    for _ in range(args.repeat):
        start = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = propagate(pos, dirs, poles, shapes, mass=mass, noise=NOISE, draws=args.draws, seed=args.seed)
        times.append(time.perf_counter() - start)
    assert result is not None
    print(f"paper sample, {args.draws} draws, noise {noise_to_dict(NOISE)}")
    print(f"time: best {min(times):.2f} s, all {', '.join(f'{t:.2f}' for t in times)} s "
          f"({1e6 * min(times) / args.draws:.0f} us per draw); failed draws {result.failed}, "
          f"implausible {result.implausible}")  # fmt: skip
    cg, pm = result.center_of_gravity, result.principal_moments
    for name, q, unit in (("CG", cg, "in"), ("principal moments", pm, "lb in^2")):
        print(f"{name} ({unit}):")
        for est, std, lo, hi in zip(q.estimate, q.std, q.low, q.high, strict=True):
            print(f"  {est:10.4g}  std {std:9.3g}  95 % [{lo:10.4g}, {hi:10.4g}]")


if __name__ == "__main__":
    main()
