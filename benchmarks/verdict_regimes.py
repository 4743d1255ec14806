"""Every answer checks itself (issue 22): silently wrong answers, coverage, efficiency, crashes.

Tests simulated by ``verdict_sim.py`` (its own forward model: scipy.linalg.eig of the
state-space form, no rigidid code), identified by ``rigidid.api.identify`` as a user would
(mass in the layout, default noise levels, warnings recorded).

- ``matrix``: the regime matrix of the modes route and the mount routes: inertia
  observability (the mounts' height offset from the CG scaled by 0.3-2.5: observability 0.02-0.3), shape noise
  0.3 / 1 / 3 % (frequency 0.1 %, damping ratio 5 % throughout), 6 / 12 / 32 sensors, three
  mounts (one turned 35 deg) or four (turned -10 to 35 deg), a mounts.json with groups and
  one that misses a support. Per draw: "silently wrong" = exit 0 (no error), no warning, and
  some reported figure (CG, inertia diagonal, principal moments, K and C diagonals, per-mount
  rates, torque roll axis) more than 4 of its own standard errors from the truth.
- ``coverage``: share of 95 % default intervals (estimate +- 1.96 SE) holding the truth, CG,
  inertia diagonal and K diagonal, over 200 draws in three regimes.
- ``efficiency``: RMS error of the free route against a noise-weighted maximum-likelihood fit
  of the same free model (CG, J, symmetric K and C: 51 parameters), written here with
  scipy.optimize.least_squares on the poles (natural frequency and damping ratio, weighted by
  their true relative noise) and the shapes (each model shape scaled by its complex least-
  squares factor, residuals over the true shape noise), started at the truth.
- ``crash``: ``--method mounts`` on 200 noisy draws of the weakly observable engine.
- ``time``: CPU time of ``rigidid identify`` (a fresh process: start-up and run) on every
  sample, with and without the default standard errors and checks (and without the
  noise-weighted refit too), the median of ``--draws`` (20) alternating rounds;
  ``instructions``: the same counted by valgrind's callgrind (repeatable; about 30 s a run).

- ``plan``: ``plan``'s predicted standard deviations (noise-weighted, and fixed weights as before)
  against the RMS error ``identify`` achieves on 200 draws of one regime.

Run: ``python benchmarks/verdict_regimes.py [matrix|coverage|efficiency|crash|time|instructions|plan|all]
[--draws N] [--baseline SRC]``
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from verdict_sim import Rig, add_noise, engine, layout

F_NOISE, Z_NOISE = 0.001, 0.05
ROOT = Path(__file__).resolve().parent.parent


# --------------------------------------------------------------------------- running rigidid


def _files(rig: Rig, pos: np.ndarray, dirs: np.ndarray, lam: np.ndarray, psi: np.ndarray, listed: int,
           groups: bool) -> tuple[Any, Any, Any]:  # fmt: skip
    from rigidid.io.files import ModeTable
    from rigidid.models import LayoutFile, MountsFile

    lay = LayoutFile.model_validate({
        "units": {"length": "m", "mass": "kg"}, "mass": rig.mass,
        "sensors": [{"id": f"s{i}", "position": p.tolist(), "direction": d.tolist()}
                    for i, (p, d) in enumerate(zip(pos, dirs, strict=True))],
    })  # fmt: skip
    w = np.abs(lam)
    table = ModeTable(tuple(range(1, 7)), w / (2 * np.pi), -lam.real / w, tuple(f"s{i}" for i in range(len(pos))), psi)
    axes = [np.linalg.eigh(k)[1] for k in rig.mount_k[:listed]]
    mounts = MountsFile.model_validate({
        "units": {"length": "m", "mass": "kg"},
        "mounts": [{"id": f"m{k}", "position": rig.mount_pos[k].tolist(), "axes": axes[k].T.tolist(),
                    **({"group": "engine"} if groups else {})} for k in range(listed)],
    })  # fmt: skip
    return lay, table, mounts


def _truth(rig: Rig, listed: int) -> dict[str, np.ndarray]:
    _m, k, c = rig.matrices()
    axes = [np.linalg.eigh(km)[1] for km in rig.mount_k[:listed]]
    return {
        "cg": rig.cg,
        "J": np.diag(rig.inertia),
        "moments": np.linalg.eigvalsh(rig.inertia),
        "K": np.diag(k),
        "C": np.diag(c),
        "rates": np.array([np.diag(u.T @ km @ u) for u, km in zip(axes, rig.mount_k, strict=False)]),
        "roll": np.linalg.solve(rig.inertia, [1.0, 0.0, 0.0]),
    }


def run_modes(rig: Rig, pos: np.ndarray, dirs: np.ndarray, lam: np.ndarray, psi: np.ndarray, *, listed: int = 0,
              groups: bool = False, method: str = "structured") -> dict[str, Any]:  # fmt: skip
    """One identification as ``rigidid identify`` does it: the figures, their SE, warnings, or the error."""
    from rigidid import api
    from rigidid.errors import RigididError

    lay, table, mounts = _files(rig, pos, dirs, lam, psi, listed or len(rig.mount_k), groups)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        try:
            res = api.identify(lay, table, method=method, mounts=mounts if method == "mounts" else None)  # type: ignore[arg-type]
            if listed:
                res = api.with_mounts(res, mounts, torque_axis=[1.0, 0.0, 0.0])
        except RigididError as exc:
            return {"error": str(exc), "crash": False}
        except Exception as exc:
            return {"error": repr(exc), "crash": True}
    ident = res.identification
    out: dict[str, Any] = {"warnings": [str(w.message) for w in seen], "error": None, "result": res}
    err = res.standard_errors
    out["value"] = {
        "cg": ident.center_of_gravity, "J": np.diag(ident.inertia_tensor), "moments": ident.principal_moments,
        "K": np.diag(ident.stiffness_matrix), "C": np.diag(ident.damping_matrix),
    }  # fmt: skip
    if err is not None:
        out["se"] = {"cg": err.center_of_gravity, "J": np.diag(err.inertia), "moments": err.principal_moments,
                     "K": np.diag(err.stiffness), "C": np.diag(err.damping)}  # fmt: skip
        if res.mounts is not None and res.mounts.stiffness_std is not None:
            out["value"]["rates"] = res.mounts.rates.stiffness
            out["se"]["rates"] = res.mounts.stiffness_std
        if res.torque_roll_axis is not None and res.torque_roll_axis_std_deg is not None:
            out["value"]["roll"] = res.torque_roll_axis.direction
            out["se"]["roll"] = res.torque_roll_axis_std_deg
    return out


def worst_z(out: dict[str, Any], truth: dict[str, np.ndarray]) -> float:
    """Largest |error| / own SE over the reported figures (angles for the roll axis)."""
    worst = 0.0
    for key, value in out["value"].items():
        if key not in out.get("se", {}):
            continue
        se = out["se"][key]
        if key == "roll":
            t = truth["roll"] / np.linalg.norm(truth["roll"])
            angle = np.degrees(np.arctan2(np.linalg.norm(np.cross(value, t)), abs(value @ t)))
            worst = max(worst, float(angle / max(se, 1e-300)))
            continue
        z = np.abs(np.asarray(value) - truth[key]) / np.maximum(se, 1e-300)
        worst = max(worst, float(np.max(z)))
    return worst


# --------------------------------------------------------------------------- the regime matrix


def cells() -> list[dict[str, Any]]:
    out = []
    for observe in (2.5, 1.0, 0.3):
        for shape in (0.003, 0.01, 0.03):
            for sensors in (6, 12, 32):
                out.append({"observe": observe, "shape": shape, "sensors": sensors, "mounts": 3})
    for extra in ({"mounts": 4}, {"mounts": 3, "groups": True}, {"mounts": 3, "missing": True}):
        for observe in (2.5, 0.3):
            out.append({"observe": observe, "shape": 0.01, "sensors": 12, **extra})
    return out


def matrix(draws: int, seed: int) -> None:
    print("regime matrix (modes route, --mounts, --torque-axis x): silently wrong = exit 0, no warning, |err| > 4 SE")
    print(f"{'observe':>7} {'obs.':>6} {'shape':>6} {'sens':>4} {'mounts':>9} | {'ok':>3} {'err':>3} {'warn':>4} "
          f"{'silent':>6} {'max z':>6}")  # fmt: skip
    total_silent = 0
    rng = np.random.default_rng(seed)
    for cell in cells():
        rig = engine(observe=cell["observe"], mounts=cell["mounts"], missing=cell.get("missing", False))
        listed = cell["mounts"]
        pos, dirs = layout(cell["sensors"])
        lam0, psi0 = rig.modes(pos, dirs)
        truth = _truth(rig, listed)
        n_ok = n_err = n_warn = silent = 0
        zmax = 0.0
        obs = np.nan
        for _ in range(draws):
            lam, psi = add_noise(lam0, psi0, rng, F_NOISE, Z_NOISE, cell["shape"])
            out = run_modes(rig, pos, dirs, lam, psi, listed=listed, groups=cell.get("groups", False))
            if out["error"] is not None:
                n_err += 1
                continue
            n_ok += 1
            obs = out["result"].identification.diagnostics.inertia_observability
            z = worst_z(out, truth)
            if out["warnings"]:
                n_warn += 1
            elif z > 4.0:
                silent += 1
            zmax = max(zmax, z if not out["warnings"] else 0.0)
        total_silent += silent
        label = f"{cell['mounts']}{' grp' if cell.get('groups') else ''}{' miss' if cell.get('missing') else ''}"
        print(f"{cell['observe']:7.2f} {obs:6.3f} {100 * cell['shape']:5.1f}% {cell['sensors']:4d} {label:>9} | "
              f"{n_ok:3d} {n_err:3d} {n_warn:4d} {silent:6d} {zmax:6.2f}")  # fmt: skip
    print(f"silently wrong answers in all: {total_silent}")


# --------------------------------------------------------------------------- coverage


def coverage(draws: int, seed: int) -> None:
    print("coverage of the default 95 % intervals (estimate +- 1.96 SE): CG, inertia diagonal, K diagonal")
    rng = np.random.default_rng(seed)
    for observe, shape, sensors in ((0.3, 0.01, 12), (1.5, 0.003, 32), (0.3, 0.03, 12)):
        rig = engine(observe=observe)
        pos, dirs = layout(sensors)
        lam0, psi0 = rig.modes(pos, dirs)
        truth = _truth(rig, 3)
        hits: dict[str, list[float]] = {"cg": [], "J": [], "K": []}
        failed = 0
        for _ in range(draws):
            lam, psi = add_noise(lam0, psi0, rng, F_NOISE, Z_NOISE, shape)
            out = run_modes(rig, pos, dirs, lam, psi)
            if out["error"] is not None:
                failed += 1
                continue
            for key in hits:
                hits[key].extend(np.abs(out["value"][key] - truth[key]) <= 1.96 * out["se"][key])
        shares = "  ".join(f"{k} {np.mean(v):.3f}" for k, v in hits.items())
        allh = np.mean([x for v in hits.values() for x in v])
        print(f"observe {observe}, shape {100 * shape:.1f} %, {sensors} sensors, {draws} draws ({failed} refused): "
              f"{shares}  all {allh:.3f}")  # fmt: skip


# --------------------------------------------------------------------------- efficiency


def _ml_fit(rig: Rig, pos: np.ndarray, dirs: np.ndarray, lam: np.ndarray, psi: np.ndarray, shape: float) -> np.ndarray:
    """Noise-weighted ML fit of CG, J/m, K/m, C/m (51 parameters) to poles and shapes; returns CG, J diag (per mass)."""
    import scipy.linalg
    from scipy.optimize import least_squares

    from verdict_sim import skew

    m_true, k_true, c_true = rig.matrices()
    iu = np.triu_indices(6)
    i3 = np.triu_indices(3)
    rms = np.sqrt(np.mean(np.abs(psi) ** 2, axis=0))
    w_meas = np.abs(lam)
    z_meas = -lam.real / w_meas

    def unpack(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        g = x[:3]
        j = np.zeros((3, 3))
        j[i3] = x[3:9]
        j = j + np.triu(j, 1).T
        k = np.zeros((6, 6))
        k[iu] = x[9:30]
        k = k + np.triu(k, 1).T
        c = np.zeros((6, 6))
        c[iu] = x[30:51]
        c = c + np.triu(c, 1).T
        return g, j, k, c

    def residual(x: np.ndarray) -> np.ndarray:
        g, j, k, c = unpack(x)
        mm = np.eye(6)
        mm[3:, 3:] = j
        a = np.block([[np.zeros((6, 6)), np.eye(6)], [-np.linalg.solve(mm, k), -np.linalg.solve(mm, c)]])
        mu, vec = scipy.linalg.eig(a)
        up = np.flatnonzero(mu.imag > 0)
        if up.size != 6:
            return np.full(12 + 12 * pos.shape[0], 1e3)
        up = up[np.argsort(np.abs(mu[up]))]
        rows = np.array([np.concatenate([d, np.cross(s - g, d)]) for s, d in zip(pos, dirs, strict=True)])
        model = rows @ vec[:6, up]
        w = np.abs(mu[up])
        z = -mu[up].real / w
        out = [(w - w_meas) / (F_NOISE * w_meas), (z - z_meas) / (Z_NOISE * z_meas)]
        for i in range(6):
            a_i = np.vdot(model[:, i], psi[:, i]) / np.vdot(model[:, i], model[:, i])
            e = (psi[:, i] - a_i * model[:, i]) / (shape * rms[i] / np.sqrt(2.0))
            out.extend([e.real, e.imag])
        return np.concatenate(out)

    x0 = np.concatenate([rig.cg, (rig.inertia / rig.mass)[i3], (k_true / rig.mass)[iu], (c_true / rig.mass)[iu]])
    del m_true, skew
    sol = least_squares(residual, x0, x_scale="jac", method="lm", xtol=1e-10, ftol=1e-10)
    g, j, _, _ = unpack(sol.x)
    return np.concatenate([g, np.diag(j) * rig.mass])


def efficiency(draws: int, seed: int) -> None:
    print("RMS error: free route (rigidid identify, default) / noise-weighted ML fit of the free model (51 parameters)")
    rng = np.random.default_rng(seed)
    regimes = ((0.05, 0.01, 12), (0.3, 0.01, 12), (1.5, 0.01, 12), (0.3, 0.03, 32), (0.3, 0.003, 6))
    for observe, shape, sensors in regimes:
        rig = engine(observe=observe)
        pos, dirs = layout(sensors)
        lam0, psi0 = rig.modes(pos, dirs)
        e_free, e_ml = [], []
        for _ in range(draws):
            lam, psi = add_noise(lam0, psi0, rng, F_NOISE, Z_NOISE, shape)
            out = run_modes(rig, pos, dirs, lam, psi)
            if out["error"] is not None:
                continue
            truth = np.concatenate([rig.cg, np.diag(rig.inertia)])
            e_free.append(np.concatenate([out["value"]["cg"], out["value"]["J"]]) - truth)
            e_ml.append(_ml_fit(rig, pos, dirs, lam, psi, shape) - truth)
        rf = np.sqrt(np.mean(np.array(e_free) ** 2, axis=0))
        rm = np.sqrt(np.mean(np.array(e_ml) ** 2, axis=0))
        cg_ratio = np.linalg.norm(rf[:3]) / np.linalg.norm(rm[:3])
        j_ratio = np.linalg.norm(rf[3:] / np.diag(rig.inertia)) / np.linalg.norm(rm[3:] / np.diag(rig.inertia))
        print(f"observe {observe}, shape {100 * shape:.1f} %, {sensors} sensors, {len(e_free)} draws: CG RMS "
              f"{1000 * np.linalg.norm(rf[:3]):.3g} vs {1000 * np.linalg.norm(rm[:3]):.3g} mm (x{cg_ratio:.2f}); "
              f"inertia RMS {100 * np.linalg.norm(rf[3:] / np.diag(rig.inertia)):.3g} vs "
              f"{100 * np.linalg.norm(rm[3:] / np.diag(rig.inertia)):.3g} % (x{j_ratio:.2f})")  # fmt: skip


# --------------------------------------------------------------------------- crashes and time


def crash(draws: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    rig = engine(observe=0.05)
    pos, dirs = layout(12)
    lam0, psi0 = rig.modes(pos, dirs)
    truth = _truth(rig, 3)
    crashes = refusals = 0
    errors = []
    inside: dict[str, list[np.ndarray]] = {}
    for _ in range(draws):
        lam, psi = add_noise(lam0, psi0, rng, F_NOISE, Z_NOISE, 0.01)
        out = run_modes(rig, pos, dirs, lam, psi, listed=3, method="mounts")
        if out["error"] is not None:
            crashes += out["crash"]
            refusals += not out["crash"]
            errors.append(out["error"])
            continue
        errors.append(None)
        for key in ("cg", "J", "K", "rates"):
            if key in out.get("se", {}):
                hit = np.abs(out["value"][key] - truth[key]) <= 1.96 * out["se"][key]
                inside.setdefault(key, []).append(np.ravel(hit))
    print(f"--method mounts, weakly observable engine, 12 sensors, 1 % shape noise: {draws} draws, {crashes} crashes, "
          f"{refusals} refusals")  # fmt: skip
    shares = {key: float(np.mean(hits)) for key, hits in inside.items()}
    every = float(np.mean(np.concatenate([np.concatenate(h) for h in inside.values()]))) if inside else float("nan")
    print("  coverage of its default 95 % intervals (linearised from the output error's Jacobian): all "
          f"{every:.3f}; " + ", ".join(f"{key} {share:.3f}" for key, share in shares.items()))  # fmt: skip
    for text in sorted({e for e in errors if e})[:3]:
        print("  ", text[:200])


# --------------------------------------------------------------------------- plan against identify


def plan_check(draws: int, seed: int) -> None:
    """``plan``'s predicted standard deviations against what ``identify`` then achieves, one regime."""
    from rigidid.core.noise import NoiseLevels
    from rigidid.core.plan import predict_uncertainty
    from rigidid.core.simulate import Body, Mount, body_modes
    from rigidid.core.uncertainty import propagate

    rig = engine(observe=0.3)
    pos, dirs = layout(12)
    shape = 0.01
    levels = NoiseLevels(frequency=F_NOISE, damping=Z_NOISE, shape=shape)
    mounts = [Mount(p, k, c) for p, k, c in zip(rig.mount_pos, rig.mount_k, rig.mount_c, strict=True)]
    body = Body(rig.mass, rig.cg, rig.inertia, mounts)
    planned = predict_uncertainty(body, pos, dirs, noise=levels, draws=400, seed=seed)
    exact = body_modes(body, pos, dirs)
    fixed = propagate(pos, dirs, exact.poles, exact.shapes, mass=rig.mass, noise=levels, draws=400, seed=seed)
    lam0, psi0 = rig.modes(pos, dirs)
    rng = np.random.default_rng(seed)
    cg_err, mom_err, cg_se, mom_se = [], [], [], []
    truth_moments = np.linalg.eigvalsh(rig.inertia)
    for _ in range(draws):
        lam, psi = add_noise(lam0, psi0, rng, F_NOISE, Z_NOISE, shape)
        out = run_modes(rig, pos, dirs, lam, psi)
        if out["error"] is not None:
            continue
        cg_err.append(out["value"]["cg"] - rig.cg)
        mom_err.append(out["value"]["moments"] - truth_moments)
        cg_se.append(out["se"]["cg"])
        mom_se.append(out["se"]["moments"])
    rms = lambda e: np.sqrt(np.mean(np.square(e), axis=0))  # noqa: E731
    mm = 1000.0
    print(f"plan vs identify: engine, observability scale 0.3, 12 sensors, shape noise {100 * shape:g} %; "
          f"{len(cg_err)} identify draws (verdict_sim), plan 400 draws")  # fmt: skip
    rows = (
        ("plan (noise-weighted kernel)", planned.figures.center_of_gravity_std, planned.figures.principal_moments_std),
        ("plan as before (fixed weights)", fixed.center_of_gravity.std, fixed.principal_moments.std),
        ("identify: RMS error achieved", rms(cg_err), rms(mom_err)),
        ("identify: mean default SE", np.mean(cg_se, axis=0), np.mean(mom_se, axis=0)),
    )
    for label, cg, mom in rows:
        print(f"  {label:>31}: CG std (mm) {np.array2string(mm * np.asarray(cg), precision=2)}, "
              f"principal moments std (kg m^2) {np.array2string(np.asarray(mom), precision=3)}")  # fmt: skip


