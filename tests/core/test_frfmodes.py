"""Modes from FRFs (core/frfmodes.py): exact recovery, a noisy round trip, scaled shapes, the command line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rigidid.core.frf import accelerance
from rigidid.core.frfmodes import body_from_scaled_modes, fit_frf_modes, residues_lsfd
from rigidid.core.geometry import sensor_matrix
from rigidid.core.simulate import body_modes, system_matrices
from rigidid.errors import InputError
from rigidid.io.files import load_modes

from ..bodies import corner_references, frf_test_on_mounts, random_body, random_layout
from ..cli_runner import run
from ..conftest import DATA, SAMPLES
from ..tolerances import FRF_EQ18_STRUCTURED, SCALED_MODES_CSV

FOUR = SAMPLES / "four-mounts"
REFS = DATA / "frf" / "references.json"


def _test(seed: int, noise: float = 0.0, lines: int = 400):  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(seed)
    body = random_body(rng)
    pos, dirs = random_layout(rng, 8, centre=body.center_of_gravity)
    rpos = corner_references(pos)
    top = float(np.abs(body_modes(body, pos, dirs).poles).max()) / (2.0 * np.pi)
    f = np.linspace(top / 50.0, 2.0 * top, lines)
    h = accelerance(body, pos, dirs, rpos, np.eye(3), f, noise=noise, rng=rng)
    return body, pos, dirs, rpos, f, h


def test_exact_frfs_give_poles_residues_and_the_body_to_rounding() -> None:
    body, pos, dirs, rpos, f, h = _test(0, lines=200)
    truth = body_modes(body, pos, dirs)
    poles = truth.poles[np.argsort(np.abs(truth.poles))]
    fitted = fit_frf_modes(f, h, pos, dirs, rpos, np.eye(3), band=(f[0], f[-1]), n_modes=6, upper=False, max_order=10)
    # pLSCF alone gave 1.6e-5 here; the refinement on the FRFs takes the poles to rounding (observed 2e-15)
    assert np.max(np.abs(fitted.poles / poles - 1.0)) < 1e-10
    assert fitted.scaled.all() and fitted.residual < 1e-10
    scaled = body_from_scaled_modes(fitted.poles, fitted.residues, pos, dirs, rpos, np.eye(3))
    assert scaled.mass == pytest.approx(body.mass, rel=1e-8)
    np.testing.assert_allclose(scaled.center_of_gravity, body.center_of_gravity, atol=1e-8)
    np.testing.assert_allclose(scaled.inertia_tensor, body.inertia_tensor, rtol=1e-7, atol=1e-8 * body.mass)
    _, k, c = system_matrices(body)  # at the CG
    np.testing.assert_allclose(scaled.stiffness_matrix, k, rtol=1e-6, atol=1e-7 * np.abs(k).max())
    np.testing.assert_allclose(scaled.damping_matrix, c, rtol=1e-6, atol=1e-7 * np.abs(c).max())
    # the scaled shapes are the true modes at the sensors, unity modal A: R_k = shape_k participation_k^T
    for k in range(6):
        np.testing.assert_allclose(
            np.outer(fitted.shapes[:, k], fitted.participation[:, k]),
            fitted.residues[k],
            atol=1e-8 * np.abs(fitted.residues[k]).max(),
        )
    mac = np.abs(np.sum(fitted.shapes.conj() * truth.shapes[:, np.argsort(np.abs(truth.poles))], axis=0)) ** 2
    norms = (
        np.sum(np.abs(fitted.shapes) ** 2, axis=0)
        * np.sum(np.abs(truth.shapes) ** 2, axis=0)[np.argsort(np.abs(truth.poles))]
    )
    np.testing.assert_allclose(mac / norms, 1.0, atol=1e-10)


def test_noisy_frfs_round_trip() -> None:
    body, pos, dirs, rpos, f, h = _test(1, noise=0.01)
    fitted = fit_frf_modes(f, h, pos, dirs, rpos, np.eye(3), n_modes=6, refine=False)
    truth = body_modes(body, pos, dirs).poles
    truth = truth[np.argsort(np.abs(truth))]
    assert np.max(np.abs(np.abs(fitted.poles) / np.abs(truth) - 1.0)) < 0.005
    scaled = body_from_scaled_modes(fitted.poles, fitted.residues, pos, dirs, rpos, np.eye(3))
    assert abs(scaled.mass / body.mass - 1.0) < 0.02
    span = float(np.ptp(pos, axis=0).max())
    assert np.linalg.norm(scaled.center_of_gravity - body.center_of_gravity) / span < 0.01
    assert len(fitted.diagram) >= 8 and any(entry.stable.any() for entry in fitted.diagram)
    # the shapes written carry their non-rigid part (the noise), the rigid part is T u exactly
    from rigidid.core.frfmodes import body_from_scaled_shapes, rigid_shapes
    from rigidid.core.identify import identify
    from rigidid.core.noise import estimate_noise

    assert estimate_noise(pos, dirs, rigid_shapes(fitted.residues, pos, dirs, rpos, np.eye(3))[0]).shape < 1e-12
    assert estimate_noise(pos, dirs, fitted.shapes).shape > 1e-4
    t = sensor_matrix(pos - pos.mean(axis=0), dirs)
    projected = t @ np.linalg.lstsq(t, fitted.shapes, rcond=None)[0]
    from_shapes = body_from_scaled_shapes(fitted.poles, fitted.shapes, pos, dirs)
    assert from_shapes.mass == pytest.approx(
        body_from_scaled_shapes(fitted.poles, projected, pos, dirs).mass, rel=1e-10
    )
    assert abs(from_shapes.mass / body.mass - 1.0) < 0.02
    a = identify(pos, dirs, fitted.poles, fitted.shapes, mass=body.mass, warn=False)
    b = identify(pos, dirs, fitted.poles, projected, mass=body.mass, warn=False)
    np.testing.assert_allclose(a.inertia_per_mass, b.inertia_per_mass, rtol=1e-6, atol=1e-9)


def test_structured_rigid_modes_bring_eq18_close_to_its_bound():
    """The issue's test (benchmarks/frf_eq18.py, seed 2): eq. (18) with the mass given on the modes fitted to FRFs."""
    from rigidid.core.identify import identify

    rng = np.random.default_rng(2)
    body, pos, dirs, rpos, _, f, h = frf_test_on_mounts(rng)
    errors = []
    for structured in (True, False):
        fitted = fit_frf_modes(f, h, pos, dirs, rpos, np.eye(3), n_modes=6, structured=structured)
        ident = identify(pos, dirs, fitted.poles, fitted.shapes, mass=body.mass, warn=False)
        errors.append(np.max(np.abs(np.diag(ident.inertia_per_mass) * body.mass / np.diag(body.inertia_tensor) - 1)))
    assert errors[0] < FRF_EQ18_STRUCTURED < errors[1]


