"""Accuracy of the estimators under measurement noise (not a test; prints figures).

Scenario: a 136 lb body like the paper's (CG 1.4 in below the top surface,
inertia diagonal 2652, 3087, 5440 lb in^2 with small products), on three
identical mounts at one height, 12 sensors; non-proportional damping. Each
draw adds 1 % complex noise to the shapes, 0.1 % to the frequencies and 5 % to
the damping ratios (see rigidid.core.simulate.add_noise), then identifies the
body with the default estimator and with ``method="paper"``.

Run: ``python benchmarks/noise_accuracy.py [--draws 200] [--seed 1]``
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

from rigidid.core.identify import identify
from rigidid.core.simulate import Body, Mount, add_noise, body_modes
from rigidid.errors import RigididError


def scenario() -> tuple[Body, np.ndarray, np.ndarray]:
    """The benchmark body (lb, in) and its 12-sensor layout."""
    inertia = np.array([[2652.0, 40.0, -25.0], [40.0, 3087.0, 15.0], [-25.0, 15.0, 5440.0]])
    # Identical mounts (same stiffness and damping) at one height, placed around the
    # CG as an engine's would be: not symmetric about it, so every rotation couples
    # to a translation. Damping is not proportional to stiffness axis by axis.
    mounts = tuple(
        Mount.from_values([x, y, -2.5], [45000.0, 45000.0, 70000.0], [60.0, 60.0, 35.0])
        for x, y in ((7.0, 3.0), (-6.0, 4.5), (-2.0, -6.0))
    )
    body = Body(136.0, np.array([0.0, 0.0, -1.4]), inertia, mounts)
    positions = np.array(
        [
            [6.75, 1.5, 0.0],
            [2.0, 5.7, -0.8],
            [7.25, 2.0, 0.75],
            [-8.4, 0.75, -3.25],
            [4.5, -4.0, 0.0],
            [-9.0, -0.7, -2.5],
            [-6.0, 4.0, 0.0],
            [0.0, -4.5, -1.0],
            [8.5, -2.0, -1.5],
            [-3.0, -4.5, 0.0],
            [-7.5, 3.0, -1.0],
            [3.0, 4.5, -2.0],
        ]
    )
    axes = np.eye(3)
    directions = (
        np.array([axes[k] for k in (2, 0, 1, 1, 2, 2, 2, 1, 0, 2, 0, 1)])
        * np.array([1, 1, -1, 1, 1, -1, 1, 1, -1, 1, 1, -1])[:, None]
    )
    return body, positions, directions


def run(draws: int, seed: int, **options: object) -> dict[str, dict[str, np.ndarray]]:
    """Errors per draw for each estimator: CG (% of sensor span), inertia diagonal (%)."""
    body, positions, directions = scenario()
    exact = body_modes(body, positions, directions)
    span = max(np.linalg.norm(a - b) for a in positions for b in positions)
    rng = np.random.default_rng(seed)
    noisy = [add_noise(exact, frequency=0.001, damping=0.05, shape=0.01, rng=rng) for _ in range(draws)]
    truth = np.diag(body.inertia_tensor)
    out: dict[str, dict[str, np.ndarray]] = {}
    for method in ("structured", "paper"):
        cg_err, j_err, failed = [], [], 0
        start = time.perf_counter()
        for modes in noisy:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                try:
                    r = identify(
                        positions, directions, modes.poles, modes.shapes, mass=body.mass, method=method, **options
                    )  # type: ignore[arg-type]
                except RigididError:
                    failed += 1
                    cg_err.append(np.inf)
                    j_err.append(np.inf)
                    continue
            assert r.inertia_tensor is not None
            cg_err.append(100.0 * np.linalg.norm(r.center_of_gravity - body.center_of_gravity) / span)
            j_err.append(100.0 * np.max(np.abs(np.diag(r.inertia_tensor) - truth) / truth))
        out[method] = {
            "cg": np.array(cg_err),
            "inertia": np.array(j_err),
            "failed": np.array(failed),
            "seconds": np.array(time.perf_counter() - start),
        }
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--draws", type=int, default=200)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    results = run(args.draws, args.seed)
    print(f"{args.draws} draws, seed {args.seed}: 12 sensors, 3 identical mounts at one height,")
    print("noise 1 % complex on shapes, 0.1 % on frequencies, 5 % on damping ratios")
    print(f"{'method':<12}{'CG median':>11}{'CG p90':>9}{'J median':>10}{'J p90':>8}{'failed':>8}{'ms/draw':>9}")
    for method, r in results.items():
        cg, j = r["cg"], r["inertia"]
        print(
            f"{method:<12}{np.median(cg):>10.3f}%{np.percentile(cg, 90):>8.3f}%"
            f"{np.median(j):>9.2f}%{np.percentile(j, 90):>7.2f}%{int(r['failed']):>8}"
            f"{1000 * float(r['seconds']) / args.draws:>9.2f}"
        )
    print("CG error: |cg - truth| as % of the largest sensor-to-sensor distance;")
    print("J error: largest relative error of the three inertia-diagonal entries.")


if __name__ == "__main__":
    main()
