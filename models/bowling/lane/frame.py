"""A frame from the foul line: the delivery of :mod:`.lane` run into the pins until they come to
rest, and the settled outcome counted as USBC counts pinfall.

* **Scene**: :func:`nbst.models.bowling.lane.scene.lane_spec` with the pins (one compiled model per ball
  and timestep, :func:`frame_model`; the oil is not in the model). The delivery only sets the
  initial state: the ball's inertia axes are placed by turning the ball body (a sphere: its
  contact is the same in any orientation) instead of recompiling, so one model serves every
  throw of a Monte Carlo batch. Pins not in play (a spare's leave) are parked standing on the
  floor plane behind the approach, out of reach, and left out of the outcome.
* **Run**: steps of ``h`` (1 ms default; the ladder runs 0.5 and 0.25 ms too). While the ball
  is on the lane, one step at a time with its friction from the oil (:mod:`.friction`; the
  lane's :class:`.oil.OilField` is worn in place: a fresh one of the pattern unless a series
  passes its own); then checked every :data:`CHECK_EVERY` s. The frame is **settled** when the
  ball has reached the pins (or left the lane) and is in the pit or slower than
  :data:`REST_SPEED`, and every pin in play that is not in the pit moves slower than
  :data:`REST_SPEED` and turns slower than :data:`REST_SPIN`, for :data:`REST_HOLD` s in a row.
  The **sweep**: a pinsetter counts the pins :data:`SWEEP_AFTER_PINS` s after the ball reaches
  the head pin's line, settled or not (Brunswick's Sync scoring manual: the picture is taken
  1.5-3 s after the ball detect, "1500-3000 milliseconds is a typical setting"; the detect sits
  just past the pins), or :data:`.lane.MAX_SECONDS` after the release if it never does; a frame
  counted at the sweep before it settled says so (``cap_hit``). ``extra_s`` runs on past the
  settle (or the sweep) before reading the outcome: the check that the outcome is settled.
* **Pinfall** (USBC Playing Rules 6a and 6b, 2012-13 rulebook, as quoted at
  ballreviews.com/miscellaneous/rules-question-300958; docs/bowling.md quotes them): a pin
  is down when it is knocked down (its axis tilts past :data:`nbst.models.bowling.pinfall.DOWN_TILT_DEG`), off the
  lane surface (below the deck, past the pit edge, or over the gutter edge: lying in the
  gutter), or leaning on and touching the kickback or side partition (dead wood, rule
  6a.4): a pin in contact with ``wall_left``/``wall_right`` in the settled state. A ball that
  leaves the lane before reaching the pins scores nothing (rule 6b.1).

Compute only: no files, no printing.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from functools import lru_cache

import numpy as np

from nbst.errors import InputError
from nbst.errors import MujocoError
from nbst.models.bowling import lane, pinfall, scene
from nbst.models.mjsearch.runner import data_warnings, mujoco_warnings_raise
from nbst.models.mjsearch.ladder import climb
from nbst.models.mjsearch.pool import WorkerPool

__all__ = ["TIMESTEP", "LADDER", "REST_SPEED", "REST_SPIN", "REST_HOLD", "CHECK_EVERY", "SWEEP_AFTER_PINS",
           "CAP_AFTER_PINS", "PARTITIONS", "PARK_X", "PARK_STEP", "FrameError", "FrameResult", "frame_model",
           "initial_qpos_qvel", "settled_pinfall", "DeckStart", "deck_start", "run_frame", "ladder", "FrameRunner"]

#: Default step (s) and the ladder of the engine-robustness check.
TIMESTEP = lane.TIMESTEP
LADDER = (0.001, 0.0005, 0.00025)
#: Rest: speeds below these (m/s; rad/s) for REST_HOLD s, checked every CHECK_EVERY s.
REST_SPEED = 0.01
REST_SPIN = 0.1
REST_HOLD = 0.2
CHECK_EVERY = 0.01
#: The pinsetter's sweep: the pins are counted this long after the ball reaches the head pin's
#: line (s): the ball detect ~0.1 s later, then a 2.5 s delay (the middle of Brunswick's typical
#: 1.5-3 s).
SWEEP_AFTER_PINS = 2.6
CAP_AFTER_PINS = SWEEP_AFTER_PINS
#: The partitions beside the deck (the scene's kickbacks and lane dividers).
PARTITIONS = ("wall_left", "wall_right")
#: Where pins not in play are parked: standing on the floor plane, behind the approach.
PARK_X = lane.LANE_START_X - 1.0
PARK_STEP = 0.3


class FrameError(InputError):
    """Bad input to a frame: one line naming the field."""


@dataclass
class FrameResult:
    """A settled frame. Pins are numbered 1..10; ``down``/``leave`` cover the pins in play."""

    delivery: dict
    oil: str
    timestep: float
    in_play: list
    down: list
    leave: list
    knocked: list  # tilted past 45 degrees
    off_deck: list  # below the deck, in the pit, or over the gutter edge (lying in the gutter)
    partition: list  # touching a kickback or side partition (dead wood)
    ball_left_lane: bool  # before the pins: rule 6b.1, no pinfall
    ball_at_pins_s: float | None
    board_at_pins: float | None  # the ball's line where it crosses the deck front, carried to x = 0
    entry_angle_deg: float | None
    settled: bool
    settle_s: float | None
    cap_hit: bool
    seconds: float
    extra_s: float = 0.0
    oil_ml: dict = field(default_factory=dict)  # the ball's trade with the lane (friction.BallOnLane.oil_ml)
    final_qpos: np.ndarray | None = field(default=None, repr=False)

    @property
    def mask(self) -> int:
        return pinfall.mask_from_pins(self.down)

    @property
    def strike(self) -> bool:
        return len(self.in_play) == 10 and not self.leave

    @property
    def converted(self) -> bool:
        """Every pin in play down (a strike on a full rack, a spare on a leave)."""
        return not self.leave

    def to_dict(self) -> dict:
        d = asdict(self)
        d.pop("final_qpos")
        return d


@lru_cache(maxsize=16)
def _compiled(ball: lane.Ball, timestep: float):
    m = lane.lane_spec(ball, lane.Delivery(), pins=True).compile()
    m.opt.timestep = timestep
    return m


def frame_model(ball: lane.Ball | None = None, *, timestep: float = TIMESTEP):
    """The lane with pins, compiled once per (ball, timestep) and shared read-only (the oil is
    the step loop's, not the model's)."""
    if isinstance(ball, str):
        raise FrameError("frame_model: the oil is no longer part of the model; pass the ball only")
    ball = (ball or lane.Ball()).check()
    if not (isinstance(timestep, (int, float)) and 1e-5 <= timestep <= 0.002):
        raise FrameError(f"timestep: must be in [1e-05, 0.002] s (the contacts' time constant is 8 ms), got {timestep!r}")
    return _compiled(ball, float(timestep))


def initial_qpos_qvel(model, delivery: lane.Delivery, standing=None, ball: lane.Ball | None = None
                      ) -> tuple[np.ndarray, np.ndarray]:
    """(qpos, qvel) at release: the pins in ``standing`` (pin numbers; default all ten) on their
    spots, the others parked; the ball at the foul line (:func:`.lane.release_state`: its body
    turned so its principal axes are where ``ball``'s layout puts them for ``delivery``)."""
    delivery = delivery.check()
    ball = (ball or lane.Ball()).check()
    standing = set(scene.PIN_NUMBERS if standing is None else standing)
    qpos = np.array(model.qpos0, dtype=float)
    qvel = np.zeros(model.nv)
    adr = pinfall.pin_addresses(model)
    for k, n in enumerate(scene.PIN_NUMBERS):
        if n not in standing:
            qpos[adr[k]:adr[k] + 7] = [PARK_X - PARK_STEP * k, 0.0, scene.FLOOR_Z, 1.0, 0.0, 0.0, 0.0]
    j = model.joint("ball_free")
    qa, va = int(j.qposadr[0]), int(j.dofadr[0])
    qpos[qa:qa + 7], qvel[va:va + 6] = lane.release_state(model, delivery, ball)
    return qpos, qvel


def settled_pinfall(model, data, in_play) -> tuple[list, list, list]:
    """(knocked, off_deck, partition): pin numbers in play down by each rule, on ``data``'s state
    (its contacts as of the last step)."""
    import mujoco

    p = pinfall.poses(model, data.qpos)
    tilted = pinfall.tilted(p)
    off = pinfall.off_deck(p)
    walls = {mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, w) for w in PARTITIONS}
    pin_body = {model.body(f"pin{n}").id: n for n in scene.PIN_NUMBERS}
    leaning = set()
    for c in data.contact[:data.ncon]:
        g1, g2 = int(c.geom1), int(c.geom2)
        for a, b in ((g1, g2), (g2, g1)):
            if a in walls and int(model.geom_bodyid[b]) in pin_body:
                leaning.add(pin_body[int(model.geom_bodyid[b])])
    play = set(in_play)
    knocked = [n for k, n in enumerate(scene.PIN_NUMBERS) if n in play and tilted[k]]
    off_deck = [n for k, n in enumerate(scene.PIN_NUMBERS) if n in play and off[k]]
    partition = sorted(n for n in leaning if n in play)
    return knocked, off_deck, partition


