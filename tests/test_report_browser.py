"""The report in a real headless browser (Debian's chromium), at 1280 and 800 px, and the mode viewer's data.

The browser test skips, with its reason, when no chromium is installed (README's test command stays green
elsewhere; .ci/run installs it). Screenshots are judged by size and by not being blank; the labels of the
interactive mode view are measured in the page (``getBoundingClientRect`` written into the DOM by a probe
script, read back with ``--dump-dom``): none may overlap another, all must lie on the canvas and be at least
9 px tall, and the page must not scroll sideways.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from rigidid import api
from rigidid.modeviewer import mode_motions, mode_viewer_html

SAMPLE = Path(__file__).resolve().parent.parent / "samples" / "engine-test"
BROWSERS = ("chromium", "chromium-browser", "google-chrome")
_PROBE = """<script>
(function () {
  const shown = [...document.querySelectorAll('.rv-label')].filter(e => e.style.display !== 'none');
  const box = e => { const r = e.getBoundingClientRect(); return [r.left, r.top, r.width, r.height]; };
  const out = {labels: shown.map(e => ({text: e.textContent, box: box(e),
                                       size: parseFloat(getComputedStyle(e).fontSize)})),
               hidden: document.querySelectorAll('.rv-label').length - shown.length,
               canvas: box(document.querySelector('.rv canvas')),
               scrollWidth: document.documentElement.scrollWidth, innerWidth: window.innerWidth};
  const pre = document.createElement('pre'); pre.id = 'rigidid-probe'; pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
})();
</script></body>"""


def _browser() -> str | None:
    return next((path for name in BROWSERS if (path := shutil.which(name)) is not None), None)


def _chromium(browser: str, profile: Path, width: int, *args: str) -> subprocess.CompletedProcess[str]:
    cmd = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
           "--disable-component-update", "--disable-sync", "--no-first-run", f"--user-data-dir={profile}",
           f"--window-size={width},2000", *args]  # fmt: skip
    return subprocess.run(cmd, capture_output=True, text=True, timeout=60, check=False)


@pytest.fixture(scope="module")
def identified():
    return api.with_mounts(api.identify(SAMPLE / "layout.json", SAMPLE / "modes.csv"), SAMPLE / "mounts.json")


@pytest.fixture(scope="module")
def page(identified, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The report, and beside it the same report with the probe that writes the labels' extents into the DOM."""
    folder = tmp_path_factory.mktemp("browser")
    text = api.report(identified, title="engine test")
    (folder / "report.html").write_text(text, encoding="utf-8")
    (folder / "probe.html").write_text(text.replace("</body>", _PROBE), encoding="utf-8")
    return folder


def test_the_viewer_moves_the_sensors_as_they_were_measured(identified) -> None:
    """Each mode's animated motion, read along the sensors' axes, is the measured mode shape (exact modes:
    to round-off), so what the reader turns and plays is the test, not a drawing of it."""
    from rigidid.io import files

    ident = identified.identification
    table = files.load_modes(SAMPLE / "modes.csv", identified.sensor_ids)
    motions = mode_motions(ident.mode_shapes_cg, identified.positions, ident.center_of_gravity)
    largest = np.linalg.norm(np.abs(motions), axis=2).max(axis=1)
    assert largest == pytest.approx(np.ones(6))  # normalised: full amplitude is the largest point's motion
    for k, label in enumerate(identified.modes_used):
        readings = np.einsum("pi,pi->p", motions[k], identified.directions)
        measured = table.shapes[:, table.labels.index(label)]
        scale = np.vdot(readings, measured) / np.vdot(readings, readings)
        assert np.abs(scale * readings - measured).max() < 1e-6 * np.abs(measured).max()  # observed ~1e-10


def test_the_viewer_is_inline_and_names_every_node(identified) -> None:
    ident = identified.identification
    text = mode_viewer_html(identified.positions, identified.sensor_ids, ident.center_of_gravity,
                            ident.mode_shapes_cg, [f"mode {k}" for k in range(6)], "mm")  # fmt: skip
    data = json.loads(re.search(r'<script type="application/json">(.*?)</script>', text).group(1))
    assert data["sensors"] == ["1+x/y/z", "2+x/y/z", "3+x/y/z", "4+x/y/z"]  # triaxial nodes, one label each
    assert len(data["points"]) == 5 and len(data["modes"]) == 6  # four nodes and the CG
    assert "src=" not in text and "http" not in text


def _overlaps(boxes: list[list[float]]) -> list[tuple[int, int]]:
    return [
        (i, j)
        for i, a in enumerate(boxes)
        for j, b in enumerate(boxes[:i])
        if a[0] < b[0] + b[2] and b[0] < a[0] + a[2] and a[1] < b[1] + b[3] and b[1] < a[1] + a[3]
    ]


