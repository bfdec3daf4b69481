"""The throw down the lane: the ball alone from the foul line to the pins, and its phases.

* **Throw** (:func:`throw`): the ball alone (no pins: the phases end where the pins would
  start) is stepped with h = 1 ms until its centre crosses the head pin's spot line (x = 0),
  its friction applied by :mod:`.friction` before every step from the oil under it (a fresh
  :class:`.oil.OilField` of the pattern, or the one given: a lane a series has worn),
  recording its state each step; :class:`ThrowResult` holds the phases in bowler's units: where
  the skid ends and the hook starts, the breakpoint, where the ball rolls, its entry angle,
  board and speed at the pins, and the track's flare.
* **Release** (:func:`release_state`): the ball at the foul line, its body turned so that its
  principal axes are where the layout puts them for the delivery (one compiled model per ball
  and timestep serves every delivery).

Compute only: no files written, no printing.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace
from functools import lru_cache

import numpy as np

from nbst.models.bowling import scene
from nbst.models.bowling.lane.ball import Ball
from nbst.models.bowling.lane.delivery import Delivery, initial_state, quat_to_mat
from nbst.models.bowling.lane.oil import LAW, OilField, OilLaw, oil_name, pattern
from nbst.models.bowling.lane.scene import ball_quat, lane_spec
from nbst.models.bowling.lane.units import ARROWS_FT, MPH, GutterBall, LaneError, hand_sign, x_to_ft, y_to_board
from nbst.models.mjsearch.runner import mujoco_warnings_raise

__all__ = ["TIMESTEP", "MAX_SECONDS", "ROLL_SLIP", "HOOK_SHARE", "BREAKPOINT_MIN", "HOOK_RISE", "FRONT_FT", "FLARE_FT", "AIM_TOL", "ThrowResult",
           "release_state", "ball_model", "run", "throw", "flare_in", "aim_angle", "board_at", "aim_at_arrows"]

#: Step and the longest run (s): a ball released at 5 mph (the slowest Delivery) takes ~11 s.
TIMESTEP = scene.TIMESTEP
MAX_SECONDS = 15.0
#: The ball rolls when its contact point slides slower than this (m/s).
ROLL_SLIP = 0.02
#: Track flare is measured over the first FLARE_FT ft (the oil, where flare matters).
FLARE_FT = 40.0
#: The hook starts (the skid ends) where the ball's sideways acceleration towards the pocket
#: first reaches this share of its peak.
HOOK_SHARE = 0.5
#: A breakpoint needs the ball to move out at least this many boards from its release, and to come
#: back at least as many by the pins (a ball that drifts out all the way has none).
BREAKPOINT_MIN = 0.25
#: A hook needs the peak sideways acceleration to reach this many times its level (median) over the
#: front of the lane, FRONT_FT ft past the foul line (the house shot's profiles: 6.1-8.7 times; on
#: oil to the pins, 1.25: no hook).
HOOK_RISE, FRONT_FT = 2.0, (1.0, 10.0)


@dataclass
class ThrowResult:
    """The phases of a throw in bowler's units (feet past the foul line, boards, mph, degrees).

    ``skid_ft``: where the hook starts (sideways acceleration towards the pocket first reaches
    HOOK_SHARE of its peak, where the peak is HOOK_RISE times its level on the front of the lane at
    least; None: no hook), or the breakpoint where the ball turns before that (it curls back in
    the oil): the skid never ends after the ball has come back; ``breakpoint_ft``/``breakpoint_board``:
    where the ball is farthest out (its board stops falling; None when it never moves out BREAKPOINT_MIN
    boards, or never comes back as many); ``roll_ft``: where the contact
    point's slip first drops below ROLL_SLIP (None if it never rolls before the pins);
    ``entry_angle_deg``: the ball's heading where its centre crosses the head pin's line,
    + towards the pocket side; ``board_at_pins``: its board there. ``flare_in``: track flare,
    the widest spread (in, arc on the cover) between the ball's spin axes over the first
    FLARE_FT ft, the spread of the oil rings a ball driller reads.
    """

    oil: str
    ball: dict
    delivery: dict
    board_at_foul_line: float
    board_at_arrows: float
    skid_ft: float | None
    breakpoint_ft: float | None
    breakpoint_board: float | None
    roll_ft: float | None
    entry_angle_deg: float
    board_at_pins: float
    speed_release_mph: float
    speed_pins_mph: float
    speed_lost_mph: float
    seconds_to_pins: float
    flare_in: float = 0.0
    timestep: float = TIMESTEP
    path: dict = field(default_factory=dict, repr=False)  # per-step arrays (not in to_dict)

    def to_dict(self) -> dict:
        d = asdict(self)
        d.pop("path")
        return d


def _qmul(a, b) -> np.ndarray:
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def release_state(model, delivery: Delivery, ball: Ball) -> tuple[np.ndarray, np.ndarray]:
    """(qpos (7,), qvel (6,)) of the ball's free joint at release on ``model`` (whose ball is laid
    out for the default delivery): at the foul line, its body turned so its principal axes are
    :func:`.scene.ball_quat`'s for ``delivery``, angular velocity in the body frame."""
    b = model.body("ball")
    q0 = np.array(model.body_iquat[b.id])  # the model's ball: laid out for the default delivery
    q = _qmul(ball_quat(delivery, ball), q0 * np.array([1.0, -1.0, -1.0, -1.0]))
    q /= np.linalg.norm(q)
    pos, v, w = initial_state(delivery)
    qmat = quat_to_mat(q[None])[0]
    return np.array([*pos, *q]), np.array([*v, *(qmat.T @ w)])


