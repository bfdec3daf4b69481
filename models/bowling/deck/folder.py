"""An atlas folder of 5 m throws on disk: its throw files, resuming, the summaries (``nbst bowl atlas``).

A folder holds ``subset-<pins>.json`` (one 5 m throw file per subset found, :mod:`.throwfile`),
all naming one ``scene.xml`` (this version's scene, full precision), and the summaries:
``summary.csv`` (every subset and its file), ``summary.md`` (found / possible by size, the
geometry's classes), ``atlas.json`` (every throw in one file a MuJoCo user replays without
nbst) and ``summary.png`` (every subset found as a triangle, :mod:`.figure`).

* :func:`prepare` -- the folder, with the throws of an ``--from`` atlas written in first
  (:func:`unpack_atlas`) and this version's scene; a folder holding another scene is refused.
* :func:`resume` -- the throws already there: the search's archive (files failing the checks
  are skipped, and found again if the search finds them).
* :class:`AtlasRun` -- the search (or the robustness pass) over one folder, writing each new
  throw as it is found, with its robustness.
* :func:`write_summaries` -- the summaries; :func:`summary_md` its markdown.

Every file goes through the one atomic writer (:mod:`nbst.outputs`); nothing here prints.
"""
from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import cast

import numpy as np

from nbst.models.bowling import geometry, pinfall, scene, deck
from nbst.models.bowling.deck import atlas as atlasmod, figure, search, throwfile
from nbst.models.bowling.subsets import SubsetArchive
from nbst.outputs import write_text_atomic, prepare_output, atomic_path

__all__ = ["throw_name", "write_throw", "atlas_json", "shipped_archive", "unpack_atlas", "prepare", "resume",
           "AtlasRun", "write_summaries", "summary_md"]

#: The option that names the folder (in error messages of the writer).
OPTION = "--out-dir"


def throw_name(mask: int) -> str:
    """The file name of a subset's throw in an atlas folder: ``subset-1_2_4.json``."""
    return "subset-" + "_".join(map(str, pinfall.pins_of(mask))) + ".json"


def write_throw(path, model, delivery, mask: int, *, shared_scene: str | None = None, option: str = "-o",
                **kw) -> None:
    """Write THROW.json and its scene XML (``<stem>.scene.xml``, with keyframe ``shot``) beside
    it, atomically; with ``shared_scene`` the file names that scene (written by the caller).
    ``kw``: :func:`.throwfile.throw_dict`'s (requested, robustness, search)."""
    path = Path(path)
    scene_name = shared_scene or f"{path.stem}.scene.xml"
    d = throwfile.throw_dict(model, delivery, scene_name=scene_name, down_mask=mask, **kw)
    if shared_scene is None:
        write_text_atomic(path.parent / scene_name, throwfile.scene_with_start(d["qpos0"], d["qvel0"]), option=option)
    write_text_atomic(path, throwfile.dumps(d), option=option)


def atlas_json(folder, *, seed=None) -> Path:
    """Gather an atlas folder's throw files into FOLDER/atlas.json: one file a MuJoCo user
    replays without nbst, ``{"kind": "nbst-bowling-atlas", "scene": "scene.xml", "shots":
    [throw, ...]}``, each throw with the throw-file keys (``scene`` relative to the atlas file),
    sorted by subset size, then pins. Files that do not pass the throw-file checks are left out."""
    folder = Path(folder)
    throws = []
    for f in sorted(folder.glob("subset-*.json")):
        try:
            throws.append(throwfile.load(f))
        except throwfile.ThrowFileError:
            continue
    throws.sort(key=lambda d: (len(d["down"]), d["down"]))
    atlas = {"kind": throwfile.ATLAS_KIND, "schema_version": 1, "scene": "scene.xml", "seed": seed,
             "subsets": len(throws), "shots": throws}
    path = folder / "atlas.json"
    write_text_atomic(path, json.dumps(atlas, indent=1) + "\n", option=OPTION)  # floats by repr: exact
    return path


