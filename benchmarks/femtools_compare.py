"""rigidid's mass line beside femtools.rbpe on the same simulated FRFs and on femtools' own example.

Run: ``.venv/bin/python benchmarks/femtools_compare.py --femtools DIR [--trials N]``

``DIR`` holds a copy of femtools' ``femtools/rbpe`` package (github 9997433-bit/femtools,
MIT; not on PyPI: the PyPI package of that name is another project): ``DIR/femtools/rbpe/``
with ``__init__.py`` and ``rbfit.py`` (commit b462208, the version with ``mount_k`` and
``restraint``) and an empty ``DIR/femtools/__init__.py`` (femtools' own imports its whole
package). It is imported from there, in this process (it needs numpy and scipy only);
nothing of it is in rigidid. Without ``--femtools`` only rigidid runs.

Scenarios (as ``benchmarks/frf_accuracy.py``): a random body (``tests.bodies.random_body``)
free-free (mounts at 1/100 of their stiffness: supports about a tenth of the band) or on its
mounts as drawn; 8 random sensors; 3 references at three corners of the sensor box along x,
y and z (and, as femtools asks for, 6 references: those three plus the other three
directions at the same corners); accelerance 0.25-400 Hz (3200 lines), one elastic mode at
300 Hz (1 % damping), 1 % complex noise. rigidid: ``rigidid.core.massline.mass_line`` with
its automatic band. femtools: ``rigid_body_properties`` as documented, (a) defaults
(averaged mass line, its own automatic band), (b) defaults on rigidid's band, (c) defaults
from rigidid's lower band edge to 60 Hz (a fifth of the elastic mode: chosen knowing the
truth, in femtools' favour), (d) ``restraint="inertia", mount_k="fit"`` on rigidid's band,
and on mounts (e) the true mount stiffness given (``mount_k``, truth rigidid does not get)
on rigidid's band. rigidid's mass line chooses its mount model (``supports="auto"``: the exact
rigid-body fit of ``rigidid.core.rigidfrf`` when it fits clearly better than the first-order
correction); the first-order correction alone is shown on the documented example.

Then femtools' documented example (its docstring of ``rigid_body_properties``: 12.5 kg, CG
(0.1, -0.05, 0.2) m, inertia diag(0.8, 1.1, 1.5) kg m^2 on four 900 N/m springs, 24 sensors
at the corners of a box, 6 inputs, exact accelerance 6-15 Hz, 21 lines) through both; and
rigidid on the same body measured 30-75 Hz (the supports' modes are at 2.6, 4.3 and 4.7 Hz,
three motions are free).

First (issue 21, ``--cases-only`` for these alone, ``--seeds N``): femtools' two soft-mount
cases (its docstring example and case 15 of its acceptance tests) exact and with 1 % and 3 %
complex noise, rigidid's mass line (band 6-15 Hz given) beside femtools' inertia restraint with
fitted stiffness (:func:`femtools_cases`).

Errors: mass (relative), CG (distance over the largest sensor-box edge), inertia diagonal
(largest relative error); median and worst over the trials; a failure (exception, or a
non-finite or non-positive result) is counted and left out of the statistics. Times are
per call, median, wall clock on this machine.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.bodies import frf_test_on_mounts

from rigidid.core.frf import accelerance
from rigidid.core.geometry import transfer_matrix
from rigidid.core.massline import mass_line
from rigidid.core.simulate import Body, Mount

Errors = tuple[float, float, float]


def test_case(seed: int, soften: float, references: int) -> dict[str, Any]:
    """One simulated FRF test (the frf_accuracy.py scenario), with 3 or 6 references."""
    rng = np.random.default_rng(seed)
    body, pos, dirs, rpos, rdirs, f, h = frf_test_on_mounts(rng, soften=soften, references=references)
    # the mount stiffness about the origin (femtools' reference point), for its mount_k
    k0 = np.zeros((6, 6))
    for m in body.mounts:
        t = transfer_matrix(m.position)[:3]
        k0 += t.T @ m.stiffness @ t
    return {"body": body, "pos": pos, "dirs": dirs, "rpos": rpos, "rdirs": rdirs, "f": f, "h": h, "k0": k0}


def errors(body: Body, pos: np.ndarray, mass: float, cg: np.ndarray, inertia: np.ndarray) -> Errors:
    if not (np.isfinite(mass) and mass > 0 and np.all(np.isfinite(cg)) and np.all(np.isfinite(inertia))):
        raise ArithmeticError("non-finite or non-positive result")
    span = float(np.ptp(pos, axis=0).max())
    return (
        abs(mass / body.mass - 1.0),
        float(np.linalg.norm(cg - body.center_of_gravity)) / span,
        float(np.max(np.abs(np.diag(inertia) / np.diag(body.inertia_tensor) - 1.0))),
    )


def timed(call: Callable[[], Any]) -> tuple[Any, float]:
    t0 = time.perf_counter()
    out = call()
    return out, time.perf_counter() - t0


def run_scenario(name: str, soften: float, references: int, trials: int, rbpe: Any) -> None:
    rows: dict[str, list[Errors]] = {}
    times: dict[str, list[float]] = {}
    failed: dict[str, list[str]] = {}

    def record(label: str, body: Body, pos: np.ndarray, call: Callable[[], Any], unpack: Callable[[Any], Any]) -> Any:
        try:
            out, dt = timed(call)
            rows.setdefault(label, []).append(errors(body, pos, *unpack(out)))
            times.setdefault(label, []).append(dt)
            return out
        except Exception as exc:
            failed.setdefault(label, []).append(f"{type(exc).__name__}: {str(exc)[:90]}")
            return None

    for seed in range(trials):
        c = test_case(seed, soften, references)
        body, pos, dirs, rpos, rdirs, f, h = (c[k] for k in ("body", "pos", "dirs", "rpos", "rdirs", "f", "h"))
        r = record(
            "rigidid mass_line (auto band)",
            body,
            pos,
            lambda: mass_line(f, h, pos, dirs, rpos, rdirs),  # noqa: B023
            lambda r: (r.mass, r.center_of_gravity, r.inertia_tensor),
        )
        if rbpe is None:
            continue
        args = {"sensors": (pos, dirs), "inputs": (rpos, rdirs)}

        def fem(out: Any) -> tuple[float, np.ndarray, np.ndarray]:
            return out.mass, out.cog_global, out.inertia

        record("femtools defaults (own band)", body, pos, lambda: rbpe(h, f, **args), fem)  # noqa: B023
        if r is None:
            continue
        band = r.band
        record("femtools defaults, rigidid's band", body, pos, lambda: rbpe(h, f, band=band, **args), fem)  # noqa: B023
        low_band = (band[0], min(band[1], 60.0))
        record(
            "femtools defaults, rigidid's low edge to 60 Hz",
            body,
            pos,
            lambda: rbpe(h, f, band=low_band, **args),  # noqa: B023
            fem,
        )
        record(
            "femtools inertia restraint + fitted K, rigidid's band",
            body,
            pos,
            lambda: rbpe(h, f, band=band, restraint="inertia", mount_k="fit", **args),  # noqa: B023
            fem,
        )
        if soften == 1.0:
            record(
                "femtools true mount K given, rigidid's band",
                body,
                pos,
                lambda: rbpe(h, f, band=band, mount_k=c["k0"], **args),  # noqa: B023
                fem,
            )
    print(f"\n{name}: {references} references, {trials} trials")
    for label in dict.fromkeys([*rows, *failed]):
        e = np.array(rows.get(label, []))
        n_fail = len(failed.get(label, []))
        if e.size:
            print(
                f"  {label:55s} mass {np.median(e[:, 0]):.4f}/{e[:, 0].max():.4f}  "
                f"CG {np.median(e[:, 1]):.4f}/{e[:, 1].max():.4f}  J {np.median(e[:, 2]):.4f}/{e[:, 2].max():.4f}  "
                f"time {1e3 * np.median(times[label]):.1f} ms  failed {n_fail}/{trials}"
            )
        else:
            print(f"  {label:55s} failed {n_fail}/{trials}")
        if n_fail:
            print(f"    e.g. {failed[label][0]}")


def documented_example(rbpe: Any) -> None:
    """femtools' own example (docstring of rigid_body_properties), exact FRFs, through both."""

    mass, cg, jdiag = 12.5, np.array([0.1, -0.05, 0.2]), np.array([0.8, 1.1, 1.5])
    pos = np.repeat([[sx, sy, sz] for sx in (-0.5, 0.5) for sy in (-0.4, 0.4) for sz in (-0.3, 0.3)], 3, axis=0)
    dirs = np.tile(np.eye(3), (8, 1))
    inputs = [0, 4, 8, 13, 17, 22]
    spring = np.diag([0.0, 0.0, 900.0])
    mounts = tuple(Mount(np.array([x, y, -0.3]), spring, np.zeros((3, 3))) for x in (-0.5, 0.5) for y in (-0.4, 0.4))
    body = Body(mass, cg, np.diag(jdiag), mounts)
    f = np.linspace(6.0, 15.0, 21)
    # the same FRFs as the example builds (-w^2 T (K - w^2 M)^-1 T_in^T); rigidid's forward model, undamped
    h = accelerance(body, pos, dirs, pos[inputs], dirs[inputs], f)
    print("\nfemtools' documented example (12.5 kg on 4 x 900 N/m, 24 sensors, 6 inputs, 6-15 Hz, 21 lines, exact)")
    runs: list[tuple[str, Callable[[], Any], Callable[[Any], Any]]] = [
        (
            "rigidid mass_line (band 6-15 Hz given)",
            lambda: mass_line(f, h, pos, dirs, pos[inputs], dirs[inputs], band=(6.0, 15.0)),
            lambda r: (r.mass, r.center_of_gravity, r.inertia_tensor),
        ),
    ]
    runs.append(
        (
            "rigidid mass_line first-order supports only",
            lambda: mass_line(f, h, pos, dirs, pos[inputs], dirs[inputs], band=(6.0, 15.0), supports="first_order"),
            lambda r: (r.mass, r.center_of_gravity, r.inertia_tensor),
        )
    )
    f_high = np.linspace(30.0, 75.0, 21)
    h_high = accelerance(body, pos, dirs, pos[inputs], dirs[inputs], f_high)
    runs.append(
        (
            "rigidid mass_line, same body measured 30-75 Hz",
            lambda: mass_line(f_high, h_high, pos, dirs, pos[inputs], dirs[inputs], band=(30.0, 75.0)),
            lambda r: (r.mass, r.center_of_gravity, r.inertia_tensor),
        )
    )
    if rbpe is not None:
        args = {"sensors": (pos, dirs), "inputs": (pos[inputs], dirs[inputs]), "band": (6.0, 15.0)}
        mk = [((x, y, -0.3), (0, 0, 1), 900.0) for x in (-0.5, 0.5) for y in (-0.4, 0.4)]

        def fem(out: Any) -> tuple[float, np.ndarray, np.ndarray]:
            return out.mass, out.cog_global, out.inertia

        runs += [
            ("femtools, mounts ignored (its example: 12.14)", lambda: rbpe(h, f, **args), fem),
            ("femtools, mount_k given (its example: 12.5)", lambda: rbpe(h, f, mount_k=mk, **args), fem),
            (
                "femtools, inertia restraint + fitted K",
                lambda: rbpe(h, f, restraint="inertia", mount_k="fit", **args),
                fem,
            ),
        ]
    for label, call, unpack in runs:
        try:
            out, dt = timed(call)
            m, c, j = unpack(out)
            e = errors(body, pos, m, c, j)
            print(
                f"  {label:48s} mass {m:.6g} kg (error {e[0]:.2e})  CG error {e[1]:.2e} of span  "
                f"J diag error {e[2]:.2e}  time {1e3 * dt:.1f} ms"
            )
        except Exception as exc:
            print(f"  {label:48s} failed: {type(exc).__name__}: {exc}")


