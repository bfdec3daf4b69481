"""The shot model: a launch a human bowler can throw, its initial state, its outcome.

A **launch** is four numbers (:class:`Launch`): lateral position ``y`` of the ball's
centre where it starts (m, + = bowler's left), ``speed`` (m/s), direction ``angle``
(degrees from straight down the lane, + = towards the left), ``spin`` (rad/s about the
travel direction, right-hand rule: + hooks the ball to the right; a right-hander's hook
into the 1-3 pocket is negative). The ball starts at x = ``LAUNCH_X`` rolling without
slip, plus the spin. :data:`BOUNDS` clamps every launch to what a bowler can throw.

A pin is **down** when, at the end of the shot (:data:`DURATION` = 2.5 s, steps of
1 ms), its axis tilts more than 45 degrees from vertical or it has left the deck (fallen
below it, into a gutter or the pit). The **signature** of a shot is its set of pins
down, a 10-bit mask (bit n-1 = pin n).

Replays are bit-identical: every launch starts from a freshly reset ``MjData`` with only
``qpos``/``qvel`` set (sleeping is on, and a reused MjData can carry sleep state that the
state ``mujoco.rollout`` sets does not cover: the calibration note saw 2/60 launches
change that way, benchmarks/bench_bowling.py 0/48; rare is not never). :class:`Launcher`
runs launches on K threads with the rollout room's runner (:mod:`nbst.models.mjsearch.runner`):
each a ``mujoco.rollout`` call on the thread's own MjData, reset before every launch, keeping
only the final state.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from nbst.errors import MujocoError  # re-exported here
from nbst.models.bowling import scene
from nbst.models.mjsearch import runner
from nbst.models.mjsearch.runner import check_state, data_warnings, mujoco_warnings_raise  # noqa: F401 (re-exported)

#: Length of a shot (s): ~1 s to reach the pins at 5 m/s, then >= 1.5 s of pin action.
DURATION = 2.5
#: Tilt beyond which a pin counts as down (degrees from vertical).
DOWN_TILT_DEG = 45.0
#: A pin whose base is this far below the deck (m) has left it (gutter, pit).
LEFT_DECK_DEPTH = 0.02

#: Ranges a human bowler throws (inclusive): lateral within the lane (ball centre at
#: least its radius from each edge), 5-10 m/s (11-22 mph; league bowlers 7-9 m/s),
#: +/-3 degrees (a board every 2 m), spin +/-30 rad/s (~290 rpm; strong crankers ~500
#: rpm are 52 rad/s, but about a tilted axis, so less about the travel direction).
BOUNDS = {
    "y": (-(scene.LANE_WIDTH / 2 - scene.BALL_RADIUS), scene.LANE_WIDTH / 2 - scene.BALL_RADIUS),
    "speed": (5.0, 10.0),
    "angle": (-3.0, 3.0),
    "spin": (-30.0, 30.0),
}
KEYS = ("y", "speed", "angle", "spin")
LO = np.array([BOUNDS[k][0] for k in KEYS])
HI = np.array([BOUNDS[k][1] for k in KEYS])


@dataclass(frozen=True)
class Launch:
    """A throw: y (m), speed (m/s), angle (deg), spin (rad/s); see the module docstring."""

    y: float
    speed: float
    angle: float
    spin: float

    def as_array(self) -> np.ndarray:
        return np.array([self.y, self.speed, self.angle, self.spin])

    @classmethod
    def from_array(cls, a) -> Launch:
        a = np.asarray(a, dtype=float)
        return cls(*(float(v) for v in a))

    def to_dict(self) -> dict:
        return asdict(self)


def clamp(x) -> np.ndarray:
    """Launch arrays, (..., 4) float, clipped to :data:`BOUNDS`."""
    return np.clip(np.asarray(x, dtype=float), LO, HI)


def initial_qpos_qvel(model, launch) -> tuple[np.ndarray, np.ndarray]:
    """(qpos, qvel) of the scene at the start of ``launch`` (a Launch or a (4,) array).

    Pins stand on their spots at rest (the model's ``qpos0``); the ball at
    (LAUNCH_X, y, radius), identity orientation, rolling without slip at ``speed``
    along the direction ``angle``, plus ``spin`` about that direction. The free joint's
    angular velocity is in the body frame, equal to the world frame at identity.
    """
    y, speed, angle, spin = clamp(launch.as_array() if isinstance(launch, Launch) else launch)
    qpos = np.array(model.qpos0, dtype=float)
    qvel = np.zeros(model.nv)
    a = math.radians(angle)
    d = np.array([math.cos(a), math.sin(a), 0.0])
    v = speed * d
    omega = np.cross([0.0, 0.0, 1.0], v) / scene.BALL_RADIUS + spin * d
    ball = model.joint("ball_free")
    qa, va = int(ball.qposadr[0]), int(ball.dofadr[0])
    qpos[qa:qa + 7] = [scene.LAUNCH_X, y, scene.BALL_RADIUS, 1.0, 0.0, 0.0, 0.0]
    qvel[va:va + 3] = v
    qvel[va + 3:va + 6] = omega
    return qpos, qvel


def pin_addresses(model) -> np.ndarray:
    """(10,) int: qpos address of each pin's free joint, pins 1..10."""
    return np.array([int(model.joint(f"pin{n}_free").qposadr[0]) for n in scene.PIN_NUMBERS])


def pins_down(model, qpos) -> np.ndarray:
    """(..., 10) bool: pin n-1 down in each final ``qpos`` (..., nq) (tilt > 45 deg or off the deck)."""
    qpos = np.asarray(qpos, dtype=float)
    adr = pin_addresses(model)
    idx = adr[:, None] + np.arange(7)
    p = qpos[..., idx]  # (..., 10, 7)
    qx, qy = p[..., 4], p[..., 5]
    qw, qz = p[..., 3], p[..., 6]
    norm2 = qw**2 + qx**2 + qy**2 + qz**2
    cos_tilt = 1.0 - 2.0 * (qx**2 + qy**2) / norm2  # z-component of the pin's axis
    tilted = cos_tilt < math.cos(math.radians(DOWN_TILT_DEG))
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    off = (z < -LEFT_DECK_DEPTH) | (x > scene.PIT_EDGE_X) | (np.abs(y) > scene.LANE_WIDTH / 2)
    return tilted | off


def mask_of(down) -> np.ndarray:
    """10-bit signature(s) from (..., 10) bool: bit n-1 set when pin n is down."""
    return (np.asarray(down, dtype=np.int64) << np.arange(10)).sum(axis=-1)


def pins_of(mask: int) -> list[int]:
    """Pin numbers in a 10-bit mask, ascending."""
    return [n for n in scene.PIN_NUMBERS if int(mask) >> (n - 1) & 1]


def mask_from_pins(pins) -> int:
    return int(sum(1 << (int(n) - 1) for n in set(pins)))


def replay_final_qpos(model, qpos0, qvel0, duration: float = DURATION) -> np.ndarray:
    """Final qpos from a fresh ``MjData`` and a plain ``mj_step`` loop: the slow reference.
    Non-finite states are refused before stepping, and MuJoCo's warnings raise
    :class:`MujocoError` (nothing is written to ``MUJOCO_LOG.TXT``)."""
    import mujoco

    check_state(qpos0, qvel0)
    d = mujoco.MjData(model)
    d.qpos[:] = qpos0
    d.qvel[:] = qvel0
    with mujoco_warnings_raise():
        mujoco.mj_step(model, d, nstep=n_steps(model, duration))
    bad = data_warnings(d)
    if bad or not np.isfinite(d.qpos).all():
        raise MujocoError(f"MuJoCo warned: {', '.join(bad) or 'non-finite state'} during the replay")
    return d.qpos.copy()


def n_steps(model, duration: float = DURATION) -> int:
    return runner.n_steps(model, duration)


class Launches:
    """What a runner of launches adds to :class:`~nbst.models.mjsearch.runner.Runner`: :meth:`launch`."""

    def launch(self, launches) -> tuple[np.ndarray, np.ndarray]:
        """(B, 4) launch arrays -> (signatures (B,) int, pins down (B, 10) bool)."""
        launches = np.atleast_2d(np.asarray(launches, dtype=float))
        states = np.array([self.initial_state(*initial_qpos_qvel(self.model, x)) for x in launches])
        down = pins_down(self.model, self.final_qpos(self.run_states(states)))
        return mask_of(down), down


class Launcher(Launches, runner.Runner):
    """Runs launches on ``jobs`` threads with ``mujoco.rollout`` (the shared
    :class:`~nbst.models.mjsearch.runner.Runner`: an MjData per thread, reset before each
    launch, so a launch's result depends on its initial state only); results in launch order."""

    def __init__(self, model=None, *, jobs: int | None = None, duration: float = DURATION):
        super().__init__(scene.build_model() if model is None else model, jobs=jobs, duration=duration)