def _pin_moving(model, data, in_play_idx) -> bool:
    adr = [int(model.joint(f"pin{scene.PIN_NUMBERS[k]}_free").dofadr[0]) for k in in_play_idx]
    qadr = pinfall.pin_addresses(model)
    for k, a in zip(in_play_idx, adr):
        if data.qpos[qadr[k]] > scene.PIT_EDGE_X:  # in the pit: down for good
            continue
        if np.linalg.norm(data.qvel[a:a + 3]) > REST_SPEED or np.linalg.norm(data.qvel[a + 3:a + 6]) > REST_SPIN:
            return True
    return False


def _in_play(standing) -> list:
    in_play = sorted(set(scene.PIN_NUMBERS if standing is None else standing))
    if not in_play or any(n not in scene.PIN_NUMBERS for n in in_play):
        raise FrameError(f"standing: pins must be numbers 1..10 (at least one), got {in_play!r}")
    return in_play


@dataclass
class DeckStart:
    """A frame's state where the ball reaches the deck front (or leaves the lane, or the time cap):
    its lane phase done. ``run_frame(..., start=s)`` runs the pin deck from here, so one lane phase
    serves many pin decks (the carry fit, benchmarks/bench_carry_fit.py: the pins' parameters do
    not touch the ball before it reaches them). ``time``, ``qpos``, ``qvel``: the state; ``prev``:
    the ball's (position, velocity) one step before; ``board``, ``angle``: where it crossed the deck
    front, carried to the head pin's line (None when it did not); ``oil_ml``: its trade with the
    lane; ``in_play``: the pins in play."""

    time: float
    qpos: np.ndarray
    qvel: np.ndarray
    prev: tuple
    board: float | None
    angle: float | None
    oil_ml: dict
    in_play: list


