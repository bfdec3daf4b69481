"""The ball on the lane: Coulomb friction at the contact point, and the oil that lane and cover trade.

Why not MuJoCo's own friction: its soft contact lifts a sliding, spinning ball off the lane
(no contact in most steps of a throw, up to 0.7 mm of lift) and delivers only 75-90 % of
Coulomb's friction at mu 0.1-0.2, a share that changes with the slip and the timestep
(docs/results/bowling.md, "The ball on the lane"). So the lane is a **frictionless** MuJoCo contact
(condim 1: MuJoCo keeps the normal force and the ball on the lane) and this module applies the
friction by hand, before every step, at the contact point (:func:`contact_step`, one numba
kernel on arrays; ``xfrc_applied`` carries it into ``mj_step``):

* **Coulomb, with stick.** The slip ``u`` is the contact point's horizontal velocity,
  ``v + omega x r`` with ``r = (0, 0, -R)``. The impulse that would stop it within the step is
  ``J = -K^-1 u``, ``K`` the contact point's 2 x 2 inverse mass (``1/m`` plus ``R^2`` times the
  world-frame inverse inertia, the ball's full tensor as it turns). If ``|J| <= mu N h``
  the ball sticks (rolls) and ``J`` is applied; else it slides and ``-mu N h u/|u|`` is.
  ``N = m g`` (a flat lane). The slip of a sliding ball then falls at
  ``mu g (1 + R^2/k^2)`` for a ball of RG ``k``, the textbook rate, at any timestep.
* **Oil.** The lane carries a film (:class:`.oil.OilField`, um by board and 0.25 ft) and the
  ball's cover one more (``cover``: um on :data:`N_CELLS` Fibonacci cells of the sphere, in the
  ball's own frame). Under the contact, a band :attr:`.oil.OilLaw.band_in` wide: the friction
  is the law's ``mu(h_lane + h_cover)``; lane and cover even out a share
  :attr:`.oil.OilLaw.exchange` of their film difference over the areas that pass through the
  band in the step (lane: ``band * |v| h``; cover: ``band * |omega x r| h``; their harmonic
  combination), oil conserved; the cover absorbs its film in ``absorb_s`` (the ball's; 0:
  never). So the track dries as the ball takes oil (depletion), the ball lays it down where
  the lane is drier than its ring (carry-down), and a flaring ball brings a fresh, dry ring to
  the lane each revolution where a ball without flare rolls on its own oily one: the
  differential acts through the oil, as ball makers describe.
* **Bookkeeping** (``acc``): oil moved lane -> cover and absorbed (ml), and the contact's
  friction, films and sliding flag at the last step, so a series (:mod:`.transition`) and the
  tests can account for every millilitre.

Everything is a plain function of arrays; :class:`BallOnLane` holds the arrays of one ball on one
lane for the step loops of :mod:`.phases` and :mod:`.frame`. numba is imported with this module
(which the lane's step loops import when they run, never at ``import nbst``).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from nbst.models.bowling import scene
from nbst.models.bowling.lane.ball import Ball
from nbst.models.bowling.lane.oil import CELL_AREA, DX_FT, LAW, NX, OilField, OilLaw
from nbst.models.bowling.lane.units import BOARD_WIDTH, FOUL_LINE_X, FT, N_BOARDS
from nbst.models.bowling.lane.delivery import quat_to_mat

__all__ = ["N_CELLS", "G", "LIFT_TOL", "cover_cells", "contact_step", "BallOnLane"]

#: Cells of the cover's oil grid (about 0.4 in apart: the 1 in track band covers ~4 of them).
N_CELLS = 2048
G = 9.81
#: :func:`contact_step` scans the cover's cells within this angle (rad) of the contact point's
#: polar angle: wider than the band's half-width (1 in: 0.12 rad) plus the lattice's largest gap
#: to its nearest cell (0.03 rad at 2,048 cells); the kernel checks it and scans every cell when not.
SCAN_RAD = 0.2
#: The ball is on the lane while its centre is less than this above R (m).
LIFT_TOL = 1e-3
#: acc's entries.
A_TO_COVER, A_ABSORBED, A_MU, A_H_LANE, A_H_COVER, A_SLIDING, A_CONTACT, A_STEPS, A_SCALE, A_SUM = range(10)
N_ACC = 10
#: prm's entries.
(P_MASS, P_R, P_MU_COVER, P_MU_OIL, P_H0, P_EXCH, P_BAND_COS, P_BAND_W, P_DECAY, P_H, P_DECK_X, P_HALF_W,
 P_QADR, P_VADR, P_BODY) = range(15)
N_PRM = 15


def cover_cells(n: int = N_CELLS) -> np.ndarray:
    """(n, 3) unit vectors spread evenly over the sphere (a Fibonacci lattice), the ball's frame."""
    i = np.arange(n) + 0.5
    phi = np.arccos(1.0 - 2.0 * i / n)
    th = math.pi * (1.0 + 5.0 ** 0.5) * i
    return np.ascontiguousarray(np.column_stack([np.cos(th) * np.sin(phi), np.sin(th) * np.sin(phi), np.cos(phi)]))


