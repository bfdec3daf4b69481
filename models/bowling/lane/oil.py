"""Oil as data: pattern files, the film they lay on the lane, and the law from film to friction.

* **Pattern file** (``nbst-oil-pattern``, one pattern per JSON file, :func:`load_pattern`).
  **Version 2 is a lane machine's pattern sheet** (Kegel's layout): ``rows``, in the order the
  machine runs them, each ``{"pass": "forward"|"reverse", "boards": "2L-2R", "loads": n,
  "ul": microlitres per board per load, "speed": in/s, "start_ft": a, "end_ft": b}`` (``n`` loads
  of ``ul`` on every board from ``2L`` (board 2 counted from the left edge) to ``2R`` (board 2
  from the right; written left to right, as the machine lays it: ``2R-2L`` is refused), laid evenly
  from ``a`` to ``b`` ft past the foul line), or a **buff** row
  ``{"pass": ..., "buff": true, "start_ft": a, "end_ft": b}``: the brush alone over ``a``-``b``,
  in the pass's direction (:func:`buffed`). The volume (``loads x boards x ul``, less what the
  brush lifts off), the length and the ratio are **computed** from the rows, never entered:
  :meth:`Pattern.sheet` prints them. ``source`` names where the numbers come from and
  ``published`` holds what the source states (length, volumes, ratios) for comparison.
  **Version 1** (still read; the house shots ship in it) gives each pass's length and volume
  and its lateral shape: ``units`` per board (39 relative numbers) or ``loads``
  (``[[from_left, to_right, n], ...]``), the pass's volume spread over its boards in their
  proportion, with an optional linear ``taper_ft``/``taper_to`` buff-out.
  Every problem is one :class:`~.units.LaneError` line naming the file and the field.
* **Film** (:meth:`Pattern.grid`): oil thickness in micrometres (um = ml/m^2) on cells of one
  board x :data:`DX_FT` from the foul line to the pin deck, the passes added. A right-hander
  and a left-hander share the grid (it is indexed by the lane's own y, not by the hand), so a
  left-hander plays the mirrored side (:class:`OilField`: the lane's state, which a series
  of throws wears, see :mod:`.friction`).
* **Law** (:class:`OilLaw`): the friction at the contact is
  ``mu = mu_oil + (mu_cover - mu_oil) exp(-h / h0)`` with ``h`` the film under the contact (lane
  film + the film the ball's cover carries there), ``mu_oil`` = 0.04 (full film, Frohlich),
  ``mu_cover`` the ball's coverstock friction on the dry lane, and ``h0`` fitted
  (docs/bowling.md: a typical release breaks at 40-45 ft on boards 5-8 of the house shot).

The shipped patterns (``patterns/*.json`` beside this module) are registered once in
:data:`PATTERNS` (an :class:`nbst.registry.Registry`); :func:`pattern` resolves a registered
name or a pattern file's path (any suffix); ``--oil`` (:func:`argtype`) reads a value that names an
existing path as that file, even one named like a shipped pattern.

Pure Python and numpy; reading a pattern file goes through :mod:`nbst.models.bowling.files`.

Length: ~700 lines, past the house's ~500: one file format in two versions (a sheet's rows and the
passes of version 1), each field checked with its own one-line refusal, the film each lays, the
brush, the sheet's printout, and the law from film to friction that reads that film.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from nbst.models.bowling import files, scene
from nbst.models.bowling.lane.units import BOARD_WIDTH, FT, N_BOARDS, LaneError, x_to_ft
from nbst.registry import Registry

__all__ = ["MU_OIL", "MU_DRY", "FORMAT", "PATTERNS_DIR", "PATTERNS", "DEFAULT_OIL", "DX_FT", "NX", "CELL_AREA",
           "BUFF_CARRY_FT", "RATIO_FT", "Pass", "Row", "Pattern", "OilLaw", "LAW", "OilField", "buffed", "load_pattern",
           "pattern_from_dict", "pattern", "oil_name", "board_of"]

#: Friction of a full oil film (Frohlich's figure, as scene.MU_OIL) and of the dry lane for
#: the default ball (scene.MU_DRY); the ball's coverstock friction replaces the latter.
MU_OIL = scene.MU_OIL
MU_DRY = scene.MU_DRY
FORMAT = "nbst-oil-pattern"
VERSION = 2
#: Versions read: 1 (passes with a volume and a lateral shape), 2 (a pattern sheet's rows).
VERSIONS = (1, 2)
PATTERNS_DIR = Path(__file__).with_name("patterns")
#: The film grid: cells of one board by DX_FT ft, from the foul line to the pin deck's front.
DX_FT = 0.25
NX = int(math.floor(float(x_to_ft(scene.DECK_FRONT_X)) / DX_FT))
CELL_AREA = BOARD_WIDTH * DX_FT * FT  # m^2
#: The shipped patterns, in the order they are listed.
SHIPPED = ("house", "house-short", "house-long", "sport-short", "sport", "sport-long", "short", "flat", "uniform",
           "pba-house", "kegel-boardwalk", "pba-chameleon", "pba-cheetah")
#: The brush's carry length (ft): over it the brush evens out with the film it passes (:func:`buffed`;
#: assumed: no published figure found).
BUFF_CARRY_FT = 2.0
#: Where :meth:`Pattern.ratio` reads a pattern without a published ratio distance (ft).
RATIO_FT = 10.0
#: A lane machine's travel speeds a sheet may give (in/s).
SPEED_RANGE = (1.0, 60.0)


class _Shipped(str):
    """A shipped pattern's name that :func:`argtype` never reads as a path: argparse passes a text
    default through ``type=``, and a file named ``house`` in the working folder must not replace
    the pattern of a throw whose ``--oil`` was not given."""


#: The pattern a throw is bowled on when none is named (``--oil``'s default).
DEFAULT_OIL = _Shipped("house")


@dataclass(frozen=True)
class Pass:
    """One pass of the lane machine: oil to ``length_ft``, ``volume_ml`` in all, ``units`` per board
    (39, board 1 the right-hander's right edge), the last ``taper_ft`` thinning to ``taper_to``."""

    length_ft: float
    volume_ml: float
    units: tuple
    taper_ft: float = 0.0
    taper_to: float = 1.0

    def shape_x(self, ft: np.ndarray) -> np.ndarray:
        ft = np.asarray(ft, dtype=float)
        s = np.where(ft < self.length_ft, 1.0, 0.0)
        if self.taper_ft > 0:
            t0 = self.length_ft - self.taper_ft
            ramp = 1.0 - (1.0 - self.taper_to) * (ft - t0) / self.taper_ft
            s = np.where((ft > t0) & (ft < self.length_ft), ramp, s)
        return s

    def to_dict(self) -> dict:
        d = {"length_ft": self.length_ft, "volume_ml": self.volume_ml, "units": list(self.units)}
        if self.taper_ft:
            d["taper_ft"], d["taper_to"] = self.taper_ft, self.taper_to
        return d


def board_of(text, where: str) -> int:
    """A sheet's board (``"2L"``: board 2 from the left edge; ``"2R"``: from the right; a bare number:
    the lane's board counted from the right edge, as a right-hander's) as the lane's board 1..39."""
    t = str(text).strip().upper() if isinstance(text, (str, int)) and not isinstance(text, bool) else ""
    side = t[-1:] if t[-1:] in ("L", "R") else "R"
    num = t[:-1] if t[-1:] in ("L", "R") else t
    if not num.isdigit() or not 1 <= int(num) <= N_BOARDS:
        raise LaneError(f"{where}: must be a board 1L..39L or 1R..39R (e.g. 2L-2R), got {text!r}")
    n = int(num)
    return N_BOARDS + 1 - n if side == "L" else n


@dataclass(frozen=True)
class Row:
    """One row of a pattern sheet: ``loads`` loads of ``ul`` microlitres on every board ``lo``..``hi``
    (the lane's boards, 1 = the right-hander's right edge) laid evenly over ``start_ft``-``end_ft``,
    in the ``direction`` pass at ``speed`` in/s; or, ``buff``, the brush alone over that range."""

    direction: str
    start_ft: float
    end_ft: float
    boards: str = ""
    lo: int = 0
    hi: int = 0
    loads: float = 0.0
    ul: float = 0.0
    speed: float = 0.0
    buff: bool = False

    @property
    def n_boards(self) -> int:
        return 0 if self.buff else self.hi - self.lo + 1

    @property
    def volume_ml(self) -> float:
        """The oil the row lays (ml): loads x boards x microlitres."""
        return 0.0 if self.buff else self.loads * self.n_boards * self.ul / 1000.0

    def span(self) -> tuple[float, float]:
        return min(self.start_ft, self.end_ft), max(self.start_ft, self.end_ft)

    def to_dict(self) -> dict:
        d: dict = {"pass": self.direction}
        if self.buff:
            d["buff"] = True
        else:
            d.update({"boards": self.boards, "loads": self.loads, "ul": self.ul, "speed": self.speed})
        d.update({"start_ft": self.start_ft, "end_ft": self.end_ft})
        return d


def buffed(h: np.ndarray, a_ft: float, b_ft: float, direction: str, carry_ft: float = BUFF_CARRY_FT) -> float:
    """The brush alone over ``a_ft``-``b_ft`` of the film ``h`` (N_BOARDS, NX; um; changed in place),
    travelling down the lane (``forward``) or back to the foul line (``reverse``): it drops clean and,
    on each cell it crosses, it and the cell share their oil in proportion to their areas (the
    brush as ``carry_ft`` of board, the cell as the part of it in the range), so it lifts oil where
    the lane is wetter than it and lays it where drier, over about ``carry_ft``. At the range's
    end it lifts with what it holds: that oil leaves the lane. Returns the ml it took away."""
    lo, hi = min(a_ft, b_ft), max(a_ft, b_ft)
    j0, j1 = int(math.floor(lo / DX_FT)), min(int(math.ceil(hi / DX_FT)), NX)
    cols = range(j0, j1) if direction == "forward" else range(j1 - 1, j0 - 1, -1)
    brush = np.zeros(N_BOARDS)  # ml per board
    a_b = carry_ft * FT * BOARD_WIDTH
    for j in cols:
        frac = (min(hi, (j + 1) * DX_FT) - max(lo, j * DX_FT)) / DX_FT
        if frac <= 0:
            continue
        a_c = CELL_AREA * frac
        total = h[:, j] * a_c + brush
        h[:, j] += (total * a_c / (a_c + a_b) - h[:, j] * a_c) / CELL_AREA
        brush = total * a_b / (a_c + a_b)
    return float(brush.sum())


@dataclass(frozen=True)
class Pattern:
    """An oil pattern: a sheet's ``rows`` (version 2), or ``passes`` (version 1, forward first).
    See the module docstring."""

    name: str
    description: str
    passes: tuple = ()
    rows: tuple = ()
    source: str = ""
    published: tuple = ()  # (key, value) pairs, as the file's "published" object
    ratio_ft: float = RATIO_FT

    @property
    def length_ft(self) -> float:
        """Where the pattern ends: the longest pass, or the far end of the last cell the rows leave oil on."""
        if not self.rows:
            return max(p.length_ft for p in self.passes)
        g = _grid(self)
        wet = np.nonzero(g.max(axis=0) > 0)[0]
        far = max(r.span()[1] for r in self.rows)
        return float(min((wet[-1] + 1) * DX_FT, far)) if len(wet) else 0.0

    @property
    def volume_ml(self) -> float:
        """The oil on the lane (ml): the passes' volumes, or the rows' less what the brush lifted."""
        if not self.rows:
            return float(sum(p.volume_ml for p in self.passes))
        return float(_grid(self).sum() * CELL_AREA)

    def applied_ml(self, direction: str | None = None) -> float:
        """The oil the rows (of the ``direction`` pass, or all) lay, before any buffing (ml)."""
        if not self.rows:
            return float(sum(p.volume_ml for k, p in enumerate(self.passes)
                             if direction is None or direction == ("forward", "reverse")[k]))
        return float(sum(r.volume_ml for r in self.rows if direction is None or r.direction == direction))

    def grid(self) -> np.ndarray:
        """(N_BOARDS, NX) oil film, um, cell centres (a new array each call)."""
        return _grid(self).copy()

    def film_at(self, ft: float, board: float) -> float:
        """Film (um) at ``ft`` past the foul line on (continuous, right-hander's) ``board``; 0 past the pattern."""
        j = int(math.floor(ft / DX_FT))
        if not 0 <= j < NX or not board == board:
            return 0.0
        i = min(max(int(math.floor(board - 0.5)), 0), N_BOARDS - 1)
        return float(_grid(self)[i, j])

    def symmetric(self) -> bool:
        """Whether board b and board 40 - b carry the same oil everywhere (mirror-symmetric)."""
        g = _grid(self)
        return bool(np.allclose(g, g[::-1], rtol=1e-12, atol=1e-15))

    def ratio(self, ft: float | None = None) -> float:
        """Inside over outside at ``ft`` (default :attr:`ratio_ft`): the mean film of boards 18-22 over
        that of boards 3 and 37 (our reading of USBC's "oil in the middle compared to the outside")."""
        ft = self.ratio_ft if ft is None else ft
        g = _grid(self)[:, min(int(ft / DX_FT), NX - 1)]
        out = (g[2] + g[36]) / 2
        return float(g[17:22].mean() / out) if out > 0 else math.inf

    def summary(self) -> str:
        """One line: length, volume and ratio, as computed."""
        r = self.ratio()
        if math.isfinite(r):
            said = f"{r:.2f}:1"
        else:   # nothing on boards 3 and 37: all the oil inside (or none at all), never "flat" (1:1)
            g = _grid(self)[:, min(int(self.ratio_ft / DX_FT), NX - 1)]
            said = "no oil on boards 3 and 37 (ratio infinite)" if g[17:22].mean() > 0 else "dry"
        return f"{self.length_ft:g} ft, {self.volume_ml:.2f} ml, {said} at {self.ratio_ft:g} ft"

    def sheet(self) -> str:
        """The pattern as a sheet: its rows with the oil each lays, the totals, the length and the ratios,
        all computed; then what the source published."""
        lines = [f"{self.name}: {self.description}"]
        if self.source:
            lines.append(f"source: {self.source}")
        if self.rows:
            lines.append(f"{'#':>3} {'pass':8} {'boards':8} {'loads':>5} {'ul':>5} {'speed':>5} {'start':>6} {'end':>6} {'ml':>6}")
            for k, r in enumerate(self.rows, 1):
                if r.buff:
                    lines.append(f"{k:>3} {r.direction:8} {'buff':8} {'':>5} {'':>5} {'':>5} {r.start_ft:>6g} {r.end_ft:>6g}")
                else:
                    lines.append(f"{k:>3} {r.direction:8} {r.boards:8} {r.loads:>5g} {r.ul:>5g} {r.speed:>5g} "
                                 f"{r.start_ft:>6g} {r.end_ft:>6g} {r.volume_ml:>6.2f}")
        fw, rv = self.applied_ml("forward"), self.applied_ml("reverse")
        lines.append(f"volume: forward {fw:.2f} ml, reverse {rv:.2f} ml, laid {fw + rv:.2f} ml; on the lane "
                     f"{self.volume_ml:.2f} ml (the brush lifted {max(fw + rv - self.volume_ml, 0.0):.2f} ml)")
        at = {self.ratio_ft, 10.0, 22.0}
        for k, v in self.published:
            if k == "ratio" and isinstance(v, tuple):
                at |= {float(x[0]) for x in v if isinstance(x, tuple) and x and isinstance(x[0], (int, float))}
        rs = ", ".join(f"{self.ratio(ft):.2f}:1 at {ft:g} ft" for ft in sorted(at) if ft < self.length_ft)
        lines.append(f"length: {self.length_ft:g} ft; ratio (boards 18-22 over 3 and 37): {rs}")
        if self.published:
            lines.append("published: " + ", ".join(f"{k} {v}" for k, v in self.published))
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """The pattern as a pattern file's content (:func:`pattern_from_dict` reads it back)."""
        if self.rows:
            d = {"format": FORMAT, "version": 2, "name": self.name, "description": self.description}
            if self.source:
                d["source"] = self.source
            if self.published:
                d["published"] = {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.published}
            if self.ratio_ft != RATIO_FT:
                d["ratio_ft"] = self.ratio_ft
            d["rows"] = [r.to_dict() for r in self.rows]
            return d
        d = {"format": FORMAT, "version": 1, "name": self.name, "description": self.description,
             "forward": self.passes[0].to_dict()}
        if len(self.passes) > 1:
            d["reverse"] = self.passes[1].to_dict()
        return d


@lru_cache(maxsize=64)
def _grid(p: Pattern) -> np.ndarray:
    g = np.zeros((N_BOARDS, NX))
    if p.rows:
        edges = np.arange(NX + 1) * DX_FT
        for r in p.rows:
            a, b = r.span()
            if r.buff:
                buffed(g, a, b, r.direction)
                continue
            w = np.clip(np.minimum(edges[1:], b) - np.maximum(edges[:-1], a), 0.0, None) / (b - a)
            g[r.lo - 1:r.hi, :] += (r.loads * r.ul * 1e-3 / CELL_AREA) * w[None, :]  # ml per board -> um
        g.setflags(write=False)
        return g
    xs = (np.arange(NX) + 0.5) * DX_FT
    for ps in p.passes:
        lat = np.asarray(ps.units, dtype=float)
        cells = np.outer(lat, ps.shape_x(xs))
        total = cells.sum() * CELL_AREA
        if total > 0:
            g += cells * (ps.volume_ml / total)  # ml / m^2 = um
    g.setflags(write=False)
    return g


@dataclass(frozen=True)
class OilLaw:
    """Film to friction, and how the ball's cover trades oil with the lane (see :mod:`.friction`).

    ``mu_oil``: friction on a full film; ``h0_um``: the film at which the dry excess falls to 1/e;
    ``exchange``: the share of the film difference that the contact band evens out as lane and
    cover pass through it; ``band_in``: the width of the contact band (the track's width)."""

    mu_oil: float = MU_OIL
    h0_um: float = 0.2
    exchange: float = 0.3
    band_in: float = 1.0

    def mu(self, mu_cover: float, h_um: float) -> float:
        return self.mu_oil + (mu_cover - self.mu_oil) * math.exp(-h_um / self.h0_um)

    def check(self, mu_cover: float | None = None) -> OilLaw:
        for k, (lo, hi) in {"mu_oil": (0.0, 0.3), "h0_um": (1e-3, 100.0), "exchange": (0.0, 1.0),
                            "band_in": (0.05, 4.0)}.items():
            v = getattr(self, k)
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v) or not lo < v <= hi:
                raise LaneError(f"oil law {k}: must be a number in ({lo:g}, {hi:g}], got {v!r}")
        if mu_cover is not None and not self.mu_oil < mu_cover:
            raise LaneError(f"mu_oil: {self.mu_oil:g} must be below the ball's coverstock friction {mu_cover:g}")
        return self


