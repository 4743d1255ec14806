"""The records route's sensor test and correction judged on bodies nobody tuned on: a regime matrix (issue 23).

Run from the worktree root (each run is one ``rigidid identify --records`` with defaults, ~3-8 s)::

    PYTHONPATH=src OPENBLAS_NUM_THREADS=1 nice -n 10 python benchmarks/chain_regimes.py
        [--cells base,exact,...] [--seeds 3] [--first-seed 800] [--runs] [--list]

The forward model is written here afresh and shares no code with rigidid (nor with chain_matrix.py): a rigid
body on linear mounts (6x6 M, K from the mounts' 3x3 stiffnesses, classical modal damping
``C = M Phi diag(2 zeta_i w_i) Phi^T M``), its 12-state system diagonalised, and the response to a half-sine
hammer pulse written in closed form per mode (the convolution of ``exp(lambda t)`` with the pulse, exact at
every sample: no time stepping). Sensors read ``g_i (a_i + t_i) . (u + theta x (p_i - CG))`` with their true
gain, axis, transverse part and position. Noise: white, a fraction of each channel's RMS over its record
(rigidid simulate's convention), 0.25 s pre-trigger.

Axes (one varied at a time from ``base``, then a few corners; ``--list`` prints every cell):

- body: ``mid`` (base: 80 kg box on four inclined mounts, modes 8-20 Hz), ``compact`` (25 kg stiff cube,
  modes 20-63 Hz), ``tall`` (a 1.6 m cabinet whose sensors sit in a 0.3 m cluster: low observability,
  modes 4-19 Hz), ``battery`` (400 kg flat pack on six mounts, modes 5-15 Hz);
- damping 3 % (base), 1 %, 8 % (each mode's ratio within +-20 % of it);
- sensors: 10 single-axis (base), 6 single-axis (3-2-1, no redundancy), 4 triaxial blocks (12 channels);
- noise 1 % (base), 0.3 %, 5 %; sample rate 2048 Hz (base), 1024, 4096;
- sensor errors: ``stated`` (base: gains +-3 %, axes +-3 degrees per normal axis, transverse up to 3 % in a
  uniform direction, positions +-3 mm per axis, all uniform: the stated distribution, those tolerances stated
  in the layout; a triaxial block's three channels share its position error) or ``exact`` (exact sensors,
  no ``tolerances`` block: rigidid's defaults hold, the sensor test's realistic null).

Records last 5 time constants of the slowest mode (3-12 s). Per cell: runs finished (exit 0) / warned /
refused (exit != 0); runs whose sensor test flagged (p < its false-alarm rate) and whose sensors were
estimated; coverage of the reported 95 % intervals (CG and the inertia tensor's six entries: 9 quantities per
run, the std from ``uncertainty_records_crb``, else ``standard_errors``); RMS and max of the z scores (error
over reported std); ``silent``: exit 0, no warning, some |z| > 4; ``target``: runs whose CG error (% of the
sensor span, largest coordinate) and inertia error (largest relative error of the diagonal, %) are within
1.25 x the floor plus 6 x the noise std (the run's ``sensor_budget.noise``, in the same units), the floor
being ``rigidid.core.estimator.estimate`` on this simulator's exact modes read through the run's erroneous
sensors (zero for exact sensors). Totals at the end; ``--runs`` prints every run.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

PRE, PULSE, Z95 = 0.25, 0.003, 1.959964
TOLERANCES = {"sensitivity": 0.03, "orientation_deg": 3.0, "transverse": 0.03, "position": 0.003}


@dataclass(frozen=True)
class Body:
    """A rigid body on mounts: mass (kg), CG and inertia about it (m, kg m^2), mounts, sensor region."""

    mass: float
    cg: tuple[float, float, float]
    inertia: tuple[tuple[float, float, float], ...]
    mounts: tuple[tuple[float, float, float], ...]  # positions (m)
    scale: tuple[float, ...]  # each mount's stiffness factor
    incline_deg: float  # mount axes tilted towards the centre
    shear: float  # shear over axial stiffness
    lowest_hz: float  # K scaled so that the lowest mode sits here
    box: tuple[tuple[float, float, float], tuple[float, float, float]]  # sensor region: low and high corner


BODIES = {
    "mid": Body(80.0, (0.03, -0.02, 0.08), ((5.0, 0.3, -0.2), (0.3, 7.0, 0.3), (-0.2, 0.3, 8.0)),
                ((0.45, 0.3, -0.2), (-0.4, 0.32, -0.2), (-0.45, -0.28, -0.2), (0.38, -0.3, -0.2)),
                (1.6, 0.5, 1.3, 0.6), 35.0, 0.133, 8.0, ((-0.45, -0.35, -0.15), (0.45, 0.35, 0.25))),
    "compact": Body(25.0, (0.01, 0.015, 0.05), ((0.45, 0.02, -0.01), (0.02, 0.5, 0.03), (-0.01, 0.03, 0.4)),
                    ((0.15, 0.14, -0.15), (-0.15, 0.15, -0.15), (-0.14, -0.15, -0.15), (0.15, -0.15, -0.15)),
                    (1.6, 0.5, 1.3, 0.6), 40.0, 0.3, 20.0, ((-0.17, -0.17, -0.12), (0.17, 0.17, 0.17))),
    "tall": Body(120.0, (0.02, -0.01, 0.75), ((28.0, 0.5, -0.8), (0.5, 26.0, 0.6), (-0.8, 0.6, 5.0)),
                 ((0.22, 0.2, 0.0), (-0.22, 0.2, 0.0), (-0.22, -0.2, 0.0), (0.22, -0.2, 0.0)),
                 (1.1, 0.9, 1.2, 0.8), 20.0, 0.2, 4.0, ((-0.15, -0.15, 0.6), (0.15, 0.15, 0.8))),
    "battery": Body(400.0, (0.05, -0.04, 0.02), ((50.0, 1.5, -0.5), (1.5, 110.0, 0.8), (-0.5, 0.8, 156.0)),
                    ((0.8, 0.5, -0.125), (-0.8, 0.5, -0.125), (-0.8, -0.5, -0.125), (0.8, -0.5, -0.125),
                     (0.0, 0.55, -0.125), (0.0, -0.55, -0.125)),
                    (1.6, 0.5, 1.3, 0.6, 1.0, 0.7), 20.0, 0.25, 5.0, ((-0.85, -0.55, -0.12), (0.85, 0.55, 0.12))),
}  # fmt: skip

# sensor sets in the sensor box's normalised coordinates ([-1, 1] per axis): (position, direction) per channel
_S10 = [((1, 1, 1), "z"), ((-1, 1, 1), "x"), ((-1, -1, 1), "y"), ((1, -1, 1), "z"), ((1, 1, -1), "x"),
        ((-1, 1, -1), "y"), ((-1, -1, -1), "z"), ((1, -1, -1), "y"), ((0, 1, 0), "x"), ((0, -1, 1), "x")]  # fmt: skip
_S6 = [((1, 1, 1), "z"), ((-1, 1, 1), "z"), ((0, -1, -1), "z"), ((1, -1, 1), "y"), ((-1, -1, -1), "y"),
       ((1, 1, -1), "x")]  # fmt: skip  # 3-2-1: six channels for six motions, no redundancy
_TRI4 = [(p, a) for p in ((1, 1, 1), (-1, 1, -1), (-1, -1, 1), (1, -1, -1)) for a in "xyz"]
SENSOR_SETS = {"s10": _S10, "s6": _S6, "tri4": _TRI4}
IMPACTS = [((1.0, 0.8, 1.0), (-0.4, -0.3, -1.0)), ((-1.0, -0.2, 0.4), (1.0, 0.5, 0.2)),
           ((0.4, -1.0, 0.0), (0.3, 1.0, -0.4))]  # fmt: skip


@dataclass(frozen=True)
class Cell:
    body: str = "mid"
    sensors: str = "s10"
    noise: float = 0.01
    rate: float = 2048.0
    damping: float = 0.03
    errors: str = "stated"
    highpass: float = 0.0  # Hz: an AC coupling nobody states (first-order, every channel)


BASE = Cell()
CELLS: dict[str, Cell] = {
    "base": BASE,
    "exact": replace(BASE, errors="exact"),
    "compact": replace(BASE, body="compact"),
    "compact-exact": replace(BASE, body="compact", errors="exact"),
    "tall": replace(BASE, body="tall"),
    "tall-exact": replace(BASE, body="tall", errors="exact"),
    "battery": replace(BASE, body="battery"),
    "battery-exact": replace(BASE, body="battery", errors="exact"),
    "damp1": replace(BASE, damping=0.01),
    "damp8": replace(BASE, damping=0.08),
    "s6": replace(BASE, sensors="s6"),
    "s6-exact": replace(BASE, sensors="s6", errors="exact"),
    "tri4": replace(BASE, sensors="tri4"),
    "tri4-exact": replace(BASE, sensors="tri4", errors="exact"),
    "n0.3": replace(BASE, noise=0.003),
    "n0.3-exact": replace(BASE, noise=0.003, errors="exact"),
    "n5": replace(BASE, noise=0.05),
    "n5-exact": replace(BASE, noise=0.05, errors="exact"),
    "r1024": replace(BASE, rate=1024.0),
    "r4096": replace(BASE, rate=4096.0),
    "battery-s6-n5": replace(BASE, body="battery", sensors="s6", noise=0.05),
    "battery-damp1-r4096": replace(BASE, body="battery", damping=0.01, rate=4096.0),
    "compact-damp8-r1024": replace(BASE, body="compact", damping=0.08, rate=1024.0),
    "compact-s6-n0.3": replace(BASE, body="compact", sensors="s6", noise=0.003),
    "tall-s6": replace(BASE, body="tall", sensors="s6"),
    "tall-tri4-n5": replace(BASE, body="tall", sensors="tri4", noise=0.05),
    "tall-damp1-exact": replace(BASE, body="tall", damping=0.01, errors="exact"),
    "tall-tri4-n0.3-exact": replace(BASE, body="tall", sensors="tri4", noise=0.003, errors="exact"),
    "base-nopos": replace(BASE, errors="stated-nopos"),
    "n0.3-nopos": replace(BASE, noise=0.003, errors="stated-nopos"),
    "compact-nopos": replace(BASE, body="compact", errors="stated-nopos"),
    "ac0.5": replace(BASE, highpass=0.5),
    "ac2": replace(BASE, highpass=2.0),
    "ac2-exact": replace(BASE, highpass=2.0, errors="exact"),
    "ac2-damp8": replace(BASE, highpass=2.0, damping=0.08),
    "ac2-n5": replace(BASE, highpass=2.0, noise=0.05),
    "ac1-tri4": replace(BASE, highpass=1.0, sensors="tri4"),
    "ac1-tall": replace(BASE, highpass=1.0, body="tall"),
    "ac3-tall": replace(BASE, highpass=3.0, body="tall"),
    "ac5-compact": replace(BASE, highpass=5.0, body="compact"),
    "ac1-battery": replace(BASE, highpass=1.0, body="battery"),
    "ac2-battery": replace(BASE, highpass=2.0, body="battery"),
    "ac0.2-battery-damp1": replace(BASE, highpass=0.2, body="battery", damping=0.01),
}
"""``*-nopos`` are diagnoses, not regimes: the stated draws with exact positions (their 3 mm tolerance still
stated), to tell what the positions' errors, which the correction does not estimate, do to it. ``ac*``: an AC
coupling nobody states (first-order, the corner in Hz, on every channel's reading and noise, scipy.signal's
bilinear filter), the refit finding and modelling it; ``ac3-tall`` puts the corner above half the lowest mode
(4 Hz), where the refit does not look for one (its answer is judged all the same)."""


def _cross(r: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def _rigid(r: np.ndarray) -> np.ndarray:
    """3x6: a point's motion at offset `r` from the CG, u + theta x r."""
    return np.hstack([np.eye(3), -_cross(r)])