def test_lsfd_with_residual_terms_and_bad_poles() -> None:
    body, pos, dirs, _rpos, f, h = _test(2)
    poles = body_modes(body, pos, dirs).poles
    res, low, up, misfit = residues_lsfd(f, h, poles, lower=True, upper=True)
    assert misfit < 1e-8 and np.abs(low).max() < 1e-6 / body.mass and np.abs(up).max() < 1e-6 / body.mass
    t = sensor_matrix(pos, dirs, body.center_of_gravity)
    assert np.linalg.matrix_rank(np.linalg.lstsq(t, res[0], rcond=None)[0], tol=1e-6 * np.abs(res[0]).max()) == 1
    with pytest.raises(InputError, match="positive imaginary"):
        residues_lsfd(f, h, np.conj(poles))


def test_modes_from_frfs_on_the_command_line_feed_identify(tmp_path: Path) -> None:
    frf, fit, js = tmp_path / "frf.csv", tmp_path / "fit.csv", tmp_path / "fit.json"
    done = run("simulate", FOUR / "body.json", FOUR / "layout.json", "-o", tmp_path / "m.csv", "--frf", frf,
               "--references", REFS, "--frf-noise", "0.01", "--seed", "1")  # fmt: skip
    assert done.returncode == 0, done.stderr
    done = run("modes", FOUR / "layout.json", "--frf", frf, "--references", REFS, "-o", fit, "--json", js)
    assert done.returncode == 0, done.stderr
    assert fit.read_text().splitlines()[0].endswith(",scaling") and ",modal_a" in fit.read_text()
    ids = [s["id"] for s in json.loads((FOUR / "layout.json").read_text())["sensors"]]
    assert len(load_modes(fit, ids).labels) == 6
    out = json.loads(js.read_text())
    assert out["method"] == "plscf" and out["stabilisation"] and all(m["scaling"] == "modal_a" for m in out["modes"])
    done = run("identify", FOUR / "layout.json", fit, "--mass", "40", "--json", "-")
    assert done.returncode == 0, done.stderr
    truth = json.loads((FOUR / "body.json").read_text())["center_of_gravity"]
    result = json.loads(done.stdout)
    assert np.linalg.norm(np.array(result["center_of_gravity"]) - truth) < 0.01
    # the modal_a scaling measures the mass (simulate --frf -> modes --frf -> identify modes.csv)
    assert abs(result["mass_measured"] / 40.0 - 1.0) < SCALED_MODES_CSV["mass"]
    assert result["mass_given"] == 40.0 and result["mass_difference"] == pytest.approx(result["mass_measured"] - 40.0)
    sm = result["scaled_modes"]
    sensors = json.loads((FOUR / "layout.json").read_text())["sensors"]
    span = float(np.ptp([s["position"] for s in sensors], axis=0).max())
    assert np.linalg.norm(np.array(sm["center_of_gravity"]) - truth) / span < SCALED_MODES_CSV["cg_span"]
    j_true = np.diag(json.loads((FOUR / "body.json").read_text())["inertia_tensor"])
    assert np.max(np.abs(np.diag(sm["inertia_tensor"]) / j_true - 1.0)) < SCALED_MODES_CSV["inertia"]


