"""Oil patterns as data, registered once: the friction a pattern puts under the ball.

* **Oil** (``oil_patterns.json``, :func:`load_patterns`): a pattern is a length and a grid of
  (distance segment x board band) cells of relative oil ``u`` in [0, 1]; each cell is a box
  whose friction ``mu = mu_dry - (mu_dry - MU_OIL) u`` rules the ball's contact
  (``priority = 1``, as the zones of :mod:`.scene`). Past the pattern the dry back end
  (``mu_dry``) runs to the pin deck of :mod:`.scene`.

The shipped patterns (``oil_patterns.json`` beside this module) are registered once in
:data:`PATTERNS` (an :class:`nbst.registry.Registry`), which the command line's ``--oil``
choices, its help and the docs read.

Pure Python (json); reading the patterns file goes through :func:`load_patterns`.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from nbst.models.bowling import scene
from nbst.models.bowling.lane.units import N_BOARDS, LaneError, x_to_ft
from nbst.registry import Registry

__all__ = ["MU_OIL", "MU_DRY", "PATTERNS_FILE", "PATTERNS", "Pattern", "load_patterns", "pattern", "friction"]

#: Friction of a full oil film (Frohlich's figure, as scene.MU_OIL) and of the dry lane for
#: the default ball (scene.MU_DRY); the ball's coverstock friction replaces the latter.
MU_OIL = scene.MU_OIL
MU_DRY = scene.MU_DRY

PATTERNS_FILE = Path(__file__).with_name("oil_patterns.json")


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


#: The oil patterns by name, registered once (the shipped file's, in its order).
PATTERNS: Registry[Pattern] = Registry("oil pattern")
for _name, _pat in load_patterns().items():
    PATTERNS.register(_name, _pat, help=_pat.description)