@njit(cache=True, fastmath=False)
def contact_step(qpos, qvel, xfrc, lane_h, cover, cells, prm, iinv_body, acc):  # pragma: no cover - numba
    """Set the ball's ``xfrc_applied`` row for the next step (friction force and torque at the
    contact point, world frame) and trade oil between ``lane_h`` and ``cover`` (both updated in
    place); ``acc`` gathers the bookkeeping. Arrays: MuJoCo's ``qpos``, ``qvel``, ``xfrc_applied``
    (the ball's addresses in ``prm``), the lane film (N_BOARDS, NX) um, the cover film (n,) um
    on ``cells`` (n, 3), ``prm`` (see P_*), the body-frame inverse inertia (3, 3)."""
    qa = int(prm[P_QADR])
    va = int(prm[P_VADR])
    b = int(prm[P_BODY])
    m = prm[P_MASS]
    R = prm[P_R]
    h = prm[P_H]
    for k in range(6):
        xfrc[b, k] = 0.0
    cell_b = 4.0 * math.pi * R * R / cells.shape[0]
    # the cover absorbs its oil, on the lane or not: its film is cover * scale, and the scale decays
    decay = prm[P_DECAY]
    if decay < 1.0:
        acc[A_ABSORBED] += acc[A_SUM] * acc[A_SCALE] * (1.0 - decay) * cell_b
        acc[A_SCALE] *= decay
        if acc[A_SCALE] < 1e-150:  # renormalise before it underflows
            for k in range(cover.shape[0]):
                cover[k] *= acc[A_SCALE]
            acc[A_SUM] *= acc[A_SCALE]
            acc[A_SCALE] = 1.0
    scale = acc[A_SCALE]
    x = qpos[qa]
    y = qpos[qa + 1]
    z = qpos[qa + 2]
    acc[A_CONTACT] = 0.0
    if x >= prm[P_DECK_X] or abs(y) >= prm[P_HALF_W] or z > R + 1e-3:
        return
    acc[A_CONTACT] = 1.0
    acc[A_STEPS] += 1.0
    qw, qx, qy, qz = qpos[qa + 3], qpos[qa + 4], qpos[qa + 5], qpos[qa + 6]
    Rm = np.empty((3, 3))  # numba keeps this small array off the heap in practice
    Rm[0, 0] = 1 - 2 * (qy * qy + qz * qz)
    Rm[0, 1] = 2 * (qx * qy - qw * qz)
    Rm[0, 2] = 2 * (qx * qz + qw * qy)
    Rm[1, 0] = 2 * (qx * qy + qw * qz)
    Rm[1, 1] = 1 - 2 * (qx * qx + qz * qz)
    Rm[1, 2] = 2 * (qy * qz - qw * qx)
    Rm[2, 0] = 2 * (qx * qz - qw * qy)
    Rm[2, 1] = 2 * (qy * qz + qw * qx)
    Rm[2, 2] = 1 - 2 * (qx * qx + qy * qy)
    wb0, wb1, wb2 = qvel[va + 3], qvel[va + 4], qvel[va + 5]
    w0 = Rm[0, 0] * wb0 + Rm[0, 1] * wb1 + Rm[0, 2] * wb2
    w1 = Rm[1, 0] * wb0 + Rm[1, 1] * wb1 + Rm[1, 2] * wb2
    vx, vy = qvel[va], qvel[va + 1]
    # slip of the contact point: v + w x (0, 0, -R)
    ux = vx - w1 * R
    uy = vy + w0 * R
    # ---- oil under the contact
    i = int(math.floor((y + prm[P_HALF_W]) / BOARD_WIDTH))
    i = min(max(i, 0), N_BOARDS - 1)
    j = int(math.floor((x - FOUL_LINE_X) / (DX_FT * FT)))
    j = min(max(j, 0), NX - 1)
    hl = lane_h[i, j]
    # the contact point in the ball's frame: R^T (0, 0, -1)
    c0, c1, c2 = -Rm[2, 0], -Rm[2, 1], -Rm[2, 2]
    band_cos = prm[P_BAND_COS]
    # the cells under the band, found once per step (their indices in ``band``, in cell order):
    # the cosines first (a loop without branches, which the compiler vectorises), then the scan.
    # Only the cells of a Fibonacci lattice (:func:`cover_cells`: cell k at height 1 - 2 (k + 1/2) / n)
    # whose polar angle is within SCAN_RAD of the contact's can be within SCAN_RAD of it: one range of k.
    # The band and the nearest cell lie inside it whenever the nearest is nearer than SCAN_RAD (always,
    # for the lattice's spacing); else every cell is scanned. Either way the same cells, in the same order.
    nc = cells.shape[0]
    phc = math.acos(min(1.0, max(-1.0, c2)))
    k0 = int(math.floor((1.0 - math.cos(max(0.0, phc - SCAN_RAD))) * nc / 2.0 - 0.5)) - 2
    k1 = int(math.ceil((1.0 - math.cos(min(math.pi, phc + SCAN_RAD))) * nc / 2.0 - 0.5)) + 3
    k0 = min(max(k0, 0), nc)
    k1 = min(k1, nc)
    dots = np.empty(nc)
    for k in range(k0, k1):
        dots[k] = cells[k, 0] * c0 + cells[k, 1] * c1 + cells[k, 2] * c2
    best = -2.0
    for k in range(k0, k1):
        if dots[k] > best:
            best = dots[k]
    if best <= math.cos(SCAN_RAD) + 1e-9 or band_cos <= math.cos(SCAN_RAD) + 1e-9:  # scan them all
        for k in range(0, k0):
            dots[k] = cells[k, 0] * c0 + cells[k, 1] * c1 + cells[k, 2] * c2
        for k in range(k1, nc):
            dots[k] = cells[k, 0] * c0 + cells[k, 1] * c1 + cells[k, 2] * c2
        k0 = 0
        k1 = nc
    band = np.empty(nc, dtype=np.int64)
    nn = 0
    hsum = 0.0
    best = -2.0
    kbest = 0
    for k in range(k0, k1):
        d = dots[k]
        if d > band_cos:
            band[nn] = k
            nn += 1
            hsum += cover[k]
        if d > best:
            best = d
            kbest = k
    nb = nn  # cells the exchange touches (``band[:nb]``)
    if nn == 0:  # the band falls between cells: the nearest one's film (the exchange: any as near within 1e-12)
        nn = 1
        hsum = cover[kbest]
        band_cos = best - 1e-12
        for k in range(k0, k1):
            if dots[k] > band_cos:
                band[nb] = k
                nb += 1
    hsum *= scale
    hb = hsum / nn
    mu = prm[P_MU_OIL] + (prm[P_MU_COVER] - prm[P_MU_OIL]) * math.exp(-(hl + hb) / prm[P_H0])
    acc[A_MU] = mu
    acc[A_H_LANE] = hl
    acc[A_H_COVER] = hb
    # ---- exchange over the areas swept through the band this step
    speed = math.sqrt(vx * vx + vy * vy)
    wr = R * math.sqrt(w0 * w0 + w1 * w1)  # |w x r| for r vertical
    a_l = prm[P_BAND_W] * speed * h
    a_b = prm[P_BAND_W] * wr * h
    if prm[P_EXCH] > 0.0 and a_l > 0.0 and a_b > 0.0:
        dv = prm[P_EXCH] * (hl - hb) * a_l * a_b / (a_l + a_b)  # ml, lane -> cover
        if dv > 0.0:
            dv = min(dv, hl * CELL_AREA)
            lane_h[i, j] = hl - dv / CELL_AREA
            add = dv / (nn * cell_b) / scale
            for t_ in range(nb):
                cover[band[t_]] += add
                acc[A_SUM] += add
        elif dv < 0.0 and hsum > 0.0:
            f = min(-dv / (hsum * cell_b), 1.0)
            moved = 0.0
            for t_ in range(nb):
                k = band[t_]
                take = cover[k] * f
                cover[k] -= take
                moved += take
            acc[A_SUM] -= moved
            dv = -moved * scale * cell_b
            lane_h[i, j] = hl - dv / CELL_AREA
        else:
            dv = 0.0
        acc[A_TO_COVER] += dv
    # ---- Coulomb with stick: the impulse that stops the slip within the step, capped at mu N h
    A = np.empty((3, 3))  # world-frame inverse inertia: Rm Ib^-1 Rm^T
    for r_ in range(3):
        for s_ in range(3):
            t = 0.0
            for p_ in range(3):
                for q_ in range(3):
                    t += Rm[r_, p_] * iinv_body[p_, q_] * Rm[s_, q_]
            A[r_, s_] = t
    k00 = 1.0 / m + R * R * A[1, 1]
    k01 = -R * R * A[1, 0]
    k11 = 1.0 / m + R * R * A[0, 0]
    det = k00 * k11 - k01 * k01
    jx = -(k11 * ux - k01 * uy) / det
    jy = -(-k01 * ux + k00 * uy) / det
    jmax = mu * m * G * h
    jn = math.sqrt(jx * jx + jy * jy)
    un = math.sqrt(ux * ux + uy * uy)
    if jn > jmax and un > 0.0:
        jx = -jmax * ux / un
        jy = -jmax * uy / un
        acc[A_SLIDING] = 1.0
    else:
        acc[A_SLIDING] = 0.0
    fx = jx / h
    fy = jy / h
    xfrc[b, 0] = fx
    xfrc[b, 1] = fy
    # torque r x F, r = (0, 0, -R)
    xfrc[b, 3] = R * fy
    xfrc[b, 4] = -R * fx


