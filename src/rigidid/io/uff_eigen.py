"""Unit and sign conventions of the complex eigenvalues of UFF dataset 55.

Exporters write the eigenvalue of a complex mode (analysis types 3 and 7)
in different conventions:

- the pole ``s = -zeta w + i w_d`` in rad/s (the common reading, and what
  rigidid writes);
- the same with the real part's sign flipped (``+zeta w``);
- the pole divided by 2 pi, so that the imaginary part is the damped
  frequency in Hz (e.g. the permas4edu example 019 export).

The file does not name its convention, so it is read from its own fields:

Sign
    Every real part <= 0: the pole as written. Every real part >= 0 (some
    > 0): the sign is flipped. Both signs in one file: an error naming a
    mode of each sign (a pole with Re > 0 among decaying modes is an
    unstable, not a physical, mode).
Unit
    Evidence, mode by mode: a frequency stated in an ID line (``f = 12.5
    Hz``, ``12.5 Hz``): ``|s| / f`` is 2 pi (rad/s) or 1 (Hz); modal A given
    as ``2 i w_d`` (purely imaginary; unit modal A scaling of many
    exporters): ``|A| / Im s`` is 2 (rad/s) or 4 pi (Hz). Evidence that
    contradicts itself is an error; no evidence leaves rad/s.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

__all__ = ["EigenConvention", "eigen_convention", "stated_frequency"]

_HZ = re.compile(r"(?<![\w.])([0-9]+(?:\.[0-9]*)?(?:[eEdD][+-]?[0-9]+)?)\s*hz\b", re.IGNORECASE)
_RATIO_TOL = 2e-3


@dataclass(frozen=True)
class EigenConvention:
    """How to turn a file's eigenvalue into a pole in rad/s: ``sign * scale * conj-to-upper(eig)``.

    Attributes
    ----------
    flip_sign : bool
        True when decaying modes are written with a positive real part.
    scale : float
        1 (rad/s) or 2 pi (eigenvalue in Hz).
    note : str
        Empty for the common convention, else what was read and why.
    """

    flip_sign: bool
    scale: float
    note: str

    def pole(self, eig: complex) -> complex:
        """The pole in rad/s (upper half plane, negative real part for decay)."""
        s = eig.conjugate() if eig.imag < 0 else eig
        s = complex(-s.real, s.imag) if self.flip_sign else s
        return s * self.scale


def stated_frequency(id_lines: Sequence[str]) -> float | None:
    """The first frequency in Hz stated in a dataset's ID lines (``f = 12.5 Hz``), or None."""
    for line in id_lines:
        m = _HZ.search(str(line))
        if m:
            try:
                value = float(m.group(1).replace("d", "e").replace("D", "E"))
            except ValueError:  # pragma: no cover - the pattern only matches numbers
                continue
            if math.isfinite(value) and value > 0.0:
                return value
    return None


def _close(ratio: float, target: float) -> bool:
    return math.isfinite(ratio) and abs(ratio / target - 1.0) <= _RATIO_TOL


def eigen_convention(
    modes: Sequence[tuple[str, complex, complex, float | None]],
) -> EigenConvention:
    """Read the convention of a file's complex eigenvalues from its own fields.

    Parameters
    ----------
    modes : sequence of (label, eigenvalue, modal_a, stated_hz)
        Per complex mode: a label for messages (``"dataset 55 #2, mode 3"``),
        the eigenvalue as written, modal A as written, the frequency stated
        in the ID lines (Hz) or None.

    Returns
    -------
    EigenConvention

    Raises
    ------
    ValueError
        Real parts of both signs; evidence for Hz and for rad/s at once.
    """
    upper = [(label, e.conjugate() if e.imag < 0 else e, a, f) for label, e, a, f in modes]
    positive = [label for label, e, _, _ in upper if e.real > 0.0]
    negative = [label for label, e, _, _ in upper if e.real < 0.0]
    if positive and negative:
        raise ValueError(
            f"eigenvalue real parts have both signs ({negative[0]}: negative, {positive[0]}: positive); "
            "decaying modes are written with one sign"
        )
    flip = bool(positive)
    hz: list[str] = []
    rad: list[str] = []
    for label, e, a, f in upper:
        if f is not None and abs(e) > 0.0:
            ratio = abs(e) / f
            if _close(ratio, 2.0 * math.pi):
                rad.append(f"{label}: |eigenvalue| / stated {f:.6g} Hz = 2 pi")
            elif _close(ratio, 1.0):
                hz.append(f"{label}: |eigenvalue| = stated {f:.6g} Hz")
        if e.imag > 0.0 and abs(a) > 0.0 and abs(a.real) <= 1e-6 * abs(a):
            ratio = abs(a) / e.imag
            if _close(ratio, 2.0):
                rad.append(f"{label}: modal A = 2i Im(eigenvalue)")
            elif _close(ratio, 4.0 * math.pi):
                hz.append(f"{label}: modal A = 4 pi i Im(eigenvalue)")
    if hz and rad:
        raise ValueError(f"eigenvalue units contradict: {hz[0]} (Hz) but {rad[0]} (rad/s)")
    notes = []
    if flip:
        notes.append(f"eigenvalues have a positive real part ({positive[0]}): read as +zeta*omega")
    if hz:
        notes.append(f"eigenvalues are in Hz ({hz[0]})")
    return EigenConvention(flip, 2.0 * math.pi if hz else 1.0, "; ".join(notes))
