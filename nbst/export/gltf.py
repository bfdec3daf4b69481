"""The world-agnostic glTF 2.0 writer: bodies with their meshes, and per-body poses over time.

A body is a name and its solids (a :class:`Solid`: triangles in the body's frame, as the renderer's
rows of position and normal, and an RGBA colour). :func:`write_glb` writes one node per body carrying one glTF mesh (a primitive per
solid, each with a material whose ``baseColorFactor`` is the solid's RGBA; ``alphaMode`` BLEND
below alpha 1; a solid coloured per corner as a renderer colours it carries ``COLOR_0``, a textured
one ``TEXCOORD_0`` and its PNG; bodies whose solids are alike to the byte share one mesh: 1,000
equal pucks are one mesh and 1,000 nodes), and one animation whose channels move each moving body: a ``translation`` and a
``rotation`` sampler per body, LINEAR interpolation, over one shared time accessor. Bodies that
never move (the floor, a road) are nodes without channels: a body moves only where its pose changes
(:func:`still_bodies`; a :class:`BodyMotion` makes a body given as moving static where its keyframes,
as the file stores them, are all one pose: a mocap paddle nothing moves); a moving body's translation or
rotation that never changes as stored (a sliding disk's rotation) gets no channel, its node's value holding. A body with nothing to
draw (no solid: a flex's vertex bodies, the cloth nbst does not export) is a node without a mesh
whose ``extras`` say so, and the scene's ``extras`` name them all (:func:`empty_note`). The file is
written with pygltflib (the binary container, one buffer) and atomically
(:func:`nbst.outputs.write_bytes_atomic`).

Storage is float32, as glTF requires for these accessors: positions, rotations and times are kept
to float32's precision (relative 6e-8; a keyframe read back matches the replay's pose within
1e-6 of the motion's extent). Rotations are MuJoCo's (w, x, y, z) written as glTF's (x, y, z, w),
renormalised and made sign-continuous from keyframe to keyframe (q and -q are one rotation; a
flip would make the LINEAR (slerp) interpolation take the long way round). The bodies' nodes are
the children of one root node, last in the node list, that turns the worlds' +z up into glTF's +y
up (a rotation of -90 degrees about x); the bodies' own transforms stay MuJoCo's world frame. Every accessor that
the specification requires it of (POSITION, the animation's input) carries ``min`` and ``max``.

Compute apart from I/O: :func:`gltf_document` builds the pygltflib document and its binary blob;
:func:`write_glb` writes it.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from nbst.errors import InputError
from nbst.outputs import write_bytes_atomic

__all__ = ["Solid", "Body", "BodyMotion", "EMPTY", "TURN_NOTE_DEG", "continuous_quaternions", "still_bodies",
           "empty_note", "turn_angles", "turn_note", "gltf_document", "write_glb"]

#: The ``extras`` of a body's node that has no mesh.
EMPTY = {"nbst": "no geoms: nothing drawn (nbst exports geoms only)"}


@dataclass(frozen=True)
class Solid:
    """One solid of a body: unshared triangles in the body's frame and its colour.

    Args:
        rows: (3 x ntriangle, 6) float array, each triangle corner's position (m, or the world's
            units) and unit normal, as the renderer's geometry gives them
            (:func:`nbst.render.core.geoms.geom_rows`).
        rgba: (4,) colour, each channel in [0, 1].
        colors: None, or (3 x ntriangle, 3) RGB in [0, 1] per corner, as a renderer colours a solid
            (a tyre's spokes, a pin's neck stripes): written as the mesh's ``COLOR_0``, which glTF
            multiplies into ``rgba`` (then white, with the solid's alpha).
    """

    rows: np.ndarray
    rgba: tuple[float, float, float, float]
    colors: np.ndarray | None = None
    #: None, or (3 x ntriangle, 2) texture coordinates per corner (glTF's: (0, 0) the image's first
    #: row's first texel) and the (H, W, 3) uint8 image they map, written as a PNG, repeated across u
    #: and clamped in v (an equirectangular ball: the foul-line ball's grip holes, pin dot and track).
    uv: np.ndarray | None = None
    texture: np.ndarray | None = None

    @classmethod
    def coloured(cls, rows9: np.ndarray, alpha: float = 1.0) -> Solid:
        """A solid from a renderer's (V, 9) rows (position, normal, RGB): one colour when every
        corner has the same, else per-corner colours."""
        rows9 = np.asarray(rows9, float)
        col = rows9[:, 6:9]
        if len(col) and (col == col[0]).all():
            return cls(rows9[:, :6], (float(col[0, 0]), float(col[0, 1]), float(col[0, 2]), float(alpha)))
        return cls(rows9[:, :6], (1.0, 1.0, 1.0, float(alpha)), np.clip(col, 0.0, 1.0))


@dataclass(frozen=True)
class Body:
    """A body to write: its name, its solids, and whether it may move (a static body keeps the pose
    of the motion's first keyframe and gets no animation channel; a :class:`BodyMotion` makes static
    a body whose pose never changes)."""

    name: str
    solids: list[Solid] = field(default_factory=list)
    moves: bool = True


@dataclass(frozen=True)
class BodyMotion:
    """Bodies and their poses at keyframe times.

    Args:
        bodies: the bodies, in the order of the pose arrays' second axis.
        times: (T,) float64 array, keyframe times in s, strictly increasing, from 0.
        pos: (T, nbody, 3) float64 array, each body's origin in the world frame.
        quat: (T, nbody, 4) float64 array, each body's orientation (w, x, y, z), MuJoCo's order.

    A body given as moving whose keyframes are all one pose (:func:`still_bodies`) is made static
    here: ``bodies`` then holds it with ``moves`` False (a mocap paddle the motion never moves).
    """

    bodies: list[Body]
    times: np.ndarray
    pos: np.ndarray
    quat: np.ndarray
    #: None, or (nbody,) each body's fastest turn (deg/s) over the whole recording, every step, not only
    #: the keyframes: a spin of a full turn between two keyframes looks like none in them (:func:`turn_note`).
    turn_rate: np.ndarray | None = None

    def __post_init__(self) -> None:
        t, n = len(self.times), len(self.bodies)
        if t < 1 or np.shape(self.pos) != (t, n, 3) or np.shape(self.quat) != (t, n, 4):
            return   # check() refuses it
        still = still_bodies(self.pos, self.quat)
        if any(b.moves and s for b, s in zip(self.bodies, still)):
            object.__setattr__(self, "bodies", [replace(b, moves=False) if b.moves and s else b
                                                for b, s in zip(self.bodies, still)])

    def check(self) -> BodyMotion:
        """This motion if its shapes and values are usable, else :class:`~nbst.errors.InputError`."""
        t, n = len(self.times), len(self.bodies)
        if t < 1 or self.pos.shape != (t, n, 3) or self.quat.shape != (t, n, 4):
            raise InputError(f"motion: poses of shape {self.pos.shape} and {self.quat.shape} do not fit {t} times "
                             f"and {n} bodies")
        if not (np.isfinite(self.times).all() and np.isfinite(self.pos).all() and np.isfinite(self.quat).all()):
            raise InputError("motion: a time or pose is not finite")
        if t > 1 and not (np.diff(self.times) > 0).all():
            raise InputError("motion: times must increase")
        return self


def continuous_quaternions(quat: np.ndarray) -> np.ndarray:
    """Unit quaternions along axis 0 with each one's sign chosen so that its dot product with the
    previous is >= 0 (the same rotations; slerp then takes the short way).

    Args:
        quat: (T, ..., 4) float64 array.

    Returns:
        (T, ..., 4) float64 array, normalised and sign-continuous.
    """
    q = np.array(quat, dtype=np.float64)
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    for k in range(1, len(q)):
        flip = np.sum(q[k] * q[k - 1], axis=-1) < 0
        q[k][flip] *= -1.0
    return q


def still_bodies(pos: np.ndarray, quat: np.ndarray) -> np.ndarray:
    """Per body, whether its pose never changes: every keyframe's position and rotation, as the file
    stores them (float32; the rotation unit and sign-continuous), equal to its first's.

    Args:
        pos: (T, nbody, 3) float64 array; quat: (T, nbody, 4) float64 array (w, x, y, z).

    Returns:
        (nbody,) bool array; False for a body with a pose not finite (refused by ``check``).
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        q = continuous_quaternions(quat).astype(np.float32)
    p = np.asarray(pos, np.float32)
    return ((p == p[:1]).all(axis=(0, 2)) & (q == q[:1]).all(axis=(0, 2))
            & np.isfinite(p).all(axis=(0, 2)) & np.isfinite(q).all(axis=(0, 2)))


def _drawable(s: Solid) -> bool:
    """Whether a solid has a triangle to write (three rows at least)."""
    return len(s.rows) >= 3


def _drawn(body: Body) -> bool:
    return any(_drawable(s) for s in body.solids)


def empty_note(motion: BodyMotion) -> str:
    """What to say of the bodies with nothing to draw (no solid), in one line, or "" when there are
    none: ``36 bodies have no geoms (cloth_0, cloth_1, cloth_2, ...): nodes without a mesh; nbst
    exports geoms only (a flex, such as cloth, or a skin is not in the file)``."""
    names = [b.name for b in motion.bodies if not _drawn(b)]
    if not names:
        return ""
    said = ", ".join(names[:3]) + (", ..." if len(names) > 3 else "")
    return (f"{len(names)} bod{'ies have' if len(names) > 1 else 'y has'} no geoms ({said}): nodes without a mesh; "
            f"nbst exports geoms only (a flex, such as cloth, or a skin is not in the file)")


#: A turn between two keyframes past this (degrees) is noted: a viewer interpolates a rotation the
#: short way, so a true turn past 180 degrees plays backwards, and one near 180 in either way.
TURN_NOTE_DEG = 90.0


def turn_angles(quat: np.ndarray) -> np.ndarray:
    """(T-1, nbody) each body's turn (deg) from one pose to the next, of (T, nbody, 4) unit quaternions
    (w, x, y, z): the short way, whatever their signs."""
    q = np.asarray(quat, float)
    with np.errstate(invalid="ignore"):
        return np.nan_to_num(np.degrees(2 * np.arccos(np.clip(np.abs(np.sum(q[1:] * q[:-1], axis=-1)), 0.0, 1.0))))


def turn_note(motion: BodyMotion, fps: float) -> str:
    """What to say when a moving body turns more than :data:`TURN_NOTE_DEG` between two keyframes (a
    spinning ball or wheel at a low ``fps``), in one line, or "" when none does: the turn read between
    the keyframes, or the body's fastest turn over the whole recording (``motion.turn_rate``) times the
    keyframes' widest gap, whichever is larger."""
    if len(motion.quat) < 2:
        return ""
    turn = turn_angles(motion.quat).max(axis=0)
    if motion.turn_rate is not None:   # a spin aliased by the keyframes (a full turn between two reads as none)
        turn = np.maximum(turn, np.asarray(motion.turn_rate, float) * float(np.diff(motion.times).max()))
    turn = np.where([b.moves for b in motion.bodies], turn, 0.0)
    k = int(np.argmax(turn))
    if turn[k] <= TURN_NOTE_DEG:
        return ""
    need = fps * turn[k] / (TURN_NOTE_DEG / 2)
    return (f"{motion.bodies[k].name} turns {turn[k]:.0f} deg or more between two keyframes at {fps:g} fps: a viewer "
            f"turns it the short way, so a spin past 180 deg plays backwards; export with --fps {math.ceil(need)} or more")


class _Blob:
    """The one binary buffer, its buffer views and accessors, 4-byte aligned."""

    def __init__(self, gl: Any, pg: Any) -> None:
        self.gl, self.pg, self.data = gl, pg, bytearray()

    def add(self, array: np.ndarray, kind: str, *, target: int | None = None, bounds: bool = False) -> int:
        pg = self.pg
        comp = pg.UNSIGNED_INT if array.dtype == np.uint32 else pg.FLOAT
        raw = np.ascontiguousarray(array).tobytes()
        self.data.extend(b"\0" * (-len(self.data) % 4))
        self.gl.bufferViews.append(pg.BufferView(buffer=0, byteOffset=len(self.data), byteLength=len(raw),
                                                 target=target))
        self.data.extend(raw)
        acc = pg.Accessor(bufferView=len(self.gl.bufferViews) - 1, componentType=comp, count=int(array.shape[0]),
                          type=kind)
        if bounds:
            flat = array.reshape(array.shape[0], -1)
            acc.min = [float(x) for x in flat.min(axis=0)]
            acc.max = [float(x) for x in flat.max(axis=0)]
        self.gl.accessors.append(acc)
        return len(self.gl.accessors) - 1

    def add_bytes(self, raw: bytes) -> int:
        """A buffer view of ``raw`` (an image): its index."""
        self.data.extend(b"\0" * (-len(self.data) % 4))
        self.gl.bufferViews.append(self.pg.BufferView(buffer=0, byteOffset=len(self.data), byteLength=len(raw)))
        self.data.extend(raw)
        return len(self.gl.bufferViews) - 1


def _material(gl: Any, pg: Any, cache: dict, rgba: tuple[float, ...]) -> int:
    key = tuple(round(float(c), 6) for c in rgba)
    if key not in cache:
        gl.materials.append(pg.Material(
            name=f"rgba({', '.join(f'{c:g}' for c in key)})", doubleSided=True,
            alphaMode=pg.BLEND if key[3] < 1.0 else pg.OPAQUE,
            pbrMetallicRoughness=pg.PbrMetallicRoughness(baseColorFactor=list(key), metallicFactor=0.0,
                                                         roughnessFactor=0.8)))
        cache[key] = len(gl.materials) - 1
    return int(cache[key])


def _textured(gl: Any, pg: Any, blob: _Blob, image: np.ndarray, rgba: tuple[float, ...]) -> int:
    """A material whose base colour is ``image`` (embedded as a PNG), repeated in u, clamped in v."""
    import io

    from PIL import Image

    png = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(image, np.uint8)).save(png, format="PNG")
    gl.images.append(pg.Image(bufferView=blob.add_bytes(png.getvalue()), mimeType="image/png"))
    gl.samplers.append(pg.Sampler(magFilter=pg.LINEAR, minFilter=pg.LINEAR, wrapS=pg.REPEAT, wrapT=pg.CLAMP_TO_EDGE))
    gl.textures.append(pg.Texture(source=len(gl.images) - 1, sampler=len(gl.samplers) - 1))
    gl.materials.append(pg.Material(
        name="texture", doubleSided=True, alphaMode=pg.BLEND if rgba[3] < 1.0 else pg.OPAQUE,
        pbrMetallicRoughness=pg.PbrMetallicRoughness(baseColorFactor=[float(c) for c in rgba], metallicFactor=0.0,
                                                     roughnessFactor=0.8,
                                                     baseColorTexture=pg.TextureInfo(index=len(gl.textures) - 1))))
    return len(gl.materials) - 1


