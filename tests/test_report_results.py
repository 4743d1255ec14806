"""The report, issue 9: one decoupling table, units an engineer reads, who made it from what."""

from __future__ import annotations

import re

import numpy as np
import pytest

from rigidid import api
from rigidid.core.spectrum import summed_spectrum
from rigidid.io.files import load_body
from rigidid.jsonout import result_to_dict
from rigidid.reporting import _sensor_labels

from .conftest import SAMPLES

pytest.importorskip("matplotlib")

ENGINE = SAMPLES / "engine-on-mounts"


@pytest.fixture(scope="module")
def engine_report() -> tuple[api.IdentifyResult, str]:
    result = api.identify(ENGINE / "layout.json", ENGINE / "modes.csv")
    body = load_body(ENGINE / "body.json")
    html = api.report(result, body=body, inputs=["layout.json", "modes.csv"])
    return result, html


def test_one_decoupling_table_in_json_and_report(engine_report: tuple[api.IdentifyResult, str]) -> None:
    result, html = engine_report
    energy = result_to_dict(result)["energy_distribution"]
    table = html[html.index("<details>") : html.index("</details>")]
    rows = re.findall(r"<tr><td class=\"label\">(\d+) \([\d.]+ Hz\)</td>(.*?)</tr>", table)
    assert [int(r[0]) for r in rows] == energy["modes"] == list(result.modes_used)
    for (_, cells), expected in zip(rows, energy["cg_axes"], strict=True):
        shown = [float(v) for v in re.findall(r"<td>(-?[\d.]+)</td>", cells)][:6]
        np.testing.assert_allclose(shown, 100 * np.asarray(expected), atol=0.051)


def test_title_inputs_version_and_force_units(engine_report: tuple[api.IdentifyResult, str]) -> None:
    _, html = engine_report
    assert "<h1>engine block, 12 single-axis accelerometers" in html  # the layout's name
    assert "input: layout.json, modes.csv" in html
    assert re.search(r"rigidid \S+ · \d{4}-\d\d-\d\d \d\d:\d\d UTC", html)
    assert "x-z block [N/mm], coupling blocks [N/rad], rx-rz block [N mm/rad]" in html
    # the body's first mount: 180000 kg/s^2 along x is 180 N/mm
    assert "180/160/420 N/mm" in html


def test_triaxial_sensors_share_one_label() -> None:
    pos = np.array([[0.0, 0, 0], [0, 0, 0], [0, 0, 0], [100, 0, 0]])
    labels = _sensor_labels(pos, ["A+x", "A+y", "A+z", "B"], 100.0)
    assert [text for _, text in labels] == ["A+x/A+y/A+z", "B"]


def test_summed_spectrum_peaks_at_the_records_frequency() -> None:
    dt = 1.0 / 256.0
    t = np.arange(4096) * dt
    one = np.column_stack([np.sin(2 * np.pi * 12.5 * t), 0.5 * np.sin(2 * np.pi * 12.5 * t + 1.0)])
    two = np.column_stack([np.sin(2 * np.pi * 40.0 * t), np.zeros_like(t)])
    f, p = summed_spectrum([one, two], dt, segment=1024)
    assert f[-1] == pytest.approx(128.0)
    peaks = f[np.argsort(-p)[:2]]
    assert sorted(np.round(peaks, 1)) == [12.5, 40.0]
