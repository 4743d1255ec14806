"""rigidid: rigid-body properties (CG, inertia, mount stiffness and damping) from impact-test modes.

The public API is loaded on first use, so that ``import rigidid`` (and the
command line) start fast:

>>> import rigidid
>>> result = rigidid.identify("samples/paper-1994/layout.json", "samples/paper-1994/modes.csv")  # doctest: +SKIP
>>> result.identification.center_of_gravity  # doctest: +SKIP
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

# Names of __all__ that do not live in rigidid.api (the rest do).
_ELSEWHERE = {
    "result_to_dict": "rigidid.jsonout",
    "result_tables": "rigidid.render",
    "RigididError": "rigidid.errors",
    "InputError": "rigidid.errors",
    "IdentificationError": "rigidid.errors",
    "RigididWarning": "rigidid.errors",
}

__all__ = [
    "IdentificationError",
    "IdentifyResult",
    "InputError",
    "PlanResult",
    "RigididError",
    "RigididWarning",
    "TestData",
    "__version__",
    "convert",
    "estimate_modes",
    "identify",
    "load_arrays",
    "load_layout",
    "load_modes",
    "load_records",
    "load_uff",
    "plan",
    "report",
    "result_tables",
    "result_to_dict",
    "simulate",
    "simulate_records",
]

if TYPE_CHECKING:
    from rigidid.api import (
        IdentifyResult,
        PlanResult,
        TestData,
        convert,
        estimate_modes,
        identify,
        load_arrays,
        load_layout,
        load_modes,
        load_records,
        load_uff,
        plan,
        report,
        simulate,
        simulate_records,
    )
    from rigidid.errors import IdentificationError, InputError, RigididError, RigididWarning
    from rigidid.jsonout import result_to_dict
    from rigidid.render import result_tables


def __getattr__(name: str) -> Any:
    if name in __all__:
        value = getattr(importlib.import_module(_ELSEWHERE.get(name, "rigidid.api")), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'rigidid' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
