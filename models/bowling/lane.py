"""The full lane from the foul line, oil patterns as data, a ball in the ball maker's units and
a delivery in a bowler's units; the ball's run down the lane in MuJoCo and its phases.

Axes as :mod:`.scene`: x down the lane, y to the bowler's left, z up, the head pin's spot at
the origin. The foul line is 60 ft before it (:data:`FOUL_LINE_X` = -18.288 m).

* **Boards** (:func:`board_to_y`): 39 across the 41.5 in lane (1.0641 in each), numbered as
  bowlers number them: board 1 at the edge on the bowler's hand side (the right edge,
  y < 0, for a right-hander), board 20 the middle (the head pin's board), 39 the far edge.
  A left-hander's board 1 is the left edge: the left-hander's lane is the right-hander's
  mirrored in y. Boards are continuous: board b's centre is ``b - 0.5`` board widths from the
  hand-side edge (board 17.5, the pocket, is 2.5 boards right of the head pin for a
  right-hander). The arrows are on boards 5, 10, ... 35, 15 ft past the foul line.
* **Oil** (``oil_patterns.json``, :func:`load_patterns`): a pattern is a length and a grid of
  (distance segment x board band) cells of relative oil ``u`` in [0, 1]; each cell is a box
  whose friction ``mu = mu_dry - (mu_dry - MU_OIL) u`` rules the ball's contact
  (``priority = 1``, as the zones of :mod:`.scene`). Past the pattern the dry back end
  (``mu_dry``) runs to the pin deck of :mod:`.scene`.
* **Ball** (:class:`Ball`): weight (lb), RG and RG differential (in), coverstock friction,
  checked against USBC's limits (RG 2.46-2.80 in, differential <= 0.06 in, friction <= 0.32,
  at most 16 lb) with one-line errors naming the field. Inertia: ``I = m RG^2`` about the
  low-RG (pin) axis and ``m (RG + diff)^2`` about the two axes across it (a symmetric core:
  differential = high RG - low RG). The pin axis is placed :data:`PIN_TO_PAP_IN` inches of arc
  from the positive axis point (PAP, the hand-side end of the release's spin axis), towards
  the top of the ball: an assumed layout. The coverstock friction is the ball's friction on
  the dry lane (the back end); on full oil every ball gets :data:`MU_OIL`.
* **Delivery** (:class:`Delivery`): hand, board at the foul line (or at the arrows), launch
  angle (degrees from straight down the lane, + towards board 1: out towards the gutter on
  the hand side, as a hook is thrown out to its breakpoint), speed (mph), rev rate (rpm),
  axis rotation (0 = end over end, 90 = pure side spin about the travel direction) and axis
  tilt (0 = a horizontal spin axis, 90 = spinning like a top). The ball's centre starts over
  the foul line on the lane (no loft), with the spin vector ``omega = rpm * (cos(tilt)
  (cos(rot) a_roll + sin(rot) a_side) + sin(tilt) a_up)``: ``a_roll`` the forward-roll axis,
  ``a_side`` along the travel direction with the sign that hooks towards the pocket
  (opposite the travel for a right-hander), ``a_up`` vertical with the PAP end tipped up.
* **Throw** (:func:`throw`): the ball alone (no pins: the phases end where the pins would
  start) is stepped with h = 1 ms until its centre crosses the head pin's spot line (x = 0),
  recording its state each step; :class:`ThrowResult` holds the phases in bowler's units.

Compute only: no files written, no printing.

Length: ~560 lines, past the house's ~500: boards, oil, ball, delivery, scene and phases share
one set of conventions (hand, board numbering, spin axes); split, each part would import the
others' conventions back.
"""
from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from nbst.errors import InputError
from nbst.models.bowling import scene

