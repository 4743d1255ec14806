"""Time-domain modal estimation from impact records (rigidid.core.timedomain)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rigidid.api import body_from_file
from rigidid.core.identify import identify
from rigidid.core.simulate import body_modes, system_matrices
from rigidid.core.statespace import modal_from_poles
from rigidid.core.timedomain import (
    Criteria,
    ModalEstimate,
    estimate_modes,
    find_impact,
    impulse_records,
    mac_matrix,
    record_time,
)
from rigidid.core.timedomain.ar import ar_fits, f_test_order
from rigidid.core.timedomain.gram import lagged_gram
from rigidid.core.timedomain.preprocess import content_range, decimate, decimation_for, fir_taps
from rigidid.core.timedomain.stabilisation import OrderPoles, cluster_stable, stabilise
from rigidid.errors import IdentificationError, InputError
from rigidid.io.files import layout_arrays, load_body, load_layout

from ..tolerances import (
    MODAL_DAMPING_REL,
    MODAL_FREQUENCY_REL,
    MODAL_MAC_MIN,
    RECORDS_CG_SPAN,
    RECORDS_INERTIA_REL,
    TIMEDOMAIN_EXACT_REL,
)

# samples/four-mounts: a 40 kg body on four mounts, designed (least squares on the mount
# values) so that its six modes are 8.0, 10.3, 14.95, 15.27 (2.1 % above the previous),
# 21.6 and 26.1 Hz with damping ratios from 0.31 % to 6.9 %; the mount damping is not
# proportional to the stiffness, so the modes are complex.
SAMPLE = Path(__file__).resolve().parent.parent.parent / "samples" / "four-mounts"
BODY = body_from_file(load_body(SAMPLE / "body.json"))
MASS, CG, INERTIA = BODY.mass, BODY.center_of_gravity, BODY.inertia_tensor
_, POSITIONS, DIRECTIONS = layout_arrays(load_layout(SAMPLE / "layout.json"))
IMPACTS = [((0.3, 0.2, 0.15), (0.3, -0.5, -1.0)), ((-0.3, -0.1, 0.0), (1.0, 0.6, 0.2))]
SAMPLE_RATE = 200.0
DURATION = 10.0
PRETRIGGER = 0.2
SPAN = max(float(np.linalg.norm(a - b)) for a in POSITIONS for b in POSITIONS)
TRUE = body_modes(BODY, POSITIONS, DIRECTIONS)
TRUE_F, TRUE_Z = modal_from_poles(TRUE.poles)


def _records(noise: float, seed: int = 7, sample_rate: float = SAMPLE_RATE) -> list[np.ndarray]:
    return impulse_records(
        BODY,
        POSITIONS,
        DIRECTIONS,
        IMPACTS,
        sample_rate=sample_rate,
        duration=DURATION,
        pretrigger=PRETRIGGER,
        noise=noise,
        seed=seed,
    )


@pytest.fixture(scope="module")
def noisy_records() -> list[np.ndarray]:
    return _records(0.01)


@pytest.fixture(scope="module", params=["ar", "era"])
def estimate(request: pytest.FixtureRequest, noisy_records: list[np.ndarray]) -> ModalEstimate:
    return estimate_modes(noisy_records, 1.0 / SAMPLE_RATE, method=request.param)


def _assert_modes(est: ModalEstimate, f_rel: float, z_rel: float, mac_min: float) -> None:
    assert est.poles.shape == (6,)
    assert est.shapes.shape == (8, 6)
    np.testing.assert_allclose(est.frequency_hz, TRUE_F, rtol=f_rel)
    np.testing.assert_allclose(est.damping_ratio, TRUE_Z, rtol=z_rel)
    mac = np.diag(mac_matrix(est.shapes, TRUE.shapes))
    assert np.all(mac > mac_min), mac


# --- the test body itself ---------------------------------------------------------------


def test_body_meets_the_design_constraints() -> None:
    ratios = TRUE_F[1:] / TRUE_F[:-1] - 1.0
    assert np.min(ratios) < 0.03  # two modes within 3 %
    assert np.all(ratios > 0.01)  # but resolvable
    assert 0.003 <= TRUE_Z.min() < 0.0035
    assert 0.065 < TRUE_Z.max() <= 0.07
    phase = np.angle(TRUE.shapes)
    assert np.max(np.abs(np.sin(phase))) > 0.2  # complex (non-proportional damping)


# --- simulation ---------------------------------------------------------------------------


def test_impulse_records_match_the_matrix_exponential() -> None:
    from scipy.linalg import expm

    rec = impulse_records(BODY, POSITIONS, DIRECTIONS, IMPACTS[:1], sample_rate=100.0, duration=2.0, pretrigger=0.1)[0]
    n_pre = 10
    assert rec.shape == (n_pre + 200, 8)
    assert np.all(rec[:n_pre] == 0.0)
    m, k, c = system_matrices(BODY)
    minv = np.linalg.inv(m)
    a = np.block([[-minv @ c, -minv @ k], [np.eye(6), np.zeros((6, 6))]])
    r_f, f = np.array(IMPACTS[0][0]), np.array(IMPACTS[0][1]) / np.linalg.norm(IMPACTS[0][1])
    z0 = np.concatenate([minv @ np.concatenate([f, np.cross(r_f - CG, f)]), np.zeros(6)])
    r = POSITIONS - CG
    t_sensor = np.hstack([DIRECTIONS, np.cross(r, DIRECTIONS)])
    for i in (0, 1, 57, 199):
        expected = t_sensor @ a[:6] @ expm(a * i / 100.0) @ z0
        np.testing.assert_allclose(rec[n_pre + i], expected, rtol=1e-9, atol=1e-12 * np.abs(rec).max())


def test_impulse_records_noise_is_seeded_and_scaled() -> None:
    clean = _records(0.0)
    a, b, other = _records(0.05, seed=3), _records(0.05, seed=3), _records(0.05, seed=4)
    assert np.array_equal(a[1], b[1])
    assert not np.array_equal(a[1], other[1])
    n_pre = round(PRETRIGGER * SAMPLE_RATE)
    for rec_noisy, rec_clean in zip(a, clean, strict=True):
        rms = np.sqrt(np.mean(rec_clean[n_pre:] ** 2, axis=0))
        ratio = np.std(rec_noisy - rec_clean, axis=0) / rms
        np.testing.assert_allclose(ratio, 0.05, rtol=0.05)


def test_impulse_records_reject_bad_arguments() -> None:
    with pytest.raises(InputError, match="sample rate"):
        impulse_records(BODY, POSITIONS, DIRECTIONS, IMPACTS, sample_rate=0.0, duration=1.0)
    with pytest.raises(InputError, match="impact 2"):
        impulse_records(BODY, POSITIONS, DIRECTIONS, [IMPACTS[0], ((0, 0, 0), (0, 0, 0))], sample_rate=100, duration=1)


def test_record_time_puts_the_impulse_at_zero() -> None:
    t = record_time(50, 100.0, pretrigger=0.1)
    assert t[10] == 0.0
    np.testing.assert_allclose(np.diff(t), 0.01)


# --- preprocessing ----------------------------------------------------------------------


def test_impact_is_found_after_the_pretrigger(noisy_records: list[np.ndarray]) -> None:
    n_pre = round(PRETRIGGER * SAMPLE_RATE)
    for rec in noisy_records:
        impact = find_impact(rec, 1.0 / SAMPLE_RATE)
        assert n_pre <= impact.onset <= n_pre + 3
        assert impact.onset <= impact.peak < impact.start <= impact.peak + 2


def test_decay_starts_after_a_hammer_pulse() -> None:
    fs = 2000.0
    rec = _records(0.01, sample_rate=fs)[0]
    n_pre = round(PRETRIGGER * fs)
    pulse = 5.0 * np.abs(rec).max() * np.sin(np.pi * np.arange(1, 5) / 5.0)  # 2.5 ms half sine
    rec = rec.copy()
    rec[n_pre : n_pre + 4] += pulse[:, None] * np.linspace(-1.0, 1.0, rec.shape[1])
    impact = find_impact(rec, 1.0 / fs, pulse_width=0.005)
    assert n_pre <= impact.onset <= n_pre + 1
    assert impact.peak in (n_pre + 1, n_pre + 2)
    assert n_pre + 4 <= impact.start <= n_pre + 10


def test_decimate_matches_scipy() -> None:
    from scipy.signal import decimate as scipy_decimate
    from scipy.signal import firwin

    rng = np.random.default_rng(0)
    x = rng.standard_normal((5003, 3))
    for q in (2, 7, 25):
        np.testing.assert_allclose(fir_taps(q), firwin(20 * q + 1, 1.0 / q, window="hamming"), atol=1e-15)
        ours = decimate(x, q)
        theirs = scipy_decimate(x, q, ftype="fir", zero_phase=True, axis=0)
        assert ours.shape[0] >= theirs.shape[0] - 22
        np.testing.assert_allclose(ours, theirs[10 : 10 + ours.shape[0]], atol=1e-12)


def test_content_range_brackets_the_modes() -> None:
    recs = _records(0.01, sample_rate=2000.0)
    low, high = content_range(recs, 1.0 / 2000.0)
    assert TRUE_F.max() <= high < 5.0 * TRUE_F.max()
    assert low < TRUE_F.min()


@settings(max_examples=25, deadline=None)
@given(
    lengths=st.lists(st.integers(6, 40), min_size=1, max_size=3),
    channels=st.integers(1, 4),
    lags=st.integers(0, 5),
    seed=st.integers(0, 2**16),
)
def test_lagged_gram_is_the_hankel_gram(lengths: list[int], channels: int, lags: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    recs = [rng.standard_normal((n, channels)) for n in lengths]
    gram, columns = lagged_gram(recs, lags)
    blocks = [np.vstack([y[i : len(y) - lags + i].T for i in range(lags + 1)]) for y in recs if len(y) > lags]
    hankel = np.hstack(blocks)
    assert columns == hankel.shape[1]
    np.testing.assert_allclose(gram, hankel @ hankel.T, atol=1e-10 * max(1.0, np.abs(gram).max()))


# --- AR pieces ----------------------------------------------------------------------------


def test_ar_fit_recovers_a_known_ar_process() -> None:
    rng = np.random.default_rng(1)
    a1 = np.array([[0.5, 0.2], [-0.1, 0.3]])
    a2 = np.array([[-0.2, 0.0], [0.1, -0.1]])
    x = np.zeros((20000, 2))
    e = rng.standard_normal(x.shape)
    for t in range(2, x.shape[0]):
        x[t] = a1 @ x[t - 1] + a2 @ x[t - 2] + e[t]
    gram, columns = lagged_gram([x], 4)
    fits = ar_fits(gram, 2, [1, 2, 3, 4])
    np.testing.assert_allclose(fits[1].coefficients, np.hstack([a1, a2]), atol=0.03)
    assert fits[0].rss > fits[1].rss >= fits[2].rss >= fits[3].rss
    np.testing.assert_allclose(fits[1].rss / (2 * columns), 1.0, rtol=0.05)
    assert f_test_order([f.rss for f in fits], [1, 2, 3, 4], columns, 2) == 2


# --- stabilisation ----------------------------------------------------------------------


def _pole(f: float, z: float) -> complex:
    w = 2 * np.pi * f
    return complex(w * (-z + 1j * np.sqrt(1 - z * z)))


def test_stabilise_keeps_physical_poles_and_marks_stable_ones() -> None:
    shape = np.array([[1.0], [0.5], [-0.2]], dtype=complex)
    models = []
    for order, drift in enumerate([0.0, 0.001, 0.0005, 0.03]):
        poles = np.array([_pole(10 * (1 + drift), 0.02), _pole(20.0, 0.5), _pole(-5.0, 0.01)])
        models.append((order + 1, poles, np.hstack([shape, shape, shape])))
    diagram = stabilise(models, (0.0, 100.0), Criteria())
    assert [d.poles.size for d in diagram] == [1, 1, 1, 1]  # damping 50 % and negative frequency dropped
    assert [bool(d.stable[0]) for d in diagram] == [False, True, True, False]  # the 3 % jump is not stable


def test_stabilise_needs_the_shape_to_repeat_too() -> None:
    """Same pole at the next order but another shape: not stable (the MAC criterion)."""
    shapes = [np.array([[1.0], [0.5], [-0.2]], dtype=complex), np.array([[0.2], [-0.4], [1.0]], dtype=complex)]
    assert float(mac_matrix(shapes[0], shapes[1])[0, 0]) < Criteria().mac
    pole = np.array([_pole(10.0, 0.02)])
    same = stabilise([(1, pole, shapes[0]), (2, pole, shapes[0])], (0.0, 100.0), Criteria())
    other = stabilise([(1, pole, shapes[0]), (2, pole, shapes[1])], (0.0, 100.0), Criteria())
    assert bool(same[1].stable[0]) and not bool(other[1].stable[0])


@pytest.mark.parametrize("f_high", [0.37, 5.0, 26.1, 90.0, 240.0])
@pytest.mark.parametrize("rate", [200.0, 512.0, 2048.0])
def test_decimation_keeps_the_anti_alias_margin(f_high: float, rate: float) -> None:
    """The largest factor whose new Nyquist frequency is still 4 times the highest frequency kept."""
    q = decimation_for(f_high, 1.0 / rate)
    nyquist = 0.5 * rate
    assert q >= 1
    if q > 1:
        assert nyquist / q >= 4.0 * f_high
    assert nyquist / (q + 1) < 4.0 * f_high


def test_cluster_separates_close_modes_by_frequency_and_shape() -> None:
    a = np.array([1.0, 0.2, 0.1], dtype=complex)
    b = np.array([0.1, 1.0, -0.3], dtype=complex)
    diagram = [
        OrderPoles(
            order,
            np.array([_pole(10.0, 0.01), _pole(10.2, 0.02)]),
            np.array([True, True]),
            np.stack([a, b], axis=1),
        )
        for order in range(1, 8)
    ]
    clusters = cluster_stable(diagram, min_count=3)
    assert len(clusters) == 2
    assert sorted(round(abs(c.pole) / (2 * np.pi), 6) for c in clusters) == [10.0, 10.2]
    assert all(c.count == 7 for c in clusters)


# --- estimation ---------------------------------------------------------------------------


@pytest.mark.parametrize("method", ["ar", "era"])
def test_noise_free_records_give_exact_modes(method: str) -> None:
    est = estimate_modes(_records(0.0), 1.0 / SAMPLE_RATE, method=method)  # type: ignore[arg-type]
    _assert_modes(est, TIMEDOMAIN_EXACT_REL, TIMEDOMAIN_EXACT_REL, 1.0 - TIMEDOMAIN_EXACT_REL)


def test_modes_from_noisy_records(estimate: ModalEstimate) -> None:
    _assert_modes(estimate, MODAL_FREQUENCY_REL, MODAL_DAMPING_REL, MODAL_MAC_MIN)


def test_identification_from_estimated_modes(estimate: ModalEstimate) -> None:
    result = identify(POSITIONS, DIRECTIONS, estimate.poles, estimate.shapes, mass=MASS)  # warnings are errors here
    assert result.diagnostics.warnings == ()
    assert np.linalg.norm(result.center_of_gravity - CG) < RECORDS_CG_SPAN[estimate.method] * SPAN
    assert result.inertia_tensor is not None
    rtol = RECORDS_INERTIA_REL[estimate.method]
    np.testing.assert_allclose(np.diag(result.inertia_tensor), np.diag(INERTIA), rtol=rtol)


def test_estimate_is_well_formed(estimate: ModalEstimate) -> None:
    assert np.all(estimate.poles.imag > 0) and np.all(estimate.poles.real < 0)
    assert np.all(np.diff(estimate.frequency_hz) > 0)
    peak = estimate.shapes[np.argmax(np.abs(estimate.shapes), axis=0), np.arange(6)]
    np.testing.assert_allclose(peak, 1.0 + 0.0j, atol=1e-12)
    np.testing.assert_allclose(np.abs(estimate.shapes).max(axis=0), 1.0)
    orders = [d.order for d in estimate.diagram]
    assert orders == sorted(orders) and len(set(orders)) == len(orders)
    for entry in estimate.diagram:
        assert entry.stable.shape == entry.poles.shape
        assert entry.shapes.shape == (8, entry.poles.size)
        assert np.all(np.diff(entry.frequency_hz) >= 0)
        assert np.all((entry.damping_ratio > 0) & (entry.damping_ratio < 0.3))
    assert np.all(estimate.stable_count >= 3)
    assert estimate.decimation == 1 and estimate.sample_interval == pytest.approx(1.0 / SAMPLE_RATE)
    assert len(estimate.impacts) == 2
    assert (estimate.adequate_order is None) == (estimate.method == "era")


@pytest.mark.parametrize("method", ["ar", "era"])
def test_high_sample_rate_is_decimated(method: str) -> None:
    recs = _records(0.01, seed=11, sample_rate=2000.0)
    est = estimate_modes(recs, 1.0 / 2000.0, method=method)  # type: ignore[arg-type]
    assert est.decimation > 1
    assert est.band[1] > TRUE_F.max()
    _assert_modes(est, MODAL_FREQUENCY_REL, MODAL_DAMPING_REL, MODAL_MAC_MIN)


def test_band_and_explicit_decimation(noisy_records: list[np.ndarray]) -> None:
    est = estimate_modes(noisy_records, 1.0 / SAMPLE_RATE, method="era", band=(4.0, 40.0), decimate=2)
    assert est.decimation == 2 and est.band == (4.0, 40.0)
    _assert_modes(est, MODAL_FREQUENCY_REL, MODAL_DAMPING_REL, MODAL_MAC_MIN)


def test_too_few_stable_modes_raise(noisy_records: list[np.ndarray]) -> None:
    with pytest.raises(IdentificationError, match=r"found 2 stable modes, 6 needed.*`band`.*`max_order`"):
        estimate_modes(noisy_records, 1.0 / SAMPLE_RATE, method="era", band=(5.0, 12.0))


def test_estimate_without_trimming_uses_the_whole_record(noisy_records: list[np.ndarray]) -> None:
    n_pre = round(PRETRIGGER * SAMPLE_RATE)
    decays = [rec[n_pre:] for rec in noisy_records]
    est = estimate_modes(decays, 1.0 / SAMPLE_RATE, method="era", trim=False)
    assert all(impact.start == 0 for impact in est.impacts)
    _assert_modes(est, MODAL_FREQUENCY_REL, MODAL_DAMPING_REL, MODAL_MAC_MIN)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"records": [np.zeros(10)]}, "samples x channels"),
        ({"records": [np.ones((50, 3)), np.ones((50, 2))]}, "2 channels, the first record has 3"),
        ({"records": [np.full((50, 3), np.nan)]}, "NaN"),
        ({"records": []}, "no records"),
        ({"dt": 0.0}, "sample interval"),
        ({"method": "dds"}, "unknown method"),
        ({"band": (10.0, 5.0)}, "band"),
        ({"decimate": 0}, "decimation"),
        ({"n_modes": 0}, "number of modes"),
        ({"pulse_width": 0.0}, "pulse width"),
    ],
)
def test_invalid_arguments_raise_input_errors(kwargs: dict[str, object], message: str) -> None:
    args: dict[str, object] = {"records": [np.ones((50, 3))], "dt": 0.01}
    args.update(kwargs)
    records = args.pop("records")
    dt = args.pop("dt")
    with pytest.raises(InputError, match=message):
        estimate_modes(records, dt, **args)  # type: ignore[arg-type]


def test_a_dead_channel_is_an_input_error(noisy_records: list[np.ndarray]) -> None:
    recs = [rec.copy() for rec in noisy_records]
    for rec in recs:
        rec[:, 3] = 0.0
    with pytest.raises(InputError, match="channel 4"):
        estimate_modes(recs, 1.0 / SAMPLE_RATE)


def test_importing_the_package_does_not_import_scipy() -> None:
    code = "; ".join(
        [
            "import sys, rigidid.core.timedomain, rigidid.io.records",
            "print(any(m.startswith('scipy') for m in sys.modules))",
        ]
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
