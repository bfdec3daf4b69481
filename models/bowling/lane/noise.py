"""Release noise in a bowler's units, and the probability of an outcome under it.

A bowler never repeats a throw exactly. :class:`Noise` draws each release parameter of a
:class:`.lane.Delivery` from a normal distribution about the aimed value (independent draws,
standard deviations in :data:`DEFAULT`):

* **board at the foul line**: 1/2 board (issue 22's figure);
* **launch angle**: 0.15 deg. An assumed figure: no published spread was found. A bowler
  aims at an arrow 15 ft out; 0.15 deg moves the ball 0.44 board there (0.66 board with the
  foul-line spread), so about 95 % of throws cross within 1.3 boards of the target arrow,
  as a bowler who "hits the mark" does; at the pins, 60 ft out, it alone spreads the ball
  by 1.8 boards;
* **speed**: 0.3 mph; **rev rate**: 15 rpm; **axis rotation**: 5 deg (issue 22's figures);
* **axis tilt**: 0 (held; an option);
* **correlations** (optional, 0 by default: independent draws): speed with revs
  (``corr_mph_rpm``) and axis rotation with revs (``corr_rotation_rpm``), for the bowler
  profiles (:mod:`.profiles`). The standard normal draws are mixed by the Cholesky factor of the
  correlation matrix before they are scaled; with both at 0 the draws are the independent ones,
  bit for bit, and :meth:`Noise.to_dict` leaves the two fields out (files as before).

Draws are clipped to the delivery's limits (rotation and tilt to [0, 90] deg, board to
[1, 39]). Everything is drawn from one ``numpy`` generator seeded by the caller, in a fixed
order, so a seed gives the same throws whatever the number of threads that run them.

The **probability** of an outcome (by default: the frame converts, every pin in play down; with
``want``: exactly the pins of ``want`` are down) is a Monte Carlo estimate over ``n`` noisy throws, with a
95 % Wilson score interval (:func:`wilson`): ``(p + z^2/2n +- z sqrt(p(1-p)/n + z^2/4n^2)) /
(1 + z^2/n)``, z = 1.96, which stays inside [0, 1] and is not empty at 0 or n successes. The
draws, the common random numbers and the interval are the rollout room's
(:mod:`nbst.models.mjsearch.probability`); the bowler's units and the leaves are this module's.

Compute only: no files, no printing.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np

from nbst.models.bowling import lane
from nbst.models.bowling.lane import frame
from nbst.models.mjsearch.probability import Z95, normal_draws, perturb, wilson  # noqa: F401 (re-exported)

__all__ = ["CLIP", "Noise", "KEYS", "CORR_KEYS", "DEFAULT", "sample", "Estimate", "wanted", "success", "estimate",
           "probability", "Z95", "wilson"]

#: Ranges the draws are clipped to (a Delivery's own limits).
CLIP = {"board": (1.0, 39.0), "angle": (-10.0, 10.0), "mph": (5.0, 30.0), "rpm": (0.0, 800.0),
        "rotation": (0.0, 90.0), "tilt": (0.0, 90.0)}


@dataclass(frozen=True)
class Noise:
    """Standard deviations of the release: boards (at the foul line), deg, mph, rpm, deg, deg."""

    board: float = 0.5
    angle: float = 0.15
    mph: float = 0.3
    rpm: float = 15.0
    rotation: float = 5.0
    tilt: float = 0.0
    corr_mph_rpm: float = 0.0
    corr_rotation_rpm: float = 0.0

    def check(self) -> Noise:
        for k, v in asdict(self).items():
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
                raise lane.LaneError(f"noise.{k}: must be a finite number, got {v!r}")
            if k in CORR_KEYS:
                if not -0.9 <= v <= 0.9:
                    raise lane.LaneError(f"noise.{k}: a correlation must be in [-0.9, 0.9], got {v!r}")
            elif not 0 <= v <= (200 if k == "rpm" else 20):
                raise lane.LaneError(f"noise.{k}: a standard deviation must be a number in [0, "
                                 f"{200 if k == 'rpm' else 20}], got {v!r}")
        if self.corr_mph_rpm ** 2 + self.corr_rotation_rpm ** 2 >= 0.99:
            raise lane.LaneError(f"noise.corr_rotation_rpm: with corr_mph_rpm {self.corr_mph_rpm:g} the correlations "
                             f"must have squares summing below 0.99 (a valid correlation matrix)")
        return self

    def to_dict(self) -> dict:
        d = asdict(self)
        for k in CORR_KEYS:  # independent noise: the fields of files written before they existed
            if d[k] == 0.0:
                del d[k]
        return d

    def mix(self, draws):
        """(n, 6) independent standard normal ``draws`` (columns :data:`KEYS`) made correlated as
        stated (the Cholesky factor of the correlation matrix); unchanged when both are 0."""
        if self.corr_mph_rpm == 0.0 and self.corr_rotation_rpm == 0.0:
            return draws
        c = np.eye(len(KEYS))
        i, j, k = KEYS.index("mph"), KEYS.index("rpm"), KEYS.index("rotation")
        c[i, j] = c[j, i] = self.corr_mph_rpm
        c[k, j] = c[j, k] = self.corr_rotation_rpm
        return np.asarray(draws) @ np.linalg.cholesky(c).T


KEYS = ("board", "angle", "mph", "rpm", "rotation", "tilt")
CORR_KEYS = ("corr_mph_rpm", "corr_rotation_rpm")
DEFAULT = Noise()


def _fields(row) -> dict[str, Any]:
    """A row of drawn values as the delivery's fields (:data:`KEYS`), Python floats."""
    return {k: float(v) for k, v in zip(KEYS, row)}