def _lane_phase(m, d, delivery, in_play, ball, pat, law, field, record) -> DeckStart:
    """Release ``delivery`` on the fresh ``d`` and step it, the ball's friction from the oil, until
    the ball reaches the deck front, leaves the lane or the time cap; ``d`` is left there."""
    import mujoco

    from nbst.models.bowling.lane.friction import BallOnLane

    qpos0, qvel0 = initial_qpos_qvel(m, delivery, in_play, ball)
    d.qpos[:], d.qvel[:] = qpos0, qvel0
    bol = BallOnLane(m, ball, lane.OilField.fresh(pat) if field is None else field, law)
    bq = int(m.joint("ball_free").qposadr[0])
    bv = int(m.joint("ball_free").dofadr[0])
    half = scene.LANE_WIDTH / 2
    board = angle = None
    prev = (d.qpos[bq:bq + 3].copy(), d.qvel[bv:bv + 3].copy())
    if record is not None:
        record(d)
    # the ball on the lane: one step at a time, its friction from the oil under it
    while d.qpos[bq] < scene.DECK_FRONT_X and abs(d.qpos[bq + 1]) < half and d.time < lane.MAX_SECONDS - 1e-9:
        prev = (d.qpos[bq:bq + 3].copy(), d.qvel[bv:bv + 3].copy())
        bol.step(d)
        mujoco.mj_step(m, d)
        if record is not None:
            record(d)
    bx, by = float(d.qpos[bq]), float(d.qpos[bq + 1])
    if bx >= scene.DECK_FRONT_X and prev[0][0] < scene.DECK_FRONT_X and abs(by) < half:
        board, angle = _entry(prev, d.qpos[bq:bq + 3], d.qvel[bv:bv + 3], delivery.hand)
    prev = (d.qpos[bq:bq + 3].copy(), d.qvel[bv:bv + 3].copy())
    d.xfrc_applied[:] = 0.0
    return DeckStart(time=float(d.time), qpos=d.qpos.copy(), qvel=d.qvel.copy(), prev=prev, board=board,
                     angle=angle, oil_ml=bol.oil_ml(), in_play=list(in_play))


