"""Coverage of the mass-line route's 95 % intervals over many noise draws, three regimes (issue 21).

Run: ``OPENBLAS_NUM_THREADS=1 PYTHONPATH=src .venv/bin/python benchmarks/frf_coverage.py
[--draws 200] [--first-seed 0] [--regimes near,mounted,free] [--routes massline,exact,first_order,auto,residues]
[--save DIR]``

Routes (``--routes``, default ``massline``): ``massline`` is ``mass_line`` with its automatic mount
model, ``exact`` the exact support fit forced (``supports="exact"``), ``first_order`` the first-order
mount correction forced, ``auto`` ``identify --frf`` with its defaults (``--method auto``, the API,
band given), ``residues`` the residues of the six rigid-body poles found in the FRFs (pLSCF +
LSFD, ``fit_frf_modes`` then ``mass_from_residues``); the residues need the rigid-body peaks, so
on ``mounted`` the same body and noise are simulated over lines from 0.7x its lowest to 6x its
highest rigid mode, and on ``near`` and ``free`` (no peaks in the lines) the route does not apply.

Regimes (``mass_line`` with the band given, its automatic mount model):

* ``near``: supports near the band, femtools' acceptance case 15 (10 kg on six springs, 24 sensors,
  6 references, 21 lines 6-15 Hz, supports up to 4.4 Hz; ``femtools_compare.femtools_case``), 1 %
  complex noise relative to each value; the exact support fit (output error) answers;
* ``mounted``: a random body of ``frf_sim`` on four mounts (2 % damping), 8 sensors, 3 references,
  0.1 Hz lines from 1.5x to 6x its highest rigid mode, half the noise relative to each value and half
  a floor (1 % in all), a new body every draw;
* ``free``: the same bodies free-free (mounts at 1e-4 of their stiffness), band 30-150 Hz at 1 Hz
  lines, below an elastic mode 10x higher; the first-order mass line answers;
* ``free_slope_low``, ``free_slope_high``: the ``free`` bodies with their noise 25x higher at the band's low
  (high) end than at its other end, a log-linear ramp along frequency (:func:`sloped`; not in the default
  ``--regimes``): one noise covariance over the band would read the noisy low lines as supports.

Per route and regime: the share of draws whose 95 % interval holds the truth, for the mass, the CG
(x, y, z) and the inertia diagonal (xx, yy, zz), with its 95 % binomial (Wilson) interval; the issue
asks 0.93-0.97 for each. Also the RMS of the mass's z (error over its own SE), the worst z over the
seven figures, and the draws with a figure beyond 4 of its own SE (and of them, those without a rigidid
warning: silently wrong). Refusals are counted. Under each row:
the mean and RMS of each figure's z (a bias shows in the mean, an interval too narrow in the RMS), and
the coverage pooled over the seven figures with its Wilson interval over the draws. ``--save DIR`` writes
each row's seeds, signed z and whether a RigididWarning was issued (``DIR/ROUTE_REGIME.npy``, one row per
answered draw; ``_FIRST`` added when ``--first-seed`` is not 0); ``--combine DIR`` reads them back (the runs
split over processes) and prints, per regime, the seeds below 200 and all of them: each figure's coverage
with its Wilson interval, mean and RMS z, the draws beyond 4 of their own SE, and of those the silently
wrong (no warning).
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from femtools_compare import femtools_case
from frf_sim import add_elastic, make_rig
from rigidid.core.frfmodes import fit_frf_modes
from rigidid.core.massline import MassLine, mass_from_residues, mass_line
from rigidid.errors import RigididError, RigididWarning

Z95 = 1.959963984540054


def near(seed: int) -> tuple[dict[str, Any], tuple[Any, ...], tuple[float, float]]:
    c = femtools_case(2)
    rng = np.random.default_rng(seed)
    h = c["h"] * (
        1.0 + 0.01 * (rng.standard_normal(c["h"].shape) + 1j * rng.standard_normal(c["h"].shape)) / np.sqrt(2)
    )
    b = c["body"]
    truth = {"mass": b.mass, "cg": b.center_of_gravity, "inertia": b.inertia_tensor}
    return truth, (c["f"], h, c["pos"], c["dirs"], c["rpos"], c["rdirs"]), (6.0, 15.0)


def simulated(seed: int, free: bool) -> tuple[dict[str, Any], tuple[Any, ...], tuple[float, float]]:
    rng = np.random.default_rng(seed)
    rig = make_rig(rng, free=free)
    if free:
        add_elastic(rig, rng, 1500.0)
        f, band = np.arange(20.0, 200.0, 1.0), (30.0, 150.0)
    else:
        top = float(rig.rigid_hz()[-1])
        f = np.arange(1.4 * top, 6.5 * top, 0.1)
        band = (1.5 * top, 6.0 * top)
    h = rig.frf(f, 0.005, rng, additive=0.005)
    truth = {"mass": rig.mass, "cg": rig.cg, "inertia": rig.inertia}
    return truth, (f, h, rig.sensors, rig.sensor_dirs, rig.refs, rig.ref_dirs), band


SLOPE = 25.0
"""The ``free_slope_*`` regimes' noise ratio between the band's ends (a log-linear ramp along frequency)."""


def sloped(seed: int, low: bool) -> tuple[dict[str, Any], tuple[Any, ...], tuple[float, float]]:
    """The ``free`` body and band, its noise times a log-linear ramp: :data:`SLOPE` times higher at the low end
    of the band than at its high end (`low`), or the reverse; the ramp's geometric mean over the band is 1."""
    rng = np.random.default_rng(seed)
    rig = make_rig(rng, free=True)
    add_elastic(rig, rng, 1500.0)
    f, band = np.arange(20.0, 200.0, 1.0), (30.0, 150.0)
    h = rig.frf(f)
    e = (rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape)) / np.sqrt(2.0)
    t = np.log(f / band[0]) / np.log(band[1] / band[0])  # 0 at the band's low end, 1 at its high end
    ramp = np.sqrt(SLOPE) ** ((1.0 - 2.0 * t) if low else (2.0 * t - 1.0))
    rms = np.sqrt(np.mean(np.abs(h) ** 2, axis=2, keepdims=True))
    h = h + (0.005 * np.abs(h) + 0.005 * rms) * ramp * e
    truth = {"mass": rig.mass, "cg": rig.cg, "inertia": rig.inertia}
    return truth, (f, h, rig.sensors, rig.sensor_dirs, rig.refs, rig.ref_dirs), band


