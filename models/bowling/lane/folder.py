"""A foul-line atlas folder on disk (``nbst bowl atlas --foul-line``): the search, its checkpoint,
the throw atlas, the checks and the summary.

A folder holds ``archive.json`` (the search's checkpoint, :func:`.atlas.archive_doc`),
``foul_atlas.json`` (one throw per subset with its probability and ladder, a throw atlas of
:mod:`.throwfile`), ``checks.json`` (per subset: the frame run 2 s past its settle, and whether
it was harvested from a noisy throw) and ``summary.md``. :class:`FoulAtlasRun` resumes from what
the folder holds (the checkpoint, else an ``--from`` throw atlas, else nothing), grows the
archive (:func:`.atlas.grow`), adds (:meth:`FoulAtlasRun.mirror`) the other hand's throw of each unmirrored subset, then
measures each subset in chunks of :data:`CHUNK` (its probability under the release noise, the
timestep ladder, 2 s longer) and writes everything after each chunk: an interrupt loses at
most the chunk in flight.

Every file goes through the one atomic writer (:mod:`nbst.outputs`); nothing here prints.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import cast

from nbst.models.bowling import files, lane, pinfall, subsets
from nbst.models.bowling.lane import atlas, frame, noise, throwfile
from nbst.outputs import write_text_atomic, signals_deferred

__all__ = ["CHUNK", "CHECKPOINT_S", "FoulAtlasRun", "atlas_points", "summary_md"]

#: Subsets whose probability, ladder and longer run are measured between two writes of the atlas.
CHUNK = 16
#: Seconds between two checkpoints of the archive during the search.
CHECKPOINT_S = 30.0
#: The option that names the folder (in the writer's error messages).
OPTION = "--out-dir"


def atlas_points(doc: dict) -> tuple[dict, bool]:
    """({mask: (7,) point} of a foul-line atlas document's full-rack throws that knock a pin
    down, in file order; whether the atlas was thrown on this nbst's lane scene): an atlas of
    this scene holds answers, one of another scene deliveries to throw again (a file without
    ``scene`` is lane-1's)."""
    points = {pinfall.mask_from_pins(t["outcome"]["down"]): atlas.point_of(lane.Delivery(**t["delivery"]))
              for t in doc["throws"] if t["standing"] == throwfile.FULL_RACK and t["outcome"]["down"]}
    return points, doc.get("scene", throwfile.SCENES[0]) == lane.SCENE


class FoulAtlasRun:
    """The foul-line atlas of one folder (see the module docstring). ``seed`` seeds the search
    and the noisy throws; ``jobs`` processes run the frames (at h = 1, 0.5 and 0.25 ms)."""

    def __init__(self, out: Path, *, seed: int, jobs: int, from_atlas=None, nz: noise.Noise = noise.DEFAULT,
                 bowler: str | None = None):
        self.out, self.seed, self.nz, self.bowler = Path(out), int(seed), nz, bowler
        self.starts: list = []  # deliveries of an atlas of another scene, to throw again first
        self.ckpt, self.atl, self.summ = self.out / "archive.json", self.out / "foul_atlas.json", self.out / "summary.md"
        self.checks_path = self.out / "checks.json"
        if self.ckpt.exists():
            self.archive = atlas.archive_from_doc(files.read_doc(self.ckpt), self.ckpt)
        elif from_atlas:
            points, here = atlas_points(throwfile.load_atlas(from_atlas))
            if here:  # this scene's answers: kept as they are
                self.archive = cast(subsets.SubsetArchive, subsets.SubsetArchive.from_elites(points))
            else:  # another scene's: its deliveries, thrown again here (:meth:`rethrow`)
                self.archive = subsets.SubsetArchive()
                self.starts = list(points.values())
        else:
            self.archive = subsets.SubsetArchive()
        self.done: dict = {}
        if self.atl.exists():
            for t in throwfile.load_atlas(self.atl)["throws"]:
                self.done[pinfall.mask_from_pins(t["outcome"]["down"])] = t
        self.checks: dict = {}
        if self.checks_path.exists():
            try:
                raw = files.read_doc(self.checks_path)
                self.checks = {int(k): v for k, v in raw.items() if str(k).isdigit() and isinstance(v, dict)}
            except (ValueError, files.BowlingFileError):
                self.checks = {}
        self.runners = [frame.FrameRunner(atlas.OIL, jobs=jobs, timestep=h) for h in frame.LADDER]
        self.start = self.archive.rollouts

    def close(self) -> None:
        for r in self.runners:
            r.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # -------------------------------------------------------------------------- writing

    def checkpoint(self) -> None:
        write_text_atomic(self.ckpt, json.dumps(atlas.archive_doc(self.archive, self.seed)) + "\n", option=OPTION)

    def write_all(self) -> None:
        """The checkpoint, the throw atlas, the checks and the summary (signals held until done)."""
        a = throwfile.atlas_dict([self.done[m] for m in sorted(self.done)], oil=atlas.OIL, noise=self.nz)
        if self.bowler is not None:
            a["bowler"] = self.bowler  # whose release noise the probabilities are (for people; not checked)
        with signals_deferred(reraise=False):
            self.checkpoint()
            write_text_atomic(self.atl, throwfile.dumps(a), option=OPTION)
            write_text_atomic(self.checks_path, json.dumps({str(k): v for k, v in sorted(self.checks.items())},
                                                           indent=1) + "\n", option=OPTION)
            write_text_atomic(self.summ, summary_md(a, self.checks, self.archive), option=OPTION)

    # -------------------------------------------------------------------------- the stages

    def rethrow(self, on_done=None) -> list[int]:
        """The ``--from`` atlas's deliveries when it was grown on another lane scene: each thrown
        once here and archived by what it knocks down here (:func:`.atlas.rethrow`); then a
        checkpoint, so a resumed run does not throw them again. Returns the new masks."""
        if not self.starts:
            return []
        new = atlas.rethrow(self.runners[0], self.archive, self.starts, on_done=on_done)
        self.starts = []
        self.checkpoint()
        return new

    def grow(self, budget: int, on_batch=None) -> None:
        """Spend ``budget`` frames on the search; ``on_batch(frames this run, subsets)`` after each
        batch; a checkpoint every :data:`CHECKPOINT_S` seconds."""
        import time

        last = [time.monotonic()]
        self.start = self.archive.rollouts  # the search's own frames (after any --from re-throws)

        def batch(a, new) -> None:
            if on_batch is not None:
                on_batch(min(budget, a.rollouts - self.start), len(a.elite))
            if time.monotonic() - last[0] > CHECKPOINT_S:
                self.checkpoint()
                last[0] = time.monotonic()

        atlas.grow(self.runners[0], self.archive, budget=budget, seed=self.seed, on_batch=batch)

    def todo(self, skip=()) -> list[int]:
        return [m for m in sorted(self.archive.elite) if m not in self.done and m not in skip]

    def mirror(self) -> list[int]:
        """The other hand's throw of each unmirrored subset (:func:`.atlas.mirror_step`)."""
        return atlas.mirror_step(self.runners[0], self.archive)

    def measure(self, samples: int, on_done=None, on_more=None) -> None:
        """Each subset's probability (``samples`` noisy throws), ladder and 2 s longer run,
        :data:`CHUNK` subsets at a time, everything written after each chunk. ``on_done()`` after
        each frame; ``on_more(k)`` when ``k`` subsets join the work (harvested from noisy throws)."""
        R, R05, R025 = self.runners
        skip: set = set()
        while True:
            todo = self.todo(skip)
            if not todo:
                break
            part = todo[:CHUNK]
            ds = [atlas.delivery_of(self.archive.elite[m]) for m in part]
            est, thr, res = atlas.probabilities(R, {m: self.archive.elite[m] for m in part}, n=samples, seed=self.seed,
                                                nz=self.nz, on_done=on_done, frames=True)
            new = atlas.harvest(self.archive, thr, res)  # subsets the noisy throws found
            for m in new:
                self.checks[m] = {"harvested": True}
            if new and on_more is not None:
                on_more(len(new))
            r1 = R.map(ds)
            r2, r4 = R05.map(ds), R025.map(ds)
            rl = R.map(ds, extra_s=2.0)
            if on_done is not None:
                for _ in range(4 * len(part)):
                    on_done()
            for j, m in enumerate(part):
                if pinfall.mask_from_pins(r1[j].down) != m:  # cannot happen: a frame is deterministic
                    skip.add(m)
                    continue
                self.done[m] = throwfile.throw_dict(r1[j], oil=atlas.OIL, requested=pinfall.pins_of(m),
                                                    estimate=est[m], want=pinfall.pins_of(m),
                                                    ladder=[r1[j], r2[j], r4[j]])
                self.checks[m] = {**self.checks.get(m, {}), "longer_leave": rl[j].leave,
                                  "longer_same": rl[j].leave == r1[j].leave}
            self.write_all()


def summary_md(a: dict, checks: dict, archive) -> str:
    """summary.md of a foul-line atlas: subsets by size, probabilities, ladder and 2 s longer."""
    throws = a["throws"]
    ps = sorted((t["probability"]["p"] for t in throws if t["probability"]), reverse=True)
    lad = [t for t in throws if t["ladder"]]
    held = sum(all(x["leave"] == t["outcome"]["leave"] for x in t["ladder"]) for t in lad)
    longer = [v for v in checks.values() if "longer_leave" in v]
    same = sum(v["longer_same"] for v in longer)
    left = sum(t["delivery"]["hand"] == "left" for t in throws)
    lines = [f"# Foul-line atlas: {len(throws)} subsets", "",
             f"{archive.rollouts} settled frames searched (oil {a['oil']}, the default ball); "
             f"{len(throws) - left} right-handed throws, {left} left-handed.", "",
             "| pins down | subsets found | possible |", "|---|---|---|"]
    lines += [f"| {k} | {f} | {p} |" for k, f, p in subsets.size_table(
        [sum(1 << (n - 1) for n in t["outcome"]["down"]) for t in throws])]
    if ps:
        lines += ["", f"Probability of the subset under the release noise ({throws[0]['probability']['n']} throws "
                      f"each): median {100 * ps[len(ps) // 2]:.0f} %; at least 50 %: "
                      f"{sum(p >= 0.5 for p in ps)}; at least 90 %: {sum(p >= 0.9 for p in ps)}; "
                      f"none of the noisy throws: {sum(p == 0 for p in ps)}."]
    if lad:
        lines += [f"Timestep ladder (1, 0.5, 0.25 ms): {held} of {len(lad)} keep their subset."]
    if longer:
        lines += [f"2 s past the settle: {same} of {len(longer)} keep their subset."]
    got = sum(1 for v in checks.values() if v.get("harvested"))
    if got:
        lines += [f"{got} subsets were first knocked down by a noisy throw of another subset's probability "
                  "estimate (that throw is their elite)."]
    return "\n".join(lines) + "\n"
