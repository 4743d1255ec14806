"""The sensors' signatures off each impact's linear columns, against least squares on the written-out design."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from rigidid.core.timedomain.chain import ChainModel, ChannelChain
from rigidid.core.timedomain.preprocess import find_impact
from rigidid.core.timedomain.refine import _design, _impact_signatures, _link, _modes, _prepare, _started
from rigidid.io.files import layout_arrays, load_layout

from .test_sensor_refit import RATE, SAMPLE, _records, _truth


@pytest.mark.parametrize("case", ["plain", "drift", "high-pass on half the channels"])
def test_structured_projection_is_the_design_least_squares(case: str) -> None:
    # G~ = G - S (S^T S)^+ S^T G with S the whole design (modal columns, each channel's offset, drift and the
    # chain's transients, where the chain has them); the structured form never writes S out
    _, pos, dirs = layout_arrays(load_layout(SAMPLE / "layout.json"))
    p = pos.shape[0]
    records, body = _records(np.ones(p), np.zeros((p, 3)), np.random.default_rng(1))
    impacts = [find_impact(r, 1 / RATE) for r in records]
    data = _prepare(records, 1 / RATE, [i.start for i in impacts], [i.onset for i in impacts], 1)
    data = replace(data, drift=case == "drift")
    chain = None
    if case.startswith("high-pass"):
        chain = ChainModel(tuple(ChannelChain(highpass_hz=1.0 if c % 2 else 0.0) for c in range(p)))
    pos_l, frame, theta = _started(pos, dirs, _truth(body))
    link = _link(chain, frame.omega, p, False)
    lam, phi, *_ = _modes(theta, pos_l, dirs, False)
    if link is not None:
        phi = phi * link.transfer(theta, lam, p)[0]
    for y, (sig, off) in zip(
        data.decays, _impact_signatures(theta, data, pos_l, dirs, frame.omega, frame.scale, link), strict=True
    ):
        n = y.shape[0]
        t = np.arange(n) * data.dt * frame.omega
        design, _ = _design(lam, phi / data.sigma[:, None], t, data.drift, None if link is None else link.nuisance(t))
        g = (sig[:, None, :, :] * np.eye(p)[None, :, None, :]).reshape(n * p, 6 * p)
        gt = g - design @ np.linalg.lstsq(design, g, rcond=None)[0]
        scale = np.max(np.abs(gt))
        np.testing.assert_allclose(off.explicit(), gt, atol=1e-12 * scale, rtol=0)  # observed 8e-16
        np.testing.assert_allclose(off.gram(), gt.T @ gt, atol=1e-13 * scale**2 * n, rtol=0)  # observed 6e-17
