"""Judge a recorded rollout against the fates: per fate met or not with a graded cost, the signature.

A :class:`Recording` is what a rollout leaves (``nbst.scene.rollout`` makes one): the positions of
the fated bodies' origins at every recorded time, their final orientation and velocities, and the
first time each touched each name its ``hits``/``never_hits`` list. :func:`judge` turns it into a
:class:`Judgement`: each fate met or not with a **cost** (0 when met, graded otherwise, so that a
search can tell near from far), one **signature** bit per body with fates (set when all of its fates
are met, as in the paper), and the total cost.

The costs (metres and radians, 1 rad counting as 1 m; a contact count as 1 m):

* ``rest_in``: the final position's distance to the region;
* ``at``: the sum, over the times asked, of the distance to the region at the recorded time nearest t;
* ``through``: the regions are passed in order (a region passed at the first recorded time inside it,
  the next looked for from then on); the cost sums, for each region not passed, the trajectory's
  nearest approach to it after the last region passed;
* ``up``: the angle (rad) by which the body-frame axis misses world +z beyond ``within_deg``;
* ``hits``: 1 per name never touched plus 1 per pair of first touches out of order, plus, per name
  never touched whose nearness was recorded, how near it came: the least gap over the run over
  the gap at the start (0 to 1; the rollout's ``closest_approach``) times :data:`HITS_NEAR`, so
  that a near miss costs less than a far one;
* ``never_hits``: 1 per name touched;
* ``at_rest``: the final speed above :data:`~nbst.scene.fates.AT_REST_SPEED` plus 0.1 s times the
  final spin above :data:`~nbst.scene.fates.AT_REST_SPIN`;
* ``still``: the farthest the origin went from its start, beyond :data:`~nbst.scene.fates.STILL_DISTANCE`.

Pure numpy: no MuJoCo, no files.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from nbst.scene.fates import AT_REST_SPEED, AT_REST_SPIN, STILL_DISTANCE, Fate, Fates

__all__ = ["HITS_NEAR", "Recording", "FateVerdict", "BodyVerdict", "Judgement", "judge", "judge_body", "length_text", "rotate",
           "signature_text"]


#: The weight of a ``hits`` name's nearness (its least gap over its gap at the start, 0 to 1) in the
#: cost of a name never touched (0: 1 per name, flat, however near it came).
HITS_NEAR = 1.0


def length_text(v: float) -> str:
    """A length (m) or coordinate in words: four significant digits, so that a millimetre scene reads as well
    as a metre one (``0.0165``, not ``0.017``; ``1.864``), and from 1 m on to the millimetre, never in
    powers of ten (``1000.234``, not ``1000``; ``12000``, not ``1.2e+04``); below 1 nm, ``0`` (rounding
    noise)."""
    v = float(v)
    if abs(v) < 1e-9:
        return "0"
    return np.format_float_positional(round(v, 3), trim="-") if abs(v) >= 1.0 else f"{v:.4g}"


@dataclass(frozen=True)
class Recording:
    """What one rollout leaves for the judge (B fated bodies, in the fates' order; T steps recorded).

    Args:
        times: (T+1,) the recorded times (s), 0 first.
        pos: (T+1, B, 3) world positions of the bodies' origins at those times.
        quat: (B, 4) final orientations, unit quaternions (w, x, y, z), body to world.
        linvel: (B, 3) final world linear velocities of the origins (m/s).
        angvel: (B, 3) final world angular velocities (rad/s).
        touches: per body, ``{name: time of its first touch}`` for the names of its ``hits`` and
            ``never_hits`` that it touched.
        near: per body, ``{name: (least gap, gap at the start)}`` (m) for names of its ``hits``
            (those whose nearness the rollout records; () or a missing name: not graded).
    """

    times: np.ndarray
    pos: np.ndarray
    quat: np.ndarray
    linvel: np.ndarray
    angvel: np.ndarray
    touches: tuple[dict[str, float], ...]
    near: tuple[dict[str, tuple[float, float]], ...] = ()


@dataclass(frozen=True)
class FateVerdict:
    """One fate of one body: ``met``, its ``cost`` (0 when met) and what happened, in words."""

    fate: str
    met: bool
    cost: float
    happened: str


@dataclass(frozen=True)
class BodyVerdict:
    """One body's fates: met when all are (its signature bit); cost their sum."""

    body: str
    met: bool
    cost: float
    fates: tuple[FateVerdict, ...]


@dataclass(frozen=True)
class Judgement:
    """A rollout judged: one :class:`BodyVerdict` per body with fates; ``signature`` one bit each."""

    bodies: tuple[BodyVerdict, ...]

    @property
    def signature(self) -> tuple[bool, ...]:
        return tuple(b.met for b in self.bodies)

    @property
    def cost(self) -> float:
        return float(sum(b.cost for b in self.bodies))

    @property
    def met(self) -> bool:
        return all(self.signature)

    @property
    def order(self) -> int:
        """The number of bits set (the paper's *order*)."""
        return sum(self.signature)

    def to_dict(self) -> dict:
        return {"met": self.met, "signature": signature_text(self.signature), "cost": self.cost,
                "bodies": {b.body: {"met": b.met, "cost": b.cost,
                                    "fates": {f.fate: {"met": f.met, "cost": f.cost, "happened": f.happened}
                                              for f in b.fates}} for b in self.bodies}}


def signature_text(sig: tuple[bool, ...]) -> str:
    """The signature as bits, the first body first: ``"101"``."""
    return "".join("1" if b else "0" for b in sig)


def rotate(quat: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``v`` (3,) turned by the unit quaternion ``quat`` (4,) (w, x, y, z): R(q) v."""
    w, x, y, z = (float(a) for a in quat)
    r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                  [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                  [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    return np.asarray(r @ np.asarray(v, dtype=float))


def _through(fate: Fate, path: np.ndarray) -> FateVerdict:
    k0, passed = 0, 0
    for r in fate.through:
        inside = np.flatnonzero(r.distance(path[k0:]) == 0.0)
        if not len(inside):
            break
        k0 += int(inside[0])
        passed += 1
    cost = 0.0
    for r in fate.through[passed:]:
        cost += float(r.distance(path[k0:]).min())
    n = len(fate.through)
    return FateVerdict("through", passed == n, cost, f"passed {passed} of {n} in order")


def _hits(fate: Fate, touches: dict[str, float], near: dict[str, tuple[float, float]]) -> FateVerdict:
    got = [touches.get(n) for n in fate.hits]
    missing = sum(t is None for t in got)
    # a name never touched: how near it came, the least gap over the gap at the start (0 to 1)
    nearness = sum(near[n][0] / near[n][1] for n, t in zip(fate.hits, got) if t is None and n in near
                   and near[n][1] > 0)
    times = [t for t in got if t is not None]
    inversions = sum(1 for i in range(len(times)) for j in range(i + 1, len(times)) if times[j] < times[i])
    order = sorted((t, n) for n, t in zip(fate.hits, got) if t is not None)
    said = ", ".join(f"{n} at {t:.3f} s" for t, n in order) or "none"
    return FateVerdict("hits", missing == 0 and inversions == 0, float(missing + inversions + HITS_NEAR * nearness),
                       f"first touches: {said}")


def judge_body(fate: Fate, times: np.ndarray, path: np.ndarray, quat: np.ndarray, linvel: np.ndarray,
               angvel: np.ndarray, touches: dict[str, float],
               near: dict[str, tuple[float, float]] | None = None) -> BodyVerdict:
    """Judge one body's fates from its own record (``path``: (T+1, 3); the rest as in :class:`Recording`)."""
    out: list[FateVerdict] = []
    end = path[-1]
    if fate.rest_in is not None:
        d = float(fate.rest_in.distance(end))
        out.append(FateVerdict("rest_in", d == 0.0, d, f"ends at ({', '.join(length_text(c) for c in end)}) m, "
                                                       f"{length_text(d)} m from the region"))
    if fate.at:
        cost, met, said = 0.0, True, []
        for t, r in fate.at:
            k = int(np.argmin(np.abs(times - t)))
            d = float(r.distance(path[k]))
            cost += d
            met = met and d == 0.0
            said.append(f"{length_text(d)} m from it at {times[k]:.3f} s")
        out.append(FateVerdict("at", met, cost, "; ".join(said)))
    if fate.through:
        out.append(_through(fate, path))
    if fate.up is not None:
        axis, within = fate.up
        a = rotate(quat, np.asarray(axis))
        ang = math.degrees(math.acos(max(-1.0, min(1.0, float(a[2]) / max(float(np.linalg.norm(a)), 1e-300)))))
        out.append(FateVerdict("up", ang <= within, math.radians(max(0.0, ang - within)),
                               f"the axis ends {ang:.1f} deg from up"))
    if fate.hits:
        out.append(_hits(fate, touches, near or {}))
    if fate.never_hits:
        hit = [n for n in fate.never_hits if n in touches]
        # a touch at the first step: the scene starts with the two in contact (a body resting on the floor it
        # must never hit), which no velocity can undo; said so, as it is easily missed
        named = ", ".join(n + (" (already touching at the start)" if touches[n] <= times[0]
                               else "") for n in hit)
        out.append(FateVerdict("never_hits", not hit, float(len(hit)), "touched " + (named or "none of them")))
    if fate.at_rest:
        v, w = float(np.linalg.norm(linvel)), float(np.linalg.norm(angvel))
        met = v <= AT_REST_SPEED and w <= AT_REST_SPIN
        out.append(FateVerdict("at_rest", met, max(0.0, v - AT_REST_SPEED) + 0.1 * max(0.0, w - AT_REST_SPIN),
                               f"ends at {v:.3f} m/s, {w:.2f} rad/s"))
    if fate.still:
        far = float(np.linalg.norm(path - path[0], axis=-1).max())
        out.append(FateVerdict("still", far <= STILL_DISTANCE, max(0.0, far - STILL_DISTANCE),
                               f"moved at most {length_text(far)} m"))
    return BodyVerdict(fate.body, all(f.met for f in out), float(sum(f.cost for f in out)), tuple(out))


def judge(fates: Fates, rec: Recording) -> Judgement:
    """Judge a rollout against every fate.

    Args:
        fates: the checked fates (their ``fates`` give the bodies' order).
        rec: the rollout's :class:`Recording`, bodies in that order.

    Returns:
        the :class:`Judgement`: per body its verdicts, the signature, the total cost.
    """
    return Judgement(tuple(judge_body(f, rec.times, rec.pos[:, i], rec.quat[i], rec.linvel[i], rec.angvel[i],
                                      rec.touches[i], rec.near[i] if rec.near else None)
                            for i, f in enumerate(fates.fates)))
