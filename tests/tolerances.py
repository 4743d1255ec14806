"""Every numerical tolerance the tests use, in one place."""

EXACT_REL = 1e-8
"""Relative error allowed when recovering a body from exact simulated modes."""

PAPER_Q_ABS = 1.0
"""Largest allowed difference from any entry of the paper's printed Q matrix."""

GOLDEN_REL = 1e-6
"""Relative tolerance of golden (expected.json) comparisons."""

GOLDEN_ABS = 1e-9
"""Absolute floor of golden comparisons (entries that are zero in truth)."""