#: The law the lane runs (its h0 fitted: docs/bowling.md, benchmarks/bench_ball_motion.py).
LAW = OilLaw()


class OilField:
    """The lane's oil now: ``h`` (N_BOARDS, NX) film (um) by board (the lane's y: index 0 is the
    right-hander's board 1) and distance; the throws of a series share one and wear it."""

    def __init__(self, h: np.ndarray, name: str = ""):
        self.h = np.ascontiguousarray(h, dtype=np.float64)
        if self.h.shape != (N_BOARDS, NX):
            raise LaneError(f"oil field: must be {N_BOARDS} x {NX} cells, got {self.h.shape}")
        self.name = name

    @classmethod
    def fresh(cls, pat: Pattern) -> OilField:
        return cls(pat.grid(), pat.name)

    def copy(self) -> OilField:
        return OilField(self.h.copy(), self.name)

    def total_ml(self) -> float:
        return float(self.h.sum() * CELL_AREA)

    def ml_past(self, ft: float) -> float:
        """Oil (ml) from ``ft`` past the foul line to the deck."""
        j = int(math.ceil(ft / DX_FT))
        return float(self.h[:, j:].sum() * CELL_AREA)


# --------------------------------------------------------------------------- files


#: A field the file does not give (``d.get(key, _MISSING)``): refused as "missing", where a ``null`` is "got None".
_MISSING = object()