def _denormalise(body: Body, p: tuple[float, ...]) -> np.ndarray:
    low, high = np.array(body.box[0]), np.array(body.box[1])
    return (low + high) / 2 + np.asarray(p, float) * (high - low) / 2


@dataclass(frozen=True)
class System:
    """The truth: 6x6 M, K, C (CG coordinates), CG, and the 12-state system's modal form."""

    m: np.ndarray
    k: np.ndarray
    c: np.ndarray
    cg: np.ndarray
    lam: np.ndarray  # 12 poles
    vec: np.ndarray  # 12x12 eigenvectors of the state matrix


def system(body: Body, damping: float) -> System:
    """M, K (scaled so the lowest undamped mode is ``body.lowest_hz``), C with modal damping of each mode
    0.8-1.2 x `damping` (lowest to highest)."""
    from scipy.linalg import eig, eigh

    cg = np.array(body.cg)
    m = np.zeros((6, 6))
    m[:3, :3], m[3:, 3:] = body.mass * np.eye(3), np.array(body.inertia)
    centre = np.mean(np.array(body.mounts), axis=0)
    k = np.zeros((6, 6))
    for where, factor in zip(body.mounts, body.scale, strict=True):
        inward = centre - np.array(where)
        inward[2] = 0.0
        axis = np.array([0.0, 0.0, 1.0]) + np.tan(np.radians(body.incline_deg)) * inward / np.linalg.norm(inward)
        axis /= np.linalg.norm(axis)
        k3 = factor * (body.shear * np.eye(3) + (1.0 - body.shear) * np.outer(axis, axis))
        t = _rigid(np.array(where) - cg)
        k += t.T @ k3 @ t
    w2, phi = eigh(k, m)
    k *= (2 * np.pi * body.lowest_hz) ** 2 / w2[0]
    w2, phi = eigh(k, m)  # phi mass-normalised
    zeta = damping * np.linspace(0.8, 1.2, 6)
    c = m @ phi @ np.diag(2 * zeta * np.sqrt(w2)) @ phi.T @ m
    a = np.block([[np.zeros((6, 6)), np.eye(6)], [-np.linalg.solve(m, k), -np.linalg.solve(m, c)]])
    lam, vec = eig(a)
    return System(m, k, c, cg, lam, vec)