def peaks(seed: int) -> tuple[dict[str, Any], tuple[Any, ...], tuple[float, float]]:
    """The ``mounted`` body and noise over lines that hold its rigid-body peaks (for the residues)."""
    rng = np.random.default_rng(seed)
    rig = make_rig(rng)
    hz = rig.rigid_hz()
    f = np.arange(0.7 * float(hz[0]), 6.5 * float(hz[-1]), 0.1)
    h = rig.frf(f, 0.005, rng, additive=0.005)
    truth = {"mass": rig.mass, "cg": rig.cg, "inertia": rig.inertia}
    return truth, (f, h, rig.sensors, rig.sensor_dirs, rig.refs, rig.ref_dirs), (float(f[0]), 6.0 * float(hz[-1]))


def auto(data: tuple[Any, ...], band: tuple[float, float]) -> MassLine:
    """``identify --frf`` with its defaults (``--method auto``) and the band given, as the API runs it."""
    from rigidid.api.frf import identify_frf_auto
    from rigidid.models import LayoutFile, ReferencesFile
    from rigidid.results import FrfData

    f, h, pos, dirs, rpos, rdirs = data
    lay = LayoutFile.model_validate(
        {
            "units": {"length": "m", "mass": "kg"},
            "sensors": [
                {"id": f"s{i}", "position": list(map(float, p)), "direction": list(map(float, d))}
                for i, (p, d) in enumerate(zip(pos, dirs, strict=True))
            ],
        }
    )
    refs = ReferencesFile.model_validate(
        {
            "references": [
                {"id": f"r{j}", "position": list(map(float, p)), "direction": list(map(float, d))}
                for j, (p, d) in enumerate(zip(rpos, rdirs, strict=True))
            ]
        }
    )
    frf = FrfData(f, h, tuple(x.id for x in lay.sensors), tuple(x.id for x in refs.references))
    return identify_frf_auto(lay, refs, frf, band=band).massline


