"""Accuracy of modal estimation from impact records, and of identification from it (not a test).

Scenario (``records_scenario.py``): the 40 kg body with modes at 8.0 to 26.1 Hz
(two 2.1 % apart), damping ratios 0.31 % to 6.9 %, complex modes; 8 sensors,
two impacts, records of 10 s at 1 kHz with 0.1 s pre-trigger (so the default
decimation applies), Gaussian noise of 0 %, 1 % and 5 % of each channel's RMS.
For each noise level and method, ``--seeds`` draws of the noise; each draw is
estimated with ``estimate_modes`` and the six modes identified with
``identify(..., mass=...)``.

Columns (median over the draws / worst draw): largest relative frequency
error of the six modes, largest relative damping-ratio error, smallest MAC
with the true shapes, CG error as a percentage of the largest sensor-to-sensor
distance, largest relative error of the three inertia-diagonal entries;
"failed" counts draws where fewer than six modes were found.

Run: ``python benchmarks/modes_accuracy.py [--seeds 10]``
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from records_scenario import BODY, CG, IMPACTS, INERTIA, MASS, layout
from rigidid.core.identify import identify
from rigidid.core.simulate import body_modes
from rigidid.core.statespace import modal_from_poles
from rigidid.core.timedomain import estimate_modes, impulse_records, mac_matrix
from rigidid.errors import RigididError

SAMPLE_RATE = 1000.0
DURATION = 10.0
PRETRIGGER = 0.1


def run(noise: float, method: str, seeds: int) -> dict[str, np.ndarray]:
    """Per-draw errors of one noise level and method (NaN for failed draws)."""
    pos, dirs = layout(8)
    true = body_modes(BODY, pos, dirs)
    f0, z0 = modal_from_poles(true.poles)
    span = max(float(np.linalg.norm(a - b)) for a in pos for b in pos)
    rows: list[list[float]] = []
    seconds = 0.0
    for seed in range(seeds):
        recs = impulse_records(
            BODY, pos, dirs, IMPACTS, sample_rate=SAMPLE_RATE, duration=DURATION, pretrigger=PRETRIGGER,
            noise=noise, seed=seed,
        )  # fmt: skip
        start = time.perf_counter()
        try:
            est = estimate_modes(recs, 1.0 / SAMPLE_RATE, method=method)  # type: ignore[arg-type]
        except RigididError:
            rows.append([np.nan] * 5)
            continue
        seconds += time.perf_counter() - start
        mac = np.diag(mac_matrix(est.shapes, true.shapes))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = identify(pos, dirs, est.poles, est.shapes, mass=MASS)
        assert result.inertia_tensor is not None
        rows.append(
            [
                float(np.max(np.abs(est.frequency_hz / f0 - 1.0))),
                float(np.max(np.abs(est.damping_ratio / z0 - 1.0))),
                float(np.min(mac)),
                100.0 * float(np.linalg.norm(result.center_of_gravity - CG)) / span,
                100.0 * float(np.max(np.abs(np.diag(result.inertia_tensor) / np.diag(INERTIA) - 1.0))),
            ]
        )
    a = np.array(rows)
    ok = max(int(np.sum(~np.isnan(a[:, 0]))), 1)
    return {"errors": a, "ms": np.array(1000.0 * seconds / ok)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=10)
    args = parser.parse_args()
    print(f"{args.seeds} noise draws per row; median / worst over the draws")
    header = (
        f"{'noise':>5} {'method':>6} | {'freq err':>17} | {'damping err':>17} | {'MAC min':>15} |"
        f" {'CG % span':>13} | {'J diag err %':>13} | {'failed':>6} {'ms':>5}"
    )
    print(header)
    print("-" * len(header))
    for noise in (0.0, 0.01, 0.05):
        for method in ("era", "ar"):
            r = run(noise, method, args.seeds)
            e = r["errors"]
            good = e[~np.isnan(e[:, 0])]
            failed = e.shape[0] - good.shape[0]
            if good.size == 0:
                print(f"{100 * noise:>4.0f}% {method:>6} | all draws failed")
                continue
            med, worst = np.median(good, axis=0), good.max(axis=0)
            worst[2] = good[:, 2].min()
            print(
                f"{100 * noise:>4.0f}% {method:>6} | {med[0]:>8.1e}/{worst[0]:>8.1e}"
                f" | {med[1]:>8.1e}/{worst[1]:>8.1e} | {med[2]:>7.5f}/{worst[2]:>7.5f}"
                f" | {med[3]:>6.3f}/{worst[3]:>6.3f} | {med[4]:>6.2f}/{worst[4]:>6.2f}"
                f" | {failed:>6} {float(r['ms']):>5.0f}"
            )


if __name__ == "__main__":
    main()
