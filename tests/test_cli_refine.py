"""identify --records refines the body on the records by default (issue 11); --no-refine keeps the modes' answer."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from .cli_runner import run
from .conftest import SAMPLES
from .tolerances import STREAMED_DECAY_ATOL, STREAMED_REFIT_REL, STREAMED_REFIT_STD_REL

FOUR = SAMPLES / "four-mounts"


def _patch(monkeypatch: pytest.MonkeyPatch, name: str, value: object) -> None:
    """Replace `name` in the package and in every API module that holds it (they import it by name)."""
    import importlib

    from rigidid import api

    monkeypatch.setattr(api, name, value)
    for module in ("load", "records", "reports"):
        owner = importlib.import_module(f"rigidid.api.{module}")
        if hasattr(owner, name):
            monkeypatch.setattr(owner, name, value)


@pytest.fixture(scope="module")
def records(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    folder = tmp_path_factory.mktemp("records")
    out = run(
        "simulate", FOUR / "body.json", FOUR / "layout.json", "-o", folder / "exact.csv", "--write-records", folder,
        "--add-record-noise", "0.01", "--seed", "3", "--sample-rate", "256", "--duration", "4", "--pretrigger", "0.2",
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    return sorted(folder.glob("record-*.csv"))


def test_refined_result_carries_its_cramer_rao_intervals(records: list[Path]) -> None:
    out = run("identify", FOUR / "layout.json", "--records", *records, "--json", "-")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    crb = data["uncertainty_records_crb"]
    assert crb["noise_from"] == "pretrigger"
    assert 0.5 < crb["normalised_cost"] < 2.0
    assert crb["converged"] is True and 0 < crb["evaluations"] < 240
    body = json.loads((FOUR / "body.json").read_text())
    assert crb["center_of_gravity"]["estimate"] == data["center_of_gravity"]
    std = np.array(crb["center_of_gravity"]["std"])
    assert np.all(std > 0)
    # the truth lies within 5 standard errors of every CG coordinate
    assert np.all(np.abs(np.subtract(data["center_of_gravity"], body["center_of_gravity"])) < 5 * std)


def test_no_refine_keeps_the_answer_from_the_modes(records: list[Path]) -> None:
    out = run("identify", FOUR / "layout.json", "--records", *records, "--no-refine", "--json", "-")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert "uncertainty_records_crb" not in data


def test_without_the_refit_records_are_streamed_not_loaded_whole(
    records: list[Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    """identify --records --no-refine estimates through the streamed reader (issue 14): the same answer."""
    from typer.testing import CliRunner

    from rigidid import api
    from rigidid.cli import app

    layout = api.load_layout(FOUR / "layout.json")
    loaded = api.load_records(records, layout)
    modes, _ = api.estimate_modes(layout, loaded)
    expected = api.identify(layout, modes)

    def refuse(*_: object, **__: object) -> None:
        raise AssertionError("records loaded whole")

    _patch(monkeypatch, "load_records", refuse)
    out = CliRunner().invoke(app, ["identify", str(FOUR / "layout.json"), "--records", *map(str, records),
                                   "--no-refine", "--json", "-"])  # fmt: skip
    assert out.exit_code == 0, out.output
    data = json.loads(out.stdout)
    cg = expected.identification.center_of_gravity
    np.testing.assert_allclose(data["center_of_gravity"], cg, rtol=1e-9, atol=1e-12)


@pytest.fixture(scope="module")
def long_records(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """Two impacts sampled at 10 kHz for 8 s (80 000 rows each): long enough to be pre-decimated while read."""
    from rigidid.api import body_from_file
    from rigidid.core.timedomain import impulse_records
    from rigidid.io.files import layout_arrays, load_body, load_layout

    folder = tmp_path_factory.mktemp("long")
    body = body_from_file(load_body(FOUR / "body.json"))
    _, pos, dirs = layout_arrays(load_layout(FOUR / "layout.json"))
    impacts = [((0.3, 0.2, 0.15), (0.3, -0.5, -1.0)), ((-0.3, -0.1, 0.0), (1.0, 0.6, 0.2))]
    recs = impulse_records(body, pos, dirs, impacts, sample_rate=10_000.0, duration=8.0, pretrigger=0.1,
                           noise=0.01, seed=8)  # fmt: skip
    paths = []
    for k, rec in enumerate(recs):
        path = folder / f"hit{k + 1}.npy"
        np.save(path, np.column_stack([np.arange(rec.shape[0]) / 10_000.0, rec]))
        paths.append(path)
    return paths


def test_the_refit_data_read_in_row_blocks_equal_the_whole_records(
    long_records: list[Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The second pass (io/records/refit) builds the refit's decays and noise levels the whole records give."""
    from rigidid import api
    from rigidid.core.timedomain import refine
    from rigidid.core.timedomain.preprocess import find_impact
    from rigidid.io.records.refit import locate_impacts, read_prepared_decays

    monkeypatch.setattr(refine, "MAX_ROWS", 40_000)  # the fit decimates (q > 1) and cuts the decays
    layout = api.load_layout(FOUR / "layout.json")
    ids = [s.id for s in layout.sensors]
    raw = api.load_records(long_records, layout)
    _, estimate = api.estimate_rigid_modes(layout, long_records)  # streamed: impacts in the files' rows
    dt = raw[0][1]
    exact = [find_impact(r, dt) for r, _ in raw]
    # the estimate's impacts are only as fine as its decimation (here they may or may not fall on the raw ones)
    assert all(abs(a.onset - b.onset) <= 2 * estimate.decimation for a, b in zip(estimate.impacts, exact, strict=True))
    reach = 22 * estimate.decimation + 52
    located = locate_impacts(long_records, ids, dt, estimate.impacts, reach)
    assert located == exact
    from rigidid.core.timedomain import Impact

    late = tuple(Impact(i.onset + 500, i.peak + 500, i.start + 500) for i in estimate.impacts)
    assert locate_impacts(long_records, ids, dt, late, 5) is None  # the rows held miss the onset: not proven
    starts, onsets = [i.start for i in exact], [i.onset for i in exact]
    whole = refine.prepare_decays([r for r, _ in raw], dt, starts, onsets, estimate.decimation)
    streamed = read_prepared_decays(long_records, ids, dt, starts=starts, onsets=onsets, factor=estimate.decimation)
    assert round(whole.dt / dt) > 1 and whole.dt == streamed.dt and whole.noise_from == streamed.noise_from
    lengths = [r.shape[0] - s for (r, _), s in zip(raw, starts, strict=True)]
    assert sum(d.size for d in whole.decays) <= 40_000 < sum(lengths) * len(ids)
    assert [d.shape for d in whole.decays] == [d.shape for d in streamed.decays]
    for a, b in zip(whole.decays, streamed.decays, strict=True):
        np.testing.assert_allclose(b, a, rtol=0.0, atol=STREAMED_DECAY_ATOL * np.abs(a).max())
    np.testing.assert_allclose(streamed.sigma, whole.sigma, rtol=STREAMED_DECAY_ATOL)


