"""The painter the time-sampling methods share: a fixed set of objects rasterized at any shutter
time with the least per-sample work (:class:`Painter`), the pixel windows they cover per time
(:func:`sample_windows`), their placements computed once per object and time
(:class:`Placements`), and per-mesh constants kept across frames (:func:`mesh_constant`).
"""

from __future__ import annotations

import weakref

import numpy as np

from .. import _core
from ..geometry import Mesh
from ..raster import Camera
from ..scene import Object, Scene
from ._layers import Layer, composite

__all__ = ["Painter", "Placements", "sample_windows", "facing_faces", "mesh_constant", "box_corners"]


# Per-mesh constants kept across frames: {(id(vertices), id(faces)): (weak refs to both, {name:
# read-only array})}, an entry dropped with its vertex array. Nothing here holds a mesh alive.
_CONSTANTS: dict[tuple[int, int], tuple] = {}


def mesh_constant(mesh: Mesh, name: str, compute) -> np.ndarray:
    """``compute(mesh)`` kept across frames for ``mesh``. A Mesh owns read-only copies of its
    vertices and faces (and its Rust side, which gives the normals, another copy), so what is
    computed from them is a constant of the mesh; should a caller unlock an array
    (``flags.writeable = True``) to edit it in place, nothing is kept or reused for that mesh."""
    v, f = mesh.vertices, mesh.faces
    if v.flags.writeable or f.flags.writeable:
        return compute(mesh)
    key = (id(v), id(f))
    hit = _CONSTANTS.get(key)
    if hit is None or hit[0]() is not v or hit[1]() is not f:
        hit = (weakref.ref(v, lambda _r, k=key: _CONSTANTS.pop(k, None)), weakref.ref(f), {})
        _CONSTANTS[key] = hit
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


def _bounds(camera: Camera, pts: np.ndarray):
    """(x0, y0, x1, y1) pixel bounds of the points, clamped to the image (None when off the
    image), or the whole image when a point is behind the camera."""
    w, h = camera.width, camera.height
    vp = camera.view_projection
    clip = pts @ vp[:3, :3].T + vp[:3, 3]
    wc = pts @ vp[3, :3] + vp[3, 3]
    if (wc <= 1e-9).any():
        return 0, 0, w, h
    x = (clip[:, 0] / wc + 1.0) * 0.5 * w
    y = (1.0 - clip[:, 1] / wc) * 0.5 * h
    x0, y0 = max(0, int(np.floor(x.min())) - 1), max(0, int(np.floor(y.min())) - 1)
    x1, y1 = min(w, int(np.ceil(x.max())) + 1), min(h, int(np.ceil(y.max())) + 1)
    if x0 >= x1 or y0 >= y1:
        return None
    return x0, y0, x1, y1


class Placements:
    """``placement(obj, t)``: ``obj.transform_at(t)``, computed once per object and time (the
    sample windows and the painter both place every moving rigid object at every sample time;
    deforming vertices are not kept: N of them would be N meshes of memory). The matrices are
    shared: read them, do not write them."""

    def __init__(self):
        self._memo: dict[tuple[int, float], np.ndarray] = {}

    def __call__(self, obj: Object, t: float) -> np.ndarray:
        key = (id(obj), float(t))
        m = self._memo.get(key)
        if m is None:
            m = self._memo[key] = obj.transform_at(t)
        return m


def sample_windows(camera: Camera, times, objects, placement=None) -> list:
    """Per time of ``times``, the pixel rectangle (x0, y0, x1, y1) of ``camera`` holding
    ``objects`` at that time (None when they are off the image). Rigid objects are bounded by
    their transformed bounding box (the projection of a box holds the projection of its content
    when the box is in front of the camera); the whole image when a point is behind the camera.
    ``placement`` (a :class:`Placements`) may carry the transforms over to the painter."""
    place = placement if placement is not None else Placements()
    corners = {}
    for obj in objects:
        if not (obj.motion is not None and obj.motion.is_deforming):
            corners[id(obj)] = mesh_constant(obj.mesh, "corners", box_corners)
    out = []
    for t in times:
        pts = []
        for obj in objects:
            if id(obj) in corners:
                m = place(obj, t)
                pts.append(corners[id(obj)] @ m[:3, :3].T + m[:3, 3])
            else:
                pts.append(obj.world_vertices(t))
        out.append(_bounds(camera, np.concatenate(pts)))
    return out


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
    """Rasterizes a fixed set of objects at any shutter time with the least per-sample work.

    Faces, colours and object-space normals are converted once. A shading group holding a
    single rigid object is drawn in object space with the model transform folded into the view
    matrix (and the lights turned into object space), so no vertex is touched per sample; other
    groups get world vertices (and rotated normals) per sample. With a still camera ``eye``, a
    rigidly translating object (every keyframe with the same rotation and scale) loses the faces
    that face away from the eye during the whole shutter, once, before the sample loop: along a
    straight segment ``n . (eye - p(t))`` is linear in t, so a face back-facing at every keyframe
    is back-facing throughout and the rasterizer would cull it at every sample anyway."""

    def __init__(self, scene: Scene, objects: list[tuple[int, Object]], eye=None, placement=None):
        self.scene = scene
        self.place = placement if placement is not None else Placements()
        self.groups: dict[str, list] = {}
        for k, o in objects:
            faces = np.ascontiguousarray(o.mesh.faces, dtype=np.int64)
            if eye is not None:
                faces = facing_faces(o, faces, np.asarray(eye, dtype=np.float64))
            rgba = np.ascontiguousarray(np.atleast_2d(o.rgba), dtype=np.float32)
            normals = mesh_constant(o.mesh, "normals32", _normals32) if o.shading == "lambert" else None
            self.groups.setdefault(o.shading, []).append((k, o, faces, rgba, normals))
        self.lights = [(np.asarray(li.direction), tuple(map(float, li.intensity))) for li in scene.lights]
        self.ambient = tuple(map(float, scene.ambient))

    def _light_args(self, rotation=None):
        if rotation is None:
            return [(tuple(map(float, d)), k) for d, k in self.lights]
        return [(tuple(map(float, rotation.T @ d)), k) for d, k in self.lights]

    def layer(self, t: float, view: np.ndarray, projection: np.ndarray, width: int, height: int) -> Layer:
        out = None
        for shading, items in self.groups.items():
            if len(items) == 1 and not (items[0][1].motion is not None and items[0][1].motion.is_deforming):
                k, o, faces, rgba, normals = items[0]
                m = self.place(o, t)
                r = m[:3, :3] / np.cbrt(np.linalg.det(m[:3, :3]))
                args = [(o.mesh.vertices, faces, rgba, normals, k, True, None)]
                vm, lights = view @ m, self._light_args(r)
            else:
                args = []
                for k, o, faces, rgba, normals in items:
                    v = np.ascontiguousarray(o.world_vertices(t))
                    n = None
                    if normals is not None and not (o.motion is not None and o.motion.is_deforming):
                        r = self.place(o, t)[:3, :3]
                        n = np.ascontiguousarray(
                            normals @ (r / np.cbrt(np.linalg.det(r))).T, dtype=np.float32
                        )
                    args.append((v, faces, rgba, n, k, True, None))
                vm, lights = view, self._light_args()
            rgba_, depth, ids, _vel, _st = _core._rasterize(
                np.ascontiguousarray(vm),
                projection,
                width,
                height,
                args,
                1,
                "exact",
                shading,
                lights,
                self.ambient,
            )
            layer = Layer(rgba_, depth, ids)
            out = layer if out is None else composite(out, layer)
        return out if out is not None else Layer.empty(height, width)
