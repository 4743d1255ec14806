"""An AC coupling nobody stated, through the records API: named, modelled and written (issue 23).

The records are written afresh by scipy's matrix exponential (``core.test_sensor_refit._records``) and
passed through scipy.signal's bilinear first-order high-pass at 1 Hz.
"""

from __future__ import annotations

import numpy as np

from rigidid.errors import ChainWarning, RefinementWarning
from rigidid.io.files import load_layout
from rigidid.jsonout import record_bound_to_dict

from .conftest import refit_with_warnings
from .core.test_coupling_refit import CORNER, _high_pass
from .core.test_sensor_refit import RATE, SAMPLE, _records

INTERVAL_Z = 4.5  # CG and inertia errors in their reported std (observed 1.5; seeds 12-14 up to 2.8)


def test_the_records_route_names_models_and_writes_an_unstated_coupling() -> None:
    layout = load_layout(SAMPLE / "layout.json")
    p = len(layout.sensors)
    clean, body = _records(np.ones(p), np.zeros((p, 3)), np.random.default_rng(11))
    records = [(r, 1.0 / RATE) for r in _high_pass(clean)]
    result, caught = refit_with_warnings(layout, records)
    chain = [str(w.message) for w in caught if issubclass(w.category, ChainWarning)]
    assert len(chain) == 1 and "AC coupling nobody stated" in chain[0] and "highpass_hz" in chain[0], chain
    bound = result.record_bound
    assert bound is not None and bound.coupling is not None and bound.coupling.modelled
    assert abs(bound.coupling.corner_hz - CORNER) < 1.5 * bound.coupling.corner_std_hz  # observed 0.08-0.36 std
    written = record_bound_to_dict(bound)["ac_coupling"]
    assert written["modelled"] is True and written["corner_hz"] == bound.coupling.corner_hz
    cg = bound.center_of_gravity
    assert np.all(np.abs(cg.estimate - body.center_of_gravity) < INTERVAL_Z * cg.std)
    inertia = bound.inertia
    assert np.all(np.abs(inertia.estimate - body.inertia_tensor) <= INTERVAL_Z * inertia.std + 1e-12)


def test_left_unmodelled_on_request_it_is_still_named() -> None:
    layout = load_layout(SAMPLE / "layout.json")
    p = len(layout.sensors)
    clean, _ = _records(np.ones(p), np.zeros((p, 3)), np.random.default_rng(11))
    records = [(r, 1.0 / RATE) for r in _high_pass(clean)]
    result, caught = refit_with_warnings(layout, records, estimate_highpass=False)
    chain = [str(w.message) for w in caught if issubclass(w.category, ChainWarning)]
    assert len(chain) == 1 and "not modelled (--no-estimate-highpass)" in chain[0], chain
    # the 1 Hz transient left in, the refit's misfit test rejects it (18 times the noise): the modes' answer
    assert result.record_bound is None
    assert any(issubclass(w.category, RefinementWarning) and "times the pre-trigger" in str(w.message) for w in caught)