def _entry(prev, pos, vel, hand: str) -> tuple[float, float]:
    """(entry board, entry angle in degrees) where the ball crossed the deck front between the
    step before (``prev``: its position and velocity) and now (``pos``, ``vel``), interpolated
    linearly; the board is where that line meets the pins' row, as a bowler reads it."""
    f = (scene.DECK_FRONT_X - prev[0][0]) / (pos[0] - prev[0][0])
    y = prev[0][1] + f * (pos[1] - prev[0][1])
    v = prev[1] + f * (vel - prev[1])
    board = float(lane.y_to_board(y - v[1] / v[0] * scene.DECK_FRONT_X, hand))
    return board, float(math.degrees(math.atan2(lane.hand_sign(hand) * v[1], v[0])))


def deck_start(delivery: lane.Delivery, oil="house", ball: lane.Ball | None = None, *, standing=None,
               timestep: float = TIMESTEP, law: lane.OilLaw = lane.LAW, field: lane.OilField | None = None,
               model=None) -> DeckStart:
    """The lane phase of :func:`run_frame` alone (the same steps): the :class:`DeckStart` where
    its ball reaches the deck front; ``run_frame(delivery, ..., start=...)`` then runs the pins."""
    import mujoco

    delivery = delivery.check()
    ball = (ball or lane.Ball()).check()
    m = model if model is not None else frame_model(ball, timestep=timestep)
    d = mujoco.MjData(m)
    with mujoco_warnings_raise():
        return _lane_phase(m, d, delivery, _in_play(standing), ball, lane.pattern(oil), law, field, None)


