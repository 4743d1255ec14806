"""Time-domain modal estimation: modes from free-decay impact records (the paper's DDS step).

The entry point is :func:`estimate_modes`: records (samples by channels, one
per impact) in, :class:`ModalEstimate` out, by a vector AR model (the paper's
Data Dependent Systems approach) or the Eigensystem Realization Algorithm, both
driven by a stabilisation diagram. :func:`impulse_records` simulates records of
a rigid body on mounts. scipy is imported only inside the functions that need it.

References
----------
.. [1] "Determination of rigid body characteristics from time domain modal test
   data", Journal of Sound and Vibration, 1994.
"""

from __future__ import annotations

from rigidid.core.timedomain.estimate import DEFAULT_METHOD, METHODS, ModalEstimate, estimate_modes
from rigidid.core.timedomain.preprocess import Impact, find_impact, free_decay
from rigidid.core.timedomain.simulate import impulse_records, record_time
from rigidid.core.timedomain.stabilisation import Criteria, OrderPoles, mac_matrix

__all__ = [
    "DEFAULT_METHOD",
    "METHODS",
    "Criteria",
    "Impact",
    "ModalEstimate",
    "OrderPoles",
    "estimate_modes",
    "find_impact",
    "free_decay",
    "impulse_records",
    "mac_matrix",
    "record_time",
]