@lru_cache(maxsize=16)
def _ball_model(ball: Ball, timestep: float):
    m = lane_spec(ball, Delivery(), pins=False).compile()
    m.opt.timestep = timestep
    return m


def ball_model(ball: Ball | None = None, timestep: float = TIMESTEP):
    """The ball alone on the lane (no pins), compiled once per ball and timestep.

    Args:
        ball: the ball (None: the default ball).
        timestep: the step (s).

    Returns:
        a ``mujoco.MjModel``.
    """
    if not (isinstance(timestep, (int, float)) and 1e-5 <= timestep <= 0.002):
        raise LaneError(f"timestep: must be in [1e-05, 0.002] s, got {timestep!r}")
    return _ball_model((ball or Ball()).check(), float(timestep))


def run(delivery: Delivery, oil="house", ball: Ball | None = None, *, law: OilLaw = LAW,
        field: OilField | None = None, timestep: float = TIMESTEP, cover=None, record_mu: bool = False):
    """Step the ball alone from the foul line until its centre crosses x = 0 (or leaves the lane
    over a gutter, or MAX_SECONDS pass): (t, pos (n,3), vel (n,3), omega_world (n,3), extra) per
    step, the release state first; ``extra``: the body-frame angular velocity (n,3), the contact's
    friction per step (when ``record_mu``; else empty) and the :class:`.friction.BallOnLane` (its
    oil bookkeeping). ``field``: the lane's oil (worn in place; default a fresh one of ``oil``).

    Args:
        delivery: the delivery (checked first).
        oil: the oil pattern (a name, a pattern file or a :class:`.oil.Pattern`).
        ball: the ball (None: the default ball).
        law: the film-to-friction law.
        field: the lane's oil now, worn in place (None: a fresh lane of ``oil``).
        timestep: the step (s).
        cover: the oil film the cover carries at release, (N_CELLS,) float array (None: fresh and dry).
        record_mu: whether to record the contact's friction per step.

    Returns:
        (t (n,), pos (n, 3), vel (n, 3), omega_world (n, 3), extra) float64 arrays, as above.

    Raises:
        LaneError: the delivery, ball or oil is refused.
    """
    import mujoco

    from nbst.models.bowling.lane.friction import A_MU, BallOnLane

    delivery = delivery.check()
    ball = (ball or Ball()).check()
    model = ball_model(ball, timestep)
    field = OilField.fresh(pattern(oil)) if field is None else field
    bol = BallOnLane(model, ball, field, law, cover)
    data = mujoco.MjData(model)
    qa, va = release_state(model, delivery, ball)
    data.qpos[:7], data.qvel[:6] = qa, va
    n_max = int(round(MAX_SECONDS / model.opt.timestep))
    qp = np.empty((n_max + 1, 7))
    qv = np.empty((n_max + 1, 6))
    mu = np.empty(n_max + 1) if record_mu else np.empty(0)
    qp[0], qv[0] = data.qpos[:7], data.qvel[:6]
    n = 0
    half = scene.LANE_WIDTH / 2
    with mujoco_warnings_raise():
        while n < n_max and data.qpos[0] < 0.0 and abs(data.qpos[1]) < half:
            bol.step(data)
            if record_mu:
                mu[n] = bol.acc[A_MU] if bol.on_lane else np.nan
            mujoco.mj_step(model, data)
            n += 1
            qp[n], qv[n] = data.qpos[:7], data.qvel[:6]
    qp, qv = qp[:n + 1], qv[:n + 1]
    omega = np.einsum("nij,nj->ni", quat_to_mat(qp[:, 3:7]), qv[:, 3:6])
    extra = {"omega_body": qv[:, 3:6], "mu": mu[:n], "ball_on_lane": bol}
    return np.arange(n + 1) * model.opt.timestep, qp[:, :3], qv[:, :3], omega, extra


