"""Unused (elastic) modes subtracted from the records before the refit (core/timedomain/nuisance.py)."""

from __future__ import annotations

import numpy as np
import pytest

from rigidid.core.timedomain.nuisance import BLOCK_ROWS, subtract_modes

POLES = np.array([-0.4 + 2j * np.pi * 5.0, -0.9 + 2j * np.pi * 9.0, -1.5 + 2j * np.pi * 17.0])


def _records(rng: np.random.Generator, n: int, start: int) -> tuple[np.ndarray, np.ndarray]:
    """Three modes of random complex amplitude on 4 channels from `start` on, an offset; and the first two alone."""
    t = np.arange(n - start) / 100.0
    amp = rng.standard_normal((3, 4)) + 1j * rng.standard_normal((3, 4))
    parts = [np.real(np.exp(POLES[k] * t)[:, None] * amp[k]) for k in range(3)]
    kept = np.zeros((n, 4))
    kept[start:] = parts[0] + parts[1]
    offset = rng.standard_normal(4)
    full = kept.copy()
    full[start:] += parts[2]
    return full + offset, kept + offset


@pytest.mark.parametrize("n", [3000, BLOCK_ROWS + 5000])  # one block, and the normal equations over two
def test_the_removed_mode_is_gone_and_the_rest_untouched(n: int) -> None:
    rng = np.random.default_rng(4)
    full, kept = _records(rng, n, start=40)
    out = subtract_modes([full], 0.01, [40], POLES, [False, False, True])[0]
    np.testing.assert_allclose(out, kept, atol=1e-9)
    np.testing.assert_array_equal(out[:40], full[:40])  # before the free decay: nothing changes
    assert not np.shares_memory(out, full)


def test_nothing_removed_returns_equal_copies() -> None:
    full, _ = _records(np.random.default_rng(1), 500, start=10)
    out = subtract_modes([full], 0.01, [10], POLES, [False, False, False])[0]
    np.testing.assert_array_equal(out, full)


def test_noise_is_left_and_the_mode_goes() -> None:
    rng = np.random.default_rng(2)
    full, kept = _records(rng, 4000, start=0)
    noise = 0.01 * rng.standard_normal(full.shape)
    out = subtract_modes([full + noise], 0.01, [0], POLES, [False, False, True])[0]
    # what remains of the removed mode is the noise's projection onto 7 columns of 4000 rows
    assert np.std(out - kept - noise) < 0.01 * np.sqrt(8 / 4000) * 3


def test_mask_must_match_the_poles() -> None:
    with pytest.raises(ValueError, match="remove has 2 entries for 3 poles"):
        subtract_modes([np.zeros((100, 2))], 0.01, [0], POLES, [True, False])
