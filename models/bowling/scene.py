"""The bowling scene, built with ``mujoco.MjSpec`` (USBC dimensions).

Axes: x down the lane, y to the bowler's left, z up; the lane surface is z = 0 and
the head pin's spot is x = y = 0. Only the last part of the lane is simulated: the
deck half's ball starts :data:`BALL_START_X` before the head pin, on the end of the oil.

* **lane** (USBC): 41.5 in wide (1.0541 m). Friction zones, one box each
  (``priority = 1`` so the zone's friction, not the ball's, rules the contact):
  oil 0.04 from where the ball starts to :data:`OIL_END_X`, dry back end 0.2 from there
  to the deck, pin deck 0.2 to the pit edge (34 3/16 in behind the head pin spot).
  A ball sliding on oil barely hooks (mu g = 0.4 m/s^2 sideways); on the back end its
  side spin turns into sideways roll (the skid-hook-roll of a real lane).
* **pins**: spots on an equilateral triangle of 12 in sides, numbered as USBC (1 in
  front; 2 and 3 behind it, 2 on the bowler's left; 7 left and 10 right in the back
  row). Each pin: a free body ``pin{n}`` standing on its spot, 4 convex mesh pieces
  for collision, a smooth visual mesh, explicit mass/inertia (:mod:`.pin`): the uniform
  solid's in the 5 m deck half (:data:`DECK_PINS`, issue 22), and in the lane half
  (:data:`LANE_PINS`) a pin graded along its axis so its centre of gravity sits at USBC's
  lowest, 5 40/64 in: the one parameter the carry fit of issue 34 moved (PBA's 74 % carry of
  pocket hits; docs/bowling.md).
* **ball**: 8.5 in (0.2159 m; USBC allows 8.500 .. 8.595 in), 6.8 kg (15 lb), uniform
  sphere (radius of gyration 2.69 in, inside USBC's 2.43 .. 2.80 in), a free body ``ball``.
* **gutters**: 9.25 in wide, 1.875 in deep, concave (an arc of 6 tilted boxes) along
  the lane and beside the deck; **kickbacks** and lane dividers: walls 1 m tall from
  where the ball starts to the back of the pit; **pit**: floor 0.25 m below the lane,
  0.9 m long, back cushion; a **floor** plane under everything (catches strays).

Contacts: ball and pins ``solref = (0.008, 0.2)``: the calibration note measured
restitution 0.51-0.52 ball-pin, 0.41-0.49 pin-pin (real pins: ~0.5); the time constant
is 8 steps of 1 ms (shorter gains energy). Static surfaces ``solref = (0.008, 1)``
(critically damped: a ball does not bounce on the lane). Friction: ball-pin and
pin-pin 0.12 (an assumed value for plastic-coated maple on a resin ball; not
calibrated), sliding only (condim 3). Sleeping is on (bodies at rest cost almost
nothing); a delivery is therefore thrown from a freshly reset ``MjData`` (see :mod:`.deck.delivery`).

Compute only: functions return a spec, a model or XML text.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from nbst.models.bowling import pin as pinmod
from nbst.models.scene import full_precision

__all__ = ["INCH", "TIMESTEP", "LANE_WIDTH", "GUTTER_WIDTH", "GUTTER_DEPTH", "PIN_SPACING", "PIT_EDGE_X",
           "DECK_FRONT_X", "OIL_END_X", "BALL_START_X", "LANE_START_X", "MU_OIL", "MU_DRY", "MU_DECK",
           "MU_BALL_PIN", "BALL_RADIUS", "BALL_MASS", "SOLREF_BODY", "SOLREF_STATIC", "MU_FLOOR", "Pins",
           "DECK_PINS", "LANE_PINS", "PIT_DEPTH", "PIT_LENGTH", "WALL_HEIGHT", "WALL_THICKNESS", "FLOOR_Z",
           "SLEEP_TOLERANCE", "GUTTER_PIECES", "GUTTER_SHELL", "LANE_RGBA", "OIL_RGBA", "DECK_RGBA", "GUTTER_RGBA",
           "WALL_RGBA", "PIN_RGBA", "BALL_RGBA", "PIN_NUMBERS", "pin_spots", "pin_names", "LaneLayout",
           "build_spec", "build_model", "scene_xml"]

INCH = 0.0254
#: Simulation step (s). Solref time constants stay >= 8 steps (see the note above).
TIMESTEP = 0.001
#: USBC lane width 41.5 in; gutters 9.25 in wide and 1.875 in deep.
LANE_WIDTH = 41.5 * INCH
GUTTER_WIDTH = 9.25 * INCH
GUTTER_DEPTH = 1.875 * INCH
#: Pin spacing: 12 in between neighbouring spots.
PIN_SPACING = 12.0 * INCH
#: From the head pin spot to the pit edge (USBC: 2 ft 10 3/16 in).
PIT_EDGE_X = 34.1875 * INCH
#: Pin deck's front edge (x); the deck's friction zone starts here.
DECK_FRONT_X = -0.3
#: Where the oil ends and the dry back end starts (x, m). A real pattern is ~40 ft of
#: the 60 ft lane; we keep its last 2 m and the 3 m dry back end before the pins.
OIL_END_X = -3.0
#: Where the deck half's ball starts (x of its centre, m) and where its lane box starts.
BALL_START_X = -5.0
LANE_START_X = -5.5
#: Friction coefficients: oil, dry back end, deck (sliding; literature 0.04 / 0.2).
MU_OIL = 0.04
MU_DRY = 0.2
MU_DECK = 0.2
MU_BALL_PIN = 0.12
#: Ball: 8.5 in, 6.8 kg (USBC maximum 16 lb; 15 lb is the common weight).
BALL_RADIUS = 4.25 * INCH
BALL_MASS = 6.8
#: Contacts: ball and pins (calibrated), static surfaces (critically damped).
SOLREF_BODY = (0.008, 0.2)
SOLREF_STATIC = (0.008, 1.0)
#: The floor plane under everything (catches strays).
MU_FLOOR = 0.2


@dataclass(frozen=True)
class Pins:
    """The pins' physical parameters: mass (kg) and centre of gravity (inches above the base; None:
    the uniform solid's, :func:`.pin.geometry`), both inside USBC's limits; sliding friction and
    contact damping ratio (``solref = (0.008, zeta)``) of ball-pin and pin-pin contacts; the pin
    deck's friction (the deck half: pins and ball on the deck; the lane half: the pins, the ball
    meeting the deck at ``MU_DECK``, :func:`nbst.models.bowling.lane.scene.lane_spec`)."""

    mass: float
    com_in: float | None
    mu_ball_pin: float
    mu_pin_pin: float
    zeta_ball_pin: float
    zeta_pin_pin: float
    mu_deck: float

    def separate(self) -> bool:
        """Whether ball-pin and pin-pin contacts differ (then the ball's geom priority rules its contacts
        with the pins: see :func:`build_spec`)."""
        return (self.mu_ball_pin, self.zeta_ball_pin) != (self.mu_pin_pin, self.zeta_pin_pin)


#: The 5 m deck half's pins (issue 22; not fitted): kept so its shipped atlas and shot files replay.
DECK_PINS = Pins(mass=pinmod.MASS, com_in=None, mu_ball_pin=MU_BALL_PIN, mu_pin_pin=MU_BALL_PIN,
                 zeta_ball_pin=SOLREF_BODY[1], zeta_pin_pin=SOLREF_BODY[1], mu_deck=MU_DECK)
#: The lane half's pins, fitted to PBA's carry of pocket hits (74 %; issue 34): the centre of gravity at
#: USBC's lowest, 5 40/64 in (the uniform solid's is 5.80 in), the rest as the deck half's. The pro's 213
#: pocket hits carry 158 (74 %) with it, 191 (90 %) with the uniform pin (benchmarks/bench_carry_fit.py,
#: docs/results/bowling.md "Pin carry, fitted"). The pin deck's friction is 0.1 (issue 48; the deck half's
#: 0.2 is the literature's pin-on-wood figure; the ball still meets the deck at MU_DECK): with 0.2 the deck's high side fell off a cliff a quarter
#: board wide (18.5 -> 18.75: 0-5 % strikes) and the pro's high hits left 7-10s and big fours at 8 % of
#: its spare attempts (ESPN: 3.0 %); chosen on fit seeds, held out in docs/results/bowling.md
#: "The pocket's high side, board by board".
LANE_PINS = replace(DECK_PINS, com_in=pinmod.COM_LIMITS_IN[0], mu_deck=0.1)
#: Pit: floor depth below the lane, length behind the pit edge; walls' height and thickness.
PIT_DEPTH = 0.25
PIT_LENGTH = 0.9
WALL_HEIGHT = 1.0
WALL_THICKNESS = 0.05
#: A plane under everything: anything that escapes lands here.
FLOOR_Z = -0.3
#: Sleeping: bodies whose speed stays under this (m/s, rad/s, scaled) for a few steps sleep.
SLEEP_TOLERANCE = 1e-4
#: Gutter arc: pieces and thickness of each box.
GUTTER_PIECES = 6
GUTTER_SHELL = 0.01

#: Colours (RGBA).
LANE_RGBA = (0.86, 0.72, 0.52, 1.0)
OIL_RGBA = (0.82, 0.68, 0.48, 1.0)
DECK_RGBA = (0.90, 0.78, 0.58, 1.0)
GUTTER_RGBA = (0.45, 0.45, 0.50, 1.0)
WALL_RGBA = (0.25, 0.27, 0.32, 1.0)
PIN_RGBA = (0.97, 0.97, 0.95, 1.0)
BALL_RGBA = (0.30, 0.62, 0.96, 1.0)  # nbst.palette.NONCUEABLE: the video's blue

PIN_NUMBERS = tuple(range(1, 11))


def pin_spots() -> np.ndarray:
    """(10, 2) float, m: the (x, y) of pin spots 1..10 (row r, r = 0..3, from the front)."""
    dx = PIN_SPACING * np.sqrt(3) / 2
    spots = []
    for row in range(4):
        for k in range(row + 1):
            spots.append((row * dx, (row / 2 - k) * PIN_SPACING))  # first of a row is leftmost (+y)
    return np.array(spots)


def pin_names() -> list[str]:
    return [f"pin{n}" for n in PIN_NUMBERS]


@dataclass(frozen=True)
class LaneLayout:
    """The full lane from the foul line, as the lane half lays it out (:mod:`.lane.scene`): what
    :func:`build_spec` puts in place of the deck half's 5 m of lane.

    ``start_x``: where the lane, its gutters and its walls start (m); ``cells``: friction boxes
    ``(name, pos, size, rgba, mu)`` in order (the oil pattern's cells, then the dry back end to
    the deck); ``marks``: visual boxes ``(name, pos, size)`` (the foul line, the arrows);
    ``camera_x``: the ``behind`` camera's x; ``center``, ``extent``: the model's statistics;
    the ball's start ``ball_pos``, and its ``ball_mass`` (kg), principal ``ball_inertia``
    (kg m^2) and ``ball_iquat`` (its inertia axes in the body frame)."""

    start_x: float
    cells: tuple
    marks: tuple
    camera_x: float
    center: tuple
    extent: float
    ball_pos: tuple
    ball_mass: float
    ball_inertia: tuple
    ball_iquat: tuple


def build_spec(lane: LaneLayout | None = None, *, pins: bool = True):
    """An ``mujoco.MjSpec`` of the scene, ball and pins at rest: the one path that builds a
    bowling scene. Without ``lane``, the deck half's: the last 5.5 m of lane (oil, dry back end)
    before the deck. With ``lane``, the full lane of that layout (the lane half's, from the foul
    line: its friction cells replace the 5 m zones, gutters and walls run from its start, its
    marks, camera, statistics and ball's inertia). ``pins=False`` leaves the pin bodies out
    (the lane half's ball-alone run)."""
    import mujoco

    G = mujoco.mjtGeom
    spec = mujoco.MjSpec()
    spec.modelname = "nbst_bowling" if lane is None else "nbst_bowling_lane"
    spec.option.timestep = TIMESTEP
    spec.option.gravity = [0.0, 0.0, -9.81]
    spec.option.enableflags |= int(mujoco.mjtEnableBit.mjENBL_SLEEP)
    spec.option.sleep_tolerance = SLEEP_TOLERANCE
    spec.compiler.inertiafromgeom = int(mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_AUTO)
    spec.visual.global_.offwidth = 1280
    spec.visual.global_.offheight = 720
    spec.stat.center = [-1.0, 0.0, 0.2] if lane is None else list(lane.center)
    spec.stat.extent = 3.0 if lane is None else lane.extent
    start = LANE_START_X if lane is None else lane.start_x
    behind = BALL_START_X - 1.5 if lane is None else lane.camera_x
    wb = spec.worldbody
    wb.add_light(name="sun", pos=[-1.0, 0.0, 4.0], dir=[0.2, 0.0, -1.0],
                 type=int(mujoco.mjtLightType.mjLIGHT_DIRECTIONAL), castshadow=0)
    wb.add_camera(name="behind", pos=[behind, 0.0, 0.9], quat=_look_quat(0.33), fovy=35.0)
    wb.add_camera(name="overhead", pos=[-0.2, 0.0, 3.0], quat=_look_quat(np.pi / 2), fovy=45.0)

    half_w = LANE_WIDTH / 2
    outer = half_w + GUTTER_WIDTH
    x_end = PIT_EDGE_X + PIT_LENGTH
    floor = wb.add_geom(name="floor", type=G.mjGEOM_PLANE, pos=[(LANE_START_X + x_end) / 2, 0, FLOOR_Z],
                        size=[20.0, 20.0, 0.1], rgba=WALL_RGBA)
    _static(floor, MU_FLOOR)
    pp = DECK_PINS if lane is None else LANE_PINS

    slab = 0.05  # half-thickness of the lane boxes
    zones = (("oil", LANE_START_X, OIL_END_X, MU_OIL, OIL_RGBA),
             ("backend", OIL_END_X, DECK_FRONT_X, MU_DRY, LANE_RGBA),
             ("deck", DECK_FRONT_X, PIT_EDGE_X, pp.mu_deck, DECK_RGBA))
    for name, x0, x1, mu, rgba in zones:
        if lane is not None and name != "deck":
            continue  # the lane's own cells replace these (after the pit, below)
        g = wb.add_geom(name=f"lane_{name}", type=G.mjGEOM_BOX, pos=[(x0 + x1) / 2, 0, -slab],
                        size=[(x1 - x0) / 2, half_w, slab], rgba=rgba)
        _static(g, mu)

    # gutters: an arc through the lane edge, the bottom (depth below the lane) and the divider
    chord = GUTTER_WIDTH
    R = (chord**2 / 4 + GUTTER_DEPTH**2) / (2 * GUTTER_DEPTH)
    phi = np.arcsin(chord / 2 / R)
    gx0, gx1 = start, PIT_EDGE_X
    for side, sgn in (("left", 1.0), ("right", -1.0)):
        yc = sgn * (half_w + chord / 2)
        zc = R - GUTTER_DEPTH
        for k in range(GUTTER_PIECES):
            a = -phi + (k + 0.5) * 2 * phi / GUTTER_PIECES  # angle from the bottom
            seg = 2 * R * np.sin(phi / GUTTER_PIECES)
            y = yc + sgn * R * np.sin(a)
            z = zc - R * np.cos(a)
            nrm = np.array([0.0, -sgn * np.sin(a), np.cos(a)])  # inward (up) normal of this piece
            y -= nrm[1] * GUTTER_SHELL
            z -= nrm[2] * GUTTER_SHELL
            ang = np.arctan2(-nrm[1], nrm[2])  # rotation about x taking z to nrm
            g = wb.add_geom(name=f"gutter_{side}{k}", type=G.mjGEOM_BOX, pos=[(gx0 + gx1) / 2, y, z],
                            quat=[np.cos(ang / 2), np.sin(ang / 2), 0.0, 0.0],
                            size=[(gx1 - gx0) / 2, seg / 2 + 1e-3, GUTTER_SHELL], rgba=GUTTER_RGBA)
            _static(g, MU_DRY)
        # divider / kickback: a tall wall outside the gutter, the lane's start to the back of the pit
        g = wb.add_geom(name=f"wall_{side}", type=G.mjGEOM_BOX,
                        pos=[(start + x_end) / 2, sgn * (outer + WALL_THICKNESS / 2),
                             WALL_HEIGHT / 2 - PIT_DEPTH],
                        size=[(x_end - start) / 2, WALL_THICKNESS / 2, WALL_HEIGHT / 2 + PIT_DEPTH / 2],
                        rgba=WALL_RGBA)
        _static(g, MU_DRY)
    g = wb.add_geom(name="pit_floor", type=G.mjGEOM_BOX, pos=[(PIT_EDGE_X + x_end) / 2, 0, -PIT_DEPTH - slab],
                    size=[(x_end - PIT_EDGE_X) / 2, outer, slab], rgba=WALL_RGBA)
    _static(g, MU_DRY)
    g = wb.add_geom(name="pit_cushion", type=G.mjGEOM_BOX,
                    pos=[x_end + WALL_THICKNESS / 2, 0, WALL_HEIGHT / 2 - PIT_DEPTH],
                    size=[WALL_THICKNESS / 2, outer + WALL_THICKNESS, WALL_HEIGHT / 2 + PIT_DEPTH / 2], rgba=WALL_RGBA)
    _static(g, MU_DRY)
    if lane is not None:
        for name, pos, size, rgba, mu in lane.cells:
            g = wb.add_geom(name=name, type=G.mjGEOM_BOX, pos=list(pos), size=list(size), rgba=rgba)
            _static(g, mu)
        for name, pos, size in lane.marks:  # visual only
            g = wb.add_geom(name=name, type=G.mjGEOM_BOX, pos=list(pos), size=list(size),
                            rgba=(0.15, 0.15, 0.2, 1.0), group=1)
            g.contype = g.conaffinity = 0

    geo = pinmod.geometry()
    piece_names = []
    for k, verts in enumerate(geo.pieces):
        m = spec.add_mesh()
        m.name = f"pin_piece{k}"
        m.uservert = verts.ravel().tolist()
        piece_names.append(m.name)
    vis = spec.add_mesh()
    vis.name = "pin_visual"
    vis.uservert = geo.visual_vertices.ravel().tolist()
    vis.userface = geo.visual_faces.ravel().tolist()

    com, inertia = pinmod.mass_properties(pp.mass, pp.com_in)
    for n, (x, y) in zip(PIN_NUMBERS, pin_spots()):
        if not pins:
            break
        body = wb.add_body(name=f"pin{n}", pos=[float(x), float(y), 0.0])
        body.add_freejoint(name=f"pin{n}_free")
        body.explicitinertial = True
        body.mass = pp.mass
        body.ipos = [_six(c) for c in com]  # 6 digits: MuJoCo writes <inertial> so, exactly
        body.inertia = [_six(c) for c in inertia]
        for k, mesh in enumerate(piece_names):
            g = body.add_geom(name=f"pin{n}_c{k}", type=G.mjGEOM_MESH, meshname=mesh, rgba=PIN_RGBA, group=3)
            _body_contact(g, pp.mu_pin_pin, pp.zeta_pin_pin)
        v = body.add_geom(name=f"pin{n}_visual", type=G.mjGEOM_MESH, meshname="pin_visual", rgba=PIN_RGBA, group=1)
        v.contype = v.conaffinity = 0

    ball = wb.add_body(name="ball", pos=[BALL_START_X, 0.0, BALL_RADIUS] if lane is None else list(lane.ball_pos))
    ball.add_freejoint(name="ball_free")
    g = ball.add_geom(name="ball", type=G.mjGEOM_SPHERE, size=[BALL_RADIUS, 0, 0],
                      mass=BALL_MASS if lane is None else lane.ball_mass, rgba=BALL_RGBA)
    _body_contact(g, pp.mu_ball_pin, pp.zeta_ball_pin)
    if pp.separate():  # the ball's own contact with the pins: it outranks them, the surfaces outrank it
        g.priority = 1
        for geom in spec.geoms:
            if geom.priority >= 1 and geom.name != "ball":
                geom.priority = 2
    if lane is not None:  # the ball maker's inertia: explicit, its axes turned by iquat
        ball.explicitinertial = True
        ball.mass = lane.ball_mass
        ball.ipos = [0.0, 0.0, 0.0]
        ball.inertia = list(lane.ball_inertia)
        ball.iquat = list(lane.ball_iquat)
    return spec


def _six(x: float) -> float:
    """x to 6 significant digits: the numbers MuJoCo's writer keeps in elements that
    :func:`scene_xml` cannot rewrite (``<inertial>``) read back exactly."""
    return float(f"{float(x):.6g}")


def _look_quat(pitch: float) -> list:
    """Camera quaternion looking down the lane (+x), tilted down by ``pitch`` rad (6 digits)."""
    # camera axes: x_cam = -y (right on screen is the bowler's right), looking along -z_cam
    c, s = np.cos(pitch), np.sin(pitch)
    fwd = np.array([c, 0.0, -s])
    xc = np.array([0.0, -1.0, 0.0])
    zc = -fwd
    yc = np.cross(zc, xc)
    R = np.column_stack([xc, yc, zc])
    w = np.sqrt(max(1e-12, 1 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    q = np.array([w, (R[2, 1] - R[1, 2]) / (4 * w), (R[0, 2] - R[2, 0]) / (4 * w), (R[1, 0] - R[0, 1]) / (4 * w)])
    return [_six(v) for v in q / np.linalg.norm(q)]


def _static(geom, mu: float) -> None:
    """A static surface: its friction rules (priority 1), critically damped contact."""
    geom.contype = geom.conaffinity = 1
    geom.priority = 1
    geom.condim = 3
    geom.friction = [mu, 0.0, 0.0]
    geom.solref = list(SOLREF_STATIC)


def _body_contact(geom, mu: float = MU_BALL_PIN, zeta: float = SOLREF_BODY[1]) -> None:
    geom.contype = geom.conaffinity = 1
    geom.condim = 3
    geom.friction = [mu, 0.0, 0.0]
    geom.solref = [SOLREF_BODY[0], zeta]


def build_model():
    """The compiled ``mujoco.MjModel`` of :func:`build_spec`."""
    return build_spec().compile()


# --- XML at full precision -------------------------------------------------------------

_EXACT = {
    "option": ("timestep", "gravity", "sleep_tolerance"),
    "statistic": ("extent", "center"),
    "body": ("pos", "quat", "mass", "ipos", "inertia", "fullinertia", "iquat"),
    "geom": ("pos", "quat", "size", "mass", "solref", "solimp", "friction", "margin", "gap", "rgba"),
    "mesh": ("vertex",),
    "camera": ("pos", "quat", "fovy"),
    "light": ("pos", "dir"),
    "key": ("time", "qpos", "qvel"),
}
_SPEC_NAME = {"vertex": "uservert"}


def scene_xml(spec=None) -> str:
    """MJCF text of the scene, every number at full precision (MuJoCo's writer keeps 6 digits).

    Reuses the rewrite of :func:`nbst.models.scene.full_precision` (shortest round-trip
    text, same entries as MuJoCo wrote) for the bowling scene's elements: meshes'
    vertices, bodies' explicit inertia, rotated geoms. A model loaded from the text equals
    :func:`build_model`'s, bit for bit (tests/test_bowling.py).
    """
    spec = build_spec() if spec is None else spec
    spec.compile()
    return full_precision(spec.to_xml(), spec, exact_attrs=_EXACT, spec_names=_SPEC_NAME, float32_attrs=("vertex",))

