"""``rigidid report --frf``: the FRF routes side by side, their fits drawn over the measured FRFs."""

from __future__ import annotations

import base64
import json
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from rigidid import api
from rigidid.api.load import load_references_for
from rigidid.frf_report import MeasuredFrfs, mass_line_model, render_frf_report, rigid_model
from rigidid.io import files
from rigidid.io.frf import load_frf_csv, reference_arrays

SAMPLE = Path(__file__).resolve().parent.parent / "samples" / "engine-test"


def run(*args: str | Path) -> SimpleNamespace:
    """The command line, in this process."""
    from typer.testing import CliRunner

    from rigidid.cli import app

    result = CliRunner().invoke(app, [str(a) for a in args])
    return SimpleNamespace(returncode=result.exit_code, stdout=result.stdout, stderr=result.stderr)


@pytest.fixture(scope="module")
def page(tmp_path_factory: pytest.TempPathFactory) -> SimpleNamespace:
    """``rigidid report layout.json --frf frf.uff --png DIR``: references from the UFF's headers, route auto."""
    import rigidid.api.frf

    folder = tmp_path_factory.mktemp("report")
    out, png = folder / "report.html", folder / "png"
    again: list[str] = []  # routes the report runs after auto: none (it reuses the ones auto ran)
    by_name = rigidid.api.frf.identify_frf_route

    def counted(*args: object, **kwargs: object) -> object:
        again.append(str(kwargs["method"]))
        return by_name(*args, **kwargs)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(rigidid.api.frf, "identify_frf_route", counted)
        done = run("report", SAMPLE / "layout.json", "--frf", SAMPLE / "frf.uff", "--png", png, "-o", out,
                   "--title", "engine FRFs")  # fmt: skip
    assert done.returncode == 0, done.stderr
    return SimpleNamespace(text=out.read_text(), png=png, stderr=done.stderr, again=again)


@pytest.fixture(scope="module")
def measured() -> MeasuredFrfs:
    lay = files.load_layout(SAMPLE / "layout.json")
    refs = load_references_for(SAMPLE / "refs.json", lay)
    ids, pos, dirs = files.layout_arrays(lay)
    rids, rpos, rdirs = reference_arrays(refs)
    freqs, h = load_frf_csv(SAMPLE / "frf.csv", ids, rids)
    return MeasuredFrfs(freqs, h, pos, dirs, rpos, rdirs, ids, rids)


@pytest.fixture(scope="module")
def routes() -> list:
    """Both routes on the sample's exact FRFs (the residues route fits the poles: the slow part, done once)."""
    return [
        api.identify_massline(SAMPLE / "layout.json", SAMPLE / "frf.csv", SAMPLE / "refs.json", method=m)
        for m in ("residues", "massline")
    ]


@pytest.mark.slow
def test_the_scaled_modes_model_reproduces_the_measured_frfs(measured: MeasuredFrfs, routes: list) -> None:
    """The rigid body on supports from the scaled modes is the FRFs' own model: exact data, exact fit (1e-9),
    and its high-frequency limit is the mass line T M^-1 T_f^T of the mass-line route."""
    scaled = routes[0].scaled
    model = rigid_model(measured, scaled.mass_matrix, scaled.stiffness_matrix, scaled.damping_matrix,
                        scaled.center_of_gravity)  # fmt: skip
    error = np.abs(model - measured.frf).max() / np.abs(measured.frf).max()
    assert error < 1e-8  # observed ~3e-11 (the CSV keeps 17 digits; the fit's round-off)
    ml = routes[1].massline
    level = mass_line_model(measured, ml.mass, ml.center_of_gravity, ml.inertia_tensor)
    far = MeasuredFrfs(
        np.array([1e9]), measured.frf[:, :, :1], measured.positions, measured.directions,
        measured.reference_positions, measured.reference_directions, measured.sensor_ids, measured.reference_ids,
    )  # fmt: skip
    limit = rigid_model(far, scaled.mass_matrix, scaled.stiffness_matrix, scaled.damping_matrix,
                        scaled.center_of_gravity)[:, :, 0]  # fmt: skip
    assert np.abs(limit - level).max() < 1e-6 * np.abs(level).max()  # the i C / (w M) term: 2e-9 at 1e9 Hz


