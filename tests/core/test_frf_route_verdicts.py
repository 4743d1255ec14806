"""Issue 21's regime matrix: the verdicts that keep an FRF route from being silently wrong."""

from __future__ import annotations

import numpy as np
import pytest

from rigidid.core.frfmodes import PEAK_SHORTFALL_Z, residue_limit, summed_power
from rigidid.core.massline import MassLine, peak_notice
from rigidid.core.simulate import body_modes
from rigidid.errors import FrfPeakBiasWarning
from tests.bodies import frf_test_on_mounts


def _mounted(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A body on mounts (issue 12's test) up to 80 Hz at 0.5 Hz, 1 % noise, and its six true poles."""
    rng = np.random.default_rng(seed)
    body, pos, dirs, _, _, f, h = frf_test_on_mounts(rng)
    keep = f < 80.0
    return f[keep][::4], h[:, :, keep][:, :, ::4], body_modes(body, pos, dirs).poles


@pytest.mark.parametrize("seed", [0, 1])
def test_an_h1_shortfall_at_the_peaks_is_seen_though_the_misfit_hides_it(seed: int) -> None:
    """2 % short at the highest peak (in proportion to the summed power): 9-15 standard errors on six
    seeds, while clean FRFs stay within 1.4; the misfit of both is about 1 noise unit."""
    f, h, poles = _mounted(seed)
    clean = residue_limit(f, h, poles, refine=False)
    g = summed_power(h)
    biased = residue_limit(f, h * (1.0 - 0.02 * g / g.max()), poles, refine=False)
    assert clean.peak_shortfall is not None and biased.peak_shortfall is not None
    assert abs(clean.peak_shortfall.z) < PEAK_SHORTFALL_Z / 2.0
    assert biased.peak_shortfall.z > 2.0 * PEAK_SHORTFALL_Z
    assert biased.misfit_units < 1.5  # the misfit alone would not tell


def test_the_peak_shortfall_warning_names_what_and_where() -> None:
    f, h, poles = _mounted(0)
    g = summed_power(h)
    fit = residue_limit(f, h * (1.0 - 0.02 * g / g.max()), poles, refine=False)
    result = MassLine(
        1.0, np.zeros(3), np.eye(3), (f[0], f[-1]), "given", f.size, 0.01, (), peak_shortfall=fit.peak_shortfall
    )
    notice = peak_notice(result, "residues")
    assert notice is not None and notice.category is FrfPeakBiasWarning
    assert "fall short of the residues fit at the resonance peaks" in notice.message
    assert f"{fit.peak_shortfall.frequency:.4g} Hz" in notice.message and "H1" in notice.message
    assert "\n" not in notice.message
    clean = residue_limit(f, h, poles, refine=False)
    assert (
        peak_notice(
            MassLine(
                1.0, np.zeros(3), np.eye(3), (1.0, 2.0), "given", 1, 0.01, (), peak_shortfall=clean.peak_shortfall
            ),
            "residues",
        )
        is None
    )