def femtools_case(which: int) -> dict[str, Any]:
    """femtools' two soft-mount cases, FRFs written afresh from M and K (undamped, as femtools builds them).

    1: its ``rigid_body_properties`` docstring example, 12.5 kg, CG (0.1, -0.05, 0.2) m, inertia
    diag(0.8, 1.1, 1.5) kg m^2 on four vertical 900 N/m springs. 2: case 15 of its acceptance tests
    (tests/test_round11_o5f_acceptance.py), 10 kg, CG (0.1, 0.05, 0.2) m, inertia diag(0.5, 0.8, 1.0)
    on the same four springs plus two lateral 400 N/m ones. Both: 24 sensors (x, y, z at the corners of
    a 1 x 0.8 x 0.6 m box), 6 references (sensors 0, 4, 8, 13, 17, 22), 21 lines 6-15 Hz.
    """
    corners = [[x, y, z] for x in (-0.5, 0.5) for y in (-0.4, 0.4) for z in (-0.3, 0.3)]
    pos, dirs = np.repeat(corners, 3, axis=0).astype(float), np.tile(np.eye(3), (8, 1))
    springs = [((x, y, -0.3), (0, 0, 1), 900.0) for x in (-0.5, 0.5) for y in (-0.4, 0.4)]
    if which == 1:
        mass, cg, inertia = 12.5, np.array([0.1, -0.05, 0.2]), np.diag([0.8, 1.1, 1.5])
    else:
        mass, cg, inertia = 10.0, np.array([0.1, 0.05, 0.2]), np.diag([0.5, 0.8, 1.0])
        springs += [((0.0, y, -0.3), (1, 0, 0), 400.0) for y in (-0.4, 0.4)]
    t = np.hstack([dirs, np.cross(pos, dirs)])
    c = np.array([[0.0, -cg[2], cg[1]], [cg[2], 0.0, -cg[0]], [-cg[1], cg[0], 0.0]])
    m6 = np.block([[mass * np.eye(3), -mass * c], [mass * c, inertia - mass * c @ c]])
    k6 = np.zeros((6, 6))
    for p, d, k in springs:
        row = np.concatenate([d, np.cross(p, d)])
        k6 += k * np.outer(row, row)
    f = np.linspace(6.0, 15.0, 21)
    drive = [0, 4, 8, 13, 17, 22]
    h = np.stack([-(w**2) * t @ np.linalg.solve(k6 - w**2 * m6, t[drive].T) for w in 2 * np.pi * f], axis=2)
    body = Body(mass, cg, inertia, ())
    return {"body": body, "pos": pos, "dirs": dirs, "rpos": pos[drive], "rdirs": dirs[drive], "f": f, "h": h}


