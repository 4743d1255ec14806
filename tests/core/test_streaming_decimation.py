"""The streaming decimator gives the whole-record decimation, whatever the chunking."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rigidid.core.timedomain.preprocess import Decimator, decimate
from rigidid.errors import InputError

from ..tolerances import STREAMED_DECIMATION


@settings(max_examples=25, deadline=None)
@given(
    factor=st.integers(1, 9),
    rows=st.integers(300, 3000),
    cuts=st.lists(st.integers(0, 3000), max_size=6),
    seed=st.integers(0, 2**16),
)
def test_chunked_equals_whole(factor: int, rows: int, cuts: list[int], seed: int) -> None:
    x = np.random.default_rng(seed).standard_normal((rows, 3))
    edges = [0, *sorted(c for c in cuts if c < rows), rows]
    stream = Decimator(factor, 3)
    whole = decimate(x, factor) if rows // factor > 2 * 10 + 1 else None
    parts = [stream.push(x[a:b]) for a, b in itertools.pairwise(edges)]
    if whole is None:
        with pytest.raises(InputError, match="too short"):
            stream.finish()
        return
    parts.append(stream.finish())
    out = np.concatenate(parts)
    assert out.shape == whole.shape
    np.testing.assert_allclose(out, whole, rtol=0.0, atol=STREAMED_DECIMATION)


def test_carry_is_bounded() -> None:
    """The rows carried between chunks do not grow with the record."""
    stream = Decimator(50, 2)
    x = np.random.default_rng(1).standard_normal((20_000, 2))
    for _ in range(10):
        stream.push(x)
        assert stream._buffer.shape[0] <= (2 * 10 + 3) * 50
    assert stream.rows_in == 200_000
