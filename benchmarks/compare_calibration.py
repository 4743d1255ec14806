"""How well `rigidid compare --sigma K` separates a repeated test from a changed body.

Two independent simulated tests of the engine of `samples/engine-test` (the body on its
mounts, modes with seeded noise on frequencies, damping and shapes), each identified
with Monte Carlo intervals that assume the same noise. Printed:

- false alarms: the share of pairs of tests of the *same* body that `compare`
  (`--rtol 1e-9`, i.e. standard errors only, `--sigma 3`) calls a regression, per
  figure, judged on its entries with standard errors (CG, inertia, principal moments,
  the stiffness diagonal: the result JSON gives no standard error off the diagonal);
- detection: the share of pairs flagged when the second body's mounts are 10 % stiffer
  (the stiffness diagonal should be flagged) or its CG 20 mm higher (the CG should);
- calibration: the share of entries of the same-body pairs within 1, 2 and 3 combined
  standard errors, against 0.683, 0.954 and 0.997 for a Gaussian.

Run: `PYTHONPATH=src python benchmarks/compare_calibration.py [--pairs N] [--draws N]`.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from rigidid import api
from rigidid.compare import compare_results
from rigidid.jsonout import result_to_dict
from rigidid.models import BodyFile

CASE = Path(__file__).resolve().parent.parent / "samples" / "engine-test"
NOISE = {"frequency": 0.002, "damping": 0.03, "shape": 0.01}
WITH_SE = ("center_of_gravity", "inertia_tensor", "principal_moments", "stiffness_force")


def _test(body: BodyFile, seed: int, draws: int) -> dict[str, Any]:
    modes = api.simulate(
        body,
        CASE / "layout.json",
        frequency_noise=NOISE["frequency"],
        damping_noise=NOISE["damping"],
        shape_noise=NOISE["shape"],
        seed=seed,
    )
    result = api.identify(CASE / "layout.json", modes, uncertainty=draws, noise=NOISE, seed=seed + 10_000)
    return result_to_dict(result)


def _changed(body: BodyFile, kind: str) -> BodyFile:
    data = json.loads(body.model_dump_json())
    if kind == "stiffer":
        for mount in data["mounts"]:
            mount["stiffness"] = (1.1 * np.asarray(mount["stiffness"])).tolist()
    else:
        data["center_of_gravity"][2] += 20.0
    return BodyFile.model_validate(data)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=100)
    parser.add_argument("--draws", type=int, default=300)
    args = parser.parse_args()
    body = BodyFile.model_validate_json((CASE / "body.json").read_text())
    variants = {
        "same body": body,
        "mounts 10 % stiffer": _changed(body, "stiffer"),
        "CG 20 mm higher": _changed(body, "cg"),
    }
    start = time.perf_counter()
    flagged = {name: {f: 0 for f in WITH_SE} for name in variants}
    within = np.zeros(3)
    entries = 0
    for k in range(args.pairs):
        reference = _test(body, 2 * k, args.draws)
        for name, variant in variants.items():
            comparison = compare_results(_test(variant, 2 * k + 1, args.draws), reference, rtol=1e-9, sigma=3.0)
            for figure in comparison.figures:
                judged = [e for e in figure.entries if e.sigma is not None]  # the diagonal of K
                if figure.name in WITH_SE and not all(e.passed(3.0) for e in judged):
                    flagged[name][figure.name] += 1
                if name == "same body" and figure.name in WITH_SE:
                    for e in figure.entries:
                        if e.sigma and e.difference is not None:
                            ratio = abs(e.difference) / e.sigma
                            within += [ratio <= 1, ratio <= 2, ratio <= 3]
                            entries += 1
    print(f"engine-test body, noise {NOISE}, {args.pairs} pairs, {args.draws} Monte Carlo draws per test, "
          f"{time.perf_counter() - start:.0f} s")  # fmt: skip
    print(f"{'second test':<22}" + "".join(f"{f:>20}" for f in WITH_SE))
    for name in variants:
        print(f"{name:<22}" + "".join(f"{flagged[name][f] / args.pairs:>20.2f}" for f in WITH_SE))
    print(f"same body, {entries} entries with standard errors: within 1, 2, 3 combined SE: "
          + ", ".join(f"{v / entries:.3f}" for v in within) + " (Gaussian: 0.683, 0.954, 0.997)")  # fmt: skip


if __name__ == "__main__":
    main()
