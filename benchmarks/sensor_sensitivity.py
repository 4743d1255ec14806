"""How the records refit reacts to the sensors' errors, one source at a time (issue 23).

Run from the worktree root::

    PYTHONPATH=src OPENBLAS_NUM_THREADS=1 nice -n 10 python benchmarks/sensor_sensitivity.py [--draws 8]
        [--sources orient,transverse,position,sens] [--noise 1e-6] [--equal-noise] [--linear]
        [--chain skew,ac,aa,hum] [--delays] [--estimate-sensors]

The body, sensors and impacts of ``benchmarks/chain_matrix.py`` (its own scipy expm simulator), the
records almost noise-free (``--noise``, relative to each channel's RMS; ``--equal-noise``: the same
absolute level on every channel, so the refit weighs the channels alike), the sensor errors drawn from
the stated distribution (rectangular within the bounds of chain_matrix's cells: 3 %, 3 degrees per
normal axis, 3 % transverse in a uniform direction, 3 mm per axis). Per source, over the draws, RMS of:

- ``refit``: the refit's error (``refine_body`` started at the truth, the tolerances stated);
- ``refit/own``: that error over the refit's own linearised type-B std (``Refinement.sensor_std``);
- ``kernel``: the kernel's error on the exact modes read through the same sensors (the floor);
- ``kernel/own``: over the kernel's linearised std (``sensor_budget`` at those modes);
- ``refit/kernel``: the RMS errors' ratio; ``own/kernel std``: the RMS linearised std's ratio;
- ``mean/kernel``: the RMS error of the two estimates' mean over the kernel's (below 1: their errors differ
  draw by draw, and a combination would gain);
- ``--linear``: the refit's error with the errors scaled by 0.1, times 10, over the full one's (1: linear).

``--chain``: chain_matrix's chain effects in the records too (``skew``: channel 5 one sample late; ``ac``:
2 Hz AC coupling; ``aa``: the 8th-order anti-alias filter; ``hum``: 50 Hz), the refit modelling them:
``ac`` and ``aa`` stated (``ChainModel``), the channels' delays fitted with ``skew`` or ``--delays``, the hum
found. The refit's own budget is then its signatures through that model (``sensor_terms`` with the link).

``--estimate-sensors``: the refit estimates the sensors' gains and tilts with the body (positions at their
prior), through the same chain model; ``refit`` is then the corrected body's error and ``own`` the type-B
std the correction predicts it leaves (``Refinement.sensor_std`` after the correction).

Per quantity class: CG (3 coordinates, % of the sensor span) and J/m's diagonal (%).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import chain_matrix as cm

BOUNDS = {"sens": 0.03, "orient": np.radians(3.0), "transverse": 0.03, "position": 0.003}


def draw(source: str, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """One draw of the sensors' errors from the stated (rectangular) distribution."""
    n = cm.SENSORS.shape[0]
    out = {"gain": np.zeros(n), "tilt": np.zeros((n, 2)), "trans": np.zeros((n, 2)), "shift": np.zeros((n, 3))}
    a = BOUNDS[source]
    if source == "sens":
        out["gain"] = rng.uniform(-a, a, n)
    elif source == "orient":
        out["tilt"] = rng.uniform(-a, a, (n, 2))
    elif source == "transverse":
        tau, phase = rng.uniform(0, a, n), rng.uniform(0, 2 * np.pi, n)
        out["trans"] = tau[:, None] * np.column_stack([np.cos(phase), np.sin(phase)])
    else:
        out["shift"] = rng.uniform(-a, a, (n, 3))
    return out


def sensors(err: dict[str, np.ndarray], scale: float = 1.0) -> dict[str, np.ndarray]:
    """The true sensors (chain_matrix's convention) for the errors scaled by `scale`."""
    from rigidid.core.sensor_budget import axis_normals

    e1, e2 = axis_normals(cm.AXES)
    tilt, trans = scale * err["tilt"], scale * err["trans"]
    axes = cm.AXES + tilt[:, :1] * e1 + tilt[:, 1:] * e2
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    reading = (axes + trans[:, :1] * e1 + trans[:, 1:] * e2) * (1.0 + scale * err["gain"])[:, None]
    return {"reading": reading, "position": cm.SENSORS + scale * err["shift"]}