def _num(v, where: str, lo: float, hi: float, *, open_lo: bool = False) -> float:
    """``v`` as a float in [lo, hi] (``(lo, hi]`` with ``open_lo``); missing, not a number and out of
    range each refused in one line that states the same domain."""
    dom = f"{'(' if open_lo else '['}{lo:g}, {hi:g}]"
    if v is _MISSING:
        raise LaneError(f"{where}: missing (a number in {dom})")
    if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
        raise LaneError(f"{where}: must be a number in {dom}, got {v!r}")
    if v < lo or v > hi or (open_lo and v == lo):
        raise LaneError(f"{where}: must be in {dom}, got {v!r}")
    return float(v)


def _units(d: dict, where: str) -> tuple:
    if ("units" in d) == ("loads" in d):
        raise LaneError(f"{where}: give either units (39 numbers, board 1..39) or loads ([[from_left, to_right, n], "
                        f"...]), not {'both' if 'units' in d else 'neither'}")
    if "units" in d:
        u = d["units"]
        if not isinstance(u, list) or len(u) != N_BOARDS:
            raise LaneError(f"{where}.units: must be a list of {N_BOARDS} numbers (board 1..{N_BOARDS}), got "
                            f"{len(u) if isinstance(u, list) else type(u).__name__}")
        out = tuple(_num(v, f"{where}.units[{k}]", 0.0, 1e6) for k, v in enumerate(u))
    else:
        loads = d["loads"]
        if not isinstance(loads, list) or not loads:
            raise LaneError(f"{where}.loads: must be a non-empty list of [from_left, to_right, n]")
        acc = np.zeros(N_BOARDS)
        for k, row in enumerate(loads):
            w = f"{where}.loads[{k}]"
            if not isinstance(row, list) or len(row) != 3:
                raise LaneError(f"{w}: must be [from_left, to_right, n] (e.g. [2, 2, 3]: 2L-2R, 3 loads), got {row!r}")
            a = _num(row[0], f"{w}[0]", 1, N_BOARDS)
            b = _num(row[1], f"{w}[1]", 1, N_BOARDS)
            n = _num(row[2], f"{w}[2]", 0, 1e6)
            if a != int(a) or b != int(b):
                raise LaneError(f"{w}: boards must be whole numbers, got {row[0]!r}, {row[1]!r}")
            lo, hi = int(b), N_BOARDS + 1 - int(a)  # right-hander's boards: to_right .. 40 - from_left
            if lo > hi:
                raise LaneError(f"{w}: {int(a)}L to {int(b)}R crosses itself (no board between)")
            acc[lo - 1:hi] += n
        out = tuple(float(v) for v in acc)
    if sum(out) <= 0:
        raise LaneError(f"{where}: the units must not all be zero")
    return out