FT = 0.3048
MPH = 0.44704
LB = 0.45359237
#: USBC: 60 ft from the foul line to the head pin's spot; the arrows 15 ft past the foul line.
LANE_LENGTH_FT = 60.0
FOUL_LINE_X = -LANE_LENGTH_FT * FT
ARROWS_FT = 15.0
ARROW_BOARDS = (5, 10, 15, 20, 25, 30, 35)
N_BOARDS = 39
BOARD_WIDTH = scene.LANE_WIDTH / N_BOARDS
#: The lane box starts this far before the foul line (the ball's centre starts on the line).
APPROACH = 0.3
LANE_START_X = FOUL_LINE_X - APPROACH
#: Friction of a full oil film (Frohlich's figure, as scene.MU_OIL) and of the dry lane for
#: the default ball (scene.MU_DRY); the ball's coverstock friction replaces the latter.
MU_OIL = scene.MU_OIL
MU_DRY = scene.MU_DRY
#: USBC ball limits.
RG_RANGE = (2.46, 2.80)
DIFF_MAX = 0.06
FRICTION_MAX = 0.32
WEIGHT_MAX_LB = 16.0
#: Assumed layout: the pin (low-RG axis) 4 1/2 in of arc from the PAP, towards the top of the ball.
PIN_TO_PAP_IN = 4.5
#: Step and the longest run (s): a ball released at 5 mph (the slowest Delivery) takes ~11 s.
TIMESTEP = scene.TIMESTEP
MAX_SECONDS = 15.0
#: The ball rolls when its contact point slides slower than this (m/s): MuJoCo's soft
#: contact leaves a creep of ~1e-3 m/s in pure roll.
ROLL_SLIP = 0.02
#: The hook starts (the skid ends) where the ball's sideways acceleration towards the pocket
#: first reaches this share of its peak.
HOOK_SHARE = 0.5
#: A breakpoint needs the ball to move out at least this many boards from its release.
BREAKPOINT_MIN = 0.25

PATTERNS_FILE = Path(__file__).with_name("oil_patterns.json")


class LaneError(InputError):
    """Bad input to the lane (a pattern, a ball, a delivery): one line naming the field."""


# --------------------------------------------------------------------------- boards


def hand_sign(hand: str) -> int:
    """+1 for a right-hander, -1 for a left-hander (the mirror in y)."""
    if hand not in ("right", "left"):
        raise LaneError(f"hand: must be 'right' or 'left', got {hand!r}")
    return 1 if hand == "right" else -1


def board_to_y(board, hand: str = "right"):
    """Lateral position (m, + = bowler's left) of a (continuous) board number for ``hand``."""
    return hand_sign(hand) * (-scene.LANE_WIDTH / 2 + (np.asarray(board, dtype=float) - 0.5) * BOARD_WIDTH)


def y_to_board(y, hand: str = "right"):
    """The (continuous) board number of a lateral position ``y`` (m) for ``hand``."""
    return (hand_sign(hand) * np.asarray(y, dtype=float) + scene.LANE_WIDTH / 2) / BOARD_WIDTH + 0.5


def ft_to_x(ft):
    """x (m) of a distance in feet past the foul line."""
    return FOUL_LINE_X + np.asarray(ft, dtype=float) * FT


def x_to_ft(x):
    return (np.asarray(x, dtype=float) - FOUL_LINE_X) / FT


# --------------------------------------------------------------------------- oil


@dataclass(frozen=True)
class Pattern:
    """An oil pattern: ``length_ft`` and ``segments``: ((to_ft, ((first, last, oil), ...)), ...)."""

    name: str
    description: str
    length_ft: float
    segments: tuple

    def oil_at(self, ft: float, board: float) -> float:
        """Relative oil at ``ft`` past the foul line on (continuous) ``board``: 0 past the pattern."""
        b = min(max(int(math.floor(board + 0.5)), 1), N_BOARDS) if board == board else 1
        start = 0.0
        for to_ft, bands in self.segments:
            if start <= ft < to_ft:
                return next(u for lo, hi, u in bands if lo <= b <= hi)
            start = to_ft
        return 0.0

    def symmetric(self) -> bool:
        """Whether board b and board 40 - b carry the same oil everywhere (mirror-symmetric)."""
        return all(self.oil_at(to - 1e-6, b) == self.oil_at(to - 1e-6, N_BOARDS + 1 - b)
                   for to, _ in self.segments for b in range(1, N_BOARDS + 1))


