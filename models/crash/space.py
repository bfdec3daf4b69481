"""The drivers' intents as a search space: one block of coordinates per vehicle.

Each vehicle's driver intent (:data:`.driver.INTENT`) is set within the ranges its script gives.
A range with two ends is a **coordinate** of the search, in the unit cube (0 = the low end);
a fixed value is set as it is; a behaviour the script leaves out is off (NaN). The coordinates
of one vehicle form its **block**, which the paper's crossover swaps whole between solutions.
``after_impact``, when the script lists several choices, is a coordinate too: [0, 1) cut into
equal parts.

When the script gives no aim point the driver aims 200 m straight ahead (or follows its
waypoints); the IDM leader and the waypoints are fixed by the script.

Compute only.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nbst.models.crash import driver as drv
from nbst.models.crash.script import AFTER_IMPACT, Range, Script

__all__ = ["STRAIGHT_AHEAD", "CrashSpace", "space_of"]

#: How far ahead (m) a driver without an aim point looks.
STRAIGHT_AHEAD = 200.0


@dataclass(frozen=True)
class CrashSpace:
    """The search space of a script: ``dim`` coordinates; ``blocks[i]`` the coordinates of vehicle
    i; ``base`` (n, len(INTENT)) the fixed values (NaN where off); ``coords`` [(vehicle, intent
    index, Range or choices)] per coordinate."""

    script: Script
    base: np.ndarray
    coords: tuple
    blocks: tuple

    @property
    def dim(self) -> int:
        return len(self.coords)

    @property
    def n(self) -> int:
        return self.script.n

    def intents(self, U) -> np.ndarray:
        """(B, n, len(INTENT)) intents of unit-cube points U (B, dim) (clipped into the cube)."""
        U = np.clip(np.atleast_2d(np.asarray(U, dtype=float)), 0.0, 1.0)
        out = np.repeat(self.base[None], len(U), axis=0)
        for k, (i, f, r) in enumerate(self.coords):
            if isinstance(r, Range):
                out[:, i, f] = r.lo + (r.hi - r.lo) * U[:, k]
            else:  # a choice among len(r)
                out[:, i, f] = [AFTER_IMPACT.index(r[min(int(u * len(r)), len(r) - 1)]) for u in U[:, k]]
        return out

    def unit_of(self, intents: np.ndarray) -> np.ndarray:
        """The unit-cube point (dim,) of one vehicle set's intents (n, len(INTENT)) (clipped)."""
        u = np.zeros(self.dim)
        for k, (i, f, r) in enumerate(self.coords):
            if isinstance(r, Range):
                u[k] = 0.5 if r.hi == r.lo else (intents[i, f] - r.lo) / (r.hi - r.lo)
            else:
                u[k] = (r.index(AFTER_IMPACT[int(intents[i, f])]) + 0.5) / len(r)
        return np.clip(u, 0.0, 1.0)

    def names(self) -> list[str]:
        """'vehicle.intent' of every coordinate."""
        return [f"{self.script.vehicles[i].name}.{drv.INTENT[f]}" for i, f, _ in self.coords]


def space_of(script: Script) -> CrashSpace:
    """The :class:`CrashSpace` of ``script`` (see the module docstring)."""
    n, P = script.n, len(drv.INTENT)
    base = np.full((n, P), np.nan)
    coords: list = []
    blocks: list = []
    IX = drv.IX
    for i, v in enumerate(script.vehicles):
        start = len(coords)
        d = v.driver

        def put(name, r: Range | None):
            if r is None:
                return
            if r.fixed:
                base[i, IX[name]] = r.lo
            else:
                coords.append((i, IX[name], r))

        put("speed", v.speed)
        if d.aim_x is not None:
            put("aim_x", d.aim_x)
            put("aim_y", d.aim_y)
        elif not d.waypoints:
            base[i, IX["aim_x"]] = v.x + STRAIGHT_AHEAD * math.cos(v.heading)
            base[i, IX["aim_y"]] = v.y + STRAIGHT_AHEAD * math.sin(v.heading)
        for name in ("arrive", "brake_at", "slide_at", "slide_steer", "slide_power", "headway", "reaction", "after_steer"):
            put(name, getattr(d, name))
        if len(d.after_impact) > 1:
            coords.append((i, IX["after"], tuple(d.after_impact)))
        else:
            base[i, IX["after"]] = AFTER_IMPACT.index(d.after_impact[0])
        blocks.append(tuple(range(start, len(coords))))
    return CrashSpace(script=script, base=base, coords=tuple(coords), blocks=tuple(blocks))