def _pass(d, where: str) -> Pass:
    if not isinstance(d, dict):
        raise LaneError(f"{where}: must be an object (length_ft, volume_ml, units or loads)")
    deck_ft = NX * DX_FT
    length = _num(d.get("length_ft", _MISSING), f"{where}.length_ft", 0.0, deck_ft, open_lo=True)
    vol = _num(d.get("volume_ml", _MISSING), f"{where}.volume_ml", 0.0, 200.0)
    taper = _num(d.get("taper_ft", 0.0), f"{where}.taper_ft", 0.0, length)
    to = _num(d.get("taper_to", 1.0), f"{where}.taper_to", 0.0, 1.0)
    return Pass(length, vol, _units(d, where), taper, to)


def _row(d, where: str) -> Row:
    if not isinstance(d, dict):
        raise LaneError(f"{where}: must be an object (pass, boards, loads, ul, speed, start_ft, end_ft; or buff)")
    deck_ft = NX * DX_FT
    known = {"pass", "buff", "boards", "loads", "ul", "speed", "start_ft", "end_ft"}
    extra = sorted(set(d) - known)
    if extra:
        raise LaneError(f"{where}.{extra[0]}: not a row field (fields: {', '.join(sorted(known))})")
    direction = d.get("pass", _MISSING)
    if direction is _MISSING:
        raise LaneError(f"{where}.pass: missing ('forward' or 'reverse')")
    if direction not in ("forward", "reverse"):
        raise LaneError(f"{where}.pass: must be 'forward' or 'reverse', got {direction!r}")
    a = _num(d.get("start_ft", _MISSING), f"{where}.start_ft", 0.0, deck_ft)
    b = _num(d.get("end_ft", _MISSING), f"{where}.end_ft", 0.0, deck_ft)
    if a == b:
        raise LaneError(f"{where}.end_ft: must differ from start_ft ({a:g} ft): a row covers a distance")
    buff = d.get("buff", False)
    if not isinstance(buff, bool):
        raise LaneError(f"{where}.buff: must be true or false, got {buff!r}")
    if buff:
        for k in ("boards", "loads", "ul", "speed"):
            if k in d:
                raise LaneError(f"{where}.{k}: a buff row is the brush alone (pass, start_ft, end_ft), no {k}")
        return Row(direction, a, b, buff=True)
    text = d.get("boards", _MISSING)
    form = "'FROM-TO' as a sheet writes it, left to right: e.g. '2L-2R', '10L-10R', '2L-15L'"
    if text is _MISSING:
        raise LaneError(f"{where}.boards: missing ({form})")
    if not isinstance(text, str) or text.count("-") != 1:
        raise LaneError(f"{where}.boards: must be {form}, got {text!r}")
    first, last = text.split("-")
    x, y = (board_of(t, f"{where}.boards") for t in (first, last))
    if x < y:  # the lane's boards count from the right edge: the first board is right of the last
        raise LaneError(f"{where}.boards: must run left to right, as a sheet writes it and the machine lays it "
                        f"(e.g. '2L-2R', '2L-15L'), got {text!r}: its first board is right of its last (for "
                        f"these boards write '{last.strip().upper()}-{first.strip().upper()}')")
    loads = _num(d.get("loads", _MISSING), f"{where}.loads", 0.0, 100.0, open_lo=True)
    ul = _num(d.get("ul", _MISSING), f"{where}.ul", 0.0, 500.0, open_lo=True)
    speed = _num(d.get("speed", _MISSING), f"{where}.speed", *SPEED_RANGE)
    return Row(direction, a, b, text.strip().upper(), y, x, loads, ul, speed)


