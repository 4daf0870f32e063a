"""Object-space geometry of the motion-volume paper (Wloka and Zeleznik 1996, sections 3 and 4).

- [`Mesh`][motionblur.geometry.Mesh]: an indexed triangle mesh with a cached edge adjacency (built once in Rust).
- [`contour_edges`][motionblur.geometry.contour_edges]: the edges between faces facing the motion and faces facing away.
- [`motion_volume`][motionblur.geometry.motion_volume]: leading, trailing and joining surfaces with per-vertex colour and alpha.
- [`spin_volume`][motionblur.geometry.spin_volume]: the special case of section 4.3 for objects that spin but barely move.
- [`ContourTable`][motionblur.geometry.ContourTable]: contour sets precomputed for K directions, looked up by the nearest one.

Every function that takes a mesh accepts a [`Mesh`][motionblur.geometry.Mesh] or any object with ``.vertices`` and
``.faces`` (a ``trimesh.Trimesh``); wrap it once in [`Mesh`][motionblur.geometry.Mesh] to reuse the adjacency.

Edge rule (boundary and non-manifold edges): for an edge, add +1 for each front face that runs
it from its lower to its higher vertex index and -1 for the other direction (``net_front``), the
same over its back faces (``net_back``). It is a contour edge when ``net_front != 0`` or
``net_back != 0``, oriented as its front faces run it (counter-clockwise), or against its back
faces when its front faces cancel. On a closed, consistently wound mesh this is exactly the
paper's rule (one front and one back face). A boundary edge (one face) is therefore always a
contour edge; a non-manifold edge (three or more faces) is one when the windings of its front
(or back) faces leave a net border. A degenerate (zero-area) face has a zero normal, so
``n . m = 0`` and it is front by the paper's ``>=`` rule; it is counted in ``Mesh.stats``.
"""

from __future__ import annotations

import numpy as np

from . import _core
from ._optional import require
from ._validate import (
    MAX_COORD,
    as_array,
    as_bool,
    as_choice,
    as_coords,
    as_float,
    as_int,
    as_rgba,
    as_segments,
    check_coords,
)

__all__ = [
    "Mesh",
    "MotionVolume",
    "ContourTable",
    "contour_edges",
    "motion_volume",
    "spin_volume",
    "as_mesh",
    "LEADING",
    "TRAILING",
    "JOINING",
    "MAX_COORD",
]

#: ``MotionVolume.part`` values: leading surface (front faces at shutter close).
LEADING: int = int(_core.LEADING)
#: trailing surface (back faces at shutter open).
TRAILING: int = int(_core.TRAILING)
#: joining surface (contour swept along the path).
JOINING: int = int(_core.JOINING)

#: The shutter filters of the volumes' alphas (defined by the compiled core).
FILTERS: tuple[str, ...] = tuple(_core.FILTERS)


def _as(value, name: str, dtype) -> np.ndarray:
    """(N,3) array of ``dtype``; a matching ndarray passes without a scan (Rust checks values)."""
    if isinstance(value, np.ndarray) and value.dtype == dtype and value.ndim == 2 and value.shape[1] == 3:
        if value.size == 0:
            raise ValueError(f"{name}: is empty")
        return value
    return as_array(value, name, dtype, (None, 3), finite=False)


