"""Issue 25 / issue 20 item 3: a report an engineer can sign off, drawn from the typed results."""

from __future__ import annotations

import ast
import json
import re
from pathlib import Path
from typing import Any

import pytest

from rigidid import api

from .conftest import ROOT, SAMPLES

pytest.importorskip("matplotlib")

CASE = SAMPLES / "engine-test"


def _section(html: str, heading: str) -> str:
    part = html[html.index(heading) :]
    return part[: part.index("</table>")]


@pytest.fixture(scope="module")
def records_report() -> tuple[str, api.IdentifyResult]:
    run = api.identify_records(CASE / "layout.json", [CASE / "hit1.csv", CASE / "hit2.csv"])
    return api.report(run.result, stabilisation=run.estimate.diagram if run.estimate else None), run.result


def test_records_route_report_has_its_cramer_rao_intervals_in_table_units(
    records_report: tuple[str, api.IdentifyResult],
) -> None:
    html, result = records_report
    bound = result.record_bound
    assert bound is not None
    table = _section(html, "<h3>Cramér-Rao bound on the records</h3>")
    # stiffness in N/mm (translations) and N mm/rad (rotations), as the stiffness matrix above; not kg/s^2
    assert '<td class="label">N/mm</td>' in table and '<td class="label">N mm/rad</td>' in table
    assert "kg/s" not in table
    k_zz = 1e-3 * float(bound.stiffness_diagonal.std[2])  # kg/s^2 -> N/mm
    cells = re.findall(r'<td class="label">z</td><td class="label">N/mm</td><td>[^<]*</td><td>([^<]*)</td>', table)
    assert cells and float(cells[0].replace("\u2009", "")) == pytest.approx(k_zz, rel=5e-3)  # std has 3 digits
    assert "normalised cost" in table and re.search(r"\d\.\d{4,}e?", table.split("</caption>")[0]) is None


@pytest.fixture(scope="module")
def mounted(tmp_path_factory: pytest.TempPathFactory) -> api.IdentifyResult:
    """The sample's modes with a ``test`` block in its layout, the mounts identified, the torque roll axis along y."""
    layout = json.loads((CASE / "layout.json").read_text())
    layout["test"] = {"id": "T-0815", "specimen": "engine E4 s/n 2231 <prototype>", "date": "2026-11-20",
                      "operator": "A. Tester", "notes": "mounts new; 21 °C"}  # fmt: skip
    path = tmp_path_factory.mktemp("signoff") / "layout.json"
    path.write_text(json.dumps(layout))
    identified = api.identify(path, CASE / "modes.csv")
    return api.with_mounts(identified, CASE / "mounts.json", torque_axis=(0.0, 1.0, 0.0))


@pytest.fixture(scope="module")
def mounted_report(mounted: api.IdentifyResult) -> str:
    """One report of `mounted`, read by every test of its tables (drawn once)."""
    return api.report(mounted)


def test_test_block_of_the_layout_is_in_the_report(mounted: api.IdentifyResult, mounted_report: str) -> None:
    result, html = mounted, mounted_report
    assert result.test is not None and result.test.operator == "A. Tester"
    block = html[html.index('<table class="test">') :]
    block = block[: block.index("</table>")]
    for text in ("T-0815", "engine E4 s/n 2231 &lt;prototype&gt;", "2026-11-20", "A. Tester", "mounts new; 21 °C"):
        assert text in block
    assert html.index('<table class="test">') < html.index("<h2>")  # under the title


def test_unknown_test_field_is_refused(tmp_path: Path) -> None:
    from rigidid.errors import InputError

    layout = json.loads((CASE / "layout.json").read_text())
    layout["test"] = {"operater": "A. Tester"}
    (tmp_path / "layout.json").write_text(json.dumps(layout))
    with pytest.raises(InputError, match=r"test\.operater"):
        api.load_layout(tmp_path / "layout.json")


def test_report_prints_cleanly(mounted_report: str) -> None:
    html = mounted_report  # the stylesheet is part of every report
    css = html[html.index("<style>") : html.index("</style>")]
    assert "@media print" in css and "@page" in css and "break-inside: avoid" in css


def test_mount_tables_read_the_typed_result(mounted_report: str) -> None:
    html = mounted_report
    table = _section(html, "<h2>Mounts (identified)</h2>")
    mounts = json.loads((CASE / "mounts.json").read_text())["mounts"]
    assert "stiffness [N/mm]" in table and "damping [N s/mm]" in table
    front = mounts[0]["stiffness"]  # kg/s^2 along x, y, z: 180, 160, 420 N/mm
    assert " / ".join(f"{1e-3 * v:g}" for v in front) in table


def test_presentation_imports_no_private_names() -> None:
    """The report, the tables and the API's report module import only public names of other modules."""
    for path in ("src/rigidid/api/reports.py", "src/rigidid/reporting.py", "src/rigidid/render.py",
                 "src/rigidid/compare.py", "src/rigidid/compare_render.py"):  # fmt: skip
        tree = ast.parse((ROOT / path).read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("rigidid"):
                private = [a.name for a in node.names if a.name.startswith("_") and not a.name.startswith("__")]
                assert not private, f"{path}: from {node.module} import {private}"
    for path in ("src/rigidid/api/reports.py", "src/rigidid/reporting.py", "src/rigidid/render.py"):
        source = (ROOT / path).read_text()
        assert "_to_dict(" not in source, path  # the typed results, not the JSON forms


def _layout_figure_of(result: api.IdentifyResult) -> object:
    from rigidid.reporting import (
        _layout_figure,  # the figure itself, to measure its texts
        identified_mount_labels,
    )

    assert result.mounts is not None
    labels = identified_mount_labels(result.mounts, result.units)
    return _layout_figure(
        result.identification, result.positions, result.directions, list(result.sensor_ids),
        result.units["length"], result.units["mass"], result.mounts.positions, labels,
        None if result.torque_roll_axis is None else result.torque_roll_axis.direction,
    )  # fmt: skip


def test_layout_labels_do_not_overlap_and_are_legible_at_800_px(mounted: api.IdentifyResult) -> None:
    """In every 2D view no two labels overlap and none sits on a marker; every text is >= 9 px at 800 px wide."""
    from matplotlib.text import Annotation

    fig: Any = _layout_figure_of(mounted)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    scale = 800.0 / fig.bbox.width  # the page shows the figure 800 px wide
    projections = [ax for ax in fig.axes if ax.name == "rectilinear" and "view" in ax.get_title()]
    assert len(projections) == 3
    for ax in projections:
        labels = [t for t in ax.texts if isinstance(t, Annotation) and t.get_text()]
        boxes = [t.get_window_extent(renderer) for t in labels]
        names = [t.get_text() for t in labels]
        assert {"CG", "M1", "M2", "M3"} <= set(names)
        for i in range(len(boxes)):
            for j in range(i):
                assert not boxes[i].overlaps(boxes[j]), (names[i], names[j], ax.get_title())
        for t, box in zip(labels, boxes, strict=True):
            assert box.height * scale >= 9.0, (t.get_text(), box.height * scale)
    for text in fig.findobj(lambda a: hasattr(a, "get_fontsize") and hasattr(a, "get_text")):
        if text.get_text().strip() and text.get_visible():
            px = text.get_fontsize() * fig.dpi / 72.0 * scale
            assert px >= 7.5, (text.get_text(), px)  # tick labels included