#: A pattern file's fields (version 2 gives rows, version 1 forward/reverse passes); another is refused.
_TOP_KEYS = frozenset({"format", "version", "name", "description", "source", "published", "ratio_ft", "rows",
                       "forward", "reverse"})
#: The most oil (ml) a pattern file may lay on one lane: four times the published sheets shipped (21-25 ml).
MAX_VOLUME_ML = 100.0


def _frozen(v):
    return tuple(_frozen(x) for x in v) if isinstance(v, list) else v


def _rows_pattern(doc: dict, src: str, name: str, desc: str) -> Pattern:
    rows = doc.get("rows")
    if not isinstance(rows, list) or not rows or len(rows) > 200:
        raise LaneError(f"{src}: rows: must be a list of 1 to 200 rows (a pattern sheet's load rows)")
    out = tuple(_row(r, f"{src}: rows[{k}]") for k, r in enumerate(rows))
    if not any(not r.buff for r in out):
        raise LaneError(f"{src}: rows: no row lays oil (only buff rows)")
    for k in ("forward", "reverse"):
        if k in doc:
            raise LaneError(f"{src}: {k}: version 2 gives rows (each with its pass), not {k}")
    source = doc.get("source", "")
    if not isinstance(source, str) or len(source) > 600:
        raise LaneError(f"{src}: source: must be a text of at most 600 characters")
    pub = doc.get("published", {})
    if not isinstance(pub, dict):
        raise LaneError(f"{src}: published: must be an object (what the source states)")
    ratio_ft = _num(doc.get("ratio_ft", RATIO_FT), f"{src}: ratio_ft", 0.0, NX * DX_FT, open_lo=True)
    pat = Pattern(name, desc, rows=out, source=source, published=tuple((k, _frozen(v)) for k, v in pub.items()),
                  ratio_ft=ratio_ft)
    if pat.volume_ml <= 0:
        raise LaneError(f"{src}: rows: the brush leaves no oil on the lane")
    if pat.volume_ml > MAX_VOLUME_ML:
        raise LaneError(f"{src}: rows: lay {pat.volume_ml:,.0f} ml on one lane, more than {MAX_VOLUME_ML:g} ml (the "
                        f"published sheets shipped lay 21-25 ml): check each row's loads and ul (microlitres a board)")
    return pat


