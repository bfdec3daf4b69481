"""The deck half's delivery: the ball 5 m before the head pin, its initial state, its rollouts.

A **delivery** is what the bowler does; in the deck half it is given as the ball's state where
the simulated lane starts (:data:`.scene.BALL_START_X`, 5 m before the head pin, on the end of
the oil), four numbers (:class:`Delivery`): lateral position ``y`` of the ball's centre (m,
+ = bowler's left), ``speed`` (m/s), direction ``angle`` (degrees from straight down the lane,
+ = towards the left), ``spin`` (rad/s about the travel direction, right-hand rule: + hooks the
ball to the right; a right-hander's hook into the 1-3 pocket is negative). The ball starts
rolling without slip, plus the spin. :data:`BOUNDS` clamps every delivery to what a bowler
throws. (The lane half gives a delivery in a bowler's units at the foul line:
:class:`nbst.models.bowling.lane.Delivery`.)

The **throw** is the result: :data:`DURATION` = 2.5 s of steps of 1 ms, then the pins down by
the rule of :mod:`.pinfall` (tilted past 45 degrees or off the deck); its **signature** is the
10-bit mask of the pins down.

Throws are bit-identical on replay: every delivery starts from a freshly reset ``MjData`` with
only ``qpos``/``qvel`` set (sleeping is on, and a reused MjData can carry sleep state that the
state ``mujoco.rollout`` sets does not cover: the calibration note saw 2/60 deliveries change
that way, benchmarks/bench_bowling.py 0/48; rare is not never). :class:`DeliveryRunner` throws on K
threads with the rollout room's runner (:mod:`nbst.models.mjsearch.runner`): each a
``mujoco.rollout`` call on the thread's own MjData, reset before every delivery, keeping only
the final state.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from nbst.errors import MujocoError
from nbst.models.bowling import pinfall, scene
from nbst.models.mjsearch import runner
from nbst.models.mjsearch.runner import check_state, data_warnings, mujoco_warnings_raise

__all__ = ["DURATION", "BOUNDS", "KEYS", "LO", "HI", "Delivery", "clamp", "initial_qpos_qvel", "replay_final_qpos",
           "n_steps", "Deliveries", "DeliveryRunner"]

#: Length of a throw (s): ~1 s to reach the pins at 5 m/s, then >= 1.5 s of pin action.
DURATION = 2.5

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
class Delivery:
    """A delivery at 5 m: y (m), speed (m/s), angle (deg), spin (rad/s); see the module docstring."""

    y: float
    speed: float
    angle: float
    spin: float

    def as_array(self) -> np.ndarray:
        return np.array([self.y, self.speed, self.angle, self.spin])

    @classmethod
    def from_array(cls, a) -> Delivery:
        a = np.asarray(a, dtype=float)
        return cls(*(float(v) for v in a))

    def to_dict(self) -> dict:
        return asdict(self)


def clamp(x) -> np.ndarray:
    """Delivery arrays clipped to :data:`BOUNDS`.

    Args:
        x: (..., 4) float array of deliveries (y, speed, angle, spin; columns :data:`KEYS`).

    Returns:
        (..., 4) float64 array, each column within its bound.
    """
    return np.clip(np.asarray(x, dtype=float), LO, HI)


def initial_qpos_qvel(model, delivery) -> tuple[np.ndarray, np.ndarray]:
    """(qpos, qvel) of the scene at the start of ``delivery`` (a Delivery or a (4,) array).

    Pins stand on their spots at rest (the model's ``qpos0``); the ball at
    (BALL_START_X, y, radius), identity orientation, rolling without slip at ``speed``
    along the direction ``angle``, plus ``spin`` about that direction. The free joint's
    angular velocity is in the body frame, equal to the world frame at identity.

    Args:
        model: the deck scene's ``mujoco.MjModel``.
        delivery: a :class:`Delivery` or a (4,) float array (y, speed, angle, spin; :data:`KEYS`).

    Returns:
        (qpos (nq,), qvel (nv,)) float64 arrays.
    """
    y, speed, angle, spin = clamp(delivery.as_array() if isinstance(delivery, Delivery) else delivery)
    qpos = np.array(model.qpos0, dtype=float)
    qvel = np.zeros(model.nv)
    a = math.radians(angle)
    d = np.array([math.cos(a), math.sin(a), 0.0])
    v = speed * d
    omega = np.cross([0.0, 0.0, 1.0], v) / scene.BALL_RADIUS + spin * d
    ball = model.joint("ball_free")
    qa, va = int(ball.qposadr[0]), int(ball.dofadr[0])
    qpos[qa:qa + 7] = [scene.BALL_START_X, y, scene.BALL_RADIUS, 1.0, 0.0, 0.0, 0.0]
    qvel[va:va + 3] = v
    qvel[va + 3:va + 6] = omega
    return qpos, qvel


def replay_final_qpos(model, qpos0, qvel0, duration: float = DURATION) -> np.ndarray:
    """Final qpos from a fresh ``MjData`` and a plain ``mj_step`` loop: the slow reference.

    Args:
        model: the deck scene's ``mujoco.MjModel``.
        qpos0: (nq,) float array, the start's positions (:func:`initial_qpos_qvel`).
        qvel0: (nv,) float array, the start's velocities.
        duration: seconds to step.

    Returns:
        (nq,) float64 array, the positions at the end.

    Raises:
        MujocoError: a non-finite start (refused before stepping) or a MuJoCo warning while stepping
            (nothing is written to ``MUJOCO_LOG.TXT``).
    """
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
    """Steps of ``model``'s timestep in ``duration`` seconds (the rollout room's count).

    Args:
        model: a ``mujoco.MjModel``.
        duration: seconds.

    Returns:
        the number of steps a rollout of ``duration`` runs.
    """
    return runner.n_steps(model, duration)


class Deliveries:
    """What a runner of deliveries adds to :class:`~nbst.models.mjsearch.runner.Runner`: :meth:`throw`."""

    def throw(self, deliveries) -> tuple[np.ndarray, np.ndarray]:
        """(B, 4) delivery arrays -> (signatures (B,) int, pins down (B, 10) bool)."""
        r: Any = self  # a mixin: the runner it is mixed into has the model and the state methods
        deliveries = np.atleast_2d(np.asarray(deliveries, dtype=float))
        states = np.array([r.initial_state(*initial_qpos_qvel(r.model, x)) for x in deliveries])
        down = pinfall.pins_down(r.model, r.final_qpos(r.run_states(states)))
        return pinfall.mask_of(down), down


class DeliveryRunner(Deliveries, runner.Runner):
    """Throws deliveries on ``jobs`` threads with ``mujoco.rollout`` (the rollout room's
    :class:`~nbst.models.mjsearch.runner.Runner`: an MjData per thread, reset before each
    delivery, so a throw depends on its delivery only); results in input order."""

    def __init__(self, model=None, *, jobs: int | None = None, duration: float = DURATION):
        super().__init__(scene.build_model() if model is None else model, jobs=jobs, duration=duration)
