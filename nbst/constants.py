"""Every tolerance and every open choice of nbst's foundation, in one place, each with why.

The search's choices (what the paper leaves open) live in ``nbst.search``'s
parameter table; this module holds those of the problem model and simulator.
"""

__all__ = ["GA_MAX_DISKS", "many_body", "OVERLAP_RTOL", "MAX_EVENTS", "MAX_EVENTS_PER_DISK", "max_events_for",
           "STALL_EVENTS_PER_DISK", "STALL_RTOL", "EVENT_BUFFER", "WALL_LEFT", "WALL_RIGHT", "WALL_BOTTOM", "WALL_TOP",
           "WALL_NAMES", "EVENT_DISK", "EVENT_WALL", "ROUNDOFF_REL", "PARALLEL_BATCH"]

#: Most disks for the signature search's compiled loop (nbst.search.loop / nbst_loop):
#: its population keeps signatures as int64 bitmasks (bit i = disk i acceptable), and
#: 63 keeps them positive. Larger problems are solved by the many-body search
#: (``nbst.search.many``), whose signatures are multiword bitsets; the data model's own
#: limit is ``nbst.domain.MAX_DISKS``.
GA_MAX_DISKS = 63


def many_body(n: int) -> bool:
    """Whether a problem of ``n`` disks is past the signature search's compiled loop: the one switch
    between the signature search and the many-body search (``nbst.search.solve``), int64 and
    multiword signatures (``nbst.sim``), islands and one process with threads (``nbst solve``)."""
    return int(n) > GA_MAX_DISKS

#: Starts may touch (centre distance == sum of radii, as the format allows);
#: this relative slack accepts touching starts written with rounded decimals.
OVERLAP_RTOL = 1e-9

#: Safety valve of the event loop, per simulation: elastic disks in a box have
#: finitely many events in finite time, but a bug or a degenerate jam must not
#: hang a search. A run that hits it is flagged (``Trajectory.truncated``) and
#: scored with cost = inf by ``evaluate``.
#:
#: Where the crossing limit (``nbst.domain.MAX_BOX_CROSSINGS``) keeps runs under it, and
#: where not: the limit bounds the wall events of a disk that meets no other disk (63
#: disks x 1,000 crossings = 63,000 events). A collision moves speed between disks and
#: between axes, so it bounds nothing after one: in a 1e9 x 2001 box with 1 unit of play
#: across, a disk sent along the box at 999 crossings that grazes a resting disk leaves
#: with ~1e8 crossings across the channel, and the run stops at this cap after 199,999
#: wall events (tests/test_search.py measures it). The search never keeps such a run (cost
#: inf), so its solutions always simulate to t_final; a hand-written solution file within
#: the crossing limit can still be truncated, and ``nbst simulate`` then says so.
MAX_EVENTS = 200_000

#: Past 1,000 disks the cap grows with N: ``max_events_for(n) = max(MAX_EVENTS,
#: MAX_EVENTS_PER_DISK * n)`` (a 10,000-disk planted motion at fixed density makes ~10
#: events per disk; the cap is 20 times that).
MAX_EVENTS_PER_DISK = 200


def max_events_for(n: int) -> int:
    """The event cap of one simulation of n disks (``MAX_EVENTS`` up to 1,000 disks)."""
    return max(MAX_EVENTS, MAX_EVENTS_PER_DISK * int(n))

#: A jam: more than this many events per disk within one instant (a window of
#: ``STALL_RTOL * t_final`` seconds) stops a run as stalled (``Trajectory.stalled``, cost
#: inf) instead of spending ``MAX_EVENTS`` on it. Rigid disks pinned between opposite
#: walls (a disk exactly as wide as the box, a row of touching disks spanning it) bounce
#: infinitely often at one instant; a legitimate simultaneous cascade (a rack of touching
#: disks struck at t = 0) takes a few events per disk.
STALL_EVENTS_PER_DISK = 1000

#: Width of "one instant" for the stall test, relative to t_final: a few thousand ulps,
#: so round-off that nudges the time of a pinned disk's bounces forward still counts.
STALL_RTOL = 1e-12

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

#: ``nbst.evaluate`` splits a batch over threads only from this many candidates per
#: thread: a thread costs ~0.1 ms to start, a candidate ~5-50 us to simulate.
PARALLEL_BATCH = 2048