def pattern_from_dict(doc, src: str = "<pattern>") -> Pattern:
    """A pattern file's decoded content as a :class:`Pattern`.

    Args:
        doc: the decoded JSON object (version 2: a sheet's rows; version 1: passes).
        src: how messages name its source (a file's path).

    Returns:
        the :class:`Pattern`, every field checked.

    Raises:
        LaneError: a field missing or outside its domain (one line naming ``src`` and the field).
    """
    if not isinstance(doc, dict):
        raise LaneError(f"{src}: a pattern file must be a JSON object")
    extra = sorted(set(doc) - _TOP_KEYS)
    if extra:
        import difflib

        near = difflib.get_close_matches(extra[0], sorted(_TOP_KEYS), n=1)
        raise LaneError(f"{src}: {extra[0]}: not a pattern field" + (f" (did you mean {near[0]!r}?)" if near else
                                                                    f" (fields: {', '.join(sorted(_TOP_KEYS))})"))
    if doc.get("format") != FORMAT:
        raise LaneError(f"{src}: format: must be {FORMAT!r}, got {doc.get('format')!r}")
    if doc.get("version") not in VERSIONS or isinstance(doc.get("version"), bool):
        raise LaneError(f"{src}: version: must be one of {', '.join(map(str, VERSIONS))}, got {doc.get('version')!r}")
    name = doc.get("name")
    if not isinstance(name, str) or not name.strip() or len(name) > 80 or not name.isprintable():
        raise LaneError(f"{src}: name: must be a short printable text, got {name!r}")
    desc = doc.get("description", "")
    if not isinstance(desc, str) or len(desc) > 400:
        raise LaneError(f"{src}: description: must be a text of at most 400 characters")
    if doc["version"] == 2:
        return _rows_pattern(doc, src, name.strip(), desc)
    if "rows" in doc:
        raise LaneError(f"{src}: rows: a sheet's rows need version 2 (version 1 gives forward/reverse passes)")
    passes = [_pass(doc.get("forward"), f"{src}: forward")]
    if doc.get("reverse") is not None:
        passes.append(_pass(doc["reverse"], f"{src}: reverse"))
    if sum(p.volume_ml for p in passes) <= 0:
        raise LaneError(f"{src}: volume_ml: the passes hold no oil")
    return Pattern(name.strip(), desc, tuple(passes))