def run_frame(delivery: lane.Delivery, oil="house", ball: lane.Ball | None = None, *,
              standing=None, timestep: float = TIMESTEP, extra_s: float = 0.0, law: lane.OilLaw = lane.LAW,
              field: lane.OilField | None = None, model=None, record=None, start: DeckStart | None = None
              ) -> FrameResult:
    """Throw ``delivery`` at the pins in ``standing`` (default all ten) on ``oil`` (a pattern, its
    name or file; ``field``: the lane's oil now, worn in place: a series) and run until they settle
    (or the sweep), then ``extra_s`` more; the USBC outcome (see the module docstring).

    Args:
        delivery: what the bowler does (``lane.Delivery``); checked first.
        oil: the oil pattern: a registered pattern's name, a pattern file's path or a ``lane.Pattern``.
        ball: the ball (``lane.Ball``; None: the default ball).
        standing: the pins standing before the throw, numbers 1..10 (None: all ten).
        timestep: MuJoCo's timestep, seconds.
        extra_s: seconds run after the pins settle (or the sweep), 0..60.
        law: the film-to-friction law (``lane.OilLaw``; default the fitted ``lane.LAW``).
        field: the lane's oil now (``lane.OilField``), worn in place by this throw (a series);
            None: a fresh lane of ``oil``.
        model: a compiled frame model to reuse (``frame_model(ball, timestep=...)``), or None.
        record: None, or ``record(data)`` called with the ``MjData`` at release and after every
            step (the same steps, one at a time: the same states as without it); it must only
            read ``data``.
        start: None, or the :class:`DeckStart` of this delivery (:func:`deck_start`, with the same
            ball, oil and pins in play) to run the pin deck from, on ``model`` (a copy whose pins'
            parameters differ: the carry fit); ``record`` then sees the deck's steps only.

    Returns:
        A :class:`FrameResult`: the pins in play, down and left, counted as USBC counts pinfall
        (with the knocked, off-deck and dead-wood pins apart), whether it settled before the
        sweep, the ball's board and entry angle at the pins, and the oil it took.

    Raises:
        FrameError: a bad ``standing`` or ``extra_s`` (one line).
    """
    import mujoco

    delivery = delivery.check()
    in_play = _in_play(standing)
    if not (isinstance(extra_s, (int, float)) and 0.0 <= extra_s <= 60.0):
        raise FrameError(f"extra_s: must be in [0, 60] s, got {extra_s!r}")
    ball = (ball or lane.Ball()).check()
    pat = lane.pattern(oil)
    m = model if model is not None else frame_model(ball, timestep=timestep)
    h = float(m.opt.timestep)
    d = mujoco.MjData(m)
    if start is None:
        with mujoco_warnings_raise():
            start = _lane_phase(m, d, delivery, in_play, ball, pat, law, field, record)
    else:
        d.time = start.time
        d.qpos[:], d.qvel[:] = start.qpos, start.qvel
        in_play = list(start.in_play)
    k = max(1, int(round(CHECK_EVERY / h)))
    bq = int(m.joint("ball_free").qposadr[0])
    bv = int(m.joint("ball_free").dofadr[0])
    idx = [scene.PIN_NUMBERS.index(n) for n in in_play]
    half = scene.LANE_WIDTH / 2
    t_pins = None
    board, angle, prev = start.board, start.angle, start.prev
    left_lane = False
    still_since = None
    settle = None
    cap = lane.MAX_SECONDS

    def step(n: int) -> None:
        if record is None:
            mujoco.mj_step(m, d, nstep=n)
            return
        for _ in range(n):
            mujoco.mj_step(m, d)
            record(d)

    with mujoco_warnings_raise():
        while True:
            step(k)
            bx, by = float(d.qpos[bq]), float(d.qpos[bq + 1])
            if t_pins is None and bx < 0.0 and abs(by) > half and bx < scene.DECK_FRONT_X:
                left_lane = True
            if board is None and bx >= scene.DECK_FRONT_X and prev[0][0] < scene.DECK_FRONT_X and not left_lane:
                board, angle = _entry(prev, d.qpos[bq:bq + 3], d.qvel[bv:bv + 3], delivery.hand)
            if t_pins is None and bx >= 0.0:
                t_pins = float(d.time)
                cap = t_pins + CAP_AFTER_PINS
            prev = (d.qpos[bq:bq + 3].copy(), d.qvel[bv:bv + 3].copy())
            ball_done = (t_pins is not None or left_lane) and (
                bx > scene.PIT_EDGE_X or np.linalg.norm(d.qvel[bv:bv + 3]) < REST_SPEED)
            if ball_done and not _pin_moving(m, d, idx):
                still_since = d.time if still_since is None else still_since
                if d.time - still_since >= REST_HOLD - 1e-9:
                    settle = float(d.time)
                    break
            else:
                still_since = None
            if d.time >= cap - 1e-9:
                break
        if extra_s > 0:
            step(int(round(extra_s / h)))
    bad = data_warnings(d)
    if bad or not np.isfinite(d.qpos).all():
        raise MujocoError(f"MuJoCo warned: {', '.join(bad) or 'non-finite state'} during the frame")
    knocked, off_deck, partition = settled_pinfall(m, d, in_play)
    down = sorted(set(knocked) | set(off_deck) | set(partition)) if not left_lane else []
    return FrameResult(
        delivery=delivery.to_dict(), oil=pat.name, timestep=h, in_play=in_play,
        down=down, leave=[n for n in in_play if n not in down], knocked=knocked, off_deck=off_deck,
        partition=partition, ball_left_lane=left_lane, ball_at_pins_s=t_pins, board_at_pins=board,
        entry_angle_deg=angle, settled=settle is not None, settle_s=settle, cap_hit=settle is None,
        seconds=float(d.time), extra_s=float(extra_s), oil_ml=dict(start.oil_ml), final_qpos=d.qpos.copy())


