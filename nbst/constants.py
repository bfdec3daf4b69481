"""Every tolerance and every open choice of nbst's foundation, in one place, each with why.

The search's choices (what the paper leaves open) live in ``nbst.search``'s
parameter table; this module holds those of the problem model and simulator.
"""

#: Most disks in one problem. Signatures are int64 bitmasks (bit i = disk i
#: acceptable); 63 keeps them positive.
MAX_DISKS = 63

#: Starts may touch (centre distance == sum of radii, as the format allows);
#: this relative slack accepts touching starts written with rounded decimals.
OVERLAP_RTOL = 1e-9

#: Safety valve of the event loop, per simulation: elastic disks in a box have
#: finitely many events in finite time, but a bug or a degenerate jam must not
#: hang a search. A run that hits it is flagged (``Trajectory.truncated``) and
#: scored with cost = inf by ``evaluate``.
MAX_EVENTS = 200_000

#: Event-buffer size that ``simulate`` starts with; doubled on overflow.
EVENT_BUFFER = 1024

#: Wall identifiers in event records (partner index of a wall event is -1 - wall).
WALL_LEFT, WALL_RIGHT, WALL_BOTTOM, WALL_TOP = 0, 1, 2, 3
WALL_NAMES = ("left", "right", "bottom", "top")

#: Event kinds in event records.
EVENT_DISK, EVENT_WALL = 0, 1

#: Round-off level of a solution, relative to the box: a disk within
#: ROUNDOFF_REL x max(W, H) of its target is as exact as float64 event chains
#: get (positions carry ~1e-13 relative error per event, amplified along a
#: chain); ``nbst solve`` stops there by default (``nbst.search.roundoff_cost``).
ROUNDOFF_REL = 1e-9