def flare_in(omega_body: np.ndarray, ft: np.ndarray, upto_ft: float = FLARE_FT) -> float:
    """Track flare (in): the widest angle between the ball's body-frame spin axes over the first
    ``upto_ft`` ft, as arc on the cover (the rings' spread)."""
    k = max(2, int(np.searchsorted(ft, upto_ft)))
    w = omega_body[:k]
    nrm = np.linalg.norm(w, axis=1)
    ax = w[nrm > 1e-6] / nrm[nrm > 1e-6, None]
    if len(ax) < 2:
        return 0.0
    a0 = ax[0]
    far = ax[int(np.argmin(ax @ a0))]
    ang = max(np.arccos(np.clip(ax @ a0, -1, 1)).max(), np.arccos(np.clip(ax @ far, -1, 1)).max())
    return float(ang * scene.BALL_RADIUS / scene.INCH)


def throw(delivery: Delivery, oil="house", ball: Ball | None = None, *, law: OilLaw = LAW,
          field: OilField | None = None, timestep: float = TIMESTEP) -> ThrowResult:
    """Run ``delivery`` down the lane with ``oil`` and ``ball``; its phases (see ThrowResult).

    Args:
        delivery: what the bowler does (:class:`Delivery`: hand, board, angle, mph, rpm, axis
            rotation and tilt); checked first.
        oil: the oil pattern: a registered pattern's name (``nbst.models.bowling.lane.oil.PATTERNS``),
            a pattern file's path or a :class:`.oil.Pattern`.
        ball: the ball (:class:`Ball`, within USBC's limits; None: the default ball).
        law: the film-to-friction law (:class:`.oil.OilLaw`; default the fitted :data:`.oil.LAW`).
        field: the lane's oil now (:class:`.oil.OilField`), worn in place by this throw (a series);
            None: a fresh lane of ``oil``.
        timestep: the step (s).

    Returns:
        A :class:`ThrowResult` in bowler's units: the skid, breakpoint and roll (feet past the
        foul line, boards), the entry angle (degrees), the board at the pins and the track flare.

    Raises:
        GutterBall: the ball left the lane before the pins (a result: no phases past it).
        LaneError: the delivery, the ball or the oil is refused (one line naming the field).
    """
    delivery = delivery.check()
    ball = (ball or Ball()).check()
    t, p, v, w, extra = run(delivery, oil, ball, law=law, field=field, timestep=timestep, record_mu=True)
    h = float(t[1] - t[0]) if len(t) > 1 else timestep
    if abs(p[-1, 1]) >= scene.LANE_WIDTH / 2:
        side = "left" if p[-1, 1] > 0 else "right"
        raise GutterBall(side, float(x_to_ft(p[-1, 0])))
    if p[-1, 0] < 0.0:
        raise LaneError(f"delivery: the ball did not reach the pins within {MAX_SECONDS:g} s "
                        f"(it was {-p[-1, 0]:.2f} m short, on board {float(y_to_board(p[-1, 1], delivery.hand)):.1f})")
    s = hand_sign(delivery.hand)
    R = scene.BALL_RADIUS
    slip = v + np.cross(w, np.array([0.0, 0.0, -R]))
    slip_h = np.hypot(slip[:, 0], slip[:, 1])
    speed = np.linalg.norm(v[:, :2], axis=1)
    ft = x_to_ft(p[:, 0])
    board = y_to_board(p[:, 1], delivery.hand)
    # sideways acceleration towards the pocket side, across the heading (central differences over 10 ms)
    k = max(1, int(round(0.01 / h)))
    a = np.zeros_like(v)
    a[k:-k] = (v[2 * k:] - v[:-2 * k]) / (2 * k * h)
    a_perp = s * (v[:, 0] * a[:, 1] - v[:, 1] * a[:, 0]) / np.maximum(speed, 1e-9)
    peak = a_perp.max()
    # a hook is a rise of the sideways acceleration: to HOOK_RISE times its level over the front of the
    # lane at least (on oil to the pins the ball curls alike all the way: no hook, it skids to the pins)
    front = (ft > FRONT_FT[0]) & (ft < FRONT_FT[1])
    base = float(np.median(a_perp[front])) if front.any() else 0.0
    hooked = peak > 0.05 and peak >= HOOK_RISE * base
    skid_i: int | None = int(np.argmax(a_perp >= HOOK_SHARE * peak)) if hooked else None
    # breakpoint: the ball's farthest board out, if it went out at least BREAKPOINT_MIN boards and came back
    # as many; where it turns there before the acceleration's rise (a ball curling back in the oil), the hook
    # starts where it turns: the skid never ends after the ball has come back
    far = int(np.argmin(board))
    bp_i = far if board[0] - board[far] >= BREAKPOINT_MIN and board[-1] - board[far] >= BREAKPOINT_MIN else None
    if bp_i is not None and (skid_i is None or skid_i > bp_i):
        skid_i = bp_i
    rolled = np.flatnonzero(slip_h < ROLL_SLIP)
    roll_i = int(rolled[0]) if len(rolled) else None
    # at the head pin's line: interpolate between the last two steps
    f = -p[-2, 0] / (p[-1, 0] - p[-2, 0])
    y_pin = p[-2, 1] + f * (p[-1, 1] - p[-2, 1])
    v_pin = v[-2] + f * (v[-1] - v[-2])
    return ThrowResult(
        oil=oil_name(oil), ball=ball.to_dict(), delivery=delivery.to_dict(),
        board_at_foul_line=float(board[0]), board_at_arrows=board_at(ft, board, ARROWS_FT),
        skid_ft=None if skid_i is None else float(ft[skid_i]),
        breakpoint_ft=None if bp_i is None else float(ft[bp_i]),
        breakpoint_board=None if bp_i is None else float(board[bp_i]),
        roll_ft=None if roll_i is None else float(ft[roll_i]),
        entry_angle_deg=float(math.degrees(math.atan2(s * v_pin[1], v_pin[0]))),
        board_at_pins=float(y_to_board(y_pin, delivery.hand)),
        speed_release_mph=float(speed[0] / MPH), speed_pins_mph=float(np.hypot(*v_pin[:2]) / MPH),
        speed_lost_mph=float((speed[0] - np.hypot(*v_pin[:2])) / MPH),
        seconds_to_pins=float(t[-2] + f * h), flare_in=flare_in(extra["omega_body"], ft), timestep=h,
        path={"t": t, "ft": ft, "board": board, "speed_mph": speed / MPH, "slip": slip_h, "a_hook": a_perp,
              "y": p[:, 1], "mu": extra["mu"], "omega_body": extra["omega_body"],
              "oil": extra["ball_on_lane"].oil_ml()})