@pytest.mark.slow
@pytest.mark.parametrize("width", [1280, 800])
def test_the_report_in_a_headless_browser(page: Path, tmp_path: Path, width: int) -> None:
    browser = _browser()
    if browser is None:
        pytest.skip("no chromium on this machine (apt-get install chromium; .ci/run installs it)")
    from matplotlib.image import imread

    shot = tmp_path / "shot.png"
    run = _chromium(browser, tmp_path / "profile", width, f"--screenshot={shot}", (page / "report.html").as_uri())
    assert shot.exists(), run.stderr[-500:]
    pixels = imread(shot)
    assert pixels.shape[:2] == (2000, width)
    assert shot.stat().st_size > 50_000  # text, tables and figures, not an empty page
    assert float(pixels[..., :3].std()) > 0.05  # not blank
    dom = _chromium(browser, tmp_path / "profile", width, "--dump-dom", (page / "probe.html").as_uri()).stdout
    found = json.loads(re.search(r'<pre id="rigidid-probe">(.*?)</pre>', dom, flags=re.S).group(1))
    labels = found["labels"]
    assert {"CG", "x", "y", "z"} <= {label["text"] for label in labels}
    assert len(labels) + found["hidden"] == 4 + 4  # CG, three axes, four nodes
    assert _overlaps([label["box"] for label in labels]) == []
    assert min(label["size"] for label in labels) >= 9.0
    left, top, w, h = found["canvas"]
    for label in labels:
        x, y, bw, bh = label["box"]
        assert left <= x and x + bw <= left + w and top <= y and y + bh <= top + h, label
    assert found["scrollWidth"] <= found["innerWidth"]  # nothing wider than the window


@pytest.mark.parametrize("width", [800])
def test_crowded_labels_are_placed_apart_or_left_out(tmp_path: Path, width: int) -> None:
    """Twenty single-axis sensors, sixteen of them on a ring a tenth of the layout wide: placed labels never
    overlap (those that find no free place are left out), whatever their number."""
    browser = _browser()
    if browser is None:
        pytest.skip("no chromium on this machine (apt-get install chromium; .ci/run installs it)")
    from rigidid.reporting import CSS

    angles = np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False)
    ring = np.column_stack([30.0 * np.cos(angles), 30.0 * np.sin(angles), np.zeros(16)])
    corners = np.array([[300.0, 0, 0], [-300.0, 0, 0], [0, 300.0, 100.0], [0, -300.0, -100.0]])
    positions = np.vstack([ring, corners])
    shapes = np.eye(6, dtype=complex)
    viewer = mode_viewer_html(positions, [f"S{k + 1:02d}" for k in range(20)], np.zeros(3), shapes,
                              [f"mode {k + 1}" for k in range(6)], "mm", still=True)  # fmt: skip
    page = tmp_path / "viewer.html"
    page.write_text(f"<!DOCTYPE html><html><head><meta charset='utf-8'><style>{CSS}</style></head><body>{viewer}"
                    f"</body></html>".replace("</body>", _PROBE), encoding="utf-8")  # fmt: skip
    dom = _chromium(browser, tmp_path / "profile", width, "--dump-dom", page.as_uri()).stdout
    found = json.loads(re.search(r'<pre id="rigidid-probe">(.*?)</pre>', dom, flags=re.S).group(1))
    labels = found["labels"]
    assert len(labels) + found["hidden"] == 4 + 20
    assert len(labels) >= 10  # most find a place
    assert _overlaps([label["box"] for label in labels]) == []


@pytest.mark.slow
def test_the_report_prints_to_a_few_a4_pages(page: Path, tmp_path: Path) -> None:
    """The print stylesheet: the browser's print gives an A4 PDF of a few pages (the interactive view left out,
    tables and figures not split); the engine test's report is six pages."""
    browser = _browser()
    if browser is None:
        pytest.skip("no chromium on this machine (apt-get install chromium; .ci/run installs it)")
    pdf = tmp_path / "report.pdf"
    _chromium(browser, tmp_path / "profile", 1280, "--no-pdf-header-footer", f"--print-to-pdf={pdf}",
              (page / "report.html").as_uri())  # fmt: skip
    data = pdf.read_bytes()
    assert data.startswith(b"%PDF")
    pages = len(re.findall(rb"/Type\s*/Page[^s]", data))
    assert 3 <= pages <= 10
    found = re.findall(rb"/MediaBox\s*\[\s*0 0 ([\d.]+) ([\d.]+)", data)
    boxes = {tuple(round(float(v)) for v in box) for box in found}
    assert boxes == {(595, 842)}  # A4 in points