def test_modes_from_frfs_bad_inputs_are_one_line_exit_2(tmp_path: Path) -> None:
    frf = tmp_path / "frf.csv"
    frf.write_text("frequency_hz,response,reference,real,imag\n")
    done = run("modes", FOUR / "layout.json", "--frf", frf)
    assert done.returncode == 2 and "--references" in done.stderr and len(done.stderr.strip().splitlines()) == 1
    import pyuff

    x = np.arange(1.0, 100.0, 1.0)
    cross = pyuff.prepare_58(
        func_type=3, rsp_node=1, rsp_dir=3, ref_node=1, ref_dir=1, ord_data_type=6, num_pts=x.size,
        abscissa_spacing=0, abscissa_spec_data_type=18, ordinate_spec_data_type=12, orddenom_spec_data_type=13,
        data=np.ones(x.size, dtype=complex), x=x, id1="cross", rsp_ent_name="b", ref_ent_name="b",
        abscissa_min=1.0, abscissa_inc=0.0,
    )  # fmt: skip
    uff = tmp_path / "cross.uff"
    pyuff.UFF(str(uff)).write_sets([cross], mode="overwrite")
    done = run("modes", FOUR / "layout.json", "--frf", uff, "--references", REFS)
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert "cross" in done.stderr.lower()


def _exact_modal_a(body, pos, dirs):  # type: ignore[no-untyped-def]
    """Poles and unity-modal-A shapes at the sensors from the body's M, K, C (residue = shape shape^T)."""
    m, k, c = system_matrices(body)
    a = np.block([[np.zeros((6, 6)), np.eye(6)], [-np.linalg.solve(m, k), -np.linalg.solve(m, c)]])
    lam, vec = np.linalg.eig(a)
    keep = [i for i in np.argsort(np.abs(lam)) if lam[i].imag > 0][:6]
    t = sensor_matrix(pos - body.center_of_gravity, dirs)
    shapes = np.zeros((pos.shape[0], 6), dtype=complex)
    for j, i in enumerate(keep):
        psi = vec[:6, i]
        shapes[:, j] = t @ (psi / np.sqrt(psi @ (2.0 * lam[i] * m + c) @ psi))
    return lam[keep], shapes