def _pattern(name: str, d, where: str) -> Pattern:
    if not isinstance(d, dict):
        raise LaneError(f"{where}: a pattern must be an object")
    length = d.get("length_ft")
    deck_ft = float(x_to_ft(scene.DECK_FRONT_X))
    if not isinstance(length, (int, float)) or isinstance(length, bool) or not 0 < length <= deck_ft:
        raise LaneError(f"{where}.length_ft: must be a number in (0, {deck_ft:.2f}] ft (the pin deck), got {length!r}")
    segs = d.get("segments")
    if not isinstance(segs, list) or not segs:
        raise LaneError(f"{where}.segments: must be a non-empty list")
    out, prev = [], 0.0
    for k, s in enumerate(segs):
        w = f"{where}.segments[{k}]"
        to = s.get("to_ft") if isinstance(s, dict) else None
        if not isinstance(to, (int, float)) or isinstance(to, bool) or not prev < to <= length:
            raise LaneError(f"{w}.to_ft: must increase past {prev:g} ft and stay within length_ft {length:g}, got {to!r}")
        bands = s.get("bands")
        if not isinstance(bands, list) or not bands:
            raise LaneError(f"{w}.bands: must be a non-empty list of [first_board, last_board, oil]")
        nxt, bs = 1, []
        for j, b in enumerate(bands):
            if (not isinstance(b, list) or len(b) != 3 or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                                  for v in b)):
                raise LaneError(f"{w}.bands[{j}]: must be [first_board, last_board, oil], got {b!r}")
            lo, hi, u = b
            if lo != nxt or not lo <= hi <= N_BOARDS or int(lo) != lo or int(hi) != hi:
                raise LaneError(f"{w}.bands[{j}]: boards must run on from board {nxt} to at most {N_BOARDS}, got {lo}..{hi}")
            if not 0.0 <= u <= 1.0:
                raise LaneError(f"{w}.bands[{j}]: oil must be in [0, 1] (relative oil), got {u!r}")
            bs.append((int(lo), int(hi), float(u)))
            nxt = int(hi) + 1
        if nxt != N_BOARDS + 1:
            raise LaneError(f"{w}.bands: must cover boards 1..{N_BOARDS}, stop at {nxt - 1}")
        out.append((float(to), tuple(bs)))
        prev = float(to)
    if prev != length:
        raise LaneError(f"{where}.segments: the last segment must end at length_ft {length:g}, ends at {prev:g}")
    return Pattern(name, str(d.get("description", "")), float(length), tuple(out))


@lru_cache(maxsize=None)
def load_patterns(path: str | None = None) -> dict:
    """{name: Pattern} from the patterns file (default: the shipped ``oil_patterns.json``)."""
    p = Path(path) if path else PATTERNS_FILE
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, ValueError) as e:
        raise LaneError(f"{p.name}: cannot read the oil patterns: {e}") from None
    pats = doc.get("patterns") if isinstance(doc, dict) else None
    if not isinstance(pats, dict) or not pats:
        raise LaneError(f"{p.name}: patterns: must be an object of named patterns")
    return {n: _pattern(n, d, f"{p.name}: patterns.{n}") for n, d in pats.items()}


def pattern(name: str) -> Pattern:
    pats = load_patterns()
    if name not in pats:
        raise LaneError(f"oil: no pattern {name!r}; patterns: {', '.join(sorted(pats))}")
    return pats[name]


def friction(oil: float, mu_dry: float, mu_oil: float = MU_OIL) -> float:
    """Lane friction under relative oil ``oil`` (0 = dry lane, 1 = full oil)."""
    return mu_dry - (mu_dry - mu_oil) * oil


# --------------------------------------------------------------------------- ball


