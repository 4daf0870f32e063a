"""Blur shells for deforming meshes (Jones and Keyser): the silhouette of motion and BlurShell.

A blur shell is a set of quad strips trailing a moving (possibly deforming) mesh: at every
*update* each polygon finds whether one of its edges is on the *silhouette of motion* and keeps
a ring of the edge's recent positions; [`BlurShell.build`][motionblur.shell.BlurShell.build] joins those positions into strips
attached to the current mesh, their alpha falling towards the past. Drawn with culling off and
transparency, the shell looks like motion blur (or speed lines, with a colour of its own).

Rules (the paper leaves some open; each choice is stated here and tested):

- **Facing.** A vertex that does not move (``p == p_prev`` in float32) is neutral (0); a
  moving vertex is back (-1) when ``n . (p - p_prev) < 0`` and front (+1) otherwise, so one
  moving in its tangent plane (``n . d == 0``) is front, the ``>= 0`` convention of
  [`motionblur.contour_edges`][motionblur.contour_edges] (a symmetric mesh moving along an axis keeps its whole
  silhouette). ``n`` is the given normal, or the unnormalised sum of the raw normals
  ``(b - a) x (c - a)`` of the faces around the vertex, added in face order. A neutral vertex
  is neither front nor back. Everything is evaluated in float32 (positions rounded to float32 first, fixed operation
  order), so a vertex whose float32 position does not change is neutral, and a numpy float32
  twin gives the same signs bit for bit. So that nothing overflows float32, positions must lie
  within ``MAX_COORD`` (1e9) and given normals within ``MAX_NORMAL`` (1e18) in every component;
  beyond that (or NaN/inf) a ValueError names the argument.
- **Silhouette edge.** A triangle with exactly one front and two back corners has the edge
  between its back corners on the silhouette, as the face runs it (``face[k] -> face[k+1]``).
  So a static polygon, or a polygon with a corner that does not move, has none; the first update (no
  previous positions) finds none; a polygon whose plane is perpendicular to its motion (all
  corners front, or all back) has none, as in the paper.
- **Ring.** Each polygon keeps ``subdivisions`` elements, one per update: the edge on the
  silhouette, or, off the silhouette, the last edge it had (the paper's "positions of the last
  blurred vertices", taken at that update). The update index is the ring slot of the newest.
- **Birth.** A polygon without a live strip that gains an edge at update ``n`` starts its strip
  with that edge at update ``n`` and at update ``n - 1`` (where the motion that put it on the
  silhouette began), so a shell fed ``subdivisions + 1`` positions spans all of them.
- **Hysteresis and fading.** A polygon off the silhouette keeps its full strip (still extended
  with its last edge) for ``hysteresis`` updates; then its fade level ``d`` rises by one per
  update, and on the silhouette again it falls by one per update. The strip is gone when
  ``d == subdivisions``, i.e. ``hysteresis + subdivisions`` updates after the polygon lost its
  edge.
- **Alpha.** Pair ``j`` of a strip (``j = 0``: the base, the polygon's last edge at the current
  positions; ``j = i + 1``: the ring element recorded ``i`` updates ago) has alpha
  ``initial_alpha * (1 - max(j, d) / subdivisions)`` in float32: the paper's ramp, falling by
  ``initial_alpha / subdivisions`` per pair and reaching 0 at ``j = subdivisions``. Any strip
  vertex present in two consecutive builds (the base of one build is ring element 0 of the
  next) changes alpha by at most ``initial_alpha / subdivisions``, and a vertex disappears only
  from an alpha of at most that: strips never pop. New strips grow out of the mesh.
- **Mask.** Masked-out polygons never record an edge, so they have no strip; the others are
  unaffected (strips are per polygon).
"""

from __future__ import annotations

import threading

import numpy as np

from . import _core
from ._optional import require
from ._validate import MAX_COORD, as_array, as_float, as_int

__all__ = ["BlurShell", "ShellMesh", "MotionSilhouette", "motion_silhouette", "shell_over_shutter"]

#: Largest accepted |coordinate| of positions (scene units): the one coordinate range of the
#: package (``motionblur.MAX_COORD``). The facing test runs in float32: face normals multiply two
#: coordinate differences and ``n . d`` a third, which would overflow float32 (3.4e38) beyond it.
MAX_COORD = MAX_COORD
#: Largest accepted |component| of given normals (``n . d`` stays finite in float32).
MAX_NORMAL = 1e18