def sample(delivery: lane.Delivery, n: int, seed: int, noise: Noise = DEFAULT) -> list[lane.Delivery]:
    """``n`` noisy copies of ``delivery`` (board given at the foul line), reproducible from ``seed``.

    Args:
        delivery: the aimed release.
        n: how many (a whole number >= 1).
        seed: the seed of the draws.
        noise: the standard deviations and correlations (:class:`Noise`).

    Returns:
        ``n`` :class:`.lane.Delivery`, each at the foul line, clipped to :data:`CLIP`.

    Raises:
        LaneError: the delivery, the noise or ``n`` refused.
    """
    delivery = delivery.check()
    noise = noise.check()
    if not (isinstance(n, int) and n >= 1):
        raise lane.LaneError(f"samples: must be a whole number >= 1, got {n!r}")
    base = replace(delivery, board=delivery.foul_board(), at="foul")
    draws = noise.mix(normal_draws(seed, n, len(KEYS)))  # a fixed order: row per throw, column per key
    X = perturb([getattr(base, k) for k in KEYS], [getattr(noise, k) for k in KEYS], draws,
                [CLIP[k][0] for k in KEYS], [CLIP[k][1] for k in KEYS])
    return [replace(base, **_fields(row)) for row in X]


@dataclass
class Estimate:
    """``k`` of ``n`` noisy throws gave the outcome: p, its 95 % Wilson interval, the seed, the
    noise, and how often each leave came up (pins standing, '-' joined; '' is none)."""

    k: int
    n: int
    p: float
    lo: float
    hi: float
    seed: int
    noise: dict
    leaves: dict

    def to_dict(self) -> dict:
        return asdict(self)

    def text(self) -> str:
        return f"{100 * self.p:.0f} % ({self.k}/{self.n}; 95 % CI {100 * self.lo:.0f}-{100 * self.hi:.0f} %)"


def wanted(want) -> list | None:
    """``want`` as a sorted list of distinct pin numbers 1..10 (None stays None: convert)."""
    if want is None:
        return None
    try:
        pins = sorted(int(p) for p in want)
    except (TypeError, ValueError):
        raise lane.LaneError(f"want: pins must be numbers 1..10, got {want!r}") from None
    if any(not 1 <= p <= 10 for p in pins) or len(set(pins)) != len(pins):
        raise lane.LaneError(f"want: pins must be distinct numbers 1..10, got {want!r}")
    return pins


def success(r, want=None) -> bool:
    """Whether frame ``r`` gave the outcome: with ``want`` None, it converted (every pin in play
    down); else exactly the pins of ``want`` (a sorted list) are down."""
    return r.converted if want is None else sorted(r.down) == want


def estimate(results: list, seed: int, noise: Noise = DEFAULT, want=None) -> Estimate:
    """The probability of the outcome from noisy frames: with ``want`` None, that a frame converts
    (every pin in play down); else that exactly the pins of ``want`` are down (no more, no fewer)."""
    want = wanted(want)
    k = sum(1 for r in results if success(r, want))
    n = len(results)
    lo, hi = wilson(k, n)
    leaves: dict = {}
    for r in results:
        name = "-".join(str(p) for p in r.leave)
        leaves[name] = leaves.get(name, 0) + 1
    return Estimate(k=k, n=n, p=k / n, lo=lo, hi=hi, seed=int(seed), noise=noise.to_dict(),
                    leaves=dict(sorted(leaves.items(), key=lambda kv: -kv[1])))


def probability(delivery: lane.Delivery, n: int, seed: int, *, runner: frame.FrameRunner, standing=None,
                noise: Noise = DEFAULT, on_done=None, want=None) -> tuple[Estimate, list]:
    """(the estimate that ``delivery`` converts the pins in ``standing`` (default: a strike) under
    ``noise``, or with ``want`` knocks down exactly those pins; the frames) from ``n`` noisy
    throws run by ``runner``.

    Args:
        delivery: the aimed release (:class:`.lane.Delivery`).
        n: noisy throws (a whole number >= 1).
        seed: the seed of the draws (an int in ``[0, 2**63-1]``): the same seed, the same throws.
        runner: the :class:`.frame.FrameRunner` that runs the frames (its oil, ball and jobs).
        standing: the pins standing before the throw (None: all ten).
        noise: the release noise (:class:`Noise`).
        on_done: called after each frame (a progress bar).
        want: the pins to knock down exactly (None: convert every pin in play).

    Returns:
        (:class:`Estimate`, the n :class:`.frame.FrameResult`).

    Raises:
        LaneError: the delivery, the noise, ``n`` or ``want`` refused.
    """
    want = wanted(want)
    throws = sample(delivery, n, seed, noise)
    results = runner.map(throws, standing=standing, on_done=on_done)
    return estimate(results, seed, noise, want), results