@dataclass(frozen=True)
class Ball:
    """A ball in the ball maker's units: weight (lb), RG and differential (in), coverstock friction."""

    weight_lb: float = 15.0
    rg: float = 2.50
    diff: float = 0.040
    friction: float = MU_DRY

    def check(self) -> Ball:
        """The ball, or LaneError naming the first field outside USBC's limits."""
        for k in ("weight_lb", "rg", "diff", "friction"):
            v = getattr(self, k)
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
                raise LaneError(f"ball.{k}: must be a finite number, got {v!r}")
        if not 6.0 <= self.weight_lb <= WEIGHT_MAX_LB:
            raise LaneError(f"ball.weight_lb: {self.weight_lb:g} lb is outside 6..{WEIGHT_MAX_LB:g} lb (USBC: at most 16 lb)")
        if not RG_RANGE[0] <= self.rg <= RG_RANGE[1]:
            raise LaneError(f"ball.rg: {self.rg:g} in is outside USBC's {RG_RANGE[0]:.2f}..{RG_RANGE[1]:.2f} in")
        if not 0.0 <= self.diff <= DIFF_MAX:
            raise LaneError(f"ball.diff: RG differential {self.diff:g} in is outside USBC's 0..{DIFF_MAX:.2f} in")
        if not 0.0 < self.friction <= FRICTION_MAX:
            raise LaneError(f"ball.friction: coverstock friction {self.friction:g} is outside USBC's (0, {FRICTION_MAX:.2f}]")
        if self.friction <= MU_OIL:
            raise LaneError(f"ball.friction: coverstock friction {self.friction:g} must exceed the oil's {MU_OIL:g}")
        return self

    @property
    def mass(self) -> float:
        return self.weight_lb * LB

    def principal_inertia(self) -> np.ndarray:
        """(3,) kg m^2: about the pin (low-RG) axis, then the two high axes."""
        lo, hi = self.rg * scene.INCH, (self.rg + self.diff) * scene.INCH
        return self.mass * np.array([lo * lo, hi * hi, hi * hi])

    def to_dict(self) -> dict:
        return asdict(self)


# --------------------------------------------------------------------------- delivery


@dataclass(frozen=True)
class Delivery:
    """A throw in a bowler's units (see the module docstring for every convention)."""

    hand: str = "right"
    board: float = 12.5
    at: str = "foul"  # "foul": board at the foul line; "arrows": board where it crosses the arrows
    angle: float = 1.5
    mph: float = 17.0
    rpm: float = 300.0
    rotation: float = 45.0
    tilt: float = 15.0

    def check(self) -> Delivery:
        hand_sign(self.hand)
        if self.at not in ("foul", "arrows"):
            raise LaneError(f"at: must be 'foul' or 'arrows', got {self.at!r}")
        lim = {"board": (1.0, 39.0), "angle": (-10.0, 10.0), "mph": (5.0, 30.0), "rpm": (0.0, 800.0),
               "rotation": (0.0, 90.0), "tilt": (0.0, 90.0)}
        for k, (lo, hi) in lim.items():
            v = getattr(self, k)
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v) or not lo <= v <= hi:
                raise LaneError(f"{k}: must be a number in [{lo:g}, {hi:g}], got {v!r}")
        if not 1.0 <= self.foul_board() <= 39.0:
            raise LaneError(f"board: {self.board:g} at the arrows, {self.angle:g} deg out, is board "
                            f"{self.foul_board():.1f} at the foul line: off the lane (1..39)")
        return self

    def foul_board(self) -> float:
        """Board at the foul line (from the arrows: the straight line back, 15 ft)."""
        if self.at == "foul":
            return float(self.board)
        return float(self.board + math.tan(math.radians(self.angle)) * ARROWS_FT * FT / BOARD_WIDTH)

    def to_dict(self) -> dict:
        return asdict(self)


def spin_axes(d: Delivery) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(travel direction, unit spin vector (right-hand rule), PAP direction) at release, world frame."""
    s = hand_sign(d.hand)
    a = math.radians(d.angle)
    t = np.array([math.cos(a), -s * math.sin(a), 0.0])  # + angle: towards board 1
    z = np.array([0.0, 0.0, 1.0])
    a_roll = np.cross(z, t)  # forward roll: omega = z x v / R
    a_side = -s * t  # a right-hander's side spin: about -t, which hooks to +y (the pocket)
    a_up = -s * z  # so that the PAP end (-s * omega) tips up
    rot, tilt = math.radians(d.rotation), math.radians(d.tilt)
    w = math.cos(tilt) * (math.cos(rot) * a_roll + math.sin(rot) * a_side) + math.sin(tilt) * a_up
    w /= np.linalg.norm(w)
    pap = -s * w  # the hand-side end of the axis
    return t, w, pap


def _quat_x_to(p: np.ndarray) -> list:
    """Unit quaternion (w, x, y, z) rotating the x axis onto the unit vector ``p``."""
    x = np.array([1.0, 0.0, 0.0])
    c = float(np.dot(x, p))
    if c < -1 + 1e-12:
        return [0.0, 0.0, 0.0, 1.0]
    v = np.cross(x, p)
    q = np.array([1.0 + c, *v])
    return list(q / np.linalg.norm(q))


def pin_axis(d: Delivery) -> np.ndarray:
    """The ball's pin (low-RG) axis at release: PIN_TO_PAP_IN of arc from the PAP, towards the top."""
    _, w, pap = spin_axes(d)
    z = np.array([0.0, 0.0, 1.0])
    n = z - np.dot(z, w) * w
    n = n / np.linalg.norm(n) if np.linalg.norm(n) > 1e-9 else np.cross(w, [0.0, 1.0, 0.0])
    beta = PIN_TO_PAP_IN / (scene.BALL_RADIUS / scene.INCH)
    return math.cos(beta) * pap + math.sin(beta) * n