def _faces(faces) -> np.ndarray:
    f = as_array(faces, "faces", np.int64, (None, 3))
    if f.min() < 0:
        raise ValueError(f"faces: indices must be >= 0, got {f.min()}")
    return f


def _rows(value, name: str, n: int | None = None) -> np.ndarray:
    """(N,3) float64 C-contiguous (no copy when it already is); finiteness is checked in Rust,
    in parallel, with the same error message."""
    if (
        isinstance(value, np.ndarray)
        and value.dtype == np.float64
        and value.ndim == 2
        and value.shape[1] == 3
    ):
        if n is not None and len(value) != n:
            raise ValueError(f"{name}: expected shape ({n},3), got {value.shape}")
        if value.size == 0:
            raise ValueError(f"{name}: is empty")
        return np.ascontiguousarray(value)
    return as_array(value, name, np.float64, (n, 3))


class ShellMesh:
    """The shell built by [`BlurShell.build`][motionblur.shell.BlurShell.build].

    Attributes:
        vertices: (N,3) float64, scene units. Each strip's base pair is the polygon's edge on the
            current mesh: exactly the positions given to ``build``, or else the float32 snapshot of
            the last update; older pairs come from float32 snapshots.
        faces: (M,3) int64, two triangles per quad; draw with culling off.
        rgba: (N,4) float32 straight (non-premultiplied) linear colour and alpha in [0, 1].
        normals: (N,3) float32 unit normals (the mesh's vertex normals when the pair was recorded:
            the given ones, or the float32 area-weighted ones of that update's positions).
        face: (N,) int64, the mesh polygon whose strip each vertex belongs to.
        step: (N,) int32, the pair index ``j`` along the strip (0 = base on the current mesh).

    Strips are stored one after the other in increasing polygon order; pair ``j`` of a strip is
    at rows ``2j`` (edge start) and ``2j + 1`` (edge end) from the strip's first row.
    """

    __slots__ = ("vertices", "faces", "rgba", "normals", "face", "step")

    def __init__(self, vertices, faces, rgba, normals, face, step):
        self.vertices, self.faces, self.rgba = vertices, faces, rgba
        self.normals, self.face, self.step = normals, face, step

    @classmethod
    def empty(cls) -> ShellMesh:
        return cls(
            np.zeros((0, 3)),
            np.zeros((0, 3), np.int64),
            np.zeros((0, 4), np.float32),
            np.zeros((0, 3), np.float32),
            np.zeros(0, np.int64),
            np.zeros(0, np.int32),
        )

    @property
    def source_face(self) -> np.ndarray:
        """(M,) int64: the mesh polygon each shell triangle belongs to."""
        return self.face[self.faces[:, 0]] if len(self.faces) else np.zeros(0, np.int64)

    @property
    def is_empty(self) -> bool:
        return len(self.faces) == 0

    def __len__(self) -> int:
        return len(self.faces)

    def __repr__(self) -> str:
        return f"ShellMesh({len(self.vertices)} vertices, {len(self.faces)} triangles)"

    def to_trimesh(self):
        """A ``trimesh.Trimesh`` (process=False) with RGBA uint8 vertex colours and the normals."""
        trimesh = require("trimesh", "to_trimesh")
        colors = np.round(np.clip(self.rgba, 0.0, 1.0) * 255.0).astype(np.uint8)
        return trimesh.Trimesh(
            vertices=self.vertices,
            faces=self.faces,
            vertex_colors=colors,
            vertex_normals=self.normals,
            process=False,
        )

    def draw(self, object_id: int = 0):
        """A [`motionblur.Draw`][motionblur.Draw] with culling off (the paper draws blur polygons unculled).
        Raises ValueError for an empty shell (check `is_empty`)."""
        from .raster import Draw

        if self.is_empty:
            raise ValueError("shell: is empty (no strips); nothing to draw")
        return Draw(
            self.vertices, self.faces, self.rgba, normals=self.normals, object_id=object_id, cull_back=False
        )


def _rgba_rows(color) -> np.ndarray:
    """``color`` (3,), (4,), (N,3) or (N,4) as (1,4) or (N,4) float32 RGBA (alpha 1 for RGB);
    RGB >= 0 and alpha in [0, 1] (errors name ``color``)."""
    c = np.asarray(color)
    width = c.shape[-1] if c.ndim in (1, 2) and c.shape[-1] in (3, 4) else 3
    shape = (width,) if c.ndim == 1 else (None, width)
    c = as_array(c, "color", np.float32, shape).reshape(-1, width)
    if (c < 0).any():
        raise ValueError("color: must be >= 0")
    if width == 3:
        return np.concatenate([c, np.ones((len(c), 1), np.float32)], axis=1)
    if (c[:, 3] > 1).any():
        raise ValueError("color: alpha must be in [0, 1]")
    return np.ascontiguousarray(c)


