"""Defaults on the paper-like regime and the engine sample, with and without --band (issue 11).

Paper-like: a 136 lb block on three springs (``benchmarks/paper_like_body.json``) at three
heights, not symmetric about the CG (CG 0.8, -0.6, -1.4 in; products of inertia), so its
inertia is determinable; six modes 5.34-7.88 Hz, damping 0.12-0.18 %, two pairs 1.5 % apart,
the paper's six sensors (``samples/paper-1994/layout.json``), three impacts,
256 Hz, 30 s, 3 % noise. Engine: ``samples/engine-on-mounts`` with the default
two impacts, 512 Hz, 8 s, 1 % noise. Errors: median (worst) over seeds; CG in
the layout's length unit, inertia the largest relative error of the diagonal.

Run: ``python benchmarks/band_defaults.py [--seeds N] [--no-refine] [--paper-only]``
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from rigidid import api
from rigidid.io.files import layout_arrays, load_body, load_layout

ROOT = Path(__file__).resolve().parent.parent
PAPER_IMPACTS = [
    ((6.75, 1.5, 0.0), (0.3, 0.5, -1.0)),
    ((-8.4, 0.75, -3.25), (1.0, 0.7, 0.2)),
    ((4.5, -4.0, 0.0), (-0.5, 1.0, 0.6)),
]


def case(body_path: Path, layout_path: Path, impacts, rate, duration, noise, seed):  # type: ignore[no-untyped-def]
    from rigidid.core.timedomain import impulse_records

    spec, lay = load_body(body_path), load_layout(layout_path)
    body = api.body_from_file(spec)
    _, pos, dirs = layout_arrays(lay)
    if impacts is None:
        far = int(np.argmax(np.linalg.norm(pos - pos[0], axis=1)))
        impacts = [(pos[0], (1.0, 1.0, 1.0)), (pos[far], (-1.0, 1.0, -1.0))]
    recs = impulse_records(
        body, pos, dirs, impacts, sample_rate=rate, duration=duration, pretrigger=0.1, noise=noise, seed=seed
    )
    return body, lay, [(r, 1.0 / rate) for r in recs]


def run(body, lay, records, band, refine):  # type: ignore[no-untyped-def]
    import warnings

    from rigidid.core.simulate import body_modes

    warnings.simplefilter("ignore")

    try:
        table, est = api.estimate_modes(lay, records, band=band)
    except Exception as exc:
        return None, f"{type(exc).__name__}: {exc}"
    result = api.identify(lay, table)
    if refine:
        result = api.with_refinement(result, records, est)
    ident = result.identification
    _, pos, dirs = layout_arrays(lay)
    truth = body_modes(body, pos, dirs)
    f_true = np.abs(truth.poles) / (2 * np.pi)
    z_true = -truth.poles.real / np.abs(truth.poles)
    dz = float(np.max(np.abs(est.damping_ratio / z_true - 1.0))) if len(est.damping_ratio) == 6 else np.nan
    cg = float(np.linalg.norm(ident.center_of_gravity - body.center_of_gravity))
    j = ident.inertia_tensor
    jd = float(np.max(np.abs(np.diag(j) / np.diag(body.inertia_tensor) - 1.0)))
    del f_true
    return (dz, cg, jd, est.decimation), ""


def table(title, body_path, layout_path, impacts, rate, duration, noise, bands, seeds, refine):  # type: ignore[no-untyped-def]
    print(f"\n{title}")
    print("| band | found | damping err % | CG err | inertia diag err % | decimation |")
    print("|---|---|---|---|---|---|")
    for band in bands:
        rows, fails = [], []
        for seed in range(seeds):
            body, lay, recs = case(body_path, layout_path, impacts, rate, duration, noise, seed)
            out, why = run(body, lay, recs, band, refine)
            if out is None:
                fails.append(why)
            else:
                rows.append(out)
        a = np.array(rows) if rows else np.full((1, 4), np.nan)
        med, worst = np.median(a, axis=0), np.max(a, axis=0)
        name = "default" if band is None else f"{band[0]:g} {band[1]:g}"
        print(
            f"| {name} | {len(rows)}/{seeds} | {100 * med[0]:.2f} ({100 * worst[0]:.2f}) "
            f"| {med[1]:.4f} ({worst[1]:.4f}) "
            f"| {100 * med[2]:.3f} ({100 * worst[2]:.3f}) | {sorted(set(int(x) for x in a[:, 3] if np.isfinite(x)))} |"
        )
        for why in sorted(set(fails)):
            print(f"  failure: {why}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--no-refine", action="store_true")
    parser.add_argument("--paper-only", action="store_true", help="only the paper-like table, default and --band 1 20")
    args = parser.parse_args()
    t0 = time.perf_counter()
    refine = not args.no_refine
    print(f"refinement on the records: {refine}")
    table(
        "paper-like regime (in, lb; body 20 in across), 6 sensors, 3 impacts, 256 Hz, 30 s, 3 % noise",
        ROOT / "benchmarks" / "paper_like_body.json",
        ROOT / "samples" / "paper-1994" / "layout.json",
        PAPER_IMPACTS,
        256.0,
        30.0,
        0.03,
        [None, (1.0, 20.0)] if args.paper_only else [None, (1.0, 20.0), (4.0, 10.0), (2.0, 40.0)],
        args.seeds,
        refine,
    )
    if args.paper_only:
        return
    table(
        "engine-on-mounts (mm, kg), 12 sensors, 2 impacts, 512 Hz, 8 s, 1 % noise",
        ROOT / "samples" / "engine-on-mounts" / "body.json",
        ROOT / "samples" / "engine-on-mounts" / "layout.json",
        None,
        512.0,
        8.0,
        0.01,
        [None, (2.0, 40.0), (5.0, 25.0)],
        args.seeds,
        refine,
    )
    print(f"\n{time.perf_counter() - t0:.0f} s", file=sys.stderr)


if __name__ == "__main__":
    main()