@lru_cache(maxsize=64)
def _load(path: str, mtime_ns: int) -> Pattern:
    try:
        doc = files.read_doc(path)
    except files.BowlingFileError as e:
        raise LaneError(str(e)) from None
    return pattern_from_dict(doc, Path(path).name)


def load_pattern(path) -> Pattern:
    """The pattern of a pattern file (read through the bowling files' gate).

    Args:
        path: an ``nbst-oil-pattern`` JSON file.

    Returns:
        the :class:`Pattern`.

    Raises:
        LaneError: the file cannot be read, or a field is refused (one line naming the file and field).
    """
    p = str(path)
    try:
        files.regular_file(p)
        return _load(p, os.stat(p).st_mtime_ns)
    except files.BowlingFileError as e:
        raise LaneError(str(e)) from None
    except OSError as e:
        raise LaneError(f"{p}: cannot read ({e.strerror or e})") from None


def _is_path(text: str) -> bool:
    """Whether ``text`` is read as a pattern file's path: it names something that exists (whatever its
    suffix: a folder, FIFO or device is then refused by :func:`load_pattern`), or it is written as
    a path (``*.json``, or with a folder in it), so that one missing is "no such file"."""
    seps = [c for c in (os.sep, os.altsep) if c]
    return os.path.lexists(text) or text.lower().endswith(".json") or any(c in text for c in seps)