def test_a_modal_a_modes_file_of_exact_scaled_modes_gives_the_body_exactly(tmp_path: Path) -> None:
    """identify on modes.csv with scaling modal_a: mass, CG, inertia, K, C from the scaled modes (10 digits)."""
    from rigidid import api
    from rigidid.api import body_from_file
    from rigidid.io.files import ModeTable, layout_arrays, load_body, load_layout, modes_csv_text
    from rigidid.jsonout import result_to_dict
    from rigidid.models import ResultFile

    body = body_from_file(load_body(FOUR / "body.json"))
    ids, pos, dirs = layout_arrays(load_layout(FOUR / "layout.json"))
    lam, shapes = _exact_modal_a(body, pos, dirs)
    table = ModeTable.numbered(np.abs(lam) / (2 * np.pi), -lam.real / np.abs(lam), ids, shapes)
    path = tmp_path / "modes.csv"
    path.write_text(modes_csv_text(table, scaling=["modal_a"] * 6))
    result = api.identify(FOUR / "layout.json", path, mass=41.0)
    sb = result.scaled
    assert sb is not None
    _, k, c = system_matrices(body)
    assert sb.mass == pytest.approx(body.mass, rel=1e-8)
    np.testing.assert_allclose(sb.center_of_gravity, body.center_of_gravity, atol=1e-8)
    np.testing.assert_allclose(sb.inertia_tensor, body.inertia_tensor, atol=1e-7 * np.abs(body.inertia_tensor).max())
    np.testing.assert_allclose(sb.stiffness_matrix, k, atol=1e-7 * np.abs(k).max())
    np.testing.assert_allclose(sb.damping_matrix, c, atol=1e-7 * np.abs(c).max())
    out = result_to_dict(result)
    ResultFile.model_validate(out)
    assert out["mass_given"] == 41.0 and out["mass_difference"] == pytest.approx(sb.mass - 41.0)
    assert out["mass_difference_relative"] == pytest.approx(sb.mass / 41.0 - 1.0)
    assert out["scaled_modes"]["mass"] == out["mass_measured"] == sb.mass
    # one mode unit_max (or no scaling column): as before, no scaled-mode keys, the same answer
    path.write_text(modes_csv_text(table, scaling=["modal_a"] * 5 + ["unit_max"]))
    mixed = api.identify(FOUR / "layout.json", path, mass=41.0)
    assert mixed.scaled is None and "mass_measured" not in result_to_dict(mixed)
    np.testing.assert_array_equal(mixed.identification.center_of_gravity, result.identification.center_of_gravity)
    path.write_text(modes_csv_text(table).replace("modal_a", "unit_max"))
    assert api.identify(FOUR / "layout.json", path).scaled is None


def test_a_bad_scaling_word_is_refused_naming_the_row(tmp_path: Path) -> None:
    from rigidid.io.files import ModeTable, modes_csv_text

    table = ModeTable.numbered(np.array([1.0]), np.array([0.01]), ["a", "b"], np.array([[1.0 + 0j], [0.5 + 0j]]))
    path = tmp_path / "modes.csv"
    path.write_text(modes_csv_text(table, scaling=["modal_b"]))
    with pytest.raises(InputError, match="row 2: scaling"):
        load_modes(path, ["a", "b"])
    lines = modes_csv_text(table, scaling=["modal_a"]).splitlines()
    path.write_text("\n".join([*lines[:2], lines[2].replace("modal_a", "unit_max")]) + "\n")
    with pytest.raises(InputError, match="row 3: scaling: scaling differs"):
        load_modes(path, ["a", "b"])
    path.write_text("\n".join(lines) + "\n")
    assert load_modes(path, ["a", "b"]).scaling == ("modal_a",)


