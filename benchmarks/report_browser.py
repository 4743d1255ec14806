"""The reports in a headless browser: what a reader sees at 1280 and 800 px, and what prints.

Usage::

    PYTHONPATH=src python benchmarks/report_browser.py [--browser chromium]

For the engine test of ``samples/engine-test`` it writes the report of the modes route (with the
mounts) and of the FRF routes, opens each in Debian's chromium (headless) at 1280 and 800 px and
prints, per page and width: the screenshot's size, the page's width against the window's (a
page wider than the window scrolls sideways), and for the interactive mode view the labels
shown and left out, the pairs of labels that overlap and the smallest label in px; then the
pages of the A4 PDF the browser prints. Nothing here is a test (tests/test_report_browser.py
checks the same things); the figures go in the report of issue 25.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "samples" / "engine-test"
PROBE = """<script>
(function () {
  const all = [...document.querySelectorAll('.rv-label')], shown = all.filter(e => e.style.display !== 'none');
  const box = e => { const r = e.getBoundingClientRect(); return [r.left, r.top, r.width, r.height]; };
  const out = {boxes: shown.map(box), sizes: shown.map(e => parseFloat(getComputedStyle(e).fontSize)),
               hidden: all.length - shown.length, scrollWidth: document.documentElement.scrollWidth,
               innerWidth: window.innerWidth};
  const pre = document.createElement('pre'); pre.id = 'probe'; pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
})();
</script></body>"""


def chromium(browser: str, profile: Path, width: int, *args: str) -> str:
    cmd = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
           "--disable-component-update", "--disable-sync", "--no-first-run", f"--user-data-dir={profile}",
           f"--window-size={width},2000", *args]  # fmt: skip
    return subprocess.run(cmd, capture_output=True, text=True, timeout=120, check=False).stdout


def overlaps(boxes: list[list[float]]) -> int:
    return sum(
        1
        for i, a in enumerate(boxes)
        for b in boxes[:i]
        if a[0] < b[0] + b[2] and b[0] < a[0] + a[2] and a[1] < b[1] + b[3] and b[1] < a[1] + a[3]
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--browser", default=None, help="the browser (default: chromium on the PATH)")
    args = parser.parse_args()
    browser = args.browser or shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        print("no chromium on this machine (apt-get install chromium)")
        return 0
    from rigidid import api

    folder = Path(tempfile.mkdtemp(prefix="rigidid-browser-"))
    result = api.with_mounts(api.identify(SAMPLE / "layout.json", SAMPLE / "modes.csv"), SAMPLE / "mounts.json")
    pages = {
        "modes route": api.report(result, title="engine test"),
        "FRF routes": api.frf_report(SAMPLE / "layout.json", SAMPLE / "frf.csv", SAMPLE / "refs.json"),
    }
    print(f"{'page':12} {'width':>5} {'shot kB':>8} {'page px':>8} {'labels':>6} {'left out':>8} "
          f"{'overlaps':>8} {'min px':>6} {'PDF pages':>9}")  # fmt: skip
    for name, text in pages.items():
        page = folder / f"{name.split()[0]}.html"
        page.write_text(text, encoding="utf-8")
        probe = folder / f"{name.split()[0]}-probe.html"
        probe.write_text(text.replace("</body>", PROBE), encoding="utf-8")
        pdf = folder / f"{name.split()[0]}.pdf"
        chromium(browser, folder / "profile", 1280, "--no-pdf-header-footer", f"--print-to-pdf={pdf}", page.as_uri())
        n_pages = len(re.findall(rb"/Type\s*/Page[^s]", pdf.read_bytes())) if pdf.exists() else 0
        for width in (1280, 800):
            shot = folder / f"{name.split()[0]}-{width}.png"
            chromium(browser, folder / "profile", width, f"--screenshot={shot}", page.as_uri())
            dom = chromium(browser, folder / "profile", width, "--dump-dom", probe.as_uri())
            found = json.loads(re.search(r'<pre id="probe">(.*?)</pre>', dom, flags=re.S).group(1))
            sizes = found["sizes"]
            smallest = min(sizes) if sizes else float("nan")
            print(f"{name:12} {width:5d} {shot.stat().st_size / 1000:8.0f} "
                  f"{found['scrollWidth']:>4}/{found['innerWidth']:<3} {len(sizes):6d} {found['hidden']:8d} "
                  f"{overlaps(found['boxes']):8d} {smallest:6.1f} {n_pages:9d}")  # fmt: skip
    print(f"(pages and screenshots in {folder})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