def pattern(oil) -> Pattern:
    """A Pattern from a Pattern, a registered name, or a pattern file's path (any suffix).

    Args:
        oil: a :class:`Pattern`, a name of :data:`PATTERNS` (any case: a registered name wins here, as
            the library's callers name patterns; ``--oil`` reads a typed path first, see :func:`argtype`),
            or a pattern file's path (one that exists, ends ``.json`` or has a folder in it).

    Returns:
        the :class:`Pattern`.

    Raises:
        LaneError: no pattern of that name, or a pattern file that is refused.
    """
    if isinstance(oil, Pattern):
        return oil
    if isinstance(oil, os.PathLike):
        oil = os.fspath(oil)
    if isinstance(oil, str) and oil in PATTERNS:
        return PATTERNS[oil]
    if isinstance(oil, str) and _is_path(oil):
        return load_pattern(oil)
    raise LaneError(f"oil: no pattern {oil!r}; patterns: {', '.join(PATTERNS.names())}, or a pattern file's path")


def argtype(flag: str = "--oil"):
    """An argparse ``type=``: a pattern file's path, read and checked here (one line naming the file and
    field), or a registered pattern's name (any case). A value that names an existing path is that
    file whatever its suffix, even one named like a shipped pattern (the user typed a path; it is
    returned as ``./NAME`` for :func:`pattern` to read it so); ``--oil``'s default is the name."""
    names = PATTERNS.argtype(flag)

    def parse(text: str):
        import argparse

        if isinstance(text, _Shipped) or not _is_path(text):
            return names(text)
        try:
            load_pattern(text)
        except LaneError as e:
            clash = (f" (a path wins over the shipped pattern of that name: for {PATTERNS.entry(text).name!r}, "
                     f"run from another folder)") if text in PATTERNS else ""
            raise argparse.ArgumentTypeError(str(e) + clash) from None
        return os.path.join(os.curdir, text) if text in PATTERNS else text

    parse.__name__ = "oil pattern"
    return parse


def oil_name(oil) -> str:
    """The name a throw records for ``oil`` (a pattern's own name).

    Args:
        oil: as :func:`pattern` takes it.

    Returns:
        the pattern's name.

    Raises:
        LaneError: as :func:`pattern`.
    """
    return pattern(oil).name


#: The oil patterns by name, registered once (the shipped files, in SHIPPED's order).
PATTERNS: Registry[Pattern] = Registry("oil pattern")
for _name in SHIPPED:
    _pat = load_pattern(PATTERNS_DIR / f"{_name}.json")
    if _pat.name != _name:
        raise LaneError(f"{_name}.json: name: {_pat.name!r} must be the file's name {_name!r}")
    PATTERNS.register(_name, _pat, help=f"{_pat.length_ft:g} ft, {_pat.volume_ml:.3g} ml, {_pat.ratio():.2g}:1")