class BlurShell:
    """The stateful blur shell of one mesh (Jones and Keyser, section 3); rules in the module docs.

    Args:
        faces: (F,3) int, counter-clockwise front; or a mesh object with ``.vertices`` and
            ``.faces`` (then its vertex count is used).
        subdivisions: int in 1..``_core.MAX_SUBDIVISIONS``: ring length, and pairs per full strip
            minus one.
        hysteresis: int in 0..``_core.MAX_HYSTERESIS``: updates a polygon keeps its full strip
            after losing its edge.
        initial_alpha: float in (0, 1]: alpha of the base pair.
        mask: optional (F,) bool: False polygons never get a strip (selective blurring).
        color: optional RGB or RGBA, (3,)/(4,) for every strip (speed lines) or (V,3)/(V,4) per
            mesh vertex (e.g. the mesh's own colours); default white. Linear, >= 0; an alpha, in
            [0, 1], scales the strip's own (a translucent object's trail is as translucent as the
            object); RGB is alpha 1.
        n_vertices: optional int V; default: the length of the first ``update``'s vertices.

    ``update(vertices, normals=None)`` feeds world positions (V,3) at one update;
    ``build(vertices=None, normals=None)`` returns the [`ShellMesh`][motionblur.shell.ShellMesh]; ``reset()`` forgets
    every update. The vertex count is fixed: an update with another count raises ValueError.
    The heavy work runs in Rust with the GIL released; results do not depend on thread count.

    A shell may be shared between threads: its calls take an internal lock, so calls from
    several threads run one after the other (in the order they get the lock). It pickles and
    deep-copies with its whole history (the copy updates and builds exactly as the original).
    """

    def __init__(
        self, faces, subdivisions=10, hysteresis=3, initial_alpha=1.0, mask=None, color=None, n_vertices=None
    ):
        if hasattr(faces, "faces") and hasattr(faces, "vertices"):
            if n_vertices is None:
                n_vertices = len(faces.vertices)
            faces = faces.faces
        # A read-only view: _faces may return the caller's own array (int64, C-contiguous).
        self._faces = _faces(faces).view()
        self._faces.flags.writeable = False
        self.subdivisions = as_int(subdivisions, "subdivisions", minimum=1, maximum=_core.MAX_SUBDIVISIONS)
        self.hysteresis = as_int(hysteresis, "hysteresis", minimum=0, maximum=_core.MAX_HYSTERESIS)
        self.initial_alpha = as_float(initial_alpha, "initial_alpha")
        # the core keeps it in float32: a positive value that rounds to 0 there is refused here,
        # not at the first update
        if not (0.0 < self.initial_alpha <= 1.0 and np.float32(self.initial_alpha) > 0):
            raise ValueError(f"initial_alpha: must be in (0, 1] (in float32), got {self.initial_alpha}")
        nf = len(self._faces)
        if mask is not None:
            m = np.asarray(mask)
            if m.dtype != np.bool_:
                raise TypeError(f"mask: expected a bool array, got dtype {m.dtype}")
            if m.shape != (nf,):
                raise ValueError(f"mask: expected shape ({nf},), got {m.shape}")
            mask = np.ascontiguousarray(m)
        self._mask = mask
        self._color = None if color is None else _rgba_rows(color)
        self._core = None
        self._lock = threading.Lock()
        if n_vertices is not None:
            self._make(as_int(n_vertices, "n_vertices", minimum=1, maximum=np.iinfo(np.int64).max))

    def _make(self, nv: int) -> None:
        if self._faces.max() >= nv:
            raise ValueError(f"faces: indices must be < the vertex count {nv}, got {self._faces.max()}")
        if self._color is not None and len(self._color) not in (1, nv):
            raise ValueError(f"color: expected one colour or {nv} (one per vertex), got {len(self._color)}")
        options = {
            "subdivisions": self.subdivisions,
            "hysteresis": self.hysteresis,
            "initial_alpha": np.float32(self.initial_alpha).item(),
        }
        self._core = _core._BlurShell(self._faces, nv, options, self._mask, self._color)

    @property
    def faces(self) -> np.ndarray:
        """(F,3) int64, read-only."""
        return self._faces

    @property
    def n_vertices(self) -> int | None:
        """V, or None before the first update when it was not given."""
        return None if self._core is None else self._core.n_vertices

    @property
    def updates(self) -> int:
        """Updates since construction or the last reset."""
        return 0 if self._core is None else self._core.updates

    @property
    def update_index(self) -> int | None:
        """The paper's global update index: the ring slot of the newest element (None before any update)."""
        return None if self._core is None else self._core.update_index

    def update(self, vertices, normals=None) -> None:
        """Feed world positions ``vertices`` (V,3) float (scene units) and optionally the vertex
        normals (V,3) used for the facing test (default: area-weighted face normals). The
        caller's arrays are read, never written. Raises ValueError naming ``vertices`` or
        ``normals`` (wrong shape, NaN/inf, a vertex count other than the shell's, a component
        beyond ``MAX_COORD`` / ``MAX_NORMAL``)."""
        v = _rows(vertices, "vertices")
        n = None if normals is None else _rows(normals, "normals")
        with self._lock:
            if self._core is None:
                if len(v) <= self._faces.max():
                    raise ValueError(
                        f"vertices: the faces use vertex {self._faces.max()}, got {len(v)} vertices"
                    )
                self._make(len(v))
            self._core.update(v, n)

    def build(self, vertices=None, normals=None) -> ShellMesh:
        """The shell after the last update, as a [`ShellMesh`][motionblur.shell.ShellMesh] (empty before any update).

        ``vertices`` / ``normals`` (V,3): the current mesh when it moved since the last update
        (a frame between updates); default: those of the last update. The base pairs take
        these positions, so strips stay attached to the mesh drawn in the same frame."""
        v = None if vertices is None else _rows(vertices, "vertices")
        n = None if normals is None else _rows(normals, "normals")
        with self._lock:
            if self._core is None:
                return ShellMesh.empty()
            return ShellMesh(*self._core.build(v, n))

    def reset(self) -> None:
        """Forget every update (no strips; the next update finds no silhouette)."""
        with self._lock:
            if self._core is not None:
                self._core.reset()

    def state(self) -> dict[str, np.ndarray]:
        """Per-vertex and per-polygon state after the last update: ``facing`` (V,) int8,
        ``last_edge`` (F,) int8 (k of edge face[k] -> face[k+1], -1 never), ``since`` (F,) int64
        updates since the polygon last had an edge (saturates at 65535), ``fade`` (F,) int32
        fade level ``d`` (>= subdivisions: no strip), ``run`` (F,) int32 ring elements in the
        strip."""
        with self._lock:
            if self._core is None:
                raise ValueError("shell: has no state before the first update")
            keys = ("facing", "last_edge", "since", "fade", "run")
            return dict(zip(keys, self._core._state()))

    def element(self, face: int, age: int) -> tuple[int, bool] | None:
        """Ring element of polygon ``face`` recorded ``age`` updates ago: (edge k, on the
        silhouette then), or None beyond its strip."""
        face = as_int(face, "face", minimum=0, maximum=len(self._faces) - 1)
        age = as_int(age, "age", minimum=0, maximum=np.iinfo(np.int64).max)
        with self._lock:
            if self._core is None:
                return None
            return self._core._element(face, age)

    def __getstate__(self) -> dict:
        with self._lock:
            history = None if self._core is None else self._core._history()
            n_vertices = None if self._core is None else self._core.n_vertices
        return {
            "faces": self._faces,
            "subdivisions": self.subdivisions,
            "hysteresis": self.hysteresis,
            "initial_alpha": self.initial_alpha,
            "mask": self._mask,
            "color": self._color,
            "n_vertices": n_vertices,
            "history": history,
        }

    def __setstate__(self, state: dict) -> None:
        self.__init__(
            state["faces"],
            state["subdivisions"],
            state["hysteresis"],
            state["initial_alpha"],
            state["mask"],
            state["color"],
            state["n_vertices"],
        )
        if state["history"] is not None:
            self._core._restore(state["history"])

    def __repr__(self) -> str:
        return (
            f"BlurShell({len(self._faces)} faces, subdivisions={self.subdivisions}, "
            f"hysteresis={self.hysteresis}, initial_alpha={self.initial_alpha:g}, updates={self.updates})"
        )