def ladder(delivery: lane.Delivery, oil: str = "house", ball: lane.Ball | None = None, *, standing=None,
           timesteps=LADDER) -> list[FrameResult]:
    """The same throw at each timestep of ``timesteps`` (the engine-robustness ladder, the
    rollout room's :func:`nbst.models.mjsearch.ladder.climb`)."""
    return climb(lambda h: run_frame(delivery, oil, ball, standing=standing, timestep=h), timesteps).results


_WORKER: dict = {}


def _worker_init(oil, ball, timestep, law) -> None:
    _WORKER["model"] = frame_model(ball, timestep=timestep)
    _WORKER["oil"], _WORKER["ball"], _WORKER["law"] = oil, ball, law


def _worker_run(delivery, standing, extra_s=0.0) -> FrameResult:
    return run_frame(delivery, _WORKER["oil"], _WORKER["ball"], standing=standing, model=_WORKER["model"],
                     extra_s=extra_s, law=_WORKER["law"])


class FrameRunner:
    """Runs many frames of one model in ``jobs`` processes (MuJoCo's ``mj_step`` holds the GIL in
    the Python bindings: two threads measured no faster than one); results in input order,
    each frame from a fresh MjData, so a frame depends on its delivery only and the results
    are the same for any ``jobs``. The processes are the rollout room's
    :class:`~nbst.models.mjsearch.pool.WorkerPool`: they die with this process, even when it
    is killed by SIGKILL."""

    def __init__(self, oil="house", ball: lane.Ball | None = None, *, timestep: float = TIMESTEP,
                 jobs: int = 1, law: lane.OilLaw = lane.LAW):
        self.pattern = lane.pattern(oil)
        self.oil, self.ball, self.law = oil, (ball or lane.Ball()).check(), law.check()
        self.model = frame_model(self.ball, timestep=timestep)
        self.jobs = max(1, int(jobs))
        self._args = (self.pattern, self.ball, float(timestep), self.law)
        self._pool = None

    def _get_pool(self):
        if self._pool is None and self.jobs > 1:
            self._pool = WorkerPool(self.jobs, _worker_init, self._args)
        return self._pool

    def close(self) -> None:
        if self._pool is not None:
            self._pool.close()
            self._pool = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def one(self, delivery: lane.Delivery, standing=None, extra_s: float = 0.0, field=None) -> FrameResult:
        return run_frame(delivery, self.pattern, self.ball, standing=standing, model=self.model, extra_s=extra_s,
                         law=self.law, field=field)

    def map(self, deliveries, standing=None, on_done=None, extra_s: float = 0.0) -> list[FrameResult]:
        """Frames of ``deliveries`` in order (each run ``extra_s`` past its settle); ``on_done()``
        after each (progress)."""
        deliveries = list(deliveries)
        pool = self._get_pool() if len(deliveries) > 1 else None
        if pool is None:
            out = []
            for dv in deliveries:
                out.append(self.one(dv, standing, extra_s))
                if on_done is not None:
                    on_done()
            return out
        return pool.map(_worker_run, [(dv, standing, extra_s) for dv in deliveries], on_done=on_done)