def test_the_order_is_raised_until_six_stable_modes_are_found() -> None:
    """Light mount damping (0.04-0.7 %) and a noise floor: order 16 finds too few stable modes and says so; the
    default raises the order (keeping the orders already fitted) until six are stable, at the true poles."""
    import dataclasses

    from rigidid import api
    from rigidid.errors import IdentificationError
    from rigidid.io.files import load_body

    body = api.body_from_file(load_body(SAMPLES / "four-mounts" / "body.json"))
    light = dataclasses.replace(
        body, mounts=tuple(dataclasses.replace(m, damping=0.1 * m.damping) for m in body.mounts)
    )
    rng = np.random.default_rng(1)
    pos, dirs = rng.uniform(-0.3, 0.3, (6, 3)), np.eye(3)[np.arange(6) % 3]
    rpos, rdirs = np.array([[0.3, 0.2, 0.15], [-0.3, 0.2, -0.15], [0.3, -0.2, -0.15]]), np.eye(3)
    f = np.arange(2.0, 32.0, 0.1)
    h = accelerance(light, pos, dirs, rpos, rdirs, f, noise=0.005, rng=rng)
    rms = np.sqrt(np.mean(np.abs(h) ** 2, axis=2, keepdims=True))
    h = h + 0.005 * rms * (rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape)) / np.sqrt(2)
    with pytest.raises(IdentificationError, match=r"stable mode\(s\) in .* 6 asked"):
        fit_frf_modes(f, h, pos, dirs, rpos, rdirs, n_modes=6, max_order=16)
    fitted = fit_frf_modes(f, h, pos, dirs, rpos, rdirs, n_modes=6)
    true = np.sort_complex(body_modes(light, pos, dirs).poles)
    assert len(fitted.diagram) > 16
    np.testing.assert_allclose(np.sort_complex(fitted.poles), true, rtol=2e-3)  # observed 6.5e-4


def test_a_high_max_order_stops_once_six_modes_are_stable() -> None:
    """`max_order` is the ceiling of the raising, not a sweep to run in full: 200 gives the default's modes."""
    body, pos, dirs, rpos, f, h = _test(3, noise=0.01, lines=200)
    default = fit_frf_modes(f, h, pos, dirs, rpos, np.eye(3), n_modes=6)
    high = fit_frf_modes(f, h, pos, dirs, rpos, np.eye(3), n_modes=6, max_order=200)
    assert len(high.diagram) < 200
    np.testing.assert_allclose(high.poles, default.poles, rtol=1e-12)
    truth = np.sort_complex(body_modes(body, pos, dirs).poles)
    np.testing.assert_allclose(np.sort_complex(high.poles), truth, rtol=1e-2)


def test_prominent_peaks_are_scipy_find_peaks_on_frfs_noise_and_flat_tops() -> None:
    """frfmodes.prominent_peaks (numpy, spares importing scipy.signal) finds the peaks and prominences of
    scipy.signal.find_peaks: on a noisy summed accelerance (the peak splitter's input), on noise, and on
    coarse data full of flat tops and ties between a peak and its neighbours' heights."""
    from scipy.signal import find_peaks

    from rigidid.core.frfmodes import prominent_peaks, summed_power

    *_, h = _test(3, noise=0.05)
    rng = np.random.default_rng(7)
    cases = [np.log(summed_power(h)), rng.normal(size=200), np.array([0.0, 1.0, 1.0, 0.0, 2.0, 2.0, 2.0, 1.0, 2.0])]
    cases += [rng.integers(0, 4, size=int(rng.integers(3, 40))).astype(float) for _ in range(200)]
    found = 0
    for x in cases:
        for prominence in (0.0, 1.0, float(np.log(2.0))):
            expected, _ = find_peaks(x, prominence=prominence)
            np.testing.assert_array_equal(prominent_peaks(x, prominence), expected)
            found += expected.size
    assert found > 1000
    assert prominent_peaks(np.array([1.0, 2.0]), 0.0).size == 0