class MotionSilhouette:
    """The silhouette of motion of a mesh between two positions.

    Attributes: ``facing`` (V,) int8: +1 front (``n . d >= 0``), -1 back, 0 neutral (does not
    move); ``face_edge`` (F,) int8: the
    local index k of each face's silhouette edge ``face[k] -> face[(k+1) % 3]``, -1 for none;
    ``edges`` (E,2) int64 vertex pairs of the silhouette edges (as their faces run them) and
    ``edge_faces`` (E,) int64 the face of each, in increasing face order.
    """

    __slots__ = ("facing", "face_edge", "edges", "edge_faces")

    def __init__(self, facing, face_edge, faces):
        self.facing, self.face_edge = facing, face_edge
        sel = np.nonzero(face_edge >= 0)[0]
        k = face_edge[sel].astype(np.int64)
        self.edge_faces = sel.astype(np.int64)
        self.edges = np.stack([faces[sel, k], faces[sel, (k + 1) % 3]], axis=1).reshape(-1, 2)

    def __repr__(self) -> str:
        return f"MotionSilhouette({len(self.edges)} edges)"


def motion_silhouette(mesh, previous_vertices, normals=None) -> MotionSilhouette:
    """The silhouette of motion (section 3.2) of ``mesh`` (a [`motionblur.Mesh`][motionblur.Mesh] or any
    object with ``.vertices`` (V,3) and ``.faces`` (F,3): its current positions) moving from
    ``previous_vertices`` (V,3) float. ``normals`` (V,3): vertex normals for the facing test
    (default: the unnormalised sums of the face normals around each vertex). Rules in the module
    docs. Raises ValueError naming the argument (NaN/inf, or a component beyond ``MAX_COORD``
    for positions or ``MAX_NORMAL`` for normals); the GIL is released."""
    if not (hasattr(mesh, "vertices") and hasattr(mesh, "faces")):
        raise TypeError(
            f"mesh: expected a Mesh or an object with .vertices and .faces, got {type(mesh).__name__}"
        )
    v = _rows(mesh.vertices, "vertices")
    f = _faces(mesh.faces)
    p = _rows(previous_vertices, "previous_vertices")
    if len(p) != len(v):
        raise ValueError(f"previous_vertices: expected {len(v)} rows (as the mesh), got {len(p)}")
    n = None if normals is None else _rows(normals, "normals", len(v))
    facing, edge = _core._motion_silhouette(v, p, f, n)
    return MotionSilhouette(facing, edge, f)