def shipped_archive() -> tuple[dict, str | None]:
    """The shipped atlas (models/bowling/deck/atlas.json) as a search archive: ({mask: (4,)
    delivery}, None), read through the throw-file gate; ({}, the one-line reason) if it cannot
    be read."""
    try:
        a, _, _ = throwfile.load_atlas(throwfile.SHIPPED_ATLAS)
    except throwfile.ThrowFileError as e:
        return {}, str(e)

    return {pinfall.mask_from_pins(d["down"]): np.array([float(d["launch"][k]) for k in deck.KEYS])
            for d in a["shots"] if "launch" in d}, None


def unpack_atlas(atlas_path, folder) -> int:
    """Write the throws of an atlas file as FOLDER/subset-<pins>.json (those not there yet)
    and its scene as FOLDER/scene.xml (when absent), every write atomic; returns how many
    throws were written. Everything is checked before anything is written: the atlas through
    the throw-file gate (its scene inside its own folder, parsed by MuJoCo, every throw's shapes
    fitting it), and its scene must be this version's (the search continues in it)."""
    folder = Path(folder)
    a, _, text = throwfile.load_atlas(atlas_path)
    if text != scene.scene_xml():
        raise throwfile.ThrowFileError(f"{atlas_path}: scene: {a['scene']!r} is not this version's bowling scene; "
                                       f"its throws would not replay beside the ones found here")
    if not (folder / "scene.xml").exists():
        write_text_atomic(folder / "scene.xml", text, option=OPTION)
    n = 0
    for d in a["shots"]:
        f = folder / throw_name(pinfall.mask_from_pins(d["down"]))
        if not f.exists():
            write_text_atomic(f, throwfile.dumps({**d, "scene": "scene.xml"}), option=OPTION)
            n += 1
    return n


def prepare(out_dir, from_atlas=None) -> Path:
    """The output folder, with the ``from_atlas`` throws in it and this version's scene.xml;
    ThrowFileError (one line) when ``from_atlas`` is refused or the folder holds another scene."""
    out = prepare_output(out_dir, directory=True, option=OPTION)
    if from_atlas:
        try:
            unpack_atlas(from_atlas, out)
        except throwfile.ThrowFileError as e:
            raise throwfile.ThrowFileError(f"--from: {e}") from None
    xml = scene.scene_xml()
    here = out / "scene.xml"
    if not here.exists():
        write_text_atomic(here, xml, option=OPTION)  # one scene for every throw (the same model)
    elif throwfile.read_scene_text(here, here) != xml:  # throws of another scene: new ones would not replay there
        raise throwfile.ThrowFileError(f"{here} is not this version's scene; use a new --out-dir folder")
    return out


def resume(out: Path) -> tuple[dict, dict, list]:
    """The throws already in the folder: ({mask: file}, {mask: (4,) delivery}, [(file, why)]);
    files that fail the throw-file checks are skipped, each with its one-line reason (naming the file) (and found
    again if the search finds their subset)."""
    files, deliveries, skipped = {}, {}, []
    for f in out.glob("subset-*.json"):
        try:
            m = pinfall.mask_from_pins(int(p) for p in f.stem.split("-", 1)[1].split("_"))
        except ValueError:
            skipped.append((f, f"{f}: its name is not subset-<pins>.json with pins 1-10"))
            continue
        try:
            d = throwfile.load(f)
        except throwfile.ThrowFileError as e:
            skipped.append((f, str(e)))
            continue
        files[m] = f
        if "launch" in d:
            deliveries[m] = np.array([float(d["launch"][k]) for k in deck.KEYS])
    return files, deliveries, sorted(skipped)