def test_the_refit_on_files_read_in_row_blocks_gives_the_whole_read_answer(
    long_records: list[Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    """api.refine_records above its threshold (lowered here) never holds the raw records: the same body."""
    from rigidid import api
    from rigidid.core.timedomain import refine

    monkeypatch.setattr(refine, "MAX_ROWS", 16_000)  # a smaller fit (still decimated and cut), for the suite's time
    layout = api.load_layout(FOUR / "layout.json")
    modes, estimate = api.estimate_rigid_modes(layout, long_records)
    start = api.identify(layout, modes)
    whole = api.refine_records(start, long_records, layout, estimate, stream_above=10**12)
    real = api.load_records

    def refuse(*_: object, **__: object) -> None:
        raise AssertionError("records loaded whole")

    _patch(monkeypatch, "load_records", refuse)
    streamed = api.refine_records(start, long_records, layout, estimate, stream_above=0)
    _patch(monkeypatch, "load_records", real)
    assert whole.record_bound is not None and streamed.record_bound is not None
    for name in ("center_of_gravity", "inertia_per_mass", "stiffness_per_mass", "damping_per_mass"):
        a, b = getattr(whole.identification, name), getattr(streamed.identification, name)
        np.testing.assert_allclose(b, a, rtol=0.0, atol=STREAMED_REFIT_REL * np.abs(a).max())
    np.testing.assert_allclose(
        streamed.record_bound.center_of_gravity.std,
        whole.record_bound.center_of_gravity.std,
        rtol=STREAMED_REFIT_STD_REL,
    )


def test_identify_records_refits_from_the_files_read_in_row_blocks(
    long_records: list[Path], monkeypatch: pytest.MonkeyPatch
) -> None:
    """identify --records (default refit) reads long record files once in row blocks, never whole (issues 14, 23):
    the refit's decays are read with the modes' reading; the JSON keys of the whole read, its body within the
    noise's standard errors, the impacts in the files' rows. (The refit's data read again in row blocks equal
    the whole read's exactly: test_refine_records_above_the_threshold_never_holds_the_raw_records.)"""
    from typer.testing import CliRunner

    from rigidid.cli import app
    from rigidid.core.timedomain import refine
    from rigidid.io.records import refit

    monkeypatch.setattr(refine, "MAX_ROWS", 16_000)  # a smaller fit (still decimated and cut), for the suite's time
    args = ["identify", str(FOUR / "layout.json"), "--records", *map(str, long_records), "--json", "-"]
    _patch(monkeypatch, "STREAM_REFIT_VALUES", 10**12)
    whole = CliRunner().invoke(app, args)
    assert whole.exit_code == 0, whole.output
    _patch(monkeypatch, "STREAM_REFIT_VALUES", 0)

    def refuse(*_: object, **__: object) -> None:
        raise AssertionError("records loaded whole")

    _patch(monkeypatch, "load_records", refuse)
    monkeypatch.setattr(refit, "locate_and_read", refuse)  # no second reading for the refit
    out = CliRunner().invoke(app, args)
    assert out.exit_code == 0, out.output
    data, expected = json.loads(out.stdout), json.loads(whole.stdout)
    assert sorted(data) == sorted(expected)
    assert sorted(data["uncertainty_records_crb"]) == sorted(expected["uncertainty_records_crb"])
    crb, crb_whole = data["uncertainty_records_crb"], expected["uncertainty_records_crb"]
    assert crb["noise_from"] == "pretrigger" and 0.5 < crb["normalised_cost"] < 2.0
    # the decays at a finer rate over a shorter span (the reader's factor: streaming.captured_decays), so the
    # same answer within noise: observed at most 1.7 of the noise's standard errors (the sensors' are common)
    se = np.maximum(*(np.asarray(c["sensor_budget"]["noise"]["center_of_gravity"]) for c in (crb, crb_whole)))
    assert np.all(np.abs(np.subtract(data["center_of_gravity"], expected["center_of_gravity"])) < 5.0 * se)
    factor = data["modal_estimation"]["decimation"]
    for impact in data["modal_estimation"]["impacts"]:  # file rows: 0.1 s (1000 rows) in, as fine as the factor
        assert 990 <= impact["onset"] <= 1000 + factor and impact["start"] > impact["peak"] >= impact["onset"]


def test_the_report_spectrum_of_files_read_in_row_blocks_is_the_whole_records(long_records: list[Path]) -> None:
    """The report's summed spectrum streamed (io/records/spectrum) equals summed_spectrum of the whole records."""
    from rigidid import api
    from rigidid.core.spectrum import summed_spectrum

    layout = api.load_layout(FOUR / "layout.json")
    raw = api.load_records(long_records, layout)
    freq, power = summed_spectrum([r for r, _ in raw], raw[0][1])
    got = api.records_spectrum(long_records, layout)
    assert got is not None
    np.testing.assert_array_equal(got[0], freq)
    np.testing.assert_allclose(got[1], power, rtol=0.0, atol=STREAMED_DECAY_ATOL * power.max())


def test_report_records_never_holds_the_raw_records(
    long_records: list[Path], monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """report --records (default refit) reads long record files in row blocks only, spectrum figure included."""
    from typer.testing import CliRunner

    from rigidid import api
    from rigidid.cli import app
    from rigidid.core.timedomain import refine

    monkeypatch.setattr(refine, "MAX_ROWS", 16_000)  # a smaller fit (still decimated and cut), for the suite's time
    _patch(monkeypatch, "STREAM_REFIT_VALUES", 0)
    seen: list[int] = []
    real = api.records_spectrum

    def spy(*args: object, **kwargs: object) -> object:
        got = real(*args, **kwargs)  # type: ignore[arg-type]
        assert got is not None
        seen.append(got[1].size)
        return got

    def refuse(*_: object, **__: object) -> None:
        raise AssertionError("records loaded whole")

    drawn: list[object] = []
    real_report = api.report

    def report(*args: object, **kwargs: object) -> str:
        drawn.append(kwargs.get("spectrum"))
        return real_report(*args, **kwargs)  # type: ignore[arg-type]

    _patch(monkeypatch, "records_spectrum", spy)
    _patch(monkeypatch, "report", report)
    _patch(monkeypatch, "load_records", refuse)
    out = CliRunner().invoke(app, ["report", str(FOUR / "layout.json"), "--records", *map(str, long_records),
                                   "-o", str(tmp_path / "r.html")])  # fmt: skip
    assert out.exit_code == 0, out.output
    assert seen == [2049]  # one streamed spectrum, the one the report draws
    assert len(drawn) == 1 and drawn[0] is not None and len(drawn[0]) == 2  # type: ignore[arg-type]
    assert (tmp_path / "r.html").stat().st_size > 0


def test_the_row_block_passes_read_csv_records_as_npy(long_records: list[Path], tmp_path: Path) -> None:
    """A CSV record (rows only estimated from its size) gives the row-block passes the .npy's numbers."""
    from rigidid import api
    from rigidid.core.timedomain import Impact
    from rigidid.io.records.refit import locate_impacts, read_prepared_decays

    layout = api.load_layout(FOUR / "layout.json")
    ids = [s.id for s in layout.sensors]
    data = np.load(long_records[0])
    csv = tmp_path / "hit1.csv"
    np.savetxt(csv, data, delimiter=",", header=",".join(["time", *ids]), comments="", fmt="%.17g")
    dt, near = 1e-4, [Impact(1000, 1028, 1336)]  # as a decimation by 28 put it
    found = [locate_impacts([p], ids, dt, near, 700) for p in (long_records[0], csv)]
    assert found[0] == found[1] and found[0] is not None and found[0][0].onset == 1000
    impact = found[0][0]
    a, b = (read_prepared_decays([p], ids, dt, starts=[impact.start], onsets=[impact.onset], factor=9)
            for p in (long_records[0], csv))  # fmt: skip
    assert a.dt == b.dt and a.noise_from == b.noise_from == "pretrigger"
    np.testing.assert_array_equal(a.decays[0], b.decays[0])
    np.testing.assert_array_equal(a.sigma, b.sigma)
    spectra = [api.records_spectrum([p], layout) for p in (long_records[0], csv)]
    assert spectra[0] is not None and spectra[1] is not None
    np.testing.assert_allclose(spectra[1][1], spectra[0][1], rtol=0.0, atol=STREAMED_DECAY_ATOL * spectra[0][1].max())


def test_warnings_describe_the_refined_answer_not_its_start(tmp_path: Path) -> None:
    """Findings about the structured start (damping not PSD...) go when the refinement replaces it (issue 22)."""
    from rigidid.core.identify import physical_checks

    out = run(
        "simulate", FOUR / "body.json", FOUR / "layout.json", "-o", tmp_path / "exact.csv", "--records", tmp_path,
        "--record-noise", "0.05", "--seed", "1", "--sample-rate", "256", "--duration", "4", "--pretrigger", "0.2",
    )  # fmt: skip
    records = sorted(tmp_path.glob("record-*.csv"))
    start = run("identify", FOUR / "layout.json", "--records", *records, "--no-refine", "--json", "-")
    out = run("identify", FOUR / "layout.json", "--records", *records, "--json", "-")
    assert out.returncode == 0 and start.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert "uncertainty_records_crb" in data and "standard_errors" not in data
    keys = ("inertia_per_mass", "stiffness_per_mass", "damping_per_mass")
    found = physical_checks(*(np.array(data[k]) for k in keys))
    start_warnings = json.loads(start.stdout)["diagnostics"]["warnings"]
    about_start = [w for w in start_warnings if w not in found and "sensor" not in w]
    assert any("semi-definite" in w for w in about_start)  # the start's damping is not PSD here
    for w in data["diagnostics"]["warnings"]:
        assert w not in about_start, w
    assert not [line for line in out.stderr.splitlines() if any(w in line for w in about_start)]