def initial_state(d: Delivery) -> tuple[np.ndarray, np.ndarray]:
    """(position (3,), linear velocity (3,), angular velocity (3,) world frame) at the foul line."""
    t, w, _ = spin_axes(d)
    y = float(board_to_y(d.foul_board(), d.hand))
    pos = np.array([FOUL_LINE_X, y, scene.BALL_RADIUS])
    return pos, d.mph * MPH * t, d.rpm * 2 * math.pi / 60 * w


# --------------------------------------------------------------------------- the scene


def build_spec(oil: str | Pattern = "house", ball: Ball | None = None, delivery: Delivery | None = None, *,
               pins: bool = True, mu_oil: float = MU_OIL):
    """An ``mujoco.MjSpec``: :mod:`.scene`'s deck, pins, pit and walls, the lane lengthened to the
    foul line with the pattern's friction cells, foul line and arrows (visual only), and the
    ball with the inertia of ``ball`` (its pin axis placed for ``delivery``); ``pins=False``
    leaves the pins out (the ball-only run of :func:`throw`); ``mu_oil``: full-oil friction."""
    import mujoco

    G = mujoco.mjtGeom
    pat = pattern(oil) if isinstance(oil, str) else oil
    ball = (ball or Ball()).check()
    delivery = (delivery or Delivery()).check()
    spec = scene.build_spec()
    spec.modelname = "nbst_bowling_lane"
    wb = spec.worldbody
    half_w = scene.LANE_WIDTH / 2
    x_end = scene.PIT_EDGE_X + scene.PIT_LENGTH
    slab = 0.05

    for name in ("lane_oil", "lane_backend"):
        spec.delete(spec.geom(name))
    # friction cells: one box per (segment, band), then the dry back end to the deck
    x0 = LANE_START_X
    for k, (to_ft, bands) in enumerate(pat.segments):
        x1 = float(ft_to_x(to_ft))
        for lo, hi, u in bands:
            ya, yb = sorted((float(board_to_y(lo - 0.5)), float(board_to_y(hi + 0.5))))
            g = wb.add_geom(name=f"oil_s{k}_b{lo}_{hi}", type=G.mjGEOM_BOX, pos=[(x0 + x1) / 2, (ya + yb) / 2, -slab],
                            size=[(x1 - x0) / 2, (yb - ya) / 2, slab], rgba=scene.OIL_RGBA)
            scene._static(g, friction(u, ball.friction, mu_oil))
        x0 = x1
    g = wb.add_geom(name="lane_backend", type=G.mjGEOM_BOX, pos=[(x0 + scene.DECK_FRONT_X) / 2, 0, -slab],
                    size=[(scene.DECK_FRONT_X - x0) / 2, half_w, slab], rgba=scene.LANE_RGBA)
    scene._static(g, ball.friction)

    # gutters and walls from the start of the lane
    for side in ("left", "right"):
        for k in range(scene.GUTTER_PIECES):
            g = spec.geom(f"gutter_{side}{k}")
            g.pos = [(LANE_START_X + scene.PIT_EDGE_X) / 2, g.pos[1], g.pos[2]]
            g.size = [(scene.PIT_EDGE_X - LANE_START_X) / 2, g.size[1], g.size[2]]
        g = spec.geom(f"wall_{side}")
        g.pos = [(LANE_START_X + x_end) / 2, g.pos[1], g.pos[2]]
        g.size = [(x_end - LANE_START_X) / 2, g.size[1], g.size[2]]
    # foul line and arrows: visual only
    marks = [("foul_line", FOUL_LINE_X, 0.0, 0.01, half_w)]
    marks += [(f"arrow{b}", float(ft_to_x(ARROWS_FT)), float(board_to_y(b)), 0.06, BOARD_WIDTH / 3)
              for b in ARROW_BOARDS]
    for name, x, y, hx, hy in marks:
        g = wb.add_geom(name=name, type=G.mjGEOM_BOX, pos=[x, y, 0.0005], size=[hx, hy, 0.0005],
                        rgba=(0.15, 0.15, 0.2, 1.0), group=1)
        g.contype = g.conaffinity = 0
    cam = spec.camera("behind")
    cam.pos = [FOUL_LINE_X - 1.5, 0.0, 0.9]
    spec.stat.center = [FOUL_LINE_X / 2, 0.0, 0.2]
    spec.stat.extent = 12.0

    if not pins:
        for n in scene.PIN_NUMBERS:
            spec.delete(spec.body(f"pin{n}"))
    body = spec.body("ball")
    body.pos = [FOUL_LINE_X, 0.0, scene.BALL_RADIUS]
    body.explicitinertial = True
    body.mass = ball.mass
    body.ipos = [0.0, 0.0, 0.0]
    body.inertia = list(ball.principal_inertia())
    body.iquat = _quat_x_to(pin_axis(delivery))
    spec.geom("ball").mass = ball.mass
    return spec


