"""Records scaled by 1e300 or 1e-300 give the body of the unscaled records (issue 24: a neutral change)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rigidid import api

from .conftest import SAMPLES

ENGINE = SAMPLES / "engine-test"
NEUTRAL_REL = 1e-9  # observed 1e-12 (a factor that is not a power of two rounds every value once)


def _hits(folder: Path, scale: float) -> list[Path]:
    paths = []
    for name in ("hit1", "hit2"):
        z = np.load(ENGINE / f"{name}.npz")
        paths.append(folder / f"{name}-{scale:g}.npz")
        np.savez(paths[-1], data=z["data"] * scale, channels=z["channels"], dt=z["dt"])
    return paths


def _bodies(paths: list[Path]) -> dict[str, np.ndarray]:
    """CG and inertia per mass: from the modes of the records streamed, of the records whole, and refitted on
    the files read whole and in row blocks."""
    layout = api.load_layout(ENGINE / "layout.json")
    modes, estimate = api.estimate_rigid_modes(layout, paths)
    start = api.identify(layout, modes)
    arrays = api.load_records(paths, layout)
    whole_modes, _ = api.estimate_rigid_modes(layout, arrays)
    found = {"modes": start, "modes of arrays": api.identify(layout, whole_modes)}
    for name, above in (("refit whole", 10**12), ("refit in blocks", 0)):
        found[name] = api.refine_records(start, paths, layout, estimate, stream_above=above)
    return {
        f"{route} {figure}": getattr(result.identification, figure)
        for route, result in found.items()
        for figure in ("center_of_gravity", "inertia_per_mass")
    }


@pytest.mark.parametrize("scale", [1e300, 1e-300])
def test_records_scaled_by_a_huge_or_tiny_factor_give_the_same_body(tmp_path: Path, scale: float) -> None:
    plain, scaled = _bodies(_hits(tmp_path, 1.0)), _bodies(_hits(tmp_path, scale))
    for name, value in plain.items():
        np.testing.assert_allclose(scaled[name], value, rtol=0.0, atol=NEUTRAL_REL * np.abs(value).max(), err_msg=name)
