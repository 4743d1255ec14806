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

_EXPORTS = {
    "identify": "rigidid.api",
    "simulate": "rigidid.api",
    "load_layout": "rigidid.api",
    "load_modes": "rigidid.api",
    "IdentifyResult": "rigidid.api",
    "result_to_dict": "rigidid.render",
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
    "RigididError",
    "RigididWarning",
    "__version__",
    "identify",
    "load_layout",
    "load_modes",
    "result_tables",
    "result_to_dict",
    "simulate",
]

if TYPE_CHECKING:
    from rigidid.api import IdentifyResult, identify, load_layout, load_modes, simulate
    from rigidid.errors import IdentificationError, InputError, RigididError, RigididWarning
    from rigidid.render import result_tables, result_to_dict


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'rigidid' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(__all__)