def stated(source: str) -> object:
    from rigidid.core.sensor_budget import SensorBounds

    return SensorBounds(
        sensitivity=0.03 if source == "sens" else 0.0,
        orientation_deg=3.0 if source == "orient" else 0.0,
        transverse=0.03 if source == "transverse" else 0.0,
        position=0.003 if source == "position" else 0.0,
    )


def _vector(cg: np.ndarray, jm: np.ndarray) -> np.ndarray:
    span = float(np.max(np.ptp(cm.SENSORS, axis=0)))
    truth = np.diag(cm.INERTIA) / cm.MASS
    return np.concatenate([100 * (cg - cm.CG) / span, 100 * (np.diag(jm) - truth) / truth])


def _std_vector(std: dict[str, np.ndarray]) -> np.ndarray:
    span = float(np.max(np.ptp(cm.SENSORS, axis=0)))
    truth = np.diag(cm.INERTIA) / cm.MASS
    return np.concatenate([100 * std["center_of_gravity"] / span, 100 * np.diag(std["inertia_per_mass"]) / truth])


CHAIN: set[str] = set()
"""``--chain``: chain_matrix's chain effects simulated in the records and modelled by the refit."""
DELAYS = False
"""``--delays``: the channels' delays fitted (also whenever ``skew`` is in :data:`CHAIN`)."""
ESTIMATE = False
"""``--estimate-sensors``: the sensors' errors estimated with the body."""


def chain_model() -> object:
    """The refit's stated chain for :data:`CHAIN` (None: nothing stated)."""
    from rigidid.core.timedomain.chain import AntiAlias, ChainModel, ChannelChain

    if not CHAIN & {"ac", "aa"}:
        return None
    aa = AntiAlias("butterworth", cm.AA_ORDER, cm.AA_CORNER) if "aa" in CHAIN else None
    one = ChannelChain(highpass_hz=cm.HP_CORNER if "ac" in CHAIN else 0.0, antialias=aa)
    return ChainModel(tuple(one for _ in range(cm.SENSORS.shape[0])))


def refit(true: dict[str, np.ndarray], source: str, noise: float, equal: bool, seed: int) -> tuple[np.ndarray, ...]:
    """The refit's error and its own type-B std (as % vectors)."""
    from rigidid.core.timedomain.refine import refine_body

    rng = np.random.default_rng(seed)
    recs = records(true, noise, equal, rng)
    onset = int(cm.PRE * cm.RATE)
    ref = refine_body(
        recs, 1.0 / cm.RATE, cm.SENSORS, cm.AXES, starts=[onset + 16] * 3, onsets=[onset] * 3, decimation=8,
        center_of_gravity=cm.CG, inertia_per_mass=cm.INERTIA / cm.MASS, stiffness_per_mass=cm.K6 / cm.MASS,
        damping_per_mass=cm.C6 / cm.MASS, sensor_bounds=stated(source), chain=chain_model(),  # type: ignore[arg-type]
        estimate_delays=DELAYS or "skew" in CHAIN, estimate_sensors=ESTIMATE,
    )  # fmt: skip
    assert ref.sensor_std is not None
    own = np.sqrt(sum(_std_vector(part) ** 2 for part in ref.sensor_std.values()))
    return _vector(ref.center_of_gravity, ref.inertia_per_mass), own, _std_vector(ref.std)


def records(true: dict[str, np.ndarray], noise: float, equal: bool, rng: np.random.Generator) -> list[np.ndarray]:
    old = cm.NOISE
    cm.NOISE = 0.0
    try:
        clean = cm.simulate(set(CHAIN), rng, true)
    finally:
        cm.NOISE = old
    level = [np.sqrt(np.mean(r**2, axis=0)) for r in clean]
    if equal:
        level = [np.full_like(x, np.median(x)) for x in level]
    return [r + noise * s * rng.standard_normal(r.shape) for r, s in zip(clean, level, strict=True)]