def sample_positions(times, positions, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """``samples`` evenly spaced times over [times[0], times[-1]] and the positions there, linear
    between keyframes: ((samples,) float64, (samples,V,3) float64)."""
    t = as_array(times, "times", np.float64, (None,))
    if isinstance(positions, (list, tuple)):
        counts = {len(np.asarray(p)) for p in positions}
        if len(counts) > 1:
            raise ValueError(
                f"positions: every time must have the same vertex count, got {sorted(counts)} "
                "(a mesh that changes vertex count cannot have a blur shell)"
            )
    p = as_array(positions, "positions", np.float64, (len(t), None, 3))
    with np.errstate(over="ignore"):
        steps, span = np.diff(t), t[-1] - t[0]
    if len(t) < 2 or not (steps > 0).all():
        raise ValueError("times: need at least 2 strictly increasing times")
    if not np.isfinite(span):
        raise ValueError(f"times: the span {t[0]:g} .. {t[-1]:g} overflows float64")
    ts = np.linspace(t[0], t[-1], samples)
    i = np.clip(np.searchsorted(t, ts, side="right") - 1, 0, len(t) - 2)
    w = ((ts - t[i]) / (t[i + 1] - t[i]))[:, None, None]
    return ts, p[i] * (1.0 - w) + p[i + 1] * w


def shell_over_shutter(
    faces, times, positions, subdivisions=10, hysteresis=3, initial_alpha=1.0, mask=None, color=None
) -> ShellMesh:
    """A shell fed by a motion over a shutter.

    ``faces`` (F,3) int; ``times`` (K,) strictly increasing (shutter time, any units);
    ``positions`` (K,V,3) float world positions at those times. The motion is sampled at
    ``subdivisions + 1`` evenly spaced times from ``times[0]`` to ``times[-1]`` (linear between
    keyframes); the shell is updated at all but the last and built at the last (the frame), so
    its strips span the whole shutter, with alpha ``initial_alpha`` at the mesh at ``times[-1]``
    falling to 0 at its position at ``times[0]``. Other options as [`BlurShell`][motionblur.shell.BlurShell]."""
    shell = BlurShell(faces, subdivisions, hysteresis, initial_alpha, mask, color)
    _, ps = sample_positions(times, positions, shell.subdivisions + 1)
    for p in ps[:-1]:
        shell.update(p)
    return shell.build(ps[-1])