SAMPLES = ("paper-1994", "four-mounts", "engine-on-mounts", "uff-local-systems", "engine-test")

_DRIVER = """
import sys
from rigidid.cli import main
what = sys.argv.pop(1)
if what in ("without", "none"):  # no default standard errors, verdict or plausibility checks
    from rigidid.api import checks
    checks.standard_errors_of = lambda *a, **k: None
    checks.checked = lambda ident, *a, **k: ident
if what == "none":  # nor the noise-weighted refit (everything issue 22 added to identify)
    from rigidid.api import identification
    core = identification.identify_core
    identification.identify_core = lambda *a, **k: core(*a, **{**k, "noise": None})
sys.argv[0] = "rigidid"
main()
"""


def _identify_command(case: str, what: str, src: str) -> tuple[list[str], dict[str, str]]:
    import os

    folder = ROOT / "samples" / case
    command = [sys.executable, "-c", _DRIVER, what, "identify", str(folder / "layout.json"), str(folder / "modes.csv"),
               "--json", os.devnull]  # fmt: skip
    return command, {**os.environ, "PYTHONPATH": src, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}


def _cpu_seconds(command: list[str], env: dict[str, str]) -> float:
    """CPU time (user + system) of one process."""
    import os
    import subprocess

    child = subprocess.Popen(command, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(child.pid, 0)
    if status != 0:
        raise RuntimeError(f"{command[3:]} failed ({status})")
    return float(usage.ru_utime + usage.ru_stime)


def _row(case: str, m: dict[str, float]) -> None:
    added, issue = 100 * (m["with"] / m["without"] - 1), 100 * (m["with"] / m["none"] - 1)
    print(f"{case:>18} {m['none']:7.3f} {m['without']:8.3f} {m['with']:7.3f}  {added:+15.1f} % {issue:+15.1f} %")


def timing(rounds: int, baseline: str) -> None:
    """CPU time of ``rigidid identify`` as a fresh process with and without the default intervals.

    Rounds alternate the variants (ABAB..., the order flipped every round) so that the
    machine's load hits them alike; the figure is the median over `rounds` processes each.
    ``with``: as shipped; ``without``: no default standard errors, verdict or checks;
    ``none``: nor the noise-weighted refit (all that issue 22 added to ``identify``).
    """
    import statistics

    src = str(ROOT / "src")
    print(f"rigidid identify as a process, CPU s (user + system), median of {rounds} alternating rounds")
    print(f"{'sample':>18} {'none':>7} {'without':>8} {'with':>7}  intervals+checks  all of issue 22")
    for case in SAMPLES:
        cpu: dict[str, list[float]] = {"none": [], "without": [], "with": []}
        for r in range(rounds):
            for what in list(cpu) if r % 2 == 0 else list(cpu)[::-1]:
                cpu[what].append(_cpu_seconds(*_identify_command(case, what, baseline or src)))
        m = {what: statistics.median(values) for what, values in cpu.items()}
        _row(case, m)


def instructions(baseline: str) -> None:
    """Instructions executed (valgrind callgrind, repeatable to about 0.1 %) by ``rigidid identify``."""
    import re
    import subprocess

    src = str(ROOT / "src")
    print("rigidid identify as a process under valgrind --tool=callgrind: instructions (1e9)")
    print(f"{'sample':>18} {'none':>7} {'without':>8} {'with':>7}  intervals+checks  all of issue 22")
    for case in SAMPLES:
        m = {}
        for what in ("none", "without", "with"):
            command, env = _identify_command(case, what, baseline or src)
            out = subprocess.run(
                ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", *command],
                env=env, capture_output=True, text=True, check=True,
            ).stderr  # fmt: skip
            m[what] = int(re.findall(r"Collected : (\d+)", out)[-1]) / 1e9
        _row(case, m)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("what", nargs="?", default="all")
    parser.add_argument("--draws", type=int, default=None)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--baseline", default=None, help="src directory of another tree to time instead of this one")
    args = parser.parse_args()
    what = args.what
    if what in ("matrix", "all"):
        matrix(args.draws or 3, args.seed)
    if what in ("coverage", "all"):
        coverage(args.draws or 200, args.seed)
    if what in ("efficiency", "all"):
        efficiency(args.draws or 40, args.seed)
    if what in ("crash", "all"):
        crash(args.draws or 200, args.seed)
    if what in ("time", "all"):
        timing(args.draws or 20, args.baseline)
    if what in ("plan", "all"):
        plan_check(args.draws or 200, args.seed)
    if what == "instructions":
        instructions(args.baseline)


if __name__ == "__main__":
    main()
