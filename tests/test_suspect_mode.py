"""The refinement's fallback warning names a used mode that is not rigid-body motion (an elastic mode)."""

from __future__ import annotations

import dataclasses

import numpy as np

from rigidid.api.identification import suspect_mode as _suspect_mode
from rigidid.core.identify import identify
from rigidid.core.simulate import body_modes

from .bodies import random_body, random_layout


def _identification():  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(3)
    body = random_body(rng)
    pos, dirs = random_layout(rng, 12, centre=body.center_of_gravity)
    modes = body_modes(body, pos, dirs)
    return identify(pos, dirs, modes.poles, modes.shapes, mass=body.mass)


def test_an_elastic_looking_mode_is_named_with_its_frequency() -> None:
    ident = _identification()
    residual = np.full(6, 4e-4)
    residual[4] = 0.25
    suspect = dataclasses.replace(
        ident, diagnostics=dataclasses.replace(ident.diagnostics, rigid_fit_residual=residual)
    )
    text = _suspect_mode(suspect)
    assert f"{ident.frequency_hz[4]:.4g} Hz" in text
    assert "0.25" in text and "--n-modes 7" in text


def test_rigid_modes_add_nothing() -> None:
    ident = _identification()
    assert _suspect_mode(ident) == ""  # exact modes: residuals ~1e-15
    even = dataclasses.replace(
        ident, diagnostics=dataclasses.replace(ident.diagnostics, rigid_fit_residual=np.full(6, 0.2))
    )
    assert _suspect_mode(even) == ""