def run(route: str, name: str, seed: int, makers: dict[str, Any]) -> tuple[dict[str, Any], MassLine] | None:
    """One route on one draw (None: the route does not apply to the regime)."""
    if route == "residues":
        if name != "mounted":
            return None
        truth, data, band = peaks(seed)
        poles = fit_frf_modes(*data, band=band, n_modes=6).poles
        return truth, mass_from_residues(*data, poles, band=band)
    truth, data, band = makers[name](seed)
    if route == "auto":
        return truth, auto(data, band)
    supports = {"massline": "auto", "exact": "exact", "first_order": "first_order"}[route]
    return truth, mass_line(*data, band=band, supports=supports)


def binomial(p: float, n: int) -> str:
    """``p`` and its 95 % interval (Wilson) over ``n`` draws."""
    if n == 0:
        return "-"
    z2 = Z95**2
    mid = (p + z2 / (2 * n)) / (1 + z2 / n)
    half = Z95 * np.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / (1 + z2 / n)
    return f"{p:.3f} [{mid - half:.2f}, {mid + half:.2f}]"


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--draws", type=int, default=200)
    ap.add_argument("--first-seed", type=int, default=0, help="seeds first..first+draws-1 (split a run over processes)")
    ap.add_argument("--regimes", default="near,mounted,free")
    ap.add_argument("--routes", default="massline")
    ap.add_argument("--save", default="", help="directory for each row's signed z per draw (ROUTE_REGIME.npy)")
    ap.add_argument("--combine", default="", help="summarise the saved rows of DIR (runs split by --first-seed)")
    a = ap.parse_args()
    if a.combine:
        combine(Path(a.combine))
        return
    makers = {
        "near": near,
        "mounted": lambda s: simulated(s, False),
        "free": lambda s: simulated(s, True),
        "free_slope_low": lambda s: sloped(s, True),
        "free_slope_high": lambda s: sloped(s, False),
    }
    names = ("mass", "CG x", "CG y", "CG z", "Jxx", "Jyy", "Jzz")
    print("| route | regime | draws | refused | " + " | ".join(names) + " | RMS z (mass) | worst z | beyond 4 SE |")
    print("|---" * (len(names) + 7) + "|")
    for route in a.routes.split(","):
        for name in a.regimes.split(","):
            table_row(route, name, a.draws, makers, names, a.save, a.first_seed)