def _readonly(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


class Mesh:
    """An indexed triangle mesh.

    Args:
        vertices: (V,3) float32 or float64 array, scene units; copied (float64).
        faces: (F,3) integer array of any dtype, counter-clockwise seen from the front; copied
            (int64). Every index must be in ``[0, V)``.

    Or ``Mesh(obj)`` with any object that has ``.vertices`` and ``.faces`` (``trimesh.Trimesh``).

    Attributes:
        vertices: (V,3) float64, read-only (the mesh's own copy).
        faces: (F,3) int64, read-only.
        stats: dict with ``faces``, ``vertices``, ``edges``, ``degenerate_faces`` (zero cross
            product), ``boundary_edges`` (one face), ``nonmanifold_edges`` (three or more faces),
            ``inconsistent_edges`` (two faces running the edge the same way),
            ``unreferenced_vertices`` and ``closed`` (no boundary, non-manifold or inconsistent edge).

    The edge adjacency is built in Rust on first use and kept on the object;
    [`with_vertices`][motionblur.geometry.Mesh.with_vertices] makes a deformed copy that shares it. Every coordinate must lie within
    ``+-MAX_COORD`` (the coordinate range). A mesh pickles and deep-copies through its two arrays
    (the copy builds its adjacency again when used).
    """

    __slots__ = ("_core", "_vertices", "_faces", "_stats")

    def __init__(self, vertices, faces=None):
        if faces is None:
            if isinstance(vertices, Mesh):
                self._core, self._vertices, self._faces, self._stats = (
                    vertices._core,
                    vertices._vertices,
                    vertices._faces,
                    vertices._stats,
                )
                return
            if not (hasattr(vertices, "vertices") and hasattr(vertices, "faces")):
                raise TypeError(
                    f"mesh: expected a Mesh or an object with .vertices and .faces, got {type(vertices).__name__}"
                )
            vertices, faces = vertices.vertices, vertices.faces
        # dtype and shape here; finiteness and index ranges are checked in Rust (in parallel).
        v = _readonly(np.array(_as(vertices, "vertices", np.float64), copy=True))
        f = _readonly(np.array(_as(faces, "faces", np.int64), copy=True))
        self._core = _core._Mesh(v, f)
        self._vertices, self._faces, self._stats = v, f, None

    def __reduce__(self):
        return Mesh, (self._vertices, self._faces)

    @classmethod
    def _from_core(cls, core, vertices, faces) -> Mesh:
        m = cls.__new__(cls)
        m._core, m._vertices, m._faces, m._stats = core, vertices, faces, None
        return m

    @property
    def vertices(self) -> np.ndarray:
        """(V,3) float64 vertex positions, read-only."""
        return self._vertices

    @property
    def faces(self) -> np.ndarray:
        """(F,3) int64 vertex indices, counter-clockwise front, read-only."""
        return self._faces

    @property
    def stats(self) -> dict:
        """Counts of faces, vertices, edges and of degenerate faces and special edges."""
        if self._stats is None:
            self._stats = dict(self._core.stats())
        return dict(self._stats)

    def face_normals(self, unit: bool = True) -> np.ndarray:
        """(F,3) float64 face normals: unit vectors (zeros for degenerate faces), or with
        ``unit=False`` the raw cross products ``(b - a) x (c - a)`` (length twice the area)."""
        return self._core.face_normals(as_bool(unit, "unit"))

    def vertex_normals(self) -> np.ndarray:
        """(V,3) float64 area-weighted unit vertex normals (zeros where undefined)."""
        return self._core.vertex_normals()

    def edges(self) -> np.ndarray:
        """(E,2) int64 undirected edges ``a < b``, sorted (zero-length edges excluded)."""
        return self._core.edges()

    def edge_face_counts(self) -> np.ndarray:
        """(E,) int64 number of faces on each edge of [`edges`][motionblur.geometry.Mesh.edges] (1 boundary, 3+ non-manifold)."""
        return self._core.edge_face_counts()

    @property
    def has_adjacency(self) -> bool:
        """Whether the cached edge adjacency has been built."""
        return bool(self._core.has_adjacency())

    def with_vertices(self, vertices) -> Mesh:
        """A mesh with the same faces and cached adjacency and new (V,3) vertex positions."""
        v = _readonly(
            np.array(as_array(vertices, "vertices", np.float64, (len(self._vertices), 3)), copy=True)
        )
        return Mesh._from_core(self._core.with_vertices(v), v, self._faces)

    def to_trimesh(self):
        """A ``trimesh.Trimesh`` of this mesh (``process=False``: the same vertices in the same
        order, float64, and faces). Needs trimesh (``pip install "motionblur[interop]"``)."""
        from .interop.trimesh import to_trimesh

        return to_trimesh(self._vertices, self._faces)

    def __len__(self) -> int:
        return len(self._faces)

    def __repr__(self) -> str:
        return f"Mesh(vertices={len(self._vertices)}, faces={len(self._faces)})"


def as_mesh(mesh, name: str = "mesh") -> Mesh:
    """``mesh`` as a [`Mesh`][motionblur.geometry.Mesh] (itself if it is one; else built from ``.vertices``/``.faces``)."""
    if isinstance(mesh, Mesh):
        return mesh
    if hasattr(mesh, "vertices") and hasattr(mesh, "faces"):
        return Mesh(mesh.vertices, mesh.faces)
    raise TypeError(
        f"{name}: expected a Mesh or an object with .vertices and .faces, got {type(mesh).__name__}"
    )


def _vec3(value, name: str) -> np.ndarray:
    """A (3,) float64 point or vector, finite and within the coordinate range."""
    return as_coords(value, name, (3,))


def _check_output(vertices: np.ndarray, name: str) -> None:
    """The volume's vertices stay in the coordinate range (a large scale or a spin about a far
    centre can carry a mesh that is in range out of it)."""
    try:
        check_coords(vertices, "volume")
    except ValueError as exc:
        raise ValueError(f"{name}: the volume leaves the coordinate range ({exc})") from None


def contour_edges(mesh, motion, camera_position=None) -> np.ndarray:
    """The contour edges of ``mesh`` for the motion vector ``motion`` (paper section 3.2).

    Faces with ``n . motion >= 0`` (``n = (b - a) x (c - a)``) are front, the others back; a
    contour edge joins a front and a back face (see the module docs for boundary, non-manifold
    and degenerate cases).

    Args:
        mesh: Mesh or trimesh-like.
        motion: (3,) float, the motion vector in the mesh's coordinates (only its direction matters).
        camera_position: optional (3,) float, scene units. If given, only the contour line: the
            edges with at least one adjacent face front-facing to the camera, ``n . (eye - a) > 0``.

    Returns:
        (E,2) int64 vertex indices ``(a, b)``, oriented as the edge runs counter-clockwise in its
            front face (so the back face is on the other side); rows in sorted order of ``(min, max)``.
    """
    m = as_mesh(mesh)
    mv = _vec3(motion, "motion")
    cam = None if camera_position is None else _vec3(camera_position, "camera_position")
    return _core.contour_edges(m._core, mv, cam)


class MotionVolume:
    """The motion volume of a mesh: leading, trailing and joining surfaces.

    Attributes:
        vertices: (N,3) float64, scene units (world placement given by the keyframes).
        faces: (M,3) int64, counter-clockwise seen from outside the volume.
        rgba: (N,4) float32 straight (non-premultiplied) linear RGBA; alpha is the colour's alpha
            times the temporal filter's opacity at the vertex's shutter time.
        normals: (N,3) float32 unit lighting normals (zeros where the mesh normal is undefined).
        part: (M,) uint8, ``LEADING`` (0), ``TRAILING`` (1) or ``JOINING`` (2) per face.
        ring_alpha: (n+1,) float64 filter opacity of the contour rings at the keyframe times,
            shutter open to close (for box/triangle/gaussian: the mean over the ring's vertices).
        contour_count: number of contour edges swept.
        segments: number of joining segments n.
        contour_error: with a ``contour_table``, the angle (radians) between the summed motion and
            the stored direction whose face split and contour were swept; 0.0 otherwise.
    """

    __slots__ = (
        "vertices", "faces", "rgba", "normals", "part", "ring_alpha", "contour_count", "segments", "contour_error"
    )  # fmt: skip

    def __init__(self, vertices, faces, rgba, normals, part, ring_alpha, contour_count, contour_error=0.0):
        self.vertices = vertices
        self.faces = faces
        self.rgba = rgba
        self.normals = normals
        self.part = part
        self.ring_alpha = ring_alpha
        self.contour_count = int(contour_count)
        self.segments = len(ring_alpha) - 1
        self.contour_error = float(contour_error)

    def to_trimesh(self):
        """A ``trimesh.Trimesh`` (``process=False``: no vertex merging) with vertex colours as
        uint8 straight RGBA and the lighting normals."""
        trimesh = require("trimesh", "to_trimesh")
        colors = np.clip(np.round(self.rgba * 255.0), 0, 255).astype(np.uint8)
        return trimesh.Trimesh(
            vertices=self.vertices,
            faces=self.faces,
            vertex_normals=self.normals.astype(np.float64),
            vertex_colors=colors,
            process=False,
        )

    def __repr__(self) -> str:
        counts = np.bincount(self.part, minlength=3)
        return (
            f"MotionVolume(vertices={len(self.vertices)}, faces={len(self.faces)}, leading={counts[0]}, "
            f"trailing={counts[1]}, joining={counts[2]}, segments={self.segments})"
        )


_DEFORMING = (
    "motion: vertex keyframes (a deforming mesh); a motion volume sweeps one rigid contour along "
    "rigid keyframes (K+1,4,4). For a deforming mesh use BlurShell / shell_over_shutter (its "
    "silhouette of motion follows every vertex), or render(scene, 'blur_shell' | 'velocity' | "
    "'opaque_image' | 'accumulation')"
)


def _keyframes(motion):
    """The rigid keyframes of ``motion`` at the times i/K, validated and split by the core's
    keyframe engine once (keyframes the engine made already are taken as they are)."""
    if isinstance(motion, _core._Keyframes):
        return motion
    deforming = getattr(motion, "is_deforming", None)
    if deforming is not None:  # a motionblur.Motion
        if deforming:
            raise ValueError(_DEFORMING)
        return motion._keys.resampled(max(1, len(motion.times) - 1))
    arr = np.asarray(motion) if not isinstance(motion, np.ndarray) else motion
    if arr.ndim == 3 and arr.shape[-1] == 3:
        raise ValueError(_DEFORMING)
    if arr.ndim == 1:
        m = _vec3(motion, "motion")
        k = np.repeat(np.eye(4)[None], 2, axis=0)
        k[1, :3, 3] = m
    else:
        k = as_array(motion, "motion", np.float64, (None, 4, 4), finite=False)
    return _core._Keyframes(np.linspace(0.0, 1.0, len(k)), k, None, "motion")


def _colors(colors, n_vertices: int) -> np.ndarray:
    if colors is None:
        return np.ones((1, 4), dtype=np.float32)
    return as_rgba(colors, "colors", n_vertices)


def _volume_options(filter, colors, face_colors, normals, camera_position, contour_line) -> dict:
    """The options both volume kernels take (``_core.motion_volume``, ``_core.spin_volume``)."""
    return {
        "filter": filter,
        "colors": colors,
        "face_colors": face_colors,
        "normals": normals,
        "camera_position": camera_position,
        "contour_line": contour_line,
    }


def _vertex_or_face_colors(colors, face_colors, n_vertices: int, n_faces: int):
    """(colour array for the core, per-face flag)."""
    if face_colors is None:
        return _colors(colors, n_vertices), False
    if colors is not None:
        raise ValueError("face_colors: give either colors or face_colors, not both")
    c = np.asarray(face_colors)
    if c.ndim != 2:
        raise ValueError(f"face_colors: expected shape (F,3) or (F,4), got {c.shape}")
    try:
        return _colors(c, n_faces), True
    except (TypeError, ValueError) as exc:
        raise type(exc)(str(exc).replace("colors:", "face_colors:", 1)) from None


def motion_volume(
    mesh,
    motion,
    segments: int = 1,
    filter: str = "ramp",
    colors=None,
    normals=None,
    camera_position=None,
    face_colors=None,
    contour_line: bool = True,
    visible_only: bool = False,
    contour_table: ContourTable | None = None,
    window=(0.0, 1.0),
) -> MotionVolume:
    """Build the motion volume of ``mesh`` over the shutter (paper sections 3.3-3.4, 4.1-4.4).

    Args:
        mesh: Mesh or trimesh-like; vertices in object space (scene units).
        motion: either a (3,) translation ``m`` over the shutter, meaning the keyframes
            ``[identity, translate(m)]``: the given vertices are the placement at shutter OPEN and the
            leading surface sits at ``v + m`` at shutter close; or a rigid [`motionblur.Motion`][motionblur.Motion]
            (resampled at the times ``i / K`` for its K keyframe intervals); or rigid keyframes (K+1,4,4) float
            (rotation, positive uniform scale, translation; row-major, acting on column vectors) at
            the equally spaced shutter times ``i / K``, applied to the vertices (the methods pass
            the core's keyframe object, ``_core._Keyframes``, at those times).
        segments: int >= 1. Each keyframe interval is cut into ``segments`` joining segments
            (translation lerp, rotation slerp, scale lerp: the keyframe engine's interpolation);
            the total is ``K * segments``, so the keyframes are always followed and ``segments``
            only subdivides them (at most ``_core.MAX_SEGMENTS`` in total).
        filter: ``"ramp"``, the paper's, exactly as stated there (leading opaque, trailing and ring
            alpha ``max(0.1, 1 - D/E)`` with D the path length to the leading ring and E the extent
            along the motion; a look, its total coverage is not the object's area); or ``"box"``,
            ``"triangle"``, ``"gaussian"`` shutter weights (our own design): every vertex gets the
            weighted fraction of the shutter during which the object covers its image, so the
            volume drawn with back-face culling and exact blending has the coverage of the
            time-averaged image (within 5% of an accumulation of rasterized renders in the tests,
            per pixel within 15%). The image is modelled with the convex hull of the object's
            projection (perspective from ``camera_position``; without one, orthographic along the
            world axis least aligned with the motion, which is less accurate), so concave objects
            are approximated: holes count as covered and a folded contour sweeps overlapping
            strips (measured +14% to +97% total coverage on a torus and a bumpy blob, the ramp
            +30% to +230%). For these filters each joining segment is cut at the two times the
            object's ends pass each contour vertex (plus 3 more cuts for triangle, 5 for gaussian),
            and coarse meshes are subdivided (each edge into up to 16 parts, at most 2**20 faces)
            so that alphas can follow the coverage profile; then faces are cut (up to three passes)
            where the linearly interpolated alpha misses the coverage by more than 0.02, chiefly
            along the outline of an object whose image grows, shrinks or turns across its motion.
            Past 64 segments the model follows the path on 64 spans, so the time is linear in the
            segments. No 0.1 floor: long streaks are faint. See ``src/volume/coverage.rs`` and
            ``src/volume/refine.rs``.
        colors: None (white, opaque), one RGB/RGBA colour, or (V,3)/(V,4) per vertex; linear,
            straight alpha, RGB >= 0, alpha in [0, 1].
        face_colors: optional (F,3)/(F,4) colour per face (linear, straight alpha), instead of
            ``colors``. Every leading and trailing face then has its own three vertices and every
            joining strip its own vertices, coloured from its front face (leading end) to its back
            face (trailing end), or all in the visible side's colour when the camera sees only one
            side (section 4.1). The volume stays closed geometrically, not as an indexed mesh.
        normals: optional (V,3) lighting normals in object space; default area-weighted normals.
        camera_position: optional (3,) world position of the camera (at shutter close). If given,
            only the contour line is swept (edges whose front face at close or back face at open
            faces the camera) and joining vertices take the normal of the visible side when only
            one side is visible (section 4.1); joining strips then have their own vertices. The
            box/triangle/gaussian alphas use it for a perspective view.
        contour_line: bool, default True. With ``camera_position``, False sweeps every contour
            edge (shared ring vertices, a closed volume) and uses the camera for the alphas only.
        visible_only: bool, default False. With ``camera_position`` and ``contour_line``, leave out
            the leading faces that face away from the camera at shutter close and the trailing faces
            that face away from it at open: drawn with back-face culling the volume gives the same
            image from fewer faces (about half of a dense mesh's), but it is no longer closed.
            Ignored otherwise.
        contour_table: optional [`ContourTable`][motionblur.geometry.ContourTable] of this mesh (paper section 4.4): the face
            split and contour edges of its stored direction nearest to the summed motion (object
            space) are swept instead of the ones computed for the motion itself (a coarse mesh
            subdivided for the alphas maps the split to its new faces and finds their contour);
            ``MotionVolume.contour_error`` is the angle between the two. The alphas still follow the
            true motion. Exactly the volume without a table when the motion's direction is stored.
        window: (a, b) with 0 <= a < b <= 1, default (0, 1): the part of the shutter the keyframes
            stand for (their times ``i / K`` are the shutter times ``a + (b - a) i / K``); the
            box/triangle/gaussian alphas weigh the time by the filter over ``[a, b]``, normalised to
            unit weight (one piece of a shutter drawn as several volumes, as ``render(...,
            "motion_volume")`` does for motions one volume cannot follow). The ramp ignores it.

    Returns:
        MotionVolume, to be drawn with back-face culling (``Draw(..., cull_back=True)``) and
            ``blend="exact"``. Without a camera, a closed consistently wound mesh gives a closed
            consistently wound volume. If every keyframe is equal (zero motion), the mesh itself, all ``LEADING`` and
            opaque.
    """
    m = as_mesh(mesh)
    keys = _keyframes(motion)
    seg = as_segments(segments)
    as_choice(filter, "filter", FILTERS)
    nv = len(m.vertices)
    col, per_face = _vertex_or_face_colors(colors, face_colors, nv, len(m.faces))
    nrm = None if normals is None else as_array(normals, "normals", np.float64, (nv, 3))
    cam = None if camera_position is None else _vec3(camera_position, "camera_position")
    contour_line = as_bool(contour_line, "contour_line")
    visible_only = as_bool(visible_only, "visible_only")
    table = None
    if contour_table is not None:
        if not isinstance(contour_table, ContourTable):
            raise TypeError(f"contour_table: expected a ContourTable, got {type(contour_table).__name__}")
        if contour_table.mesh is not m and not np.array_equal(contour_table.mesh.faces, m.faces):
            raise ValueError("contour_table: was computed for another mesh (its faces differ from mesh's)")
        table = contour_table._core
    win = as_array(window, "window", np.float64, (2,))
    options = _volume_options(filter, col, per_face, nrm, cam, contour_line)
    options.update(visible_only=visible_only, contour_table=table, window=(float(win[0]), float(win[1])))
    out = _core.motion_volume(m._core, keys, seg, options)
    _check_output(out[0], "motion")
    return MotionVolume(*out)


def spin_volume(
    mesh,
    axis,
    angle: float,
    center=(0.0, 0.0, 0.0),
    translation=None,
    segments: int | None = None,
    filter: str = "box",
    colors=None,
    normals=None,
    camera_position=None,
    face_colors=None,
) -> MotionVolume:
    """The motion volume of an object that spins but barely moves (end of paper section 4.3).

    The paper's rule: the contour comes from the rotation axis instead of the motion vector,
    and the transparency follows the rotational speed. Our construction (``src/volume/spin.rs``):
    faces with ``n . axis >= 0`` are front; the leading surface is the front faces at shutter
    close, the trailing surface the back faces at open, and the contour is swept around the
    axis through the last ``min(|angle|, 2 pi)`` radians (rings at most ``pi/12`` apart). A
    vertex at distance r from the axis gets alpha ``theta(r) / (theta(r) + B(r) * sweep)``,
    theta(r) the angle the object covers on that circle seen along the axis and B(r) the number
    of arcs (blades) there: each blade draws its leading face and one swept sector, so the total
    coverage of every circle is kept and alpha falls as 1 / speed; a full circle (a hub) stays
    opaque. The filter weights the rings by its density at their shutter time (weight 1 for
    more than one turn). Draw it with back-face culling and ``blend="exact"``.

    Use it when the rotation dominates (a propeller, a wheel seen along its axle);
    [`motion_volume`][motionblur.geometry.motion_volume] with rotating keyframes handles slow rotation with translation.

    Args:
        mesh: Mesh or trimesh-like; vertices are the placement at shutter OPEN (scene units).
        axis: (3,) float, the rotation axis (non-zero; normalised).
        angle: float, radians turned over the shutter, right hand about ``axis`` (any sign, any
            size; 0 gives [`motion_volume`][motionblur.geometry.motion_volume] of the translation, the mesh itself without one).
        center: (3,) float, a point on the axis.
        translation: optional (3,) float, a (small) translation over the shutter.
        segments: optional int in 1..``_core.MAX_SEGMENTS``, the number of sweep steps (default one
            per pi/12).
        filter: ``"box"``, ``"ramp"``, ``"triangle"`` or ``"gaussian"``.
        colors: as in [`motion_volume`][motionblur.geometry.motion_volume].
        normals: as in [`motion_volume`][motionblur.geometry.motion_volume].
        camera_position: as in [`motion_volume`][motionblur.geometry.motion_volume].
        face_colors: as in [`motion_volume`][motionblur.geometry.motion_volume].

    Returns:
        MotionVolume (``ring_alpha`` is the mean alpha of each ring's contour vertices).
    """
    m = as_mesh(mesh)
    ax = _vec3(axis, "axis")
    if not np.any(ax):
        raise ValueError("axis: is zero; a spin needs an axis")
    ang = as_float(angle, "angle")
    c = _vec3(center, "center")
    t = np.zeros(3) if translation is None else _vec3(translation, "translation")
    seg = None if segments is None else as_segments(segments)
    as_choice(filter, "filter", FILTERS)
    nv = len(m.vertices)
    col, per_face = _vertex_or_face_colors(colors, face_colors, nv, len(m.faces))
    nrm = None if normals is None else as_array(normals, "normals", np.float64, (nv, 3))
    cam = None if camera_position is None else _vec3(camera_position, "camera_position")
    try:
        spin = {"axis": ax, "angle": ang, "center": c, "translation": t, "segments": seg}
        out = _core.spin_volume(m._core, spin, _volume_options(filter, col, per_face, nrm, cam, True))
    except ValueError as exc:  # the core's keyframes of the spin are called "motion": not an argument here
        if not str(exc).startswith("motion:"):
            raise
        raise ValueError(f"center: the spin about it leaves the coordinate range ({exc})") from None
    _check_output(out[0], "center")
    return MotionVolume(*out)


class ContourTable:
    """Contour sets precomputed for K motion directions (paper section 4.4).

    Args:
        mesh: Mesh or trimesh-like.
        directions: int K (1..65536): K directions drawn uniformly on the unit sphere from ``seed``
            (stochastic, as the paper recommends); or a (K,3) float array of directions (normalised),
            e.g. clustered around a preferred direction of motion.
        seed: int >= 0, the generator's seed (splitmix64; the same seed gives the same table).

    A table pickles and deep-copies (rebuilt from its mesh, directions and seed: the same sets).

    ``lookup(motion)`` returns the contour edges of the stored direction nearest to ``motion``
    (largest cosine) and the angle between the two in radians. ``motion_volume(...,
    contour_table=table)`` and ``render(scene, "motion_volume", contour_table=...)`` sweep the
    stored split and contour instead of computing them each frame.
    """

    __slots__ = ("_core", "mesh", "_args")

    def __init__(self, mesh, directions=64, seed: int = 0):
        self.mesh = as_mesh(mesh)
        s = as_int(seed, "seed", minimum=0, maximum=2**64 - 1)
        if isinstance(directions, (int, np.integer)) and not isinstance(directions, bool):
            k = as_int(directions, "directions", minimum=1, maximum=65536)
            self._args = (k, s)
            self._core = _core._ContourTable(self.mesh._core, k, s, None)
        elif np.ndim(directions) == 0:
            raise TypeError(f"directions: expected an int or a (K,3) array, got {type(directions).__name__}")
        else:
            d = as_coords(directions, "directions", (None, 3))
            if len(d) > 65536:
                raise ValueError(f"directions: at most 65536, got {len(d)}")
            if (np.linalg.norm(d, axis=1) == 0).any():
                raise ValueError("directions: a direction is zero")
            d = np.array(d, copy=True)  # kept for pickling; the caller's array may change
            d.flags.writeable = False
            self._args = (d, s)
            self._core = _core._ContourTable(self.mesh._core, len(d), s, d)

    def __reduce__(self):
        # Rebuilt from what made it (the directions or their count and seed): the same table.
        return ContourTable, (self.mesh, *self._args)

    def __len__(self) -> int:
        return len(self._core)

    @property
    def directions(self) -> np.ndarray:
        """(K,3) float64 unit directions."""
        return self._core.directions()

    def nearest(self, motion) -> tuple[int, float]:
        """(index of the nearest stored direction, angle to it in radians) for a (3,) motion."""
        return self._core.nearest(_vec3(motion, "motion"))

    def lookup(self, motion) -> tuple[np.ndarray, float]:
        """The (E,2) int64 contour edges of the nearest stored direction to the (3,) ``motion``
        (as [`contour_edges`][motionblur.geometry.contour_edges] gives for that direction) and the angular error in radians."""
        i, err = self.nearest(motion)
        return self._core.edges(i), err

    def edges(self, index: int) -> np.ndarray:
        """(E,2) int64 contour edges stored for direction ``index``."""
        return self._core.edges(as_int(index, "index", minimum=0, maximum=len(self) - 1))

    def front_faces(self, index: int) -> np.ndarray:
        """(F,) bool: the faces facing direction ``index`` (``n . d >= 0``)."""
        return self._core.front(as_int(index, "index", minimum=0, maximum=len(self) - 1))

    @property
    def storage_bytes(self) -> int:
        """Bytes held by the stored sets (12 per edge: its adjacency index and two vertices; 1 per
        face flag and direction)."""
        return int(self._core.storage_bytes())
