"""``rigidid plan``'s first-order shortcuts against the Monte Carlo they replace (issue 20).

    PYTHONPATH=src python benchmarks/plan_speed.py [--mount-draws 200] [--mount-seed 0] [--skip-mounts]
        [--plan-time] [--only-plan-time]

1. ``plan --add 2`` (:func:`rigidid.core.plan.suggest_sensors`, 300 draws, the default grid of
   81 candidates): per sample with a body estimate, the sensors chosen with the first-order
   short list (:data:`rigidid.core.plan.SHORTLIST` candidates judged by the Monte Carlo) and by
   the Monte Carlo of every candidate (the short list made longer than the candidates), the
   first-order rank of the Monte Carlo's choice and of its best five, whether the five best
   (what ``--json`` shows) agree, and the CPU seconds of each.
2. ``plan --mounts`` (the mount model's predicted standard deviations): the first-order
   prediction (:func:`rigidid.core.mounts.predict_mount_model_linearised`, one fit) against the
   Monte Carlo of noisy refits (:func:`rigidid.core.mounts.predict_mount_model`), each ratio with
   the Monte Carlo's own relative error ``1 / sqrt(2 (draws - 1))``, and the share of tests the
   F test flags.

3. ``--plan-time``: ``rigidid plan LAYOUT --body BODY`` (the API, default 1000 draws) per sample with a
   body estimate, CPU seconds without and with ``--records`` (the records route's sensor budget for the
   default records test, 512 Hz, 8 s, two impacts: :func:`rigidid.core.plan.predict_records_budget`), best of 3.
   Measured (s31-plan23, 2 busy cores): without 0.24-0.39 CPU s, with ``--records`` +0.05-0.11 on the engine
   samples (1,105-1,154 of 4,096 rows per impact used) and +0.54 on four-mounts (its slow decays: all 4,096 rows).

Measured (fe3e9eb + issue 20's change, 2 busy cores, ``--mount-draws 200``):

- suggestions: the same two sensors, with bit-identical figures, on all four cases (engine-test
  with cad-estimate.json and with body.json, engine-on-mounts, four-mounts); the Monte Carlo's
  choice has first-order rank 0-7 (short list 12); the five best agree in 6 of 8 steps (in the
  other two the 4th-5th entries have first-order ranks 12-19 and are replaced by the next best
  of the short list). CPU: 2.8-3.2 s per case against 9.2-9.8 s.
- mounts, engine-test (cad-estimate.json, mounts.json), 200 refits (32 CPU s; first order 0.8):
  first order / Monte Carlo 1.03, 0.97, 1.05 for the CG, 0.98, 0.90, 1.14 for the inertia
  diagonal, 0.98-1.03 off it (the Monte Carlo's error 5 %); flagged 0.010 against 0.010. With
  the refits' seed 1 instead of 0: 1.05, 1.02, 0.94 and 0.99, 0.99, 0.98 (0.95-1.06 off the
  diagonal), flagged 0.020: the 1.14 of seed 0 was the Monte Carlo's error.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from rigidid.api.load import body_from_file
from rigidid.api.mounts import read_mount_spec
from rigidid.core import plan as plan_module
from rigidid.core.mounts import predict_mount_model, predict_mount_model_linearised
from rigidid.core.noise import DEFAULT_NOISE
from rigidid.io import files

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = ROOT / "samples"
CASES = (
    ("engine-test", "cad-estimate.json"),
    ("engine-test", "body.json"),
    ("engine-on-mounts", "body.json"),
    ("four-mounts", "body.json"),
)


def _load(case: str, body: str) -> tuple[object, np.ndarray, np.ndarray, object]:
    lay = files.load_layout(SAMPLES / case / "layout.json", require_rank=False)
    _, pos, dirs = files.layout_arrays(lay)
    return lay, pos, dirs, body_from_file(files.load_body(SAMPLES / case / body))


def _suggest(body: object, pos: np.ndarray, dirs: np.ndarray, shortlist: int) -> tuple[object, float]:
    plan_module.SHORTLIST = shortlist
    start = time.process_time()
    result = plan_module.suggest_sensors(body, pos, dirs, add=2, noise=DEFAULT_NOISE, draws=300, seed=0)  # type: ignore[arg-type]
    return result, time.process_time() - start


def _first_order_ranking(body: object, pos: np.ndarray, dirs: np.ndarray, chosen: list[int]) -> list[int]:
    """Every remaining candidate of the default grid, best first by the first-order score."""
    from rigidid.core.simulate import body_modes

    c_pos = np.repeat(plan_module.candidate_grid(pos), 3, axis=0)
    c_dir = np.tile(np.eye(3), (c_pos.shape[0] // 3, 1))
    modes = body_modes(body, np.vstack([pos, c_pos]), np.vstack([dirs, c_dir]))  # type: ignore[arg-type]
    p = pos.shape[0]
    remaining = np.array([c for c in range(c_pos.shape[0]) if c not in chosen], dtype=np.intp)
    lay = plan_module._layouts((pos, dirs, modes.shapes[:p]), (c_pos, c_dir, modes.shapes[p:]), chosen, remaining)
    rough = plan_module._first_order_scores(body, *lay, modes.poles, DEFAULT_NOISE, 0.3)  # type: ignore[arg-type]
    return [int(remaining[i]) for i in np.argsort(rough, kind="stable")]


def suggestions() -> None:
    default = plan_module.SHORTLIST
    print(f"plan --add 2: short list of {default} against the Monte Carlo of every candidate")
    print("| case | step | chosen (short / full) | score equal | first-order rank of the MC's best 5 | top 5 equal |")
    print("|---|---|---|---|---|---|")
    for case, body_file in CASES:
        _, pos, dirs, body = _load(case, body_file)
        short, t_short = _suggest(body, pos, dirs, default)
        full, t_full = _suggest(body, pos, dirs, 10**6)
        chosen: list[int] = []
        for a, b in zip(short.steps, full.steps, strict=True):  # type: ignore[attr-defined]
            rank = _first_order_ranking(body, pos, dirs, chosen)
            ranks = [rank.index(cand) for cand, _ in b.ranking[:5]]
            chosen.append(b.candidate)
            print(f"| {case} {body_file} | {a.step} | {a.candidate} / {b.candidate} | "
                  f"{a.figures.score == b.figures.score} | {ranks} | {a.ranking[:5] == b.ranking[:5]} |")  # fmt: skip
        print(f"|   CPU s: short list {t_short:.2f}, every candidate {t_full:.2f} | | | | | |")
    plan_module.SHORTLIST = default


def mounts(draws: int, seed: int) -> None:
    lay, pos, dirs, body = _load("engine-test", "cad-estimate.json")
    units = {"length": lay.units.length, "mass": lay.units.mass}  # type: ignore[attr-defined]
    where, axes, spec = read_mount_spec(SAMPLES / "engine-test" / "mounts.json", units)
    groups = [m.group for m in spec.mounts]
    start = time.process_time()
    first = predict_mount_model_linearised(body, pos, dirs, where, axes, groups=groups, noise=DEFAULT_NOISE)  # type: ignore[arg-type]
    t_first = time.process_time() - start
    start = time.process_time()
    mc = predict_mount_model(body, pos, dirs, where, axes, groups=groups, noise=DEFAULT_NOISE, draws=draws, seed=seed)  # type: ignore[arg-type]
    t_mc = time.process_time() - start
    print(f"\nplan --mounts, engine-test: first order ({t_first:.2f} CPU s) against {draws} refits ({t_mc:.1f} CPU s)")
    print(f"Monte Carlo relative error of a standard deviation: {1.0 / np.sqrt(2.0 * (draws - 1)):.3f}")
    cg_first, cg_mc = first.center_of_gravity_std, mc.center_of_gravity_std
    print("CG std (mm), first order:", np.round(cg_first, 4), "Monte Carlo:", np.round(cg_mc, 4),
          "ratio:", np.round(cg_first / cg_mc, 3))  # fmt: skip
    d_first, d_mc = np.diag(first.inertia_std), np.diag(mc.inertia_std)
    print("inertia diagonal std (kg mm^2), first order:", np.round(d_first), "Monte Carlo:", np.round(d_mc),
          "ratio:", np.round(d_first / d_mc, 3))  # fmt: skip
    print("all inertia entries, ratio:", np.round(first.inertia_std / mc.inertia_std, 3).tolist())
    print(f"flagged: first order {first.flagged:.3f}, Monte Carlo {mc.flagged:.3f}")


def plan_time() -> None:
    from rigidid import api

    print("\nrigidid plan LAYOUT --body BODY (API, 1000 draws), CPU s, best of 3: without / with --records")
    for case, body_file in CASES:
        times = []
        for records in (False, True):
            best = np.inf
            for _ in range(3):
                start = time.process_time()
                result = api.plan(SAMPLES / case / "layout.json", body=SAMPLES / case / body_file, records=records)
                best = min(best, time.process_time() - start)
            times.append(best)
        test = result.records_test or {}
        print(
            f"  {case} {body_file}: {times[0]:.2f} / {times[1]:.2f} (+{times[1] - times[0]:.2f}; fitted at "
            f"1/{test.get('fit_decimation')}, {test.get('rows_used')} of {test.get('fit_rows')} rows per impact)"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mount-draws", type=int, default=200)
    parser.add_argument("--mount-seed", type=int, default=0)
    parser.add_argument("--skip-mounts", action="store_true")
    parser.add_argument("--plan-time", action="store_true", help="also time plan without and with --records")
    parser.add_argument("--only-plan-time", action="store_true", help="only time plan without and with --records")
    args = parser.parse_args()
    if not args.only_plan_time:
        suggestions()
        if not args.skip_mounts:
            mounts(args.mount_draws, args.mount_seed)
    if args.plan_time or args.only_plan_time:
        plan_time()


if __name__ == "__main__":
    main()