def table_row(
    route: str, name: str, draws: int, makers: dict[str, Any], names: tuple[str, ...], save: str = "", first: int = 0
) -> None:
    """One route on one regime over `draws` draws: coverage of each figure with its binomial interval."""
    t0 = time.perf_counter()
    zs, refused, seeds, warned = [], 0, [], []
    for seed in range(first, first + draws):
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                out = run(route, name, seed, makers)
        except (RigididError, np.linalg.LinAlgError):
            refused += 1
            continue
        if out is None:
            print(f"| {route} | {name} | does not apply (no rigid-body peaks in the lines) |", flush=True)
            return
        truth, r = out
        if r.intervals is None:
            refused += 1
            continue
        iv = r.intervals
        z = [(r.mass - truth["mass"]) / iv.mass.std]
        z += list((r.center_of_gravity - truth["cg"]) / iv.center_of_gravity.std)
        z += list(np.diag(r.inertia_tensor - truth["inertia"]) / np.diag(iv.inertia_tensor.std))
        zs.append(z)
        seeds.append(seed)
        warned.append(any(issubclass(w.category, RigididWarning) for w in caught))
    zz = np.array(zs, dtype=float).reshape(-1, len(names))
    if save:
        out = Path(save) / f"{route}_{name}{f'_{first}' if first else ''}.npy"
        np.save(out, np.column_stack([seeds, zz, warned]) if len(zs) else zz)
    za = np.abs(zz)
    cov = np.mean(za < Z95, axis=0) if len(zs) else np.full(len(names), np.nan)
    rms = float(np.sqrt(np.mean(za[:, 0] ** 2))) if len(zs) else np.nan
    worst = float(za.max()) if len(zs) else np.nan
    beyond = int(np.count_nonzero(za.max(axis=1) > 4.0)) if len(zs) else 0
    silent = int(np.count_nonzero((za.max(axis=1) > 4.0) & ~np.array(warned, dtype=bool))) if len(zs) else 0
    cells = " | ".join(binomial(float(c), len(zs)) for c in cov)
    print(
        f"| {route} | {name} | {len(zs)} | {refused} | {cells} | {rms:.2f} | {worst:.1f} | {beyond} "
        f"({silent} unwarned) |"
        f"  ({time.perf_counter() - t0:.0f} s)",
        flush=True,
    )
    if len(zs):
        print(
            f"    {route} {name} per figure, mean z / RMS z: "
            + ", ".join(
                f"{n} {m:+.2f}/{r:.2f}"
                for n, m, r in zip(names, zz.mean(axis=0), np.sqrt(np.mean(zz**2, axis=0)), strict=True)
            )
        )
        print(f"    {route} {name} pooled over the {len(names)} figures: {pooled(za)}", flush=True)


def combine(directory: Path) -> None:
    """The saved rows of `directory` (``ROUTE_REGIME[_FIRST].npy``) put together: per route and regime, the seeds
    below 200 and all of them."""
    names = ("mass", "CG x", "CG y", "CG z", "Jxx", "Jyy", "Jzz")
    groups: dict[str, list[np.ndarray]] = {}
    for path in sorted(directory.glob("*.npy")):
        parts = path.stem.split("_")
        key = "_".join(parts[:-1] if parts[-1].isdigit() else parts)  # ROUTE_REGIME (the regime may hold "_")
        groups.setdefault(key, []).append(np.load(path))
    for key, arrays in groups.items():
        rows = np.concatenate(arrays)
        rows = rows[np.argsort(rows[:, 0])]
        for label, sel in (("seeds 0-199", rows[:, 0] < 200), (f"all {len(rows)} draws", np.ones(len(rows), bool))):
            z, warned = rows[sel, 1:8], rows[sel, 8].astype(bool)
            za = np.abs(z)
            n = len(z)
            if n < 2:
                continue
            beyond = za.max(axis=1) > 4.0
            print(f"{key}, {label} ({n} answered):")
            for j, nm in enumerate(names):
                m, r = float(z[:, j].mean()), float(np.sqrt(np.mean(z[:, j] ** 2)))
                print(
                    f"  {nm:5s} coverage {binomial(float(np.mean(za[:, j] < Z95)), n)}  mean z {m:+.3f}"
                    f" (+-{z[:, j].std(ddof=1) / np.sqrt(n):.3f})  RMS z {r:.3f}"
                    f"  beyond 4 SE {int(np.sum(za[:, j] > 4))}"
                )
            print(
                f"  pooled: {pooled(za)}; draws beyond 4 SE: {int(beyond.sum())} (worst {float(za.max()):.2f}),"
                f" silently wrong (no warning): {int(np.sum(beyond & ~warned))}; warned draws: {int(warned.sum())}",
                flush=True,
            )


def pooled(za: np.ndarray) -> str:
    """Coverage pooled over the figures with its 95 % interval: Wilson's over the draws (the figures of one draw
    are correlated, so the draws, not the figures, are the independent units: a conservative count)."""
    p = float(np.mean(za < Z95))
    return f"{binomial(p, za.shape[0])}, RMS z {float(np.sqrt(np.mean(za**2))):.3f}"


if __name__ == "__main__":
    main()
