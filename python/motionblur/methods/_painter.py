"""The painter the time-sampling methods share: a fixed set of objects rasterized at any shutter
time with the least per-sample work (`Painter`, the compiled core's), the faces a
translating object turns away during the whole shutter (`facing_faces`), and per-mesh
constants kept across frames (`mesh_constant`).
"""

from __future__ import annotations

import weakref

import numpy as np

from .. import _core
from ..geometry import Mesh
from ..renderer import current_renderer
from ..scene import Object, Scene
from ._layers import Layer

__all__ = ["Painter", "painter_for", "facing_faces", "mesh_constant", "box_corners"]


def mesh_constant(mesh: Mesh, name: str, compute) -> np.ndarray:
    """``compute(mesh)`` kept across frames for ``mesh`` (on the renderer running,
    [`motionblur.Renderer`][motionblur.Renderer]). A Mesh owns read-only copies of its
    vertices and faces (and its Rust side, which gives the normals, another copy), so what is
    computed from them is a constant of the mesh; should a caller unlock an array
    (``flags.writeable = True``) to edit it in place, nothing is kept or reused for that mesh."""
    v, f = mesh.vertices, mesh.faces
    if v.flags.writeable or f.flags.writeable:
        return compute(mesh)
    # {(id(vertices), id(faces)): (weak refs to both, {name: read-only array})}: an entry is
    # dropped with its vertex array and checked against both on use; nothing holds a mesh alive
    store = current_renderer().mesh_constants
    key = (id(v), id(f))
    hit = store.get(key)
    if hit is None or hit[0]() is not v or hit[1]() is not f:
        hit = (weakref.ref(v, lambda _r, k=key: store.pop(k, None)), weakref.ref(f), {})
        store[key] = hit
    values = hit[2]
    if name not in values:
        a = compute(mesh)
        a.flags.writeable = False
        values[name] = a
    return values[name]


def box_corners(mesh: Mesh) -> np.ndarray:
    """(8,3) float64 corners of the mesh's axis-aligned bounding box."""
    v = mesh.vertices
    a, b = v.min(axis=0), v.max(axis=0)
    return np.array([[x, y, z] for x in (a[0], b[0]) for y in (a[1], b[1]) for z in (a[2], b[2])])


def _normals32(mesh: Mesh) -> np.ndarray:
    """(V,3) float32 vertex normals."""
    return mesh.vertex_normals().astype(np.float32)


def facing_faces(obj: Object, faces: np.ndarray, eye: np.ndarray) -> np.ndarray:
    """The faces of a rigidly translating ``obj`` that face ``eye`` at some time of the shutter
    (all faces for other motions), conservatively: near edge-on faces are kept. A face is kept
    when ``n . (e_k - a) > -1e-9 |n| |e_k - a|`` at some keyframe's object-space eye ``e_k``
    (``n`` its normal, ``a`` its first vertex), computed in Rust (``_core._facing_faces``)."""
    m = obj.motion
    if m is None or m.is_deforming:
        return faces
    keys = m.transforms
    if np.abs(keys[:, :3, :3] - keys[0, :3, :3]).max() > 1e-12 * (1.0 + np.abs(keys[0, :3, :3]).max()):
        return faces
    lin = keys[0, :3, :3]
    scale = np.cbrt(np.linalg.det(lin))
    rot = lin / scale
    # the eye in object space at the held ends and every keyframe in between
    eyes = np.array([rot.T @ (eye - key[:3, 3]) / scale for key in keys])
    kept = _core._facing_faces(np.ascontiguousarray(obj.mesh.vertices), faces, eyes)
    return faces if len(kept) == len(faces) else kept


class Painter:
    """Rasterizes a fixed set of objects at any shutter time with the least per-sample work:
    the compiled painter (``_core._Painter``, ``src/accumulate/painter.rs``), made once.

    Faces, colours, object-space normals and the objects' keyframes go to the core once. A
    shading group holding a single rigid object is drawn in object space with the model
    transform folded into the view matrix (and the lights turned into object space), so no
    vertex is touched per sample; other groups get world vertices (and rotated normals) per
    sample. With a still camera ``eye``, a rigidly translating object (every keyframe with the
    same rotation and scale) loses the faces that face away from the eye during the whole
    shutter, once (`facing_faces`): along a straight segment ``n . (eye - p(t))`` is
    linear in t, so a face back-facing at every keyframe is back-facing throughout and the
    rasterizer would cull it at every sample anyway. `layer` draws one time;
    ``core.accumulate_still`` and ``core.accumulate_moving`` a whole accumulation frame."""

    def __init__(self, scene: Scene, objects: list[tuple[int, Object]], eye=None):
        items = []
        for k, o in objects:
            faces = np.ascontiguousarray(o.mesh.faces, dtype=np.int64)
            if eye is not None:
                faces = facing_faces(o, faces, np.asarray(eye, dtype=np.float64))
            rgba = np.ascontiguousarray(np.atleast_2d(o.rgba), dtype=np.float32)
            normals = mesh_constant(o.mesh, "normals32", _normals32) if o.shading == "lambert" else None
            keys = None if o.motion is None else o.motion._keys
            items.append(
                {"id": k, "shading": o.shading, "vertices": o.mesh.vertices, "faces": faces, "rgba": rgba,
                 "normals": normals, "keyframes": keys}
            )  # fmt: skip
        lights = [(tuple(map(float, li.direction)), tuple(map(float, li.intensity))) for li in scene.lights]
        self.core = _core._Painter(items, lights, tuple(map(float, scene.ambient)))

    def layer(self, t: float, view: np.ndarray, projection: np.ndarray, width: int, height: int) -> Layer:
        """The objects at shutter time ``t`` seen through ``view`` and ``projection`` (4,4) in a
        ``width`` x ``height`` Layer (one sample a pixel)."""
        c = np.ascontiguousarray
        return Layer(
            *self.core.layer(
                float(t), c(view, dtype=np.float64), c(projection, dtype=np.float64), width, height
            )
        )


def _parts(objects) -> list:
    """What a painter is made of, per object: the Object, its mesh's arrays and its motion."""
    return [p for _, o in objects for p in (o, o.mesh.vertices, o.mesh.faces, o.motion)]


def painter_for(scene: Scene, objects: list[tuple[int, Object]], eye=None) -> Painter:
    """A `Painter` of ``objects`` kept across frames (up to 4, on the renderer running) while the objects (the
    same Object, mesh and motion, colour and shading), the eye, the lights and the ambient
    light stay the same, as a real-time loop reuses what it set up. The entry holds no object
    alive (weak references; it goes with its objects), and is never made for a mesh whose
    arrays a caller unlocked (``flags.writeable = True``)."""
    if any(o.mesh.vertices.flags.writeable or o.mesh.faces.flags.writeable for _, o in objects):
        return Painter(scene, objects, eye)
    parts = _parts(objects)
    key = (
        tuple(id(p) for p in parts),
        tuple((k, o.shading, o.color.tobytes()) for k, o in objects),
        None if eye is None else np.asarray(eye, dtype=np.float64).tobytes(),
        tuple((li.direction.tobytes(), li.intensity.tobytes()) for li in scene.lights),
        np.asarray(scene.ambient, dtype=np.float64).tobytes(),
    )
    kept = current_renderer().painters
    hit = kept.get(key, lambda hit: all(r() is p for r, p in zip(hit[1], parts)))
    if hit is not None:
        return hit[0]
    painter = Painter(scene, objects, eye)
    refs = [(lambda: None) if p is None else weakref.ref(p, lambda _r, k=key: kept.discard(k)) for p in parts]
    kept.put(key, (painter, refs))
    return painter