def kernel(true: dict[str, np.ndarray], source: str) -> tuple[np.ndarray, np.ndarray]:
    """The kernel's error on the exact modes through the true sensors, and its linearised std."""
    from rigidid.core.estimator import estimate
    from rigidid.core.sensor_budget import sensor_budget

    freq, zeta, q = cm.modes()
    lam = -zeta * 2 * np.pi * freq + 1j * 2 * np.pi * freq * np.sqrt(1 - zeta**2)
    read = np.array([r @ cm._point(p - cm.CG) for r, p in zip(true["reading"], true["position"], strict=True)])
    shapes = read @ q
    est = estimate(cm.SENSORS[None], cm.AXES[None], lam[None], shapes[None])
    budget = sensor_budget(cm.SENSORS, cm.AXES, lam, shapes, stated(source))  # type: ignore[arg-type]
    return _vector(est.center_of_gravity[0], est.inertia_per_mass[0]), _std_vector(budget.total)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--draws", type=int, default=8)
    parser.add_argument("--sources", default="orient,transverse,position,sens")
    parser.add_argument("--noise", type=float, default=1e-6)
    parser.add_argument("--equal-noise", action="store_true")
    parser.add_argument("--linear", action="store_true")
    parser.add_argument("--runs", action="store_true", help="print each draw's largest errors")
    parser.add_argument("--chain", default="", help="chain effects in the records, modelled: skew,ac,aa,hum")
    parser.add_argument("--delays", action="store_true", help="fit the channels' delays")
    parser.add_argument("--estimate-sensors", action="store_true", help="estimate the sensors' errors with the body")
    args = parser.parse_args()
    global DELAYS, ESTIMATE
    CHAIN.update(x for x in args.chain.split(",") if x)
    DELAYS, ESTIMATE = args.delays, args.estimate_sensors
    print(f"{'source':<11} {'class':<3} {'refit':>7} {'refit/own':>9} {'kernel':>7} {'kernel/own':>10} "
          f"{'refit/kernel':>12} {'own/kernel std':>14} {'mean/kernel':>11}"
          + (f" {'linear':>7}" if args.linear else ""))  # fmt: skip
    for source in args.sources.split(","):
        rng = np.random.default_rng(7)
        rows = []
        for k in range(args.draws):
            err = draw(source, rng)
            true = sensors(err)
            r_err, r_own, _ = refit(true, source, args.noise, args.equal_noise, k)
            k_err, k_own = kernel(true, source)
            lin = np.full(6, np.nan)
            if args.linear:
                small, *_ = refit(sensors(err, 0.1), source, args.noise, args.equal_noise, k)
                lin = 10 * small
            rows.append((r_err, r_own, k_err, k_own, lin))
            if args.runs:
                print(
                    f"    draw {k}: max CG refit/kernel {np.abs(r_err[:3]).max():.3f}/{np.abs(k_err[:3]).max():.3f}"
                    f"  max J {np.abs(r_err[3:]).max():.2f}/{np.abs(k_err[3:]).max():.2f}",
                    flush=True,
                )
        a = [np.array([row[i] for row in rows]) for i in range(5)]
        for name, cols in (("CG", slice(0, 3)), ("J", slice(3, 6))):
            rms = [float(np.sqrt(np.mean(x[:, cols] ** 2))) for x in (a[0], a[0] / a[1], a[2], a[2] / a[3])]
            own = float(np.sqrt(np.mean(a[1][:, cols] ** 2)) / np.sqrt(np.mean(a[3][:, cols] ** 2)))
            mean = float(np.sqrt(np.mean(((a[0] + a[2])[:, cols] / 2) ** 2))) / rms[2]
            line = (f"{source:<11} {name:<3} {rms[0]:>7.3f} {rms[1]:>9.2f} {rms[2]:>7.3f} {rms[3]:>10.2f} "
                    f"{rms[0] / rms[2]:>12.2f} {own:>14.2f} {mean:>11.2f}")  # fmt: skip
            if args.linear:
                line += f" {float(np.sqrt(np.mean(a[4][:, cols] ** 2)) / rms[0]):>7.2f}"
            print(line, flush=True)


if __name__ == "__main__":
    main()
