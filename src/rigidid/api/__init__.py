"""The Python API: what the command line does, as functions a notebook can call.

One module per workflow; every public name is also reachable here, loaded on first use so
that the command line imports only the workflow it runs:

- :mod:`rigidid.api.load`: layout, modes, records, UFF and body files, the one unit check
- :mod:`rigidid.api.identification`: the modes route (mode choice, data and result checks)
- :mod:`rigidid.api.mounts`: per-mount rates, the torque roll axis and the mount model
- :mod:`rigidid.api.records`: modes from impact records and the output-error refit on them
  (:func:`identify_records` is what ``rigidid identify --records`` does)
- :mod:`rigidid.api.frf`: the FRF routes (modes from FRFs, mass line, simulated FRFs)
- :mod:`rigidid.api.planning`, :mod:`rigidid.api.simulation`, :mod:`rigidid.api.conversion`,
  :mod:`rigidid.api.reports`, :mod:`rigidid.api.comparison` (a result against a reference)

The result types live in :mod:`rigidid.results`, below the API and the presentation.

>>> import rigidid
>>> layout = rigidid.load_layout("samples/paper-1994/layout.json")  # doctest: +SKIP
>>> modes = rigidid.load_modes("samples/paper-1994/modes.csv", layout)  # doctest: +SKIP
>>> result = rigidid.identify(layout, modes)  # doctest: +SKIP
>>> result.identification.center_of_gravity  # doctest: +SKIP
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

# Where each public name lives.
_HOME = {
    "Arrays": "rigidid.results",
    "FrfData": "rigidid.results",
    "IdentifyResult": "rigidid.results",
    "MassLineResult": "rigidid.results",
    "MountModelFit": "rigidid.results",
    "Mounts": "rigidid.results",
    "PlanResult": "rigidid.results",
    "TestData": "rigidid.results",
    "body_from_file": "rigidid.api.load",
    "body_with_mounts": "rigidid.api.load",
    "load_arrays": "rigidid.api.load",
    "load_layout": "rigidid.api.load",
    "load_modes": "rigidid.api.load",
    "load_records": "rigidid.api.load",
    "load_uff": "rigidid.api.load",
    "identify": "rigidid.api.identification",
    "with_warnings": "rigidid.api.identification",
    "with_mounts": "rigidid.api.mounts",
    "estimate_modes": "rigidid.api.records",
    "estimate_rigid_modes": "rigidid.api.records",
    "estimate_records_modes": "rigidid.api.records",
    "fitted_layout": "rigidid.api.records",
    "identify_test": "rigidid.api.records",
    "load_test": "rigidid.api.load",
    "TestRun": "rigidid.results",
    "identify_records": "rigidid.api.records",
    "records_spectrum": "rigidid.api.records",
    "refine_records": "rigidid.api.records",
    "with_record_spread": "rigidid.api.records",
    "with_refinement": "rigidid.api.records",
    "STREAM_REFIT_VALUES": "rigidid.api.records",
    "fit_modes_frf": "rigidid.api.frf",
    "identify_massline": "rigidid.api.frf",
    "simulate_frf": "rigidid.api.frf",
    "plan": "rigidid.api.planning",
    "simulate": "rigidid.api.simulation",
    "simulate_records": "rigidid.api.simulation",
    "write_simulated_frf": "rigidid.api.simulation",
    "convert": "rigidid.api.conversion",
    "compare": "rigidid.api.comparison",
    "report": "rigidid.api.reports",
    "report_pngs": "rigidid.api.reports",
}

__all__ = [
    "STREAM_REFIT_VALUES",
    "Arrays",
    "FrfData",
    "IdentifyResult",
    "MassLineResult",
    "MountModelFit",
    "Mounts",
    "PlanResult",
    "TestData",
    "TestRun",
    "body_from_file",
    "body_with_mounts",
    "compare",
    "convert",
    "estimate_modes",
    "estimate_records_modes",
    "estimate_rigid_modes",
    "fit_modes_frf",
    "fitted_layout",
    "identify",
    "identify_massline",
    "identify_records",
    "identify_test",
    "load_arrays",
    "load_layout",
    "load_modes",
    "load_records",
    "load_test",
    "load_uff",
    "plan",
    "records_spectrum",
    "refine_records",
    "report",
    "report_pngs",
    "simulate",
    "simulate_frf",
    "simulate_records",
    "with_mounts",
    "with_record_spread",
    "with_refinement",
    "with_warnings",
    "write_simulated_frf",
]

if TYPE_CHECKING:
    from rigidid.api.comparison import compare
    from rigidid.api.conversion import convert
    from rigidid.api.frf import fit_modes_frf, identify_massline, simulate_frf
    from rigidid.api.identification import identify, with_warnings
    from rigidid.api.load import (
        body_from_file,
        body_with_mounts,
        load_arrays,
        load_layout,
        load_modes,
        load_records,
        load_test,
        load_uff,
    )
    from rigidid.api.mounts import with_mounts
    from rigidid.api.planning import plan
    from rigidid.api.records import (
        STREAM_REFIT_VALUES,
        estimate_modes,
        estimate_records_modes,
        estimate_rigid_modes,
        fitted_layout,
        identify_records,
        identify_test,
        records_spectrum,
        refine_records,
        with_record_spread,
        with_refinement,
    )
    from rigidid.api.reports import report, report_pngs
    from rigidid.api.simulation import simulate, simulate_records, write_simulated_frf
    from rigidid.results import (
        Arrays,
        FrfData,
        IdentifyResult,
        MassLineResult,
        MountModelFit,
        Mounts,
        PlanResult,
        TestData,
        TestRun,
    )


def __getattr__(name: str) -> Any:
    if name in _HOME:
        value = getattr(importlib.import_module(_HOME[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'rigidid.api' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
