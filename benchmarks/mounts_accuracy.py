"""The mount model beside the free 6x6 route under measurement noise (not a test; prints figures).

Scenario: the body, mounts and 12-sensor layout of ``noise_accuracy.py`` (136 lb, three
identical mounts at one height), the same noise per draw (1 % complex on shapes, 0.1 % on
frequencies, 5 % on damping ratios). Each draw is identified three ways: the free route
(``identify``, six modes), the mount model with six modes and the mount model with five
(the highest mode dropped: the free route cannot run on five).

Run: ``python benchmarks/mounts_accuracy.py [--draws 200] [--seed 1]``
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

from noise_accuracy import scenario
from rigidid.core.identify import identify
from rigidid.core.mounts import fit_mount_model
from rigidid.core.simulate import add_noise, body_modes
from rigidid.errors import RigididError


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--draws", type=int, default=200)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    body, positions, directions = scenario()
    mounts = np.array([m.position for m in body.mounts])
    exact = body_modes(body, positions, directions)
    span = max(np.linalg.norm(a - b) for a in positions for b in positions)
    truth = np.diag(body.inertia_tensor)
    rng = np.random.default_rng(args.seed)
    errors: dict[str, list[tuple[float, float]]] = {"free, 6 modes": [], "mounts, 6 modes": [], "mounts, 5 modes": []}
    seconds = dict.fromkeys(errors, 0.0)
    failed = dict.fromkeys(errors, 0)

    def record(name: str, cg: np.ndarray, inertia: np.ndarray) -> None:
        errors[name].append(
            (100.0 * np.linalg.norm(cg - body.center_of_gravity) / span,
             100.0 * np.max(np.abs(np.diag(inertia) - truth) / truth))
        )  # fmt: skip

    for _ in range(args.draws):
        modes = add_noise(exact, frequency=0.001, damping=0.05, shape=0.01, rng=rng)
        start = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                free = identify(positions, directions, modes.poles, modes.shapes, mass=body.mass)
                record("free, 6 modes", free.center_of_gravity, body.mass * free.inertia_per_mass)
            except RigididError:
                failed["free, 6 modes"] += 1
        seconds["free, 6 modes"] += time.perf_counter() - start
        for name, n in (("mounts, 6 modes", 6), ("mounts, 5 modes", 5)):
            start = time.perf_counter()
            fit = fit_mount_model(positions, directions, modes.poles[:n], modes.shapes[:, :n], mounts)
            seconds[name] += time.perf_counter() - start
            record(name, fit.center_of_gravity, body.mass * fit.inertia_per_mass)
    print(f"{args.draws} draws, seed {args.seed}: noise_accuracy.py's body, 3 identical mounts, 12 sensors")
    print(f"{'route':18} {'CG median':>10} {'CG p90':>8} {'J median':>9} {'J p90':>8} {'failed':>7} {'ms/draw':>8}")
    for name, values in errors.items():
        arr = np.array(values)
        cg, j = arr[:, 0], arr[:, 1]
        print(
            f"{name:18} {np.median(cg):9.3f}% {np.percentile(cg, 90):7.3f}% {np.median(j):8.2f}% "
            f"{np.percentile(j, 90):7.2f}% {failed[name]:7d} {1000 * seconds[name] / args.draws:8.2f}"
        )
    print("CG error: % of the largest sensor-to-sensor distance; J error: worst of the inertia diagonal (%).")


if __name__ == "__main__":
    main()
