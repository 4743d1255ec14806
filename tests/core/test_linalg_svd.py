"""The SVD that falls back to LAPACK's QR iteration when divide and conquer does not converge."""

from __future__ import annotations

import numpy as np
import pytest

from rigidid.core import linalg


def test_the_fallback_gives_the_same_decomposition(monkeypatch: pytest.MonkeyPatch) -> None:
    # numpy's gesdd failing (as on chain_matrix's "all" seed 1005, an R factor with singular values at 1e-46)
    # is hard to provoke on purpose: it is made to fail, and gesvd must give the same factors
    rng = np.random.default_rng(0)
    a = rng.standard_normal((9, 6)) @ np.diag([1.0, 1.0, 1e-3, 1e-9, 0.0, 0.0]) @ rng.standard_normal((6, 6))
    s0 = linalg.svd(a)[1]

    def diverges(*args, **kwargs):  # type: ignore[no-untyped-def]
        raise np.linalg.LinAlgError("SVD did not converge")

    monkeypatch.setattr(np.linalg, "svd", diverges)
    u, s, vt = linalg.svd(a)
    np.testing.assert_allclose(s, s0, atol=1e-12 * s0[0])
    np.testing.assert_allclose((u[:, :6] * s) @ vt, a, atol=1e-12 * s0[0])
    assert vt.shape == (6, 6) and u.shape == (9, 9)