def exact_modes(sys_: System) -> tuple[np.ndarray, np.ndarray]:
    """The six poles (upper half plane, by frequency) and their displacement shapes (6 x 6, columns)."""
    up = np.flatnonzero(sys_.lam.imag > 0)
    up = up[np.argsort(np.abs(sys_.lam[up]))]
    return sys_.lam[up], sys_.vec[:6, up]


def draw_sensors(body: Body, kind: str, errors: str, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Stated positions and axes, and the true reading vectors (gain x (axis + transverse)) and positions."""
    spec = SENSOR_SETS[kind]
    pos = np.array([_denormalise(body, p) for p, _ in spec])
    axes = np.array([np.eye(3)["xyz".index(a)] for _, a in spec])
    n = len(spec)
    if errors == "exact":
        return {"position": pos, "axis": axes, "reading": axes.copy(), "true_position": pos.copy()}
    helper = np.where(np.abs(axes[:, [0]]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    e1 = np.cross(axes, helper)
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    e2 = np.cross(axes, e1)
    tilt = np.radians(rng.uniform(-3.0, 3.0, (n, 2)))
    true_axis = axes + tilt[:, :1] * e1 + tilt[:, 1:] * e2
    true_axis /= np.linalg.norm(true_axis, axis=1)[:, None]
    tau, phase = rng.uniform(0.0, 0.03, (n, 1)), rng.uniform(0.0, 2 * np.pi, (n, 1))
    reading = true_axis + tau * (np.cos(phase) * e1 + np.sin(phase) * e2)
    reading *= rng.uniform(0.97, 1.03, (n, 1))
    _, block = np.unique(pos, axis=0, return_inverse=True)  # a triaxial block's channels share its position
    shift = rng.uniform(-0.003, 0.003, (int(block.max()) + 1, 3))[block.ravel()]
    if errors == "stated-nopos":  # diagnosis: the same draws, the positions exact (their tolerance still stated)
        shift = 0.0 * shift
    return {"position": pos, "axis": axes, "reading": reading, "true_position": pos + shift}


def _response(lam: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Each mode's response to a unit half-sine pulse of width PULSE starting at tau = 0 (samples x modes).

    z(tau) = int_0^min(tau, w) exp(lam (tau - u)) sin(pi u / w) du, in closed form."""
    w = np.pi / PULSE
    u = np.clip(tau, 0.0, PULSE)[:, None]
    a = -lam[None, :]
    part = (np.exp(a * u) * (a * np.sin(w * u) - w * np.cos(w * u)) + w) / (a**2 + w**2)
    return np.where(tau[:, None] >= 0, np.exp(lam[None, :] * np.maximum(tau, 0.0)[:, None]) * part, 0.0)


def simulate(sys_: System, body: Body, sensors: dict[str, np.ndarray], cell: Cell, rng: np.random.Generator,
             duration: float) -> list[np.ndarray]:  # fmt: skip
    """One record per impact (samples x channels), the chain's noise added."""
    t = np.arange(round(duration * cell.rate)) / cell.rate
    out = np.array([r @ _rigid(p - sys_.cg) for r, p in zip(sensors["reading"], sensors["true_position"],
                                                             strict=True)])  # fmt: skip
    minv_k, minv_c = np.linalg.solve(sys_.m, sys_.k), np.linalg.solve(sys_.m, sys_.c)
    records = []
    for where, direction in IMPACTS:
        d = np.asarray(direction, float) / np.linalg.norm(direction)
        force_6 = _rigid(_denormalise(body, where) - sys_.cg).T @ d * 300.0 * body.mass / 80.0
        b = np.concatenate([np.zeros(6), np.linalg.solve(sys_.m, force_6)])
        z = _response(sys_.lam, t - PRE) * np.linalg.solve(sys_.vec, b)[None, :]
        x = np.real(z @ sys_.vec.T)  # samples x 12
        f = np.where((t >= PRE) & (t < PRE + PULSE), np.sin(np.pi * np.clip(t - PRE, 0, PULSE) / PULSE), 0.0)
        qdd = -x[:, :6] @ minv_k.T - x[:, 6:] @ minv_c.T + np.outer(f, b[6:])
        acc = qdd @ out.T
        rms = np.sqrt(np.mean(acc**2, axis=0))
        y = acc + cell.noise * rms * rng.standard_normal(acc.shape)
        if cell.highpass > 0.0:  # the sensors' AC coupling, on the reading and its noise alike
            from scipy.signal import bilinear, lfilter

            num, den = bilinear([1.0, 0.0], [1.0, 2 * np.pi * cell.highpass], cell.rate)
            y = lfilter(num, den, y, axis=0)
        records.append(y)
    return records


def duration_of(sys_: System) -> float:
    """Five time constants of the slowest-decaying mode, within 3-12 s."""
    return float(np.clip(5.0 / np.min(-sys_.lam.real), 3.0, 12.0))


def write_case(folder: Path, cell: Cell, body: Body, sensors: dict[str, np.ndarray],
               records: list[np.ndarray]) -> list[Path]:  # fmt: skip
    names = [f"c{i + 1}" for i in range(len(sensors["position"]))]
    layout: dict[str, object] = {
        "name": f"chain_regimes {cell}",
        "units": {"length": "m", "mass": "kg"},
        "mass": body.mass,
        "sensors": [{"id": n, "position": p.tolist(), "direction": a.tolist()}
                    for n, p, a in zip(names, sensors["position"], sensors["axis"], strict=True)],
    }  # fmt: skip
    if cell.errors != "exact":
        layout["tolerances"] = TOLERANCES
    (folder / "layout.json").write_text(json.dumps(layout))
    paths = []
    for k, rec in enumerate(records):
        path = folder / f"record-{k + 1}.csv"
        time = np.arange(rec.shape[0]) / cell.rate
        np.savetxt(path, np.column_stack([time, rec]), delimiter=",", header="time," + ",".join(names),
                   comments="", fmt=["%.10g"] + ["%.8g"] * rec.shape[1])  # fmt: skip
        paths.append(path)
    return paths


def _errors(body: Body, sensors: dict[str, np.ndarray], cg: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """CG error (% of the sensor span, largest coordinate), inertia error (largest relative diagonal, %)."""
    span = float(np.max(np.ptp(sensors["position"], axis=0)))
    truth = np.array(body.inertia)
    return np.array([100 * np.max(np.abs(cg - np.array(body.cg))) / span,
                     100 * np.max(np.abs(np.diag(inertia) - np.diag(truth)) / np.diag(truth))])  # fmt: skip


def floor(sys_: System, body: Body, sensors: dict[str, np.ndarray]) -> np.ndarray:
    """The modal kernel's errors on this simulator's exact modes read through the run's sensors (CG, J)."""
    from rigidid.core.estimator import estimate

    lam, shapes = exact_modes(sys_)
    read = np.array([r @ _rigid(p - sys_.cg) for r, p in zip(sensors["reading"], sensors["true_position"],
                                                              strict=True)])  # fmt: skip
    est = estimate(sensors["position"][None], sensors["axis"][None], lam[None], (read @ shapes)[None])
    return _errors(body, sensors, est.center_of_gravity[0], body.mass * est.inertia_per_mass[0])


def _z_scores(body: Body, data: dict) -> tuple[np.ndarray, dict | None]:  # type: ignore[type-arg]
    """z of the CG and the inertia tensor's six entries against the reported std; the refit's block."""
    crb = data.get("uncertainty_records_crb")
    source = crb if crb is not None else data.get("standard_errors", {})
    cg_sd = np.asarray(source["center_of_gravity"]["std"] if crb is not None else source["center_of_gravity"])
    j_sd = np.asarray(source["inertia_tensor"]["std"] if crb is not None else source["inertia_tensor"])
    upper = np.triu_indices(3)
    err_cg = np.array(data["center_of_gravity"]) - np.array(body.cg)
    err_j = (np.array(data["inertia_tensor"]) - np.array(body.inertia))[upper]
    return np.concatenate([err_cg / cg_sd, err_j / j_sd[upper]]), crb


def sensor_z(sensors: dict[str, np.ndarray], corrections: dict) -> np.ndarray:  # type: ignore[type-arg]
    """z of the estimated sensor errors the records determine (gains, tilts about e1 and e2; the transverse
    part reads as a tilt) against the truth, over their posterior std."""
    axes, reading = sensors["axis"], sensors["reading"]
    helper = np.where(np.abs(axes[:, [0]]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    e1 = np.cross(axes, helper)
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    e2 = np.cross(axes, e1)
    size = np.linalg.norm(reading, axis=1)
    unit = reading / size[:, None]
    z = []
    for i, est in enumerate(corrections[f"c{i + 1}"] for i in range(len(axes))):
        along = float(unit[i] @ axes[i])  # rigidid's axis: normalise(a + t1 e1 + t2 e2), the records over 1 + gain
        truth = (size[i] - 1.0, float(unit[i] @ e1[i]) / along, float(unit[i] @ e2[i]) / along)
        value = (est["gain"], *est["tilt_rad"])
        std = (est["gain_std"], *est["tilt_std_rad"])
        z += [(v - t) / sd for v, t, sd, d in zip(value, truth, std, est["determined"], strict=True) if d and sd > 0]
    return np.array(z)


def cg_sd_of(crb: dict) -> np.ndarray:  # type: ignore[type-arg]
    """The refit's reported std of the CG."""
    return np.asarray(crb["center_of_gravity"]["std"])


def j_sd_of(crb: dict) -> np.ndarray:  # type: ignore[type-arg]
    """The refit's reported std of the inertia tensor's six entries (upper triangle)."""
    return np.asarray(crb["inertia_tensor"]["std"])[np.triu_indices(3)]


def run(name: str, seed: int, keep: str | None = None) -> dict[str, object]:
    """One run of cell `name` with `seed`: simulate, identify with defaults, judge; `keep`: a folder the case
    (layout and records) is written to, ``<keep>/<cell>-<seed>``, for diagnosis."""
    cell = CELLS[name]
    body = BODIES[cell.body]
    rng = np.random.default_rng([seed, list(CELLS).index(name.removesuffix("-nopos"))])  # nopos: its twin's draws
    sys_ = system(body, cell.damping)
    sensors = draw_sensors(body, cell.sensors, cell.errors, rng)
    records = simulate(sys_, body, sensors, cell, rng, duration_of(sys_))
    with tempfile.TemporaryDirectory() as tmp_dir:
        tmp = Path(keep) / f"{name}-{seed}" if keep else Path(tmp_dir)
        tmp.mkdir(parents=True, exist_ok=True)
        paths = write_case(tmp, cell, body, sensors, records)
        command = [sys.executable, "-m", "rigidid", "identify", str(Path(tmp) / "layout.json"), "--records",
                   *map(str, paths), "--mass", str(body.mass), "--json", "-"]  # fmt: skip
        out = subprocess.run(command, capture_output=True, text=True, env=dict(os.environ), check=False)
    row: dict[str, object] = {"cell": name, "seed": seed, "exit": out.returncode, "floor": floor(sys_, body, sensors)}
    row["warnings"] = [line for line in out.stderr.splitlines() if "warning" in line]
    if out.returncode != 0:
        row["error"] = out.stderr.strip().splitlines()[-1] if out.stderr.strip() else ""
        return row
    data = json.loads(out.stdout)
    row["errors"] = _errors(body, sensors, np.array(data["center_of_gravity"]), np.array(data["inertia_tensor"]))
    z, crb = _z_scores(body, data)
    row["z"], row["refit"] = z, crb is not None
    row["silent"] = bool(np.max(np.abs(z)) > 4 and not row["warnings"])
    row["sensor_test"] = (crb or {}).get("sensor_test")
    row["ac_coupling"] = (crb or {}).get("ac_coupling")
    if (crb or {}).get("sensor_corrections"):
        row["sensor_z"] = sensor_z(sensors, crb["sensor_corrections"])  # type: ignore[index]
    row["false_sensor_warnings"] = sum("the records say its" in w for w in row["warnings"])  # type: ignore[attr-defined]
    noise = ((crb or {}).get("sensor_budget") or {}).get("noise")
    if noise is not None:
        span = float(np.max(np.ptp(sensors["position"], axis=0)))
        j_sd = np.diag(np.array(noise["inertia_tensor"])) / np.diag(np.array(body.inertia))
        se = np.array([100 * np.max(noise["center_of_gravity"]) / span, 100 * np.max(j_sd)])
        row["noise_se"] = se
        upper = np.triu_indices(3)
        sd = np.concatenate([noise["center_of_gravity"], np.array(noise["inertia_tensor"])[upper]])
        row["z_noise"] = z * np.concatenate([cg_sd_of(crb), j_sd_of(crb)]) / sd  # type: ignore[arg-type]
        row["target"] = bool(np.all(row["errors"] <= 1.25 * row["floor"] + 6 * se))  # type: ignore[operator]
    return row


def cell_of(name: str) -> Cell:
    """The cell called `name`."""
    return CELLS[name]


def _coupling_text(found: object, truth: float) -> str:
    """A run's AC coupling test (``ac_coupling``): the corner found (and its z against `truth`, Hz, when there is
    one), whether the refit modelled it."""
    if not isinstance(found, dict):
        return ""
    sd = found.get("corner_std_hz")
    z = f" z {(found['corner_hz'] - truth) / sd:.1f}" if truth > 0 and sd else ""
    return (f"ac {found['corner_hz']:.3g} Hz{z} p {found['p_value']:.2g} interior {found.get('interior')} "
            f"modelled {found['modelled']} ")  # fmt: skip


def summary(name: str, rows: list[dict[str, object]]) -> dict[str, float]:
    """The cell's line: finished/warned/refused, flagged/estimated, coverage, RMS z, max |z|, silent, target,
    RMS of the z against the noise std alone, the sensor estimates' largest |z| and runs with one beyond 4,
    the SensorCorrectionWarnings (all false: every true error is within its tolerance or zero)."""
    done = [r for r in rows if r["exit"] == 0]
    tests = [r["sensor_test"] for r in done if r.get("sensor_test")]
    flagged = sum(t["p_value"] < t["false_alarm_rate"] for t in tests)  # type: ignore[index]
    estimated = sum(bool(t["sensors_estimated"]) for t in tests)  # type: ignore[index]
    z = np.concatenate([r["z"] for r in done]) if done else np.full(1, np.nan)  # type: ignore[misc]
    zn = np.concatenate([r["z_noise"] for r in done if "z_noise" in r] or [np.full(1, np.nan)])  # type: ignore[misc]
    sz = [float(np.max(np.abs(r["sensor_z"]), initial=0.0)) for r in done if "sensor_z" in r]  # type: ignore[call-overload]
    out = {
        "runs": len(rows), "finished": len(done), "warned": sum(bool(r["warnings"]) for r in done),
        "refused": len(rows) - len(done), "refit": sum(bool(r.get("refit")) for r in done), "flagged": flagged,
        "estimated": estimated, "covered": float(np.sum(np.abs(z) <= Z95)) if done else 0.0,
        "quantities": z.size if done else 0, "silent": sum(bool(r.get("silent")) for r in done),
        "target": sum(bool(r.get("target")) for r in done), "judged": sum("target" in r for r in done),
        "sensor_nonsense": sum(v > 4 for v in sz),
        "false_sensor_warnings": sum(int(r.get("false_sensor_warnings", 0)) for r in done),  # type: ignore[call-overload]
    }  # fmt: skip
    worst = np.max([r["errors"] for r in done], axis=0) if done else [np.nan, np.nan]
    fl = np.max([r["floor"] for r in rows], axis=0)
    cover = out["covered"] / max(out["quantities"], 1)
    note = next((str(r.get("error") or r["warnings"][0]) for r in rows if r.get("error") or r["warnings"]), "")  # type: ignore[index]
    rms_z, max_z, rms_zn = (_stat(f, v) for f, v in ((np.mean, z**2), (np.max, np.abs(z)), (np.mean, zn**2)))
    print(f"{name:<21} {out['finished']}/{out['warned']}/{out['refused']:<3} {out['refit']:>5} "
          f"{flagged:>3}/{estimated:<3} {cover:>6.2f} {np.sqrt(rms_z):>6.2f} {max_z:>6.2f} "
          f"{out['silent']:>6} {out['target']:>3}/{out['judged']:<3} {np.sqrt(rms_zn):>7.2f} "
          f"{max(sz, default=np.nan):>7.2f}/{out['sensor_nonsense']:<2} {out['false_sensor_warnings']:>4} "
          f"{worst[0]:>7.3f}/{worst[1]:<6.2f} {fl[0]:>6.3f}/{fl[1]:<6.2f} {note.replace('rigidid: ', '')[:80]}",
          flush=True)  # fmt: skip
    return out


def _stat(f: object, values: np.ndarray) -> float:
    """`f` over the finite `values` (nan when none)."""
    finite = values[np.isfinite(values)]
    return float(f(finite)) if finite.size else float("nan")  # type: ignore[operator]


def describe() -> None:
    """Every cell and its truth's modes."""
    for name, cell in CELLS.items():
        sys_ = system(BODIES[cell.body], cell.damping)
        lam, _ = exact_modes(sys_)
        print(f"{name:<21} {cell}  modes " + " ".join(f"{abs(v) / 2 / np.pi:.1f}" for v in lam)
              + f" Hz  zeta {100 * np.min(-lam.real / abs(lam)):.1f}-{100 * np.max(-lam.real / abs(lam)):.1f} %"
              + f"  record {duration_of(sys_):.1f} s")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", default=",".join(CELLS))
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--first-seed", type=int, default=800)
    parser.add_argument("--runs", action="store_true", help="print every run")
    parser.add_argument("--list", action="store_true", help="print the cells and their modes, run nothing")
    parser.add_argument("--keep", help="write each case (layout, records) to KEEP/<cell>-<seed>")
    args = parser.parse_args()
    if args.list:
        describe()
        return
    print(f"{'cell':<21} {'fin/warn/ref':<9} {'refit':>5} {'flag/est':>7} {'cover':>6} {'RMS z':>6} {'max|z|':>6} "
          f"{'silent':>6} {'target':>7} {'RMS zn':>7} {'sens z/>4':>10} {'swarn':>5} {'worst CG%/J%':>14} "
          f"{'floor CG/J':>13} first warning or error")  # fmt: skip
    totals: dict[str, float] = {}
    for name in args.cells.split(","):
        rows = []
        for seed in range(args.first_seed, args.first_seed + args.seeds):
            r = run(name, seed, args.keep)
            rows.append(r)
            if args.runs:
                test = r.get("sensor_test") or {}
                print(f"    {name} seed {seed}: exit {r['exit']} errors {np.round(r.get('errors', []), 3).tolist()} "  # type: ignore[arg-type]
                      f"floor {np.round(r['floor'], 3).tolist()} "  # type: ignore[arg-type]
                      f"noise se {np.round(r.get('noise_se', []), 3).tolist()} "  # type: ignore[arg-type]
                      f"z {np.round(r.get('z', []), 2).tolist()} target {r.get('target')} silent {r.get('silent')} "  # type: ignore[arg-type]
                      f"T {test.get('statistic')} dof {test.get('dof')} p {test.get('p_value')} "
                      f"estimated {test.get('sensors_estimated')} warnings {len(r['warnings'])} "  # type: ignore[arg-type]
                      f"{_coupling_text(r.get('ac_coupling'), cell_of(name).highpass)}"
                      f"{(r.get('error') or (r['warnings'][0] if r['warnings'] else ''))[:150]}", flush=True)  # type: ignore[index]  # fmt: skip
        for key, value in summary(name, rows).items():
            totals[key] = totals.get(key, 0) + value
    print(f"TOTAL runs {totals['runs']:.0f}: finished {totals['finished']:.0f}, warned {totals['warned']:.0f}, "
          f"refused {totals['refused']:.0f}, refit kept {totals['refit']:.0f}, sensor test flagged "
          f"{totals['flagged']:.0f}, estimated {totals['estimated']:.0f}, coverage "
          f"{totals['covered'] / max(totals['quantities'], 1):.3f}, silently wrong {totals['silent']:.0f}, "
          f"within target {totals['target']:.0f}/{totals['judged']:.0f}, sensor estimates beyond 4 std "
          f"{totals['sensor_nonsense']:.0f} runs, false sensor warnings "
          f"{totals['false_sensor_warnings']:.0f}")  # fmt: skip


if __name__ == "__main__":
    main()
