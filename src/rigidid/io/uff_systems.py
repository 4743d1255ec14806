"""UFF coordinate systems (datasets 18 and 2420) and their use on nodes and directions.

A UFF node has a *definition* system (dataset 15 gives its coordinates in
it; dataset 2411 gives them in the part, that is global, system, its field
2 being only the system the node was exported in) and a *displacement*
system (its measured directions, 58 ``rsp_dir`` and 55
vector components, are along that system's axes). System 0 is the global
system. Only cartesian systems are supported: a cylindrical or spherical
system is kept as a reason, and using it for a node is an error naming the
system and the node.

Conventions
-----------
Dataset 18 (method 1)
    Origin, a point on the +x axis and a point in the +xz plane, all in the
    reference system (``ref_cs_num``, 0 = global; references are followed).
    x = (x point - origin) normalised; z = the part of (xz point - origin)
    normal to x, normalised; y = z cross x. The points carry 6 significant
    digits (``1P6E13.5``).
Dataset 2420
    A 4 x 3 matrix: rows 1-3 are the system's x, y, z axes as unit vectors
    in global axes, row 4 its origin in global axes (``1P3D25.16``: full
    double precision).
System 1 when no dataset defines it
    The global system: I-DEAS and the exporters that follow it number the
    global system 1 (ArtemiS, permas4edu and other exports give every node
    definition system 1 and no dataset 18 or 2420). A defined system 1
    (Test.Lab writes one per node) is used as defined.
A node's global position is ``origin + R @ local`` and a measured direction
``+a`` (a = x, y, z) of a node is the column ``R[:, a]``, where the columns
of ``R`` are the system's axes in global axes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["CoordinateSystemError", "CoordinateSystems"]

Array = NDArray[np.float64]

_TYPES = {0: "cartesian", 1: "cylindrical", 2: "spherical"}
_ORTHONORMAL_TOL = 1e-6


class CoordinateSystemError(ValueError):
    """A coordinate system that cannot be built or used; ``where`` names the dataset."""

    def __init__(self, message: str, where: str) -> None:
        super().__init__(message)
        self.where = where


@dataclass
class CoordinateSystems:
    """Coordinate systems of one test, by number (0 = global)."""

    rotation: dict[int, Array] = field(default_factory=dict)
    origin: dict[int, Array] = field(default_factory=dict)
    where: dict[int, str] = field(default_factory=dict)
    unusable: dict[int, str] = field(default_factory=dict)
    _pending: dict[int, tuple[int, Array, Array, str]] = field(default_factory=dict)

    def _define(self, num: int, where: str) -> None:
        if num == 0:
            raise CoordinateSystemError("coordinate system 0 is the global system and cannot be redefined", where)
        if num in self.where:
            raise CoordinateSystemError(f"coordinate system {num} is defined twice (also {self.where[num]})", where)
        self.where[num] = where

    def add_18(self, dset: dict[str, Any], where: str) -> None:
        """Take the systems of a dataset 18 (origin, +x point, +xz point in a reference system)."""
        nums = [int(n) for n in np.asarray(dset.get("cs_num", []), dtype=int).reshape(-1)]
        kinds = np.asarray(dset.get("cs_type", []), dtype=int).reshape(-1)
        refs = np.asarray(dset.get("ref_cs_num", []), dtype=int).reshape(-1)
        methods = np.asarray(dset.get("method", []), dtype=int).reshape(-1)
        o = np.asarray(dset.get("ref_o", []), dtype=float).reshape(-1, 3)
        xp = np.asarray(dset.get("x_point", []), dtype=float).reshape(-1, 3)
        xzp = np.asarray(dset.get("xz_point", []), dtype=float).reshape(-1, 3)
        n = len(nums)
        if not all(a.shape[0] == n for a in (kinds, refs, methods, o, xp, xzp)):
            raise CoordinateSystemError("the coordinate system records are incomplete", where)
        for i, num in enumerate(nums):
            here = f"{where}, coordinate system {num}"
            self._define(num, here)
            kind = int(kinds[i])
            if kind != 0:
                self.unusable[num] = (
                    f"coordinate system {num} ({here}) is {_TYPES.get(kind, f'of type {kind}')}; "
                    "only cartesian coordinate systems are supported"
                )
                continue
            if int(methods[i]) != 1:
                self.unusable[num] = (
                    f"coordinate system {num} ({here}) uses definition method {int(methods[i])}; "
                    "only method 1 (origin, +x axis point, +xz plane point) is supported"
                )
                continue
            if not (np.all(np.isfinite(o[i])) and np.all(np.isfinite(xp[i])) and np.all(np.isfinite(xzp[i]))):
                raise CoordinateSystemError(f"coordinate system {num} has non-finite points", here)
            self._pending[num] = (int(refs[i]), _axes_from_points(o[i], xp[i], xzp[i], here), o[i].copy(), here)

    def add_2420(self, dset: dict[str, Any], where: str) -> None:
        """Take the systems of a dataset 2420 (rows 1-3: axes in global axes, row 4: origin)."""
        nums = [int(n) for n in dset.get("CS_sys_labels", [])]
        kinds = [int(k) for k in dset.get("CS_types", [])]
        mats = [np.asarray(m, dtype=float) for m in dset.get("CS_matrices", [])]
        if not (len(kinds) == len(mats) == len(nums)):
            raise CoordinateSystemError("the coordinate system records are incomplete", where)
        for num, kind, m in zip(nums, kinds, mats, strict=True):
            here = f"{where}, coordinate system {num}"
            self._define(num, here)
            if kind != 0:
                self.unusable[num] = (
                    f"coordinate system {num} ({here}) is {_TYPES.get(kind, f'of type {kind}')}; "
                    "only cartesian coordinate systems are supported"
                )
                continue
            if m.shape != (4, 3) or not np.all(np.isfinite(m)):
                raise CoordinateSystemError(
                    f"coordinate system {num}: the transformation matrix is not 4 x 3 finite", here
                )
            r = m[:3].T.copy()
            err = float(np.max(np.abs(r.T @ r - np.eye(3))))
            if err > _ORTHONORMAL_TOL or np.linalg.det(r) < 0.0:
                raise CoordinateSystemError(
                    f"coordinate system {num}: rows 1-3 of the matrix are not a right-handed set of unit axes "
                    f"(orthonormality error {err:.3g})",
                    here,
                )
            self.rotation[num] = r
            self.origin[num] = m[3].copy()

    def resolve(self) -> None:
        """Express every dataset 18 system in global axes (following reference systems)."""
        for num in list(self._pending):
            self._resolve(num, [])

    def _resolve(self, num: int, chain: list[int]) -> None:
        if num not in self._pending:
            return
        ref, r_local, o_local, here = self._pending[num]
        if num in chain:
            raise CoordinateSystemError(f"coordinate systems refer to each other in a loop: {[*chain, num]}", here)
        if ref != 0:
            if ref in self._pending:
                self._resolve(ref, [*chain, num])
            if ref in self.unusable:
                self.unusable[num] = (
                    f"coordinate system {num} ({here}) is defined in an unusable system: " + (self.unusable[ref])
                )
                del self._pending[num]
                return
            if ref not in self.rotation:
                raise CoordinateSystemError(f"reference coordinate system {ref} of system {num} is not defined", here)
            r_ref, o_ref = self.rotation[ref], self.origin[ref]
            self.rotation[num] = r_ref @ r_local
            self.origin[num] = o_ref + r_ref @ o_local
        else:
            self.rotation[num] = r_local
            self.origin[num] = o_local
        del self._pending[num]

    def is_global(self, num: int) -> bool:
        """System 0, or system 1 when no dataset defines it (I-DEAS numbers its global system 1)."""
        return num == 0 or (num == 1 and 1 not in self.where)

    def check(self, num: int, what: str) -> str | None:
        """Why system `num` cannot be used for `what` (``"node 3's position"``), or None."""
        if self.is_global(num) or num in self.rotation:
            return None
        if num in self.unusable:
            return f"{what}: {self.unusable[num]}"
        return f"{what}: coordinate system {num} is not defined (no dataset 18 or 2420 gives it)"

    def to_global(self, num: int, local: Array) -> Array:
        """Global coordinates of a point given in system `num` (must be usable)."""
        if self.is_global(num):
            return np.asarray(local, dtype=float)
        out: Array = self.origin[num] + self.rotation[num] @ np.asarray(local, dtype=float)
        return out

    def axis(self, num: int, code: int) -> Array:
        """Global unit vector of signed axis `code` (1..3, -1..-3) of system `num`."""
        sign = 1.0 if code > 0 else -1.0
        if self.is_global(num):
            e = np.zeros(3)
            e[abs(code) - 1] = sign
            return e
        return sign * self.rotation[num][:, abs(code) - 1]


def _axes_from_points(origin: Array, x_point: Array, xz_point: Array, where: str) -> Array:
    """Columns: unit x, y, z of a system given by its origin, a +x point and a +xz-plane point."""
    x = x_point - origin
    nx = float(np.linalg.norm(x))
    v = xz_point - origin
    scale = max(nx, float(np.linalg.norm(v)), 1e-300)
    if nx <= 1e-9 * scale or nx == 0.0:
        raise CoordinateSystemError("the +x axis point coincides with the origin", where)
    x = x / nx
    z = v - (v @ x) * x
    nz = float(np.linalg.norm(z))
    if nz <= 1e-9 * scale:
        raise CoordinateSystemError("the +xz plane point lies on the x axis", where)
    z = z / nz
    y = np.cross(z, x)
    return np.column_stack([x, y, z])