def aim_angle(delivery: Delivery, board: float = 17.5, oil="house", ball: Ball | None = None, *,
              law: OilLaw = LAW, field: OilField | None = None, tol: float = 0.05,
              angles: tuple = (-3.0, 6.0)) -> tuple[Delivery, ThrowResult]:
    """The launch angle that brings ``delivery`` (its board at the foul line, speed, revs, axis
    kept) to ``board`` at the head pin's line, the ball alone (``field`` is copied, not worn):
    (the aimed delivery, its throw). A bracketed secant (Illinois) on the angle, within
    ``angles``; LaneError (one line) when no angle in the range reaches the board.

    Args:
        delivery: the release to aim (:class:`Delivery`; its board is taken at the foul line).
        board: the board to reach at the head pin's line.
        oil: the oil pattern (a name of :data:`.oil.PATTERNS`, a pattern file or a :class:`.oil.Pattern`).
        ball: the ball (None: the default ball).
        law: the film-to-friction law.
        field: the lane's oil now (copied, not worn); None: a fresh lane of ``oil``.
        tol: how near ``board`` the ball must come (boards).
        angles: the launch angles (deg) searched, low and high.

    Returns:
        (the aimed :class:`Delivery`, its :class:`ThrowResult`).

    Raises:
        LaneError: the delivery is refused, or no angle in ``angles`` reaches ``board``.
    """
    base = replace(delivery.check(), board=delivery.foul_board(), at="foul")

    def f(a: float):
        d = replace(base, angle=float(a))
        try:
            r = throw(d, oil, ball, law=law, field=None if field is None else OilField(field.h.copy(), field.name))
        except LaneError:
            return None, d, None
        return r.board_at_pins - board, d, r

    lo, hi = angles
    f0, d0, r0 = f(lo)
    f1, d1, r1 = f(hi)
    k = 0
    while f0 is None and k < 12 and lo < hi:  # a gutter at the end of the range: come in
        lo += 0.5
        f0, d0, r0 = f(lo)
        k += 1
    k = 0
    while f1 is None and k < 12 and hi > lo:
        hi -= 0.5
        f1, d1, r1 = f(hi)
        k += 1
    if f0 is None or f1 is None or f0 * f1 > 0:
        raise LaneError(f"aim: no launch angle in [{angles[0]:g}, {angles[1]:g}] deg from board {base.board:.1f} "
                        f"brings this release to board {board:g} at the head pin")
    side = 0
    for _ in range(40):
        a = (lo * f1 - hi * f0) / (f1 - f0)
        fm, dm, rm = f(a)
        if fm is None:
            raise LaneError(f"aim: the ball leaves the lane at {a:.2f} deg between two angles that reach the pins")
        if abs(fm) <= tol:
            return dm, rm
        if fm * f0 > 0:
            lo, f0 = a, fm
            if side == -1:
                f1 /= 2
            side = -1
        else:
            hi, f1 = a, fm
            if side == 1:
                f0 /= 2
            side = 1
    raise LaneError(f"aim: no angle found within {tol:g} board of board {board:g} in 40 steps")


