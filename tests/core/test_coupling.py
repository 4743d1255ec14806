"""The unstated AC coupling's score test against least squares on the whole design, and its null."""

from __future__ import annotations

import numpy as np

from rigidid.core.timedomain.coupling import coupling_score, coupling_statistic


def _case(rng: np.random.Generator, n: int = 400, p: int = 5, k: int = 3) -> tuple:
    t = np.linspace(0.0, 8.0, n)
    lam = -0.03 * np.arange(1, k + 1) + 1j * np.arange(1, k + 1)
    ex = np.exp(np.outer(t, lam))
    shapes = rng.standard_normal((p, k)) + 1j * rng.standard_normal((p, k))
    local = np.column_stack([np.ones(n), t / t[-1], np.cos(2.3 * t)])
    return t, ex, shapes, local


def _design(ex: np.ndarray, shapes: np.ndarray, local: np.ndarray) -> np.ndarray:
    """The linear columns written out: modal [Re, -Im] of e_k phi_k, then each channel's own local columns."""
    n, p = ex.shape[0], shapes.shape[0]
    u = ex[:, None, :] * shapes[None]
    modal = np.concatenate([u.real, -u.imag], axis=2).reshape(n * p, -1)
    own = np.einsum("nq,cd->ncdq", local, np.eye(p)).reshape(n * p, -1)
    return np.hstack([modal, own])


def test_statistic_is_the_drop_in_residual_of_the_written_out_design() -> None:
    # T(a) s2 is the residual sum of squares the columns e^{-a t} per channel take out of the residual
    # orthogonal to the design: least squares on the whole written-out design, an independent route
    rng = np.random.default_rng(0)
    t, ex, shapes, local = _case(rng)
    n, p = ex.shape[0], shapes.shape[0]
    design = _design(ex, shapes, local)
    y = rng.standard_normal(n * p) + 0.3 * np.repeat(np.exp(-0.7 * t), p) * np.tile(rng.standard_normal(p), n)
    r = y - design @ np.linalg.lstsq(design, y, rcond=None)[0]
    rates = np.array([0.2, 0.7, 2.0])
    stat, dof = coupling_statistic([r.reshape(n, p)], [t], [ex], [local], shapes, rates)
    for a, s, d in zip(rates, stat, dof, strict=True):
        z = np.einsum("n,cd->ncd", np.exp(-a * t), np.eye(p)).reshape(n * p, p)
        both = np.hstack([design, z])
        left = y - both @ np.linalg.lstsq(both, y, rcond=None)[0]
        assert abs(s - (r @ r - left @ left)) < 1e-9 * (r @ r)
        assert d == p


def test_with_the_tangent_it_is_the_drop_of_a_design_that_holds_the_parameters_too() -> None:
    # two impacts sharing m parameters: their Jacobian columns span both impacts' rows, projected off each
    # impact's linear columns (as the refit's), and joined to the written-out design
    rng = np.random.default_rng(4)
    t, ex, shapes, local = _case(rng)
    n, p, m = ex.shape[0], shapes.shape[0], 4
    one = _design(ex, shapes, local)
    design = np.block([[one, np.zeros_like(one)], [np.zeros_like(one), one]])
    jac = rng.standard_normal((2 * n * p, m))
    jac -= design @ np.linalg.lstsq(design, jac, rcond=None)[0]
    full = np.hstack([design, jac])
    y = rng.standard_normal(2 * n * p)
    r = y - full @ np.linalg.lstsq(full, y, rcond=None)[0]
    rates = np.array([0.3, 1.1])
    halves = [r[: n * p].reshape(n, p), r[n * p :].reshape(n, p)]
    tangent = [jac[: n * p].reshape(n, p, m), jac[n * p :].reshape(n, p, m)]
    stat, dof = coupling_statistic(halves, [t, t], [ex, ex], [local, local], shapes, rates, tangent)
    for a, s, d in zip(rates, stat, dof, strict=True):
        z = np.einsum("n,cd->ncd", np.exp(-a * t), np.eye(p)).reshape(n * p, p)
        zz = np.block([[z, np.zeros_like(z)], [np.zeros_like(z), z]])
        both = np.hstack([full, zz])
        left = y - both @ np.linalg.lstsq(both, y, rcond=None)[0]
        assert abs(s - (r @ r - left @ left)) < 1e-9 * (r @ r)
        assert d == 2 * p


def test_null_p_values_and_a_transient_found_at_its_rate() -> None:
    # pure noise: the Bonferroni p-value is conservative (under the null most draws read p = 1);
    # a transient at rate 0.7 is found there within its standard error
    rng = np.random.default_rng(1)
    t, ex, shapes, local = _case(rng, n=600)
    n, p = ex.shape[0], shapes.shape[0]
    design = _design(ex, shapes, local)
    hat = np.linalg.pinv(design)
    flagged = 0
    for _ in range(40):
        y = rng.standard_normal(n * p)
        r = (y - design @ (hat @ y)).reshape(n, p)
        score = coupling_score([r], [t], [ex], [local], shapes, variance=1.0, rate_range=(0.05, 5.0), hz_per_rate=1.0)
        assert score is not None
        flagged += score.flagged
    assert flagged == 0  # false-alarm rate 1e-9, Bonferroni over the grid
    inside = 0
    for _ in range(30):  # a transient at rate 0.7: found, its corner within 1.96 standard errors 0.95 of the time
        y = rng.standard_normal(n * p) + 3.0 * np.outer(np.exp(-0.7 * t), rng.standard_normal(p)).reshape(-1)
        r = (y - design @ (hat @ y)).reshape(n, p)
        score = coupling_score([r], [t], [ex], [local], shapes, variance=1.0, rate_range=(0.05, 5.0), hz_per_rate=1.0)
        assert score is not None and score.flagged and score.p_value < 1e-6
        inside += abs(score.corner_hz - 0.7) < 1.96 * score.corner_std_hz
    assert inside >= 24  # 60 draws: 0.95, every one flagged
    # a misfit decaying faster than any rate tried (largest at the decay's start, as sensor errors leave): the
    # statistic is large but peaks at the grid's end, which is not a coupling
    y = rng.standard_normal(n * p) + 2.0 * np.outer(np.exp(-20.0 * t), rng.standard_normal(p)).reshape(-1)
    r = (y - design @ (hat @ y)).reshape(n, p)
    score = coupling_score([r], [t], [ex], [local], shapes, variance=1.0, rate_range=(0.05, 5.0), hz_per_rate=1.0)
    assert score is not None and score.p_value < 1e-6 and not score.interior and not score.flagged
