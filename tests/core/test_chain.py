"""The acquisition chain in the refit (rigidid.core.timedomain.chain, issue 23).

Records simulated by rigidid's impulse simulator, then passed through a chain built with
scipy.signal (bilinear high-pass, a sample shift), which shares no code with the estimator's
closed-form transfer functions.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rigidid.api import body_from_file
from rigidid.core.geometry import layout_frame
from rigidid.core.simulate import system_matrices
from rigidid.core.timedomain import impulse_records
from rigidid.core.timedomain.chain import AntiAlias, ChainModel, ChannelChain
from rigidid.core.timedomain.refine import N_PARAMETERS, _Data, _evaluate, _Frame, _Link, refine_body
from rigidid.errors import InputError
from rigidid.io.files import layout_arrays, load_body, load_layout

SAMPLE = Path(__file__).resolve().parents[2] / "samples" / "four-mounts"
IMPACTS = [((0.3, 0.2, 0.15), (0.3, -0.5, -1.0)), ((-0.3, -0.1, 0.0), (1.0, 0.6, 0.2))]
RATE = 128.0
SKEWED = 2


@pytest.fixture(scope="module")
def rig() -> tuple[object, np.ndarray, np.ndarray]:
    body = body_from_file(load_body(SAMPLE / "body.json"))
    _, pos, dirs = layout_arrays(load_layout(SAMPLE / "layout.json"))
    return body, pos, dirs


def _through_chain(records: list[np.ndarray], corner: float) -> list[np.ndarray]:
    from scipy.signal import bilinear, lfilter

    b, a = bilinear([1.0, 0.0], [1.0, 2 * np.pi * corner], RATE)
    out = []
    for r in records:
        y = lfilter(b, a, r, axis=0)
        y[1:, SKEWED] = y[:-1, SKEWED].copy()  # one sample late
        out.append(y)
    return out


@pytest.mark.parametrize("kind", ["butterworth", "bessel"])
def test_antialias_transfer_is_the_data_sheets_filter(kind: str) -> None:
    from scipy.signal import bessel, butter, freqs

    corner = 300.0
    design = butter if kind == "butterworth" else bessel
    extra = {} if kind == "butterworth" else {"norm": "mag"}
    b, a = design(6, 2 * np.pi * corner, analog=True, **extra)
    w = 2 * np.pi * np.array([5.0, 40.0, 150.0, corner])
    ours, _ = ChannelChain(antialias=AntiAlias(kind, 6, corner)).transfer(1j * w)
    np.testing.assert_allclose(ours, freqs(b, a, w)[1], rtol=1e-9)
    assert abs(abs(ours[-1]) - 2**-0.5) < 1e-9


def test_transfer_derivative_is_the_slope() -> None:
    chain = ChannelChain(highpass_hz=2.0, highpass_order=2, antialias=AntiAlias("bessel", 4, 200.0), delay=1e-3)
    s = np.array([-3.0 + 60.0j, -10.0 + 140.0j])
    h = 1e-4
    slope = (chain.transfer(s + h)[0] - chain.transfer(s - h)[0]) / (2 * h)
    np.testing.assert_allclose(chain.transfer(s)[1], slope, rtol=1e-7)


def test_jacobian_with_the_chain_and_delays_matches_finite_differences(rig, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    from rigidid.core.timedomain import refine

    monkeypatch.setattr(refine, "_GOLUB_PEREYRA", True)  # the exact projected Jacobian: the residual is not small
    body, pos, dirs = rig
    records = impulse_records(body, pos, dirs, IMPACTS, sample_rate=RATE, duration=0.8, noise=1e-5, seed=0)
    _, k, c = system_matrices(body)
    lf = layout_frame(pos)
    frame = _Frame(lf.centre, lf.scale, 60.0)
    p = pos.shape[0]
    theta = frame.to_theta(body.center_of_gravity, body.inertia_tensor / body.mass, k / body.mass, c / body.mass)
    theta = np.concatenate([theta, 0.01 * np.arange(1, p)])
    chain = ChainModel(
        tuple(ChannelChain(highpass_hz=1.0, antialias=AntiAlias("butterworth", 4, 50.0)) for _ in range(p))
    )
    link = _Link(chain, 60.0, tuple(range(1, p)))
    data = _Data([r[:90] for r in records], np.ones(p), 1.0 / RATE, "residual")
    pos_l = lf.to_local(pos)
    r0, jac = _evaluate(theta, data, pos_l, dirs, 60.0, True, link)
    assert jac.shape == (r0.size, N_PARAMETERS + p - 1)
    for i in (0, 5, 20, 40, N_PARAMETERS, N_PARAMETERS + SKEWED - 1, theta.size - 1):
        h = 1e-6 * max(1.0, abs(theta[i]))
        up, down = theta.copy(), theta.copy()
        up[i] += h
        down[i] -= h
        fd = (_evaluate(up, data, pos_l, dirs, 60.0, False, link)[0]
              - _evaluate(down, data, pos_l, dirs, 60.0, False, link)[0]) / (2 * h)  # fmt: skip
        assert np.linalg.norm(jac[:, i] - fd) <= 1e-4 * np.linalg.norm(fd) + 1e-9


def _refit(rig, records, chain, estimate_delays=False, evaluations=40, onset=26):  # type: ignore[no-untyped-def]
    body, pos, dirs = rig
    _, k, c = system_matrices(body)
    m = body.mass
    return refine_body(
        records, 1.0 / RATE, pos, dirs, starts=[onset + 1] * 2, onsets=[onset] * 2, decimation=1,
        center_of_gravity=body.center_of_gravity + 1e-4, inertia_per_mass=body.inertia_tensor / m * 1.0005,
        stiffness_per_mass=k / m * 1.0005, damping_per_mass=c / m * 1.002, max_evaluations=evaluations,
        chain=chain, estimate_delays=estimate_delays,
    )  # fmt: skip


def test_a_stated_chain_makes_the_refit_exact_and_its_delay_is_estimated(rig) -> None:  # type: ignore[no-untyped-def]
    body, pos, dirs = rig
    clean = impulse_records(body, pos, dirs, IMPACTS, sample_rate=RATE, duration=1.2, pretrigger=0.2, noise=0.0)
    records = _through_chain(clean, 1.0)
    p = pos.shape[0]
    stated = ChainModel(tuple(ChannelChain(highpass_hz=1.0, delay=1 / RATE if i == SKEWED else 0.0) for i in range(p)))
    j = body.inertia_tensor / body.mass
    ref = _refit(rig, records, stated)
    # exact (the chain ignored, the CG is 2 mm off)
    assert np.max(np.abs(ref.center_of_gravity - body.center_of_gravity)) < 7e-7  # observed 2.1e-7
    assert np.max(np.abs(ref.inertia_per_mass - j)) < 6e-6 * np.max(j)  # observed 1.8e-6
    # the high-pass stated, the delay estimated: one sample on the skewed channel, none elsewhere
    hp = ChainModel(tuple(ChannelChain(highpass_hz=1.0) for _ in range(p)))
    fitted = _refit(rig, records, hp, estimate_delays=True)
    assert fitted.delays is not None and fitted.delays_std is not None
    expected = np.where(np.arange(p) == SKEWED, 1 / RATE, 0.0)
    np.testing.assert_allclose(fitted.delays, expected, atol=1e-4 / RATE)  # observed 3e-5 samples
    assert np.max(np.abs(fitted.center_of_gravity - body.center_of_gravity)) < 7e-5


def test_an_unmodelled_skew_is_named_by_its_delay_score(rig) -> None:  # type: ignore[no-untyped-def]
    body, pos, dirs = rig
    clean = impulse_records(body, pos, dirs, IMPACTS, sample_rate=RATE, duration=1.2, pretrigger=0.3, noise=0.002,
                            seed=3)  # fmt: skip
    records = _through_chain(clean, 1.0)
    hp = ChainModel(tuple(ChannelChain(highpass_hz=1.0) for _ in range(pos.shape[0])))
    ref = _refit(rig, records, hp, onset=38)
    assert ref.misfit is not None and not ref.misfit.accepted
    assert ref.delay_score is not None
    z = np.abs(ref.delay_score[1])
    assert int(np.argmax(z)) == SKEWED and z[SKEWED] > 5.0
    assert np.max(np.delete(z, SKEWED)) < z[SKEWED] / 3


def test_shapes_through_the_chain_are_corrected() -> None:
    chain = ChainModel((ChannelChain(highpass_hz=2.0), ChannelChain(delay=0.01)))
    poles = np.array([-1.0 + 50.0j, -2.0 + 90.0j])
    true = np.array([[1.0, 0.5], [-0.3, 2.0]], dtype=complex)
    seen = true * chain.transfer(poles)[0]
    np.testing.assert_allclose(chain.correct_shapes(poles, seen), true, rtol=1e-14)
    assert chain.settle_time() == 0.01 and ChainModel((ChannelChain(),)).identity  # the late channel passed


def test_layout_chain_is_validated(tmp_path: Path) -> None:
    import json

    from rigidid.api.records import chain_model
    from rigidid.io.files import load_layout as load

    base = json.loads((SAMPLE / "layout.json").read_text())
    first = base["sensors"][0]["id"]
    base["chain"] = {"highpass_hz": 0.5, "antialias": {"type": "bessel", "order": 4, "corner_hz": 200.0},
                     "sensors": {first: {"delay_s": 0.001, "highpass_hz": 0.0}}}  # fmt: skip
    (tmp_path / "layout.json").write_text(json.dumps(base))
    model = chain_model(load(tmp_path / "layout.json"))
    assert model is not None
    assert model.channels[0] == ChannelChain(0.0, 1, AntiAlias("bessel", 4, 200.0), 0.001)
    assert model.channels[1].highpass_hz == 0.5 and model.channels[1].delay == 0.0
    # the modal routes' shapes with the chain divided out, sensor by sensor
    from rigidid.api.records import chain_corrected
    from rigidid.io.files import ModeTable

    lay = load(tmp_path / "layout.json")
    ids = [x.id for x in lay.sensors][::-1]  # any order of the layout's sensors
    seen = np.ones((len(ids), 2), dtype=complex)
    table = chain_corrected(ModeTable.numbered(np.array([8.0, 20.0]), np.array([0.02, 0.05]), ids, seen), lay)
    w = 2 * np.pi * np.array([8.0, 20.0])
    poles = -np.array([0.02, 0.05]) * w + 1j * w * np.sqrt(1 - np.array([0.02, 0.05]) ** 2)
    np.testing.assert_allclose(table.shapes[-1], 1 / model.channels[0].transfer(poles)[0], rtol=1e-12)
    np.testing.assert_allclose(table.shapes[0], 1 / model.channels[len(ids) - 1].transfer(poles)[0], rtol=1e-12)
    for bad, where in (({"sensors": {"nope": {"delay_s": 0.0}}}, "chain.sensors.nope"),
                       ({"antialias": {"type": "cheby", "order": 4, "corner_hz": 1.0}}, "chain.antialias.type"),
                       ({"highpass_hz": -1.0}, "chain.highpass_hz")):  # fmt: skip
        base["chain"] = bad
        (tmp_path / "layout.json").write_text(json.dumps(base))
        with pytest.raises(InputError, match=where.replace(".", r"\.")):
            load(tmp_path / "layout.json")


def test_mains_hum_is_found_modelled_and_left_out_of_the_modes(rig) -> None:  # type: ignore[no-untyped-def]
    from rigidid.core.timedomain.hum import find_hum
    from rigidid.core.timedomain.stabilisation import _physical

    body, pos, dirs = rig
    rng = np.random.default_rng(5)
    white = [rng.standard_normal((300, 4)) for _ in range(2)]
    assert find_hum(white, 1.0 / RATE) == []
    t = np.arange(300) / RATE
    hummed = [w + 0.5 * np.sin(2 * np.pi * 50.0 * t + k)[:, None] for k, w in enumerate(white)]
    (hz, _, amplitude), *rest = find_hum(hummed, 1.0 / RATE)
    assert hz == 50.0 and not rest and 0.4 < amplitude < 0.6
    # a sweep's pole at 50 Hz with no damping is hum, not a mode; a damped one is a mode
    poles = 2 * np.pi * 50.0 * np.array([-1e-4 + 1j, -0.02 + 1j])
    assert list(_physical(poles, (1.0, 60.0), 0.3)) == [False, True]
    # the refit with hum of 3 % of the peak: found, modelled, the body as exact as without it
    clean = impulse_records(body, pos, dirs, IMPACTS, sample_rate=RATE, duration=1.2, pretrigger=0.3, noise=0.0)
    t = np.arange(clean[0].shape[0]) / RATE
    peak = np.max(np.abs(clean[0]), axis=0)
    phase = 0.3 * np.arange(pos.shape[0])
    records = [r + 0.03 * peak * np.sin(2 * np.pi * 50.0 * t[:, None] + phase) for r in clean]
    ref = _refit(rig, records, None, onset=38)
    assert [h for h, _, _ in ref.hum] == [50.0]
    assert np.max(np.abs(ref.center_of_gravity - body.center_of_gravity)) < 1e-6


def test_with_the_chain_and_delays_fitted_the_sensor_budget_is_the_refits_own_linearisation(rig) -> None:  # type: ignore[no-untyped-def]
    """Issue 23: the refit's sensor signatures through the chain and the fitted delays predict how the refit
    moves with small sensor errors (noise-free records through a 3 Hz AC coupling, one channel a sample late, the
    chain stated and the channels' delays fitted beyond it)."""
    from rigidid.core.sensor_budget import SensorBounds, axis_normals
    from rigidid.core.timedomain.refine import _output_gradient, _settled, _started, prepare_decays, sensor_terms

    body, pos, dirs = rig
    p = pos.shape[0]
    dirs = dirs / np.linalg.norm(dirs, axis=1)[:, None]
    x = np.zeros((6, p))  # the sensors' errors, rows as SensorTerms' columns: gain, two tilts, shift x, y, z
    x[0, SKEWED], x[1, 4], x[2, 6], x[3, 0], x[5, 3] = 0.004, 0.003, -0.002, 0.002, -0.0015
    e1, e2 = axis_normals(dirs)
    clean = impulse_records(body, pos + x[3:].T, dirs + x[1][:, None] * e1 + x[2][:, None] * e2, IMPACTS,
                            sample_rate=RATE, duration=1.2, pretrigger=0.3)  # fmt: skip
    level = 1e-7 * max(float(np.max(np.abs(r))) for r in clean)  # the same tiny noise on every channel
    rng = np.random.default_rng(0)
    records = _through_chain([r * (1.0 + x[0]) + level * rng.standard_normal(r.shape) for r in clean], 3.0)
    hp = ChainModel(tuple(ChannelChain(highpass_hz=3.0, delay=1 / RATE if i == SKEWED else 0.0) for i in range(p)))
    _, k, c = system_matrices(body)
    truth = (body.center_of_gravity, body.inertia_tensor / body.mass, k / body.mass, c / body.mass)
    starts, onsets = [39] * 2, [38] * 2
    ref = refine_body(
        records, 1.0 / RATE, pos, dirs, starts=starts, onsets=onsets, decimation=1, center_of_gravity=truth[0],
        inertia_per_mass=truth[1], stiffness_per_mass=truth[2], damping_per_mass=truth[3], chain=hp,
        estimate_delays=True, sensor_bounds=SensorBounds(sensitivity=0.03, orientation_deg=3.0, transverse=0.0,
                                                         position=0.003),
    )  # fmt: skip
    assert ref.sensor_std is not None  # the refit's own budget, with the delays free and the chain modelled
    # the prediction at the truth, in the refit's model: the records move by G x, the fit by -(J^T J)^-1 J^T G~ x
    pos_l, frame, theta = _started(pos, dirs, truth)
    link = _Link(hp, frame.omega, tuple(range(1, p)))
    theta = np.concatenate([theta, np.zeros(p - 1)])  # the skew stated, the delays fitted beyond it: none
    data = _settled(prepare_decays(records, 1.0 / RATE, starts, onsets, 1), hp, True, 1.0 / RATE)
    r, jm = _evaluate(theta, data, pos_l, dirs, frame.omega, True, link)
    terms = sensor_terms(theta, data, pos_l, dirs, frame.omega, jm, r, frame.scale, link)
    moved = -_output_gradient(theta, frame, pos_l, dirs) @ np.linalg.solve(jm.T @ jm, terms.cross @ x.ravel())
    actual = np.concatenate([ref.center_of_gravity - truth[0], (ref.inertia_per_mass - truth[1]).ravel()])
    assert np.max(np.abs(actual)) > 5e-4  # the errors move the CG by 0.8 mm (the chain's own error: 1e-5)
    # observed 0.007 of the largest (the signatures without the skewed channel's chain: 0.052)
    np.testing.assert_allclose(moved[:12], actual, rtol=0, atol=0.025 * np.max(np.abs(actual)))


def test_the_sensors_are_estimated_through_a_stated_ac_coupling_with_the_delays_fitted(rig) -> None:  # type: ignore[no-untyped-def]
    """Issue 23: the sensors estimated with a modelled chain and fitted delays (it was refused, then only forced):
    records through a stated 2 Hz AC coupling, one channel a sample late, one sensor's gain 6 % high (the
    tolerance stated at 6 %); by default (the sensor test flags) the correction reads the virtual sensors through
    the chain and the fitted delays, moves the delays with the body, keeps them on its second pass, recovers the
    gain and takes its error out of the body."""
    from scipy.signal import bilinear, lfilter

    from rigidid.core.sensor_budget import SensorBounds

    body, pos, dirs = rig
    p = pos.shape[0]
    gain = np.ones(p)
    gain[5] = 1.06
    clean = impulse_records(body, pos, dirs, IMPACTS, sample_rate=RATE, duration=1.2, pretrigger=0.3, noise=0.002,
                            seed=5)  # fmt: skip
    b, a = bilinear([1.0, 0.0], [1.0, 2 * np.pi * 2.0], RATE)
    records = [lfilter(b, a, r * gain, axis=0) for r in clean]
    for r in records:
        r[1:, SKEWED] = r[:-1, SKEWED].copy()  # one sample late
    hp = ChainModel(tuple(ChannelChain(highpass_hz=2.0) for _ in range(p)))
    bounds = SensorBounds(sensitivity=0.06, orientation_deg=0.0, transverse=0.0, position=0.0)
    _, k, c = system_matrices(body)
    m, j = body.mass, body.inertia_tensor / body.mass

    fixed = refine_body(
        records, 1.0 / RATE, pos, dirs, starts=[39] * 2, onsets=[38] * 2, decimation=1,
        center_of_gravity=body.center_of_gravity + 1e-4, inertia_per_mass=j * 1.0005,
        stiffness_per_mass=k / m * 1.0005, damping_per_mass=c / m * 1.002, max_evaluations=40, chain=hp,
        sensor_bounds=bounds, estimate_sensors=None, estimate_delays=True,
    )  # fmt: skip
    error = np.concatenate([fixed.center_of_gravity - body.center_of_gravity, np.diag(fixed.inertia_per_mass - j)])
    assert fixed.sensor_test is not None and fixed.sensor_test.flagged and fixed.sensor_test.estimated
    x = fixed.sensor_correction
    assert x is not None and x.determined[0].all()
    assert fixed.delays is not None and fixed.delays_std is not None  # the second pass fitted them too
    late = np.where(np.arange(p) == SKEWED, 1 / RATE, 0.0)
    assert np.max(np.abs(fixed.delays - late)[1:] / fixed.delays_std[1:]) < 4.0
    # a common gain is undetermined (no force): the gains relative to their mean; observed 4e-4 of 6 %
    rel = (x.value[0] - x.value[0].mean()) - (gain - gain.mean())
    assert np.max(np.abs(rel)) < 1.5e-3 and np.max(np.abs(rel)) < np.min(x.std[0])
    assert fixed.sensor_std is not None
    noise = np.concatenate([fixed.std["center_of_gravity"], np.diag(fixed.std["inertia_per_mass"])])
    typeb = [np.concatenate([x["center_of_gravity"], np.diag(x["inertia_per_mass"])])
             for x in fixed.sensor_std.values()]  # fmt: skip
    z = error / np.sqrt(noise**2 + sum(t**2 for t in typeb))
    assert np.max(np.abs(z)) < 3.0  # observed 0.96: the corrected body within its intervals
    # observed 1.1e-4 (without the correction 1.5e-3; with it, but the step the fit left at its end
    # taken for sensor errors, the gains 17 % off and the body 8e-3)
    assert np.max(np.abs(error)) < 4e-4


def test_with_hum_the_noise_levels_still_come_from_the_pretrigger(rig) -> None:  # type: ignore[no-untyped-def]
    """Issue 23: hum of 3 % of each channel's peak over noise of 1 % (the hum's variance 4.5 times the noise's)
    is taken out of the pre-trigger by least squares, so the levels are the noise's and the misfit test keeps
    its stated rate (noise drawn here, on rigidid's noise-free records)."""
    body, pos, dirs = rig
    clean = impulse_records(body, pos, dirs, IMPACTS, sample_rate=RATE, duration=2.0, pretrigger=1.0, noise=0.0)
    rng = np.random.default_rng(11)
    t = np.arange(clean[0].shape[0]) / RATE
    peak = np.max(np.abs(clean[0]), axis=0)
    phase = rng.uniform(0.0, 2 * np.pi, pos.shape[0])
    hum = 0.03 * peak * np.sin(2 * np.pi * 50.0 * t[:, None] + phase)
    records = [r + hum + 0.01 * peak * rng.standard_normal(r.shape) for r in clean]
    ref = _refit(rig, records, None, evaluations=60, onset=127)
    assert [h for h, _, _ in ref.hum] == [50.0]
    assert ref.noise_from == "pretrigger" and ref.misfit is not None and ref.misfit.p_value > 0.001
    # at the noise's own level the cost is about 1 (0.94-1.11 on seeds 0-11); with the hum left in the levels, 0.18
    assert 0.85 < ref.normalised_cost < 1.2
    z = (ref.center_of_gravity - body.center_of_gravity) / ref.std["center_of_gravity"]
    assert np.max(np.abs(z)) < 4.0
