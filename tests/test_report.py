"""The self-contained HTML report and its PNG figures, on the 1994 paper's sample."""

from __future__ import annotations

import base64
import re
import struct
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rigidid.core.geometry import sensor_outline
from rigidid.core.identify import Identification, identify
from rigidid.core.noise import NoiseLevels
from rigidid.core.uncertainty import IntervalEstimate, Uncertainty
from rigidid.errors import InputError, PhysicalPlausibilityWarning
from rigidid.reporting import render_report, save_pngs

from .paper_sample import UNITS, paper_identification, paper_modes

pytest.importorskip("matplotlib")

MOUNTS = [(7.0, 0.0, -4.5), (-4.0, 6.0, -4.5), (-4.0, -6.0, -4.5)]
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def png_size(data: bytes) -> tuple[int, int]:
    """Width and height from a PNG's IHDR chunk (checks the signature and the chunk order)."""
    assert data[:8] == PNG_SIGNATURE
    assert data[12:16] == b"IHDR"
    width, height = struct.unpack(">II", data[16:24])
    assert data.rstrip(b"\x00")[-8:-4] == b"IEND"
    return int(width), int(height)


def embedded_pngs(html: str) -> list[bytes]:
    return [base64.b64decode(m) for m in re.findall(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', html)]


def stabilisation(ident: Identification) -> list[tuple[int, np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(4)
    entries = []
    for order in range(6, 30, 4):
        f = np.concatenate([ident.frequency_hz * (1 + 0.002 * rng.standard_normal(6)), rng.uniform(2.0, 20.0, 2)])
        entries.append((order, f, np.arange(8) < 6))
    return entries


def _interval(estimate: list[float], std: list[float]) -> IntervalEstimate:
    est, sd = np.array(estimate), np.array(std)
    return IntervalEstimate(est, sd, est - 1.96 * sd, est + 1.96 * sd)


UNCERTAINTY = Uncertainty(
    center_of_gravity=_interval([-0.31, -0.19, -1.63], [0.03, 0.028, 0.065]),
    inertia=IntervalEstimate(
        np.diag([2454.0, 3115.0, 5070.0]), np.full((3, 3), 50.0), np.diag([2300.0] * 3), np.diag([5200.0] * 3)
    ),
    principal_moments=_interval([2454.0, 3115.0, 5070.0], [107.0, 64.0, 177.0]),
    stiffness_diagonal=_interval([4.3e5, 4.4e5, 8.6e5, 2.1e7, 2.2e7, 3.9e7], [1e3] * 6),
    damping_diagonal=_interval([1.0e3, 1.1e3, 2.0e3, 3.0e4, 3.1e4, 5.0e4], [10.0] * 6),
    per_mass=False,
    noise=NoiseLevels(frequency=0.001, damping=0.05, shape=5.238479517691258e-11),
    draws=200,
    failed=0,
    implausible=0,
    seed=0,
)


@pytest.fixture(scope="module")
def paper() -> tuple[Identification, list[str], np.ndarray, np.ndarray]:
    return paper_identification()


@pytest.fixture(scope="module")
def report(paper: tuple[Identification, list[str], np.ndarray, np.ndarray]) -> str:
    ident, ids, pos, dirs = paper
    return render_report(
        ident,
        pos,
        dirs,
        ids,
        UNITS,
        mounts=MOUNTS,
        stabilisation=stabilisation(ident),
        uncertainty=UNCERTAINTY,
        title="Paper sample",
    )


def test_paper_cg_is_below_the_sensor_plane(paper: tuple[Identification, list[str], np.ndarray, np.ndarray]) -> None:
    ident, _, pos, _ = paper
    np.testing.assert_allclose(ident.center_of_gravity, [-0.3, -0.19, -1.63], atol=0.03)
    assert ident.center_of_gravity[2] < np.mean(pos[:, 2])


def test_report_is_one_html_document(report: str) -> None:
    assert report.startswith("<!DOCTYPE html>")
    assert report.rstrip().endswith("</html>")
    for tag in ("<html", "<head>", "<body>", "</body>", "</html>", "<title>"):
        assert report.count(tag) == 1, tag
    assert '<meta charset="utf-8">' in report
    assert "<title>Paper sample</title>" in report


def test_report_holds_the_results_with_units(
    report: str, paper: tuple[Identification, list[str], np.ndarray, np.ndarray]
) -> None:
    ident = paper[0]
    for heading in (
        "Centre of gravity",
        "Inertia tensor about the CG",
        "Principal moments and axes",
        "Stiffness matrix at the CG",
        "Damping matrix at the CG",
        "Modes",
        "Decoupling: kinetic energy distribution",
        "Layout",
        "Mode shapes",
        "Stabilisation diagram",
        "Uncertainty",
        "Diagnostics",
    ):
        assert f">{heading}<" in report, heading
    for value in ident.center_of_gravity:  # the CG, to 5 significant digits
        assert f"<td>{value:.5g}</td>" in report
    assert "<td>-0.31173</td>" in report and "<td>-1.6283</td>" in report
    assert "[lb·in²]" in report  # inertia
    assert "x-z block [lb/s²], coupling blocks [lb·in/s²], rx-rz block [lb·in²/s²]" in report
    assert "x-z block [lb/s], coupling blocks [lb·in/s], rx-rz block [lb·in²/s]" in report
    assert "mass 136 lb" in report
    assert "damping matrix is not positive semi-definite" in report  # the warning is shown
    # the uncertainty table: in the units of the tables above, its caption in words and rounded numbers
    table = report[report.index(">Uncertainty<") :]
    table = table[: table.index("</table>")]
    assert "200 draws of the measurement errors (0 failed, 0 implausible, seed 0)" in table
    assert "shape 5.24e-09 %" in table and "5.238479517691258e-11" not in table  # no raw floats
    k_zz = 8.6e5 / 386.08858  # lb/s^2 -> lbf/in
    matrix = report[report.index(">Stiffness matrix at the CG<") :]
    rotation = re.search(r"rx-rz block \[([^\]]+)\]", matrix)
    assert rotation is not None and f'<td class="label">{rotation.group(1)}</td>' in table  # as the matrix
    assert '<td class="label">lbf/in</td>' in table and "lb/s²" not in table
    assert f"<td>{k_zz:,.1f}</td>".replace(",", "\u2009") in table  # 2 227.5 lbf/in


def test_decoupling_numbers_are_in_the_report(report: str) -> None:
    # the collapsible table of the heat map: six modes, rows of percentages summing to about 100
    table = report[report.index("<details>") : report.index("</details>")]
    rows = re.findall(r"<tr><td class=\"label\">(\d) \(([\d.]+) Hz\)</td>(.*?)</tr>", table)
    assert [r[0] for r in rows] == ["1", "2", "3", "4", "5", "6"]
    for _, _, cells in rows:
        values = [float(v) for v in re.findall(r"<td>(-?[\d.]+)</td>", cells)]
        assert len(values) == 12
        assert sum(values[:6]) == pytest.approx(100.0, abs=0.5)
        assert sum(values[6:]) == pytest.approx(100.0, abs=0.5)


def test_report_is_self_contained(report: str) -> None:
    assert "http://" not in report and "https://" not in report
    # one inline script, rigidid's own mode viewer, with its data inline: nothing fetched, no src attribute
    scripts = re.findall(r"<script([^>]*)>", report, flags=re.IGNORECASE)
    assert scripts == [' type="application/json"', ""]
    assert "fetch(" not in report and "XMLHttpRequest" not in report and "import(" not in report
    assert "<link" not in report.lower()
    assert "@import" not in report and "url(" not in report
    assert re.findall(r'src="([^"]{0,22})', report) == ["data:image/png;base64,"] * 4


def test_report_figures_are_sane_pngs(report: str) -> None:
    pngs = embedded_pngs(report)
    assert len(pngs) == 4  # layout, modes, decoupling, stabilisation
    for data in pngs:
        width, height = png_size(data)
        assert 600 <= width <= 2000
        assert 300 <= height <= 2000
        assert len(data) > 20_000  # drawn, not blank
        assert b"http" not in data  # no URL even in the PNG metadata


def test_report_per_unit_mass_without_options(
    paper: tuple[Identification, list[str], np.ndarray, np.ndarray],
) -> None:
    _, ids, pos, dirs = paper
    with pytest.warns(PhysicalPlausibilityWarning, match="damping matrix"):
        per_mass = identify(pos, dirs, *paper_modes(ids), mass=None)
    html = render_report(per_mass, pos, dirs, ids, {"length": "mm", "mass": "kg"})
    assert len(embedded_pngs(html)) == 3
    assert ">Stabilisation diagram<" not in html and ">Uncertainty<" not in html
    assert ">Stiffness matrix at the CG per unit mass<" in html
    assert "[mm² (per unit mass)]" in html
    assert "x-z block [1/s²], coupling blocks [mm/s²], rx-rz block [mm²/s²]" in html
    assert "results per unit mass" in html


def test_save_pngs_writes_the_figures(
    tmp_path: Path, paper: tuple[Identification, list[str], np.ndarray, np.ndarray]
) -> None:
    """Every figure by name, no temporary file left; files replaced get the usual permissions (umask 022)."""
    import os

    ident, ids, pos, dirs = paper
    paths = save_pngs(tmp_path, ident, pos, dirs, ids, UNITS, mounts=MOUNTS, stabilisation=stabilisation(ident))
    assert [p.name for p in paths] == ["layout.png", "modes.png", "decoupling.png", "stabilisation.png"]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in paths)  # no temporary files left
    for p in paths:
        width, height = png_size(p.read_bytes())
        assert width >= 600 and height >= 300
    mask = os.umask(0o022)
    try:
        again = save_pngs(tmp_path, ident, pos, dirs, ids, UNITS)
    finally:
        os.umask(mask)
    assert [p.name for p in again] == ["layout.png", "modes.png", "decoupling.png"]
    assert all(p.stat().st_mode & 0o777 == 0o644 for p in again)
    with pytest.raises(InputError, match="not an existing folder"):
        save_pngs(tmp_path / "missing", ident, pos, dirs, ids, UNITS)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"stabilisation": [(10, [1.0, 2.0], [True])]}, "2 frequencies but 1 stable flags"),
        ({"stabilisation": [(10, [1.0])]}, "expected \\(order, frequencies, stable flags\\)"),
        ({"uncertainty": replace(UNCERTAINTY, center_of_gravity=_interval([1, 2], [1, 2]))}, "not three numbers"),
        ({"units": {"length": "in"}}, "units need 'length' and 'mass'"),
        ({"sensor_ids": ["1", "2"]}, "6 positions, 6 directions and 2 sensor ids"),
    ],
)  # fmt: skip
def test_bad_report_arguments(
    paper: tuple[Identification, list[str], np.ndarray, np.ndarray], kwargs: dict[str, Any], message: str
) -> None:
    ident, ids, pos, dirs = paper
    args: dict[str, Any] = {"sensor_ids": ids, "units": UNITS, **kwargs}
    with pytest.raises(InputError, match=message):
        render_report(ident, pos, dirs, **args)


