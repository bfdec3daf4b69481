"""The accepted input domain: every limit a problem or solution file must meet, each with why.

``nbst.problem`` and ``nbst.solution`` apply these when they read (so every
command gets them); ``docs/formats.md`` has the same table. Inside the domain
the exact simulator gives finite final positions inside the box; outside it a
file is refused with one line naming the field (``ProblemError``).

Lengths are in the problem's unit, times in seconds, masses in any unit: the
physics is scale-free, so the absolute limits below only keep float64 far from
overflow and underflow, and the relative ones keep the tolerances meaningful.
"""
from __future__ import annotations

import unicodedata

from nbst.errors import InputError


# --------------------------------------------------------------------------- the JSON text

__all__ = ["MAX_JSON_BYTES", "MAX_JSON_DEPTH", "MAX_JSON_VALUES", "MAX_INT_DIGITS", "MAX_DISKS", "MAX_NAME_CHARS",
           "MAX_DESCRIPTION_CHARS", "BOX_MIN", "BOX_MAX", "RADIUS_MIN_FRACTION", "MASS_MIN", "MASS_MAX",
           "MAX_MASS_RATIO", "T_FINAL_MIN", "T_FINAL_MAX", "MAX_BOX_CROSSINGS", "BIDI_CONTROLS", "bad_text", "plain",
           "parse_number"]

#: Largest file read (bytes): a 63-disk problem is ~10 kB and a solution with
#: its search history well under 1 MB; this stops a stray multi-GB file early.
MAX_JSON_BYTES = 64 * 1024 * 1024

#: Deepest nesting of lists/objects: a problem needs 4 levels and a solution's
#: metadata a few more; Python's parser would recurse ~1000 deep and then fail.
MAX_JSON_DEPTH = 64

#: Most JSON values in one file, counted before parsing as the number of ',', ':', '[' and
#: '{' bytes (each value but the first is preceded by one of them; inside strings they are
#: counted too, an over-estimate). Parsed, a value costs 30-200 bytes of Python objects
#: (an empty list 56, a float 24): this bound keeps a parsed file in a few hundred MB and
#: a few seconds however it is shaped, where 64 MiB of ``[],`` took 3.2 GB and 36-50 s
#: (``benchmarks/fuzz_inputs.py --huge`` measures both). A disk of a problem is 11 values
#: written minimally (``{"start": [x, y], "target": [x, y], "radius": r}``) and 15 with
#: ``mass`` and ``cueable``, so MAX_DISKS disks of either form fit (1.5 million); the largest
#: file nbst writes besides, the shipped bowling atlas, holds ~78,000 (328 subsets; all 1,023
#: would be ~250,000); a solution with its history, under 10,000.
MAX_JSON_VALUES = 2_000_000

#: Longest integer literal (digits): float64 holds 309-digit integers at most;
#: longer ones cannot be a number nbst uses (Python itself stops at 4300 digits).
MAX_INT_DIGITS = 400

# --------------------------------------------------------------------------- size

#: Most disks in one problem. Signatures have no width limit (files hold them as strings of
#: N characters; the kernels as multiword bitsets), so the limit is the file and memory:
#: a disk is 11-15 JSON values in a problem and 3 in a solution, and MAX_JSON_VALUES lets
#: 100,000 of them load in either form (tests/test_problem.py loads one). The event kernel needs
#: ~150 bytes per disk at this size (cell grid), and ``simulate`` 64 bytes per recorded event on top.
MAX_DISKS = 100_000

# --------------------------------------------------------------------------- text fields

#: Longest ``name`` (characters): it becomes titles, file names and MJCF model names.
MAX_NAME_CHARS = 200

#: Longest ``description`` (characters): free text shown in listings and reports.
MAX_DESCRIPTION_CHARS = 10_000

# --------------------------------------------------------------------------- numbers

#: Box sides (W, H), units: [1e-6, 1e9]. The collision test squares lengths of
#: order side * (side / radius) and velocity * time; these bounds keep those
#: squares within float64 (overflow ~1e308, subnormals below ~1e-308).
BOX_MIN, BOX_MAX = 1e-6, 1e9