@lru_cache(maxsize=32)
def _model(oil, ball: Ball, delivery: Delivery, pins: bool, mu_oil: float):
    return build_spec(oil, ball, delivery, pins=pins, mu_oil=mu_oil).compile()


def build_model(oil: str = "house", ball: Ball | None = None, delivery: Delivery | None = None, *, pins: bool = True,
                mu_oil: float = MU_OIL):
    """The compiled model of :func:`build_spec` (cached by its arguments)."""
    if not (isinstance(mu_oil, (int, float)) and 0.0 < mu_oil < (ball or Ball()).friction):
        raise LaneError(f"mu_oil: must be in (0, the ball's friction), got {mu_oil!r}")
    return _model(oil, (ball or Ball()).check(), (delivery or Delivery()).check(), pins, float(mu_oil))


# --------------------------------------------------------------------------- the throw


@dataclass
class ThrowResult:
    """The phases of a throw in bowler's units (feet past the foul line, boards, mph, degrees).

    ``skid_ft``: where the hook starts (sideways acceleration towards the pocket first reaches
    HOOK_SHARE of its peak); ``breakpoint_ft``/``breakpoint_board``: where the ball is farthest
    out (its board stops falling; None when it never moves out); ``roll_ft``: where the contact
    point's slip first drops below ROLL_SLIP (None if it never rolls before the pins);
    ``entry_angle_deg``: the ball's heading where its centre crosses the head pin's line,
    + towards the pocket side; ``board_at_pins``: its board there.
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
    timestep: float = TIMESTEP
    path: dict = field(default_factory=dict, repr=False)  # per-step arrays (not in to_dict)

    def to_dict(self) -> dict:
        d = asdict(self)
        d.pop("path")
        return d


def _quat_to_mat(q: np.ndarray) -> np.ndarray:
    """(n, 4) unit quaternions (w, x, y, z) -> (n, 3, 3) rotation matrices."""
    w, x, y, z = q.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], -2)


def run(delivery: Delivery, oil: str = "house", ball: Ball | None = None, *, mu_oil: float = MU_OIL):
    """Step the ball alone from the foul line until its centre crosses x = 0 (or leaves the lane
    over a gutter, or MAX_SECONDS pass): (t, pos (n,3), vel (n,3), omega_world (n,3)) per step,
    the release state first."""
    import mujoco

    from nbst.models.bowling.shot import mujoco_warnings_raise

    delivery = delivery.check()
    model = build_model(oil, ball, delivery, pins=False, mu_oil=mu_oil)
    data = mujoco.MjData(model)
    pos0, v0, w0 = initial_state(delivery)
    data.qpos[:7] = [*pos0, 1.0, 0.0, 0.0, 0.0]
    data.qvel[:3] = v0
    data.qvel[3:6] = w0  # body frame = world frame at the identity orientation
    n_max = int(round(MAX_SECONDS / model.opt.timestep))
    qp = np.empty((n_max + 1, 7))
    qv = np.empty((n_max + 1, 6))
    qp[0], qv[0] = data.qpos[:7], data.qvel[:6]
    n = 0
    with mujoco_warnings_raise():
        while n < n_max and data.qpos[0] < 0.0 and abs(data.qpos[1]) < scene.LANE_WIDTH / 2:
            mujoco.mj_step(model, data)
            n += 1
            qp[n], qv[n] = data.qpos[:7], data.qvel[:6]
    qp, qv = qp[:n + 1], qv[:n + 1]
    omega = np.einsum("nij,nj->ni", _quat_to_mat(qp[:, 3:7]), qv[:, 3:6])
    return np.arange(n + 1) * model.opt.timestep, qp[:, :3], qv[:, :3], omega


def throw(delivery: Delivery, oil: str = "house", ball: Ball | None = None, *, mu_oil: float = MU_OIL) -> ThrowResult:
    """Run ``delivery`` down the lane with ``oil`` and ``ball``; its phases (see ThrowResult)."""
    delivery = delivery.check()
    ball = (ball or Ball()).check()
    t, p, v, w = run(delivery, oil, ball, mu_oil=mu_oil)
    if abs(p[-1, 1]) >= scene.LANE_WIDTH / 2:
        side = "left" if p[-1, 1] > 0 else "right"
        raise LaneError(f"delivery: a gutter ball: it left the lane into the {side} gutter "
                        f"{float(x_to_ft(p[-1, 0])):.1f} ft past the foul line; no phases to report")
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
    k = 10
    a = np.zeros_like(v)
    a[k:-k] = (v[2 * k:] - v[:-2 * k]) / (2 * k * TIMESTEP)
    a_perp = s * (v[:, 0] * a[:, 1] - v[:, 1] * a[:, 0]) / np.maximum(speed, 1e-9)
    peak = a_perp.max()
    skid_i = int(np.argmax(a_perp >= HOOK_SHARE * peak)) if peak > 0.05 else None
    # breakpoint: the ball's farthest board out, if it went out at least BREAKPOINT_MIN boards
    bp_i = int(np.argmin(board))
    bp_i = bp_i if board[0] - board[bp_i] >= BREAKPOINT_MIN and bp_i < len(board) - 1 else None
    rolled = np.flatnonzero(slip_h < ROLL_SLIP)
    roll_i = int(rolled[0]) if len(rolled) else None
    # at the head pin's line: interpolate between the last two steps
    f = -p[-2, 0] / (p[-1, 0] - p[-2, 0])
    y_pin = p[-2, 1] + f * (p[-1, 1] - p[-2, 1])
    v_pin = v[-2] + f * (v[-1] - v[-2])
    arrows_i = int(np.argmax(ft >= ARROWS_FT))
    return ThrowResult(
        oil=oil if isinstance(oil, str) else oil.name, ball=ball.to_dict(), delivery=delivery.to_dict(),
        board_at_foul_line=float(board[0]), board_at_arrows=float(board[arrows_i]),
        skid_ft=None if skid_i is None else float(ft[skid_i]),
        breakpoint_ft=None if bp_i is None else float(ft[bp_i]),
        breakpoint_board=None if bp_i is None else float(board[bp_i]),
        roll_ft=None if roll_i is None else float(ft[roll_i]),
        entry_angle_deg=float(math.degrees(math.atan2(s * v_pin[1], v_pin[0]))),
        board_at_pins=float(y_to_board(y_pin, delivery.hand)),
        speed_release_mph=float(speed[0] / MPH), speed_pins_mph=float(np.hypot(*v_pin[:2]) / MPH),
        speed_lost_mph=float((speed[0] - np.hypot(*v_pin[:2])) / MPH),
        seconds_to_pins=float(t[-2] + f * TIMESTEP),
        path={"t": t, "ft": ft, "board": board, "speed_mph": speed / MPH, "slip": slip_h, "a_hook": a_perp,
              "y": p[:, 1]})