def board_at(ft, board, at_ft: float) -> float:
    """The ball's board where its path crosses ``at_ft`` feet past the foul line, interpolated
    between the two steps around it (``ft``, ``board``: the path's per-step arrays)."""
    i = int(np.argmax(ft >= at_ft))
    if i == 0:
        return float(board[0])
    f = (at_ft - ft[i - 1]) / (ft[i] - ft[i - 1])
    return float(board[i - 1] + f * (board[i] - board[i - 1]))


#: How close (boards) the ball's real path must cross the arrows to the board asked.
AIM_TOL = 0.01


def aim_at_arrows(delivery: Delivery, oil="house", ball: Ball | None = None, *, law: OilLaw = LAW,
                  tol: float = AIM_TOL, iters: int = 8) -> Delivery:
    """A delivery given at the arrows (``at="arrows"``), aimed along the ball's real path: the
    foul-line delivery (``at="foul"``) whose ball, thrown on ``oil`` with ``ball``, crosses the
    asked board 15 ft out within ``tol`` boards. ``Delivery.foul_board`` carries the board back
    along a straight line; a hooking ball is off that line before the arrows (0.07 board for the
    typical release, 2.1 boards at 500 rpm), so the foul board is corrected by what the run
    shows (Newton's step with slope 1: a board moved at the foul line moves the crossing by about
    a board), each correction one run of the ball alone. A delivery given at the foul line is
    returned as it is. LaneError when the ball leaves the lane before the arrows or no foul
    board within ``iters`` runs crosses there.

    Args:
        delivery: the delivery (``at="arrows"`` to be aimed; ``at="foul"`` returned as it is).
        oil: the oil pattern (a name, a pattern file or a :class:`.oil.Pattern`).
        ball: the ball (None: the default ball).
        law: the film-to-friction law.
        tol: how near the asked board the ball must cross the arrows (boards).
        iters: runs of the ball alone at most.

    Returns:
        the foul-line :class:`Delivery` (``at="foul"``).

    Raises:
        LaneError: as above.
    """
    delivery = delivery.check()
    if delivery.at != "arrows":
        return delivery
    want = float(delivery.board)
    b = delivery.foul_board()
    for _ in range(iters):
        d = replace(delivery, board=float(b), at="foul").check()
        _, p, _, _, _ = run(d, oil, ball, law=law)
        ft = x_to_ft(p[:, 0])
        if ft[-1] < ARROWS_FT:
            raise LaneError(f"board: the ball aimed at board {want:g} at the arrows leaves the lane "
                            f"{float(ft[-1]):.1f} ft past the foul line, before the arrows")
        off = board_at(ft, y_to_board(p[:, 1], d.hand), ARROWS_FT) - want
        if abs(off) <= tol:
            return d
        b -= off
        if not 1.0 <= b <= 39.0:
            break
    raise LaneError(f"board: no board at the foul line puts this ball on board {want:g} at the arrows "
                    f"({iters} runs of the ball alone)")