#: Smallest radius as a fraction of the box's longer side: contact distances
#: must stay well above the box's round-off (1e-16 relative) for collisions to
#: be found; this also caps the aspect ratio of the box (2r <= shorter side).
RADIUS_MIN_FRACTION = 1e-6

#: Masses, any unit: (MASS_MIN, MASS_MAX) keeps m_i + m_j finite; MAX_MASS_RATIO
#: bounds max/min mass so a light disk trapped by a heavy one makes about
#: pi * sqrt(ratio) ~ 3,000 collisions, far below the event cap.
MASS_MIN, MASS_MAX = 1e-100, 1e100
MAX_MASS_RATIO = 1e6

#: t_final, seconds: [1e-6, 1e6]. Time is scale-free for the exact simulator;
#: the bounds keep velocity * t_final finite and MuJoCo/video step counts finite.
T_FINAL_MIN, T_FINAL_MAX = 1e-6, 1e6

#: target_radius R: > 0 and at most the box diagonal (a larger R accepts every
#: position in the box, so it says nothing more).

#: Starts may touch; overlap is judged with the relative slack ``OVERLAP_RTOL``
#: of ``nbst.constants`` (on the sum of radii, which the radius floor keeps far
#: above round-off of the box's coordinates).

#: Most box crossings one disk may make on its own in t_final:
#: |vx| t / (W - 2r) + |vy| t / (H - 2r). Each crossing is a wall event, so disks
#: that meet nothing make at most 63,000 wall events (all 63 at this limit), within half
#: the simulator's event cap (MAX_EVENTS = 200,000). The bound stops at collisions: one
#: can turn a run along a long box's length into bounces across its narrow side (a
#: 1e9 x 2001 box: ~1e8 of them), so the commands refuse a solution whose motion
#: truncates, in one line (``nbst.cli.args.exact_motion``), and the search never keeps
#: one (cost inf). 1,000 crossings is far past any useful shot (the search's randomize
#: reaches 6). A disk as wide as the box (W = 2r) may not move along that axis at all.
MAX_BOX_CROSSINGS = 1_000


#: Bidirectional embeddings, overrides and isolates: they reorder the text shown
#: after them (a name could make a terminal line or a report say something else).
BIDI_CONTROLS = frozenset("\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069")


def _unprintable(ch: str) -> bool:
    # Cc: C0/C1 controls (ESC, NUL, newline, DEL, NEL); Cs: lone surrogates (not UTF-8);
    # Zl/Zp: line and paragraph separators
    return unicodedata.category(ch) in ("Cc", "Cs", "Zl", "Zp") or ch in BIDI_CONTROLS


def bad_text(s: str, *, allow_newlines: bool = False) -> str | None:
    """Why ``s`` cannot be shown as it is, or None: control characters (ESC, NUL,
    newlines, ...; tab and newlines allowed with ``allow_newlines``), bidirectional
    overrides, or lone surrogates (not encodable as UTF-8)."""
    for ch in s:
        if not _unprintable(ch) or (allow_newlines and ch in "\t\n\r\u2028\u2029"):
            continue
        if unicodedata.category(ch) == "Cs":
            return f"contains {ch!r}, a lone surrogate (not valid UTF-8)"
        return f"contains the control character {ch!r}"
    return None


def plain(s) -> str:
    """``str(s)`` safe for one terminal line: the characters ``bad_text`` refuses
    (newlines too) written as Python escapes (``\\x1b``), the rest unchanged."""
    s = str(s)
    if not any(_unprintable(ch) for ch in s):
        return s
    return "".join(ascii(ch)[1:-1] if _unprintable(ch) else ch for ch in s)


def parse_number(text: str, *, integer: bool = False) -> int | float:
    """A number written as text: an integer (underscores allowed) or a float.

    Args:
        text: the text, blanks around it ignored.
        integer: read an ``int`` rather than a ``float``.

    Returns:
        the number (a float may be ``inf`` or ``nan``: the caller bounds it).

    Raises:
        InputError: the text is not a number of that kind.
    """
    t = str(text).strip()
    try:
        return int(t.replace("_", "")) if integer else float(t)
    except (ValueError, OverflowError):
        raise InputError(f"must be {'an integer' if integer else 'a number'}, got {text!r}") from None