def test_sensor_outline_is_a_closed_ring_of_distinct_points() -> None:
    square = np.array([[0, 0, 0], [1, 1, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=float)
    ring = sensor_outline(square)
    assert ring[0] == ring[-1]
    assert sorted(ring[:-1]) == [0, 1, 2, 3]  # the repeated point (index 4) counts once
    corners = square[ring]
    steps = np.linalg.norm(np.diff(corners, axis=0), axis=1)
    np.testing.assert_allclose(steps, 1.0)  # walks round the square, never across it
    assert sensor_outline(square[:2]) == [0, 1]
    assert sensor_outline(np.zeros((3, 3))) == [0]


def test_stabilisation_accepts_order_poles_of_the_time_domain_estimator() -> None:
    from rigidid.core.timedomain.stabilisation import OrderPoles
    from rigidid.reporting import check_stabilisation

    poles = np.array([-0.1 + 2 * np.pi * 6.0j, -0.2 + 2 * np.pi * 9.0j])
    entry = OrderPoles(order=8, poles=poles, stable=np.array([True, False]), shapes=np.ones((6, 2), dtype=complex))
    ((order, freq, stable),) = check_stabilisation([entry])
    assert order == 8
    np.testing.assert_allclose(freq, np.abs(poles) / (2 * np.pi))
    assert stable.tolist() == [True, False]