class BallOnLane:
    """The arrays of one ball on one lane for :func:`contact_step`: the model's ball (its mass and
    inertia as MuJoCo integrates them), the lane's :class:`.oil.OilField` (worn in place), the
    cover's film (fresh and dry unless given), the law and the bookkeeping."""

    def __init__(self, model, ball: Ball, field: OilField, law: OilLaw = LAW, cover: np.ndarray | None = None):
        law = law.check(ball.friction)
        j = model.joint("ball_free")
        body = model.body("ball")
        bid = int(body.id)
        h = float(model.opt.timestep)
        self.field = field
        self.law = law
        self.cells = _CELLS
        self.cover = np.zeros(N_CELLS) if cover is None else np.ascontiguousarray(cover, dtype=np.float64)
        self.acc = np.zeros(N_ACC)
        self.acc[A_SCALE] = 1.0
        self.acc[A_SUM] = float(self.cover.sum())
        self._views: tuple | None = None
        R = scene.BALL_RADIUS
        prm = np.zeros(N_PRM)
        prm[P_MASS] = float(model.body_mass[bid])
        prm[P_R] = R
        prm[P_MU_COVER] = ball.friction
        prm[P_MU_OIL] = law.mu_oil
        prm[P_H0] = law.h0_um
        prm[P_EXCH] = law.exchange
        prm[P_BAND_COS] = math.cos(law.band_in * scene.INCH / 2 / R)
        prm[P_BAND_W] = law.band_in * scene.INCH
        prm[P_DECAY] = math.exp(-h / ball.absorb_s) if ball.absorb_s > 0 else 1.0
        prm[P_H] = h
        prm[P_DECK_X] = scene.DECK_FRONT_X
        prm[P_HALF_W] = scene.LANE_WIDTH / 2
        prm[P_QADR], prm[P_VADR], prm[P_BODY] = int(j.qposadr[0]), int(j.dofadr[0]), bid
        self.prm = prm
        q = np.array(model.body_iquat[bid], dtype=float)

        Q = quat_to_mat(q[None])[0]
        self.iinv_body = np.ascontiguousarray(Q @ np.diag(1.0 / np.array(model.body_inertia[bid])) @ Q.T)

    def step(self, data) -> None:
        """Set the friction for the next ``mj_step`` of ``data`` (and trade oil)."""
        v = self._views
        if v is None or v[0] is not data:
            v = self._views = (data, data.qpos, data.qvel, data.xfrc_applied)
        contact_step(v[1], v[2], v[3], self.field.h, self.cover, self.cells, self.prm, self.iinv_body, self.acc)

    def cover_film(self) -> np.ndarray:
        """(N_CELLS,) the cover's film now (um)."""
        return self.cover * self.acc[A_SCALE]

    @property
    def on_lane(self) -> bool:
        return bool(self.acc[A_CONTACT])

    def oil_ml(self) -> dict:
        """Where the oil went: lane now, on the cover now, absorbed, taken from the lane (net)."""
        cell_b = 4.0 * math.pi * scene.BALL_RADIUS ** 2 / N_CELLS
        return {"lane": self.field.total_ml(), "cover": float(self.cover_film().sum() * cell_b),
                "absorbed": float(self.acc[A_ABSORBED]), "taken": float(self.acc[A_TO_COVER])}


_CELLS = cover_cells()
_CELLS.setflags(write=False)