class AtlasRun:
    """The search (or the robustness pass) over one folder, writing each new throw as it is
    found, with its robustness (unless ``robustness`` is False); ``probes`` counts the
    robustness rollouts. ``on_progress(n, found)`` after each batch (search: rollouts so far;
    robustness pass: throws done)."""

    def __init__(self, runner, out: Path, files: dict, deliveries: dict, *, seed: int, method: str,
                 robustness: bool = True, on_progress=None):
        self.runner, self.out, self.files, self.deliveries = runner, out, files, deliveries
        self.seed, self.method, self.robustness, self.on_progress = seed, method, robustness, on_progress
        self.arch = atlasmod.SubsetArchive.from_elites(deliveries)
        self.probes = 0

    def add_robustness(self, mask: int, f: Path) -> None:
        d = throwfile.load(f)
        rob = search.robustness_ladder(self.runner, self.deliveries[mask], mask)
        self.probes += rob["lateral_m_rollouts"] + rob["speed_m_s_rollouts"]
        d["robustness"] = rob
        write_text_atomic(f, throwfile.dumps(d), option=OPTION)

    def on_new(self, masks) -> None:
        for m in masks:
            f = self.out / throw_name(m)
            write_throw(f, self.runner.model, self.arch.elite[m], m, shared_scene="scene.xml", option=OPTION,
                        requested=m, search={"seed": self.seed, "method": self.method,
                                             "found_after": self.arch.found_at[m]})
            self.files[m], self.deliveries[m] = f, self.arch.elite[m]
            if self.robustness:
                self.add_robustness(m, f)

    def lacking_robustness(self) -> list[int]:
        """The masks of the folder's throws without their robustness."""
        todo = []
        for m in sorted(self.files):
            try:
                if m in self.deliveries and "robustness" not in throwfile.load(self.files[m]):
                    todo.append(m)
            except throwfile.ThrowFileError:
                continue
        return todo

    def robustness_pass(self, todo) -> None:
        """Add the robustness to the throws of ``todo`` (masks), one file at a time."""
        for k, m in enumerate(todo):
            self.add_robustness(m, self.files[m])
            if self.on_progress:
                self.on_progress(k + 1, len(self.arch))

    def search(self, budget: int, *, per_subset: int = atlasmod.PER_SUBSET) -> None:
        """Spend ``budget`` rollouts growing the folder (:func:`.atlas.run`). KeyboardInterrupt
        propagates; what ran is written."""
        def progress(arch):
            if self.on_progress:
                self.on_progress(arch.rollouts, len(arch))

        atlasmod.run(self.runner, cast(SubsetArchive, self.arch), method=self.method, budget=budget, seed=self.seed,
                     per_subset=per_subset, on_new=self.on_new, callback=progress)


def write_summaries(out: Path, run: AtlasRun, *, seconds: float) -> int:
    """summary.csv, summary.md, atlas.json and summary.png of the folder; returns the subsets held."""
    have = {m: f.name for m, f in run.files.items()}
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["mask", "pins", "size", "file"])
    for m in range(1, geometry.N_SUBSETS + 1):
        pins = pinfall.pins_of(m)
        w.writerow([m, "-".join(map(str, pins)), len(pins), have.get(m, "")])
    write_text_atomic(out / "summary.csv", buf.getvalue(), option=OPTION)
    write_text_atomic(out / "summary.md", summary_md(have, rollouts=run.arch.rollouts, probes=run.probes,
                                                     seconds=seconds, seed=run.seed, method=run.method,
                                                     archive=run.arch), option=OPTION)
    atlas_json(out, seed=run.seed)
    fig = figure.atlas_figure(have, title=f"{len(have)} of {geometry.N_SUBSETS:,} subsets "
                                          f"(red frame: needs a flying pin)")
    with atomic_path(out / "summary.png", option=OPTION) as tmp:
        figure.save(fig, tmp)
    return len(have)


def summary_md(have: dict, *, rollouts: int, probes: int, seconds: float, seed: int, method: str,
               archive=None) -> str:
    """The atlas's summary table (markdown): found / possible by size, and the geometry classes."""
    found = sorted(have)
    lines = ["# Bowling atlas", "", f"{len(found)} of {geometry.N_SUBSETS} subsets found; this run: {rollouts} search "
             f"rollouts ({method}) and {probes} robustness rollouts in {seconds:.0f} s (seed {seed}).", ""]
    if archive is not None and method.startswith("elites") and rollouts:
        (nu, hu), kids = archive.uniform, sum(archive.children.values())
        new = sum(1 for v in archive.found_at.values() if v >= 0)
        lines[-1:-1] = ["", f"New subsets this run: {new}; from its {nu} uniform deliveries: {hu}; from its "
                            f"{kids} children of elites: {sum(archive.hits.values())}."]
    return "\n".join(lines + geometry.summary_lines(found)) + "\n"
