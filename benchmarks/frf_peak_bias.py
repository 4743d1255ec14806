"""False alarms and power of the residues route's peak-shortfall test (issue 21, the H1-bias cell).

Run: ``OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/frf_peak_bias.py [--seeds 20]
[--cells default,zeta0.5%,...]``

Per cell of ``benchmarks/frf_regimes.py`` and seed: the statistic ``z`` of
:func:`rigidid.core.frfmodes.peak_shortfall` from the residues fitted with the true poles (refined,
as ``mass_from_residues`` does). Printed per cell: the largest ``|z|`` and the share above
:data:`rigidid.core.frfmodes.PEAK_SHORTFALL_Z` (false alarms on clean cells; the power on
``h1_bias*`` cells).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from frf_regimes import CELLS, draw, poles_of
from rigidid.core.frfmodes import PEAK_SHORTFALL_Z, residue_limit

CLEAN = "default,zeta0.5%,zeta10%,df0.05,df1,noise0.3%,noise3%,refs6,start0.7x"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--cells", default=CLEAN + ",h1_bias2%,h1_bias1%")
    a = ap.parse_args()
    for name in a.cells.split(","):
        cell = CELLS[name]
        zs = []
        for seed in range(a.seeds):
            rig, f, h = draw(cell, seed)
            zs.append(residue_limit(f, h, poles_of(rig)).peak_shortfall.z)  # type: ignore[union-attr]
        z = np.array(zs)
        print(
            f"{name:12s} {a.seeds} seeds: max |z| {np.max(np.abs(z)):.2f}, median {np.median(z):.2f}, "
            f"above {PEAK_SHORTFALL_Z:g}: {np.mean(np.abs(z) > PEAK_SHORTFALL_Z):.2f}",
            flush=True,
        )


if __name__ == "__main__":
    main()
