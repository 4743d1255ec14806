"""The mount model beside the free 6x6 route under measurement noise, and its F test (prints figures).

Scenario: the body, mounts and 12-sensor layout of ``noise_accuracy.py`` (136 lb, three
identical mounts at one height), the same noise per draw (1 % complex on shapes, 0.1 % on
frequencies, 5 % on damping ratios). Each draw is identified by the free route
(``identify``, six modes) and by the mount model (``fit_mount_model``):

- ``equation error``: the eigenproblem residual only (no noise levels);
- ``independent``: refined by the noise-weighted output-error fit (the default of
  ``rigidid identify --method mounts``), every mount with its own three rates;
- ``estimated noise``: as ``independent`` but weighted as ``rigidid identify`` does by default:
  0.1 % and 5 % on frequencies and damping, the shape noise measured from each draw's
  rigid-body fit (``estimate_noise``);
- ``one group``: the three mounts declared identical (``"group"`` in mounts.json);

each with six modes and with five (the highest dropped: the free route cannot run on
five). The F test's verdict is counted on the same draws (correct model: the share
flagged should be about ``ADEQUATE_P``), and on a body with a hidden support that
``mounts.json`` does not list (``--hose``: a hose of that stiffness, as a fraction of a
mount's vertical rate, at the body's side).

Run: ``python benchmarks/mounts_accuracy.py [--draws 200] [--seed 1] [--hose 0.1]``
"""

from __future__ import annotations

import argparse
import dataclasses
import time
import warnings
from typing import Any

import numpy as np

from noise_accuracy import scenario
from rigidid.core.identify import identify
from rigidid.core.mounts import fit_mount_model
from rigidid.core.noise import DEFAULT_NOISE, estimate_noise
from rigidid.core.simulate import Mount, add_noise, body_modes
from rigidid.errors import RigididError

ROUTES: dict[str, dict[str, Any]] = {
    "equation error": {"noise": None},
    "independent": {"noise": DEFAULT_NOISE},
    "estimated noise": {"noise": "estimated"},
    "one group": {"noise": DEFAULT_NOISE, "groups": ["engine", "engine", "engine"]},
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--draws", type=int, default=200)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--hose", type=float, default=0.1, help="hidden support, fraction of a mount's z rate")
    args = parser.parse_args()
    body, positions, directions = scenario()
    mounts = np.array([m.position for m in body.mounts])
    exact = body_modes(body, positions, directions)
    k_z = float(body.mounts[0].stiffness[2, 2])
    hose = Mount.from_values([0.0, 8.0, 0.0], [args.hose * k_z] * 3, [0.0, 0.0, 0.0])
    hosed = body_modes(dataclasses.replace(body, mounts=(*body.mounts, hose)), positions, directions)
    span = max(np.linalg.norm(a - b) for a in positions for b in positions)
    truth = np.diag(body.inertia_tensor)
    rng = np.random.default_rng(args.seed)
    names = ["free, 6 modes"] + [f"{r}, {n} modes" for r in ROUTES for n in (6, 5)]
    errors: dict[str, list[tuple[float, float]]] = {name: [] for name in names}
    seconds = dict.fromkeys(names, 0.0)
    failed = dict.fromkeys(names, 0)
    flagged = dict.fromkeys(names, 0)
    hose_flagged = dict.fromkeys(names, 0)

    def record(name: str, cg: np.ndarray, inertia: np.ndarray) -> None:
        errors[name].append(
            (100.0 * np.linalg.norm(cg - body.center_of_gravity) / span,
             100.0 * np.max(np.abs(np.diag(inertia) - truth) / truth))
        )  # fmt: skip

    for _ in range(args.draws):
        modes = add_noise(exact, frequency=0.001, damping=0.05, shape=0.01, rng=rng)
        noisy_hose = add_noise(hosed, frequency=0.001, damping=0.05, shape=0.01, rng=rng)
        start = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                free = identify(positions, directions, modes.poles, modes.shapes, mass=body.mass)
                record("free, 6 modes", free.center_of_gravity, body.mass * free.inertia_per_mass)
            except RigididError:
                failed["free, 6 modes"] += 1
        seconds["free, 6 modes"] += time.perf_counter() - start
        for route, options in ROUTES.items():
            for n in (6, 5):
                name = f"{route}, {n} modes"
                start = time.perf_counter()
                if options["noise"] == "estimated":
                    options = {"noise": estimate_noise(positions, directions, modes.shapes[:, :n])}
                fit = fit_mount_model(positions, directions, modes.poles[:n], modes.shapes[:, :n], mounts, **options)
                seconds[name] += time.perf_counter() - start
                record(name, fit.center_of_gravity, body.mass * fit.inertia_per_mass)
                flagged[name] += fit.adequate is False
                if options["noise"] is not None:
                    if route == "estimated noise":
                        options = {"noise": estimate_noise(positions, directions, noisy_hose.shapes[:, :n])}
                    bad = fit_mount_model(
                        positions, directions, noisy_hose.poles[:n], noisy_hose.shapes[:, :n], mounts, **options
                    )
                    hose_flagged[name] += bad.adequate is False
    print(f"{args.draws} draws, seed {args.seed}: noise_accuracy.py's body, 3 identical mounts, 12 sensors")
    print(
        f"{'route':24} {'CG median':>10} {'CG p90':>8} {'CG max':>8} {'J median':>9} {'J p90':>8} {'J max':>7} "
        f"{'failed':>7} {'ms/draw':>8} "
        f"{'flagged':>8} {'hose flagged':>13}"
    )
    for name, values in errors.items():
        arr = np.array(values)
        cg, j = arr[:, 0], arr[:, 1]
        test = name.startswith(("independent", "estimated", "one group"))
        print(
            f"{name:24} {np.median(cg):9.3f}% {np.percentile(cg, 90):7.3f}% {np.max(cg):7.3f}% {np.median(j):8.2f}% "
            f"{np.percentile(j, 90):7.2f}% {np.max(j):6.2f}% {failed[name]:7d} "
            f"{1000 * seconds[name] / args.draws:8.2f} "
            + (
                f"{100 * flagged[name] / args.draws:7.1f}% {100 * hose_flagged[name] / args.draws:12.1f}%"
                if test
                else ""
            )
        )
    print("CG error: % of the largest sensor-to-sensor distance; J error: worst of the inertia diagonal (%).")
    print(f"flagged: F test p < 0.01 on the correct model; hose flagged: with a hidden {args.hose:g} x k_z support.")


if __name__ == "__main__":
    main()