def femtools_cases(rbpe: Any, seeds: int) -> None:
    """Both femtools cases exact and with 1 % and 3 % complex noise (relative to each value), `seeds` draws.

    rigidid: ``mass_line`` with the band 6-15 Hz given (its automatic mount model: the exact
    rigid-body fit, by output error); femtools: ``restraint="inertia", mount_k="fit"``. Per route:
    the worst mass, CG (m) and inertia-diagonal errors over the seeds, and for rigidid the largest
    error in its own standard errors (mass, CG, inertia diagonal).
    """
    for which, name in ((1, "docstring example, 12.5 kg on 4 springs"), (2, "acceptance case 15, 10 kg on 6 springs")):
        c = femtools_case(which)
        body = c["body"]
        print(f"\nfemtools' {name} (24 sensors, 6 references, 21 lines 6-15 Hz), worst over {seeds} seeds")
        for level in (0.0, 0.01, 0.03):
            rows: dict[str, list[tuple[float, ...]]] = {}
            for seed in range(seeds if level else 1):
                rng = np.random.default_rng(seed)
                noise = (rng.standard_normal(c["h"].shape) + 1j * rng.standard_normal(c["h"].shape)) / np.sqrt(2)
                h = c["h"] * (1.0 + level * noise)
                args = (c["f"], h, c["pos"], c["dirs"], c["rpos"], c["rdirs"])
                try:
                    r = mass_line(*args, band=(6.0, 15.0))
                    iv = r.intervals
                    z = (np.nan, np.nan, np.nan)
                    if iv is not None:
                        dj = np.abs(np.diag(r.inertia_tensor - body.inertia_tensor))
                        z = (
                            abs(r.mass - body.mass) / iv.mass.std,
                            float(
                                np.max(np.abs(r.center_of_gravity - body.center_of_gravity) / iv.center_of_gravity.std)
                            ),
                            float(np.max(dj / np.diag(iv.inertia_tensor.std))),
                        )
                    err = _abs_errors(body, r.mass, r.center_of_gravity, r.inertia_tensor)
                    rows.setdefault(f"rigidid mass_line ({r.supports})", []).append((*err, *z))
                except Exception as exc:  # a refusal is counted as a failure
                    rows.setdefault("rigidid mass_line", []).append((np.inf,) * 3 + (np.nan,) * 3)
                    print(f"    rigidid seed {seed}: {type(exc).__name__}: {str(exc)[:90]}")
                if rbpe is not None:
                    fe = rbpe(h, c["f"], sensors=(c["pos"], c["dirs"]), inputs=(c["rpos"], c["rdirs"]),
                              band=(6.0, 15.0), restraint="inertia", mount_k="fit")  # fmt: skip
                    err = _abs_errors(body, fe.mass, fe.cog_global, fe.inertia)
                    rows.setdefault("femtools inertia restraint + fitted K", []).append((*err, np.nan, np.nan, np.nan))
            for label, vals in rows.items():
                e = np.array(vals)
                zs = (
                    ""
                    if np.all(np.isnan(e[:, 3:]))
                    else "  worst in own SE: mass {:.2f}, CG {:.2f}, J {:.2f}".format(*np.max(e[:, 3:], axis=0))
                )
                print(
                    f"  noise {100 * level:.0f} %  {label:42s} mass {e[:, 0].max():.2e}  CG {e[:, 1].max():.2e} m  "
                    f"J diag {e[:, 2].max():.2e}{zs}"
                )