def test_the_report_puts_the_routes_side_by_side(page: SimpleNamespace) -> None:
    """The references come from the UFF's headers (no --references), every route tried is listed with the one
    chosen, both are tabled with their intervals, and --png writes the page's own figures."""
    text = page.text
    assert "12 responses \u00d7 3 references" in text
    tried = re.search(r"<h2>Routes tried</h2>.*?<tbody>(.*?)</tbody>", text, re.S).group(1)
    assert tried.count("<tr>") == 2 and tried.count("<td>chosen</td>") == 1 and "<td>applies</td>" in tried
    section = text[text.index("<h2>Mass, centre of gravity and inertia</h2>") :]
    header = re.search(r"<thead><tr>(.*?)</tr></thead>", section).group(1)
    assert "scaled modes (residues): estimate" in header and "mass line: estimate" in header
    assert header.count("95 % interval") == 2
    mass_row = re.search(r"<tr><td class=\"label\">mass</td>(.*?)</tr>", section).group(1)
    assert mass_row.count(">142<") == 2  # both routes measure the 142 kg through the force
    assert mass_row.count("<td>± ") == 2  # each route's interval, in kg
    for name in ("FRFs and the fits", "Mass line", "Stabilisation diagram", "Stiffness matrix at the CG"):
        assert f"<h2>{name}" in text
    embedded = re.findall(r"data:image/png;base64,([A-Za-z0-9+/=]+)", text)
    assert len(embedded) == 3
    assert "http://" not in text and "https://" not in text  # self-contained
    files = sorted(page.png.iterdir())
    assert [f.name for f in files] == ["frf.png", "massline.png", "stabilisation.png"]
    assert sorted(base64.b64decode(e) for e in embedded) == sorted(f.read_bytes() for f in files)
    assert page.stderr.strip().splitlines()[-1] == f"rigidid: wrote 3 figures to {page.png}"
    assert page.again == []  # the route auto did not choose is tabled from its own run, not run a second time


def test_report_frf_refuses_options_of_other_routes(tmp_path: Path) -> None:
    out = tmp_path / "r.html"
    done = run("report", SAMPLE / "layout.json", "--frf", SAMPLE / "frf.csv", "--references", SAMPLE / "refs.json",
               "--uncertainty", "50", "-o", out)  # fmt: skip
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "rigidid: error: --uncertainty: applies to the modes and records routes, not to a report of FRFs (--frf)"
    ]
    assert not out.exists()


def test_report_frf_refuses_references_that_contradict_the_uff_headers(tmp_path: Path) -> None:
    """The references are resolved as identify resolves them: references.json against the UFF's headers,
    one line naming both, nothing written."""
    refs = json.loads((SAMPLE / "refs.json").read_text())
    refs["references"][0]["position"] = [p + 50.0 for p in refs["references"][0]["position"]]
    (tmp_path / "refs.json").write_text(json.dumps(refs))
    out, png = tmp_path / "r.html", tmp_path / "png"
    done = run("report", SAMPLE / "layout.json", "--frf", SAMPLE / "frf.uff", "--references", tmp_path / "refs.json",
               "--png", png, "-o", out)  # fmt: skip
    assert done.returncode == 2
    line = done.stderr.strip()
    assert "\n" not in line and "is at" in line and "refs.json" in line and "frf.uff's FRF headers" in line
    assert not out.exists() and not png.exists()


@pytest.mark.slow
def test_routes_that_disagree_beyond_their_errors_are_flagged(
    measured: MeasuredFrfs, routes: list, page: SimpleNamespace
) -> None:
    """The last column is the routes' difference over their combined standard error; beyond 3 the page says so,
    naming the entries (a route 5 SE off in mass is flagged, the same route agreeing is not)."""
    from dataclasses import replace

    figures = {f.stem: f.read_bytes() for f in page.png.iterdir()}  # drawn once: this test is about the tables

    ml = routes[0].massline
    intervals = replace(ml.intervals, mass=replace(ml.intervals.mass, std=np.asarray(0.1)))  # 0.1 kg each
    residues = replace(routes[0], massline=replace(ml, intervals=intervals))
    twin = replace(residues, route="massline")  # same figures, same intervals: differ by 0 SE
    text = render_frf_report(measured, [residues, twin], created="2026-01-01", figures=figures)
    assert '<div class="warn">' not in text
    off = replace(twin, massline=replace(twin.massline, mass=twin.massline.mass + 5.0 * np.sqrt(2.0) * 0.1))
    text = render_frf_report(measured, [residues, off], created="2026-01-01", figures=figures)
    mass_row = re.search(r"<tr><td class=\"label\">mass</td>(.*?)</tr>", text).group(1)
    assert mass_row.endswith("<td>5</td>")
    warning = re.search(r'<div class="warn">(.*?)</div>', text).group(1)
    assert "in: mass." in warning  # only the mass