def gltf_document(motion: BodyMotion, *, name: str = "nbst") -> tuple[Any, bytes]:
    """The glTF document of ``motion`` and its binary buffer (not yet attached).

    Args:
        motion: the bodies and poses (checked here).
        name: the scene's and the animation's name.

    Returns:
        ``(pygltflib.GLTF2, bytes)``.

    Raises:
        InputError: the motion's shapes or values are unusable.
    """
    import pygltflib as pg

    motion = motion.check()
    gl = pg.GLTF2(asset=pg.Asset(generator="nbst export", version="2.0"))
    blob = _Blob(gl, pg)
    materials: dict = {}
    quat = continuous_quaternions(motion.quat)
    nodes = []
    shared: dict = {}   # a body's solids (their bytes) -> its mesh: bodies alike share one
    users: list[list[str]] = []   # each mesh's bodies
    for b, body in enumerate(motion.bodies):
        q0 = quat[0, b]
        node = pg.Node(name=body.name, translation=[float(x) for x in motion.pos[0, b]],
                       rotation=[float(q0[1]), float(q0[2]), float(q0[3]), float(q0[0])])
        key = tuple((np.asarray(s.rows, np.float32).tobytes(), tuple(round(float(c), 6) for c in s.rgba),
                     None if s.colors is None else np.asarray(s.colors, np.float32).tobytes(),
                     None if s.texture is None else (np.asarray(s.uv, np.float32).tobytes(), s.texture.tobytes()))
                    for s in filter(_drawable, body.solids))
        if key and key in shared:
            node.mesh = shared[key]
            users[node.mesh].append(body.name)
            gl.nodes.append(node)
            nodes.append(len(gl.nodes) - 1)
            continue
        prims = []
        for s in filter(_drawable, body.solids):
            # corners shared by triangles (same position, normal and colour) stored once, and indexed
            rows = np.asarray(s.rows, np.float32)
            if s.colors is not None:
                rows = np.concatenate([rows, np.asarray(s.colors, np.float32)], axis=1)
            if s.texture is not None:
                rows = np.concatenate([rows, np.asarray(s.uv, np.float32)], axis=1)
            corners, inverse = np.unique(rows, axis=0, return_inverse=True)
            v, nrm = np.ascontiguousarray(corners[:, :3]), corners[:, 3:6]
            nrm = np.ascontiguousarray(nrm / np.linalg.norm(nrm, axis=1, keepdims=True))
            idx = np.asarray(inverse, dtype=np.uint32).reshape(-1)
            att = pg.Attributes(POSITION=blob.add(v, pg.VEC3, target=pg.ARRAY_BUFFER, bounds=True),
                                NORMAL=blob.add(nrm, pg.VEC3, target=pg.ARRAY_BUFFER))
            if s.colors is not None:
                att.COLOR_0 = blob.add(np.ascontiguousarray(corners[:, 6:9]), pg.VEC3, target=pg.ARRAY_BUFFER)
            if s.texture is not None:
                att.TEXCOORD_0 = blob.add(np.ascontiguousarray(corners[:, -2:]), pg.VEC2, target=pg.ARRAY_BUFFER)
            material = (_material(gl, pg, materials, s.rgba) if s.texture is None
                        else _textured(gl, pg, blob, s.texture, s.rgba))
            prims.append(pg.Primitive(attributes=att, indices=blob.add(idx, pg.SCALAR, target=pg.ELEMENT_ARRAY_BUFFER),
                                      material=material))
        if prims:
            gl.meshes.append(pg.Mesh(name=body.name, primitives=prims))
            node.mesh = shared[key] = len(gl.meshes) - 1
            users.append([body.name])
        else:   # said, not left out: its node index is its body's, its keyframes its body's
            node.extras = dict(EMPTY)
        gl.nodes.append(node)
        nodes.append(len(gl.nodes) - 1)
    for mesh, names in zip(gl.meshes, users):
        if len(names) > 1:
            mesh.name = f"{names[0]} and {len(names) - 1} more alike"
    # glTF's up is +y; MuJoCo's (and every nbst world's) +z: one root node turns the world -90 deg about
    # x, so (x, y, z) shows as (x, z, -y) and a floor lies flat (Blender's importer turns it z-up again)
    h = float(np.sqrt(0.5))
    gl.nodes.append(pg.Node(name=f"{name} (z-up)", rotation=[-h, 0.0, 0.0, h], children=nodes))
    note = empty_note(motion)
    gl.scenes.append(pg.Scene(name=name, nodes=[len(gl.nodes) - 1], extras={"nbst": note} if note else {}))
    gl.scene = 0
    moving = [b for b, body in enumerate(motion.bodies) if body.moves]
    if moving and len(motion.times) > 1:
        anim = pg.Animation(name=name)
        t_acc = blob.add(np.asarray(motion.times, dtype=np.float32), pg.SCALAR, bounds=True)
        for b in moving:
            xyzw = quat[:, b][:, [1, 2, 3, 0]]
            for path, values, kind in ((pg.TRANSLATION, motion.pos[:, b], pg.VEC3), (pg.ROTATION, xyzw, pg.VEC4)):
                if not np.ptp(np.asarray(values, np.float32), axis=0).any():
                    continue   # never changes as stored (a disk's rotation): the node's own value holds
                anim.samplers.append(pg.AnimationSampler(input=t_acc, interpolation=pg.ANIM_LINEAR,
                                                         output=blob.add(np.asarray(values, np.float32), kind)))
                anim.channels.append(pg.AnimationChannel(sampler=len(anim.samplers) - 1,
                                                         target=pg.AnimationChannelTarget(node=nodes[b], path=path)))
        gl.animations.append(anim)
    gl.buffers.append(pg.Buffer(byteLength=len(blob.data)))
    return gl, bytes(blob.data)


def write_glb(path: str | os.PathLike, motion: BodyMotion, *, name: str = "nbst", option: str = "--gltf") -> int:
    """Write ``motion`` as a binary glTF 2.0 file (.glb), atomically.

    Args:
        path: the output file (checked by :func:`nbst.outputs.write_bytes_atomic`: never a link,
            FIFO or folder).
        motion: the bodies and poses.
        name: the scene's and the animation's name.
        option: the output's name in a refusal's line.

    Returns:
        the file's size in bytes.

    Raises:
        InputError: the motion's shapes or values are unusable.
        OutputError: the path cannot be written.
    """
    gl, data = gltf_document(motion, name=name)
    gl.set_binary_blob(data)
    raw = b"".join(gl.save_to_bytes())
    write_bytes_atomic(path, raw, option=option)
    return len(raw)
