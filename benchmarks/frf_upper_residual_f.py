"""Null distribution of the exact support fit's upper-residual F test on mounted bodies (issue 21).

Run: ``OPENBLAS_NUM_THREADS=1 PYTHONPATH=src .venv/bin/python benchmarks/frf_upper_residual_f.py [--draws 200]
[--regime mounted]``

The bodies and noise of ``benchmarks/frf_coverage.py`` (``mounted``: a random body of ``frf_sim`` on four
mounts, no elastic mode, so no upper residual in the data; ``free``: free-free below an elastic mode, where
the residual is needed; ``near``: femtools' acceptance case 15). Each draw runs ``mass_line`` with its
automatic mount model and records, where the exact support fit weighs the upper residual
(``massline._residual_needed``), the statistic ``F`` of :func:`rigidid.core.massline.upper_residual_f`
and its effective degrees of freedom ``nu``. Prints: the draws tested, the mean and SD of ``F`` against the
SD ``chi2(nu) / nu`` predicts (RMS over draws) and against the ``sqrt(2 / k)`` of the test before
(``k = b 6 q`` coefficients); the share of draws beyond the 5 % and 0.1 % quantiles of ``chi2(nu)``; the
share the test before kept (``F > 1 + 3 sqrt(2 / k)``); the share the residual was kept (either rule of
``_residual_needed``: the F test or the cheap residual).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from frf_coverage import near, simulated
from rigidid.core import massline
from rigidid.core.chisquare import chi2_quantile
from rigidid.core.massline import upper_residual_f
from rigidid.errors import RigididError


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--draws", type=int, default=200)
    ap.add_argument("--regime", default="mounted", choices=("mounted", "free", "near"))
    a = ap.parse_args()
    seen: list[tuple[float, float, int, bool]] = []
    needed = massline._residual_needed

    def spy(plain: Any, full: Any, n_basis: int) -> bool:
        keep = needed(plain, full, n_basis)
        if plain.misfit_rows is not None and full.misfit_rows is not None:
            f_stat, nu = upper_residual_f(plain.misfit_rows, full.misfit_rows, n_basis)
            seen.append((f_stat, nu, n_basis * plain.misfit_rows.shape[0] // 2, keep))
        return keep

    massline._residual_needed = spy  # type: ignore[assignment]
    for seed in range(a.draws):
        _truth, data, band = near(seed) if a.regime == "near" else simulated(seed, a.regime == "free")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                massline.mass_line(*data, band=band)
            except RigididError:
                continue
    f, nu, k, kept = (np.array(c) for c in zip(*seen, strict=True))
    print(f"{a.regime}: {f.size} exact fits weighed the upper residual over {a.draws} draws")
    print(f"  F mean {f.mean():.3f}, SD {f.std():.3f}; chi2(nu)/nu predicts SD {np.sqrt(np.mean(2 / nu)):.3f}")
    print(f"  (nu {nu.min():.1f}-{nu.max():.1f}, median {np.median(nu):.1f}); the test before assumed SD")
    print(f"  sqrt(2 / k) = {np.sqrt(np.mean(2 / k)):.3f} (k = {int(k[0])})")
    z5, z01 = 1.6448536269514722, 3.090232306167813
    beyond5 = np.mean([fi * ni > chi2_quantile(ni, z5) for fi, ni in zip(f, nu, strict=True)])
    beyond01 = np.mean([fi * ni > chi2_quantile(ni, z01) for fi, ni in zip(f, nu, strict=True)])
    print(f"  beyond chi2(nu)'s 5 % quantile: {beyond5:.3f}; beyond its 0.1 % quantile (the test now): {beyond01:.3f}")
    print(f"  the test before (F > 1 + 3 sqrt(2 / k)) would keep: {np.mean(f > 1 + 3 * np.sqrt(2 / k)):.3f}")
    print(f"  kept (the F test now, or the cheap residual): {kept.mean():.3f}")


if __name__ == "__main__":
    main()