def _abs_errors(body: Body, mass: float, cg: np.ndarray, inertia: np.ndarray) -> tuple[float, float, float]:
    """Mass (relative), CG (m) and the largest relative inertia-diagonal error."""
    return (
        abs(mass / body.mass - 1.0),
        float(np.linalg.norm(cg - body.center_of_gravity)),
        float(np.max(np.abs(np.diag(inertia) / np.diag(body.inertia_tensor) - 1.0))),
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--trials", type=int, default=10)
    parser.add_argument("--femtools", type=Path, default=None, help="folder holding the femtools package")
    parser.add_argument("--seeds", type=int, default=5, help="noise draws per femtools case")
    parser.add_argument("--cases-only", action="store_true", help="only femtools' two cases (issue 21)")
    args = parser.parse_args()
    rbpe = None
    if args.femtools is not None:
        sys.path.insert(0, str(args.femtools.resolve()))
        from femtools.rbpe.rbfit import rigid_body_properties

        rbpe = rigid_body_properties
    femtools_cases(rbpe, args.seeds)
    if args.cases_only:
        return
    warm = test_case(0, 0.01, 3)  # imports and first calls out of the timings
    mass_line(warm["f"], warm["h"], warm["pos"], warm["dirs"], warm["rpos"], warm["rdirs"])
    documented_example(rbpe)
    for references in (3, 6):
        run_scenario("free-free (supports 1/100 stiffness)", 0.01, references, args.trials, rbpe)
        run_scenario("on mounts (as drawn)", 1.0, references, args.trials, rbpe)


if __name__ == "__main__":
    main()
