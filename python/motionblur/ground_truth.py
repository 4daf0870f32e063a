"""Ground truth that follows surfaces through the shutter: optical flow, sharp frames, the blur's
mean motion and the objects' screen trajectories.

Every function here follows the surface seen at a pixel at one time (from a sharp render's depth
and ids) with its object's rigid motion and the camera's motion, and projects it at other
times; the background, where nothing is seen, is a point at infinity (it moves with the camera's
rotation only). These are closed forms of the scene's motion, not estimates from images.
Deforming objects have no rigid path for their surface points: pixels that see one raise
ValueError naming the object.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ._validate import as_array, as_int
from .raster import Camera, Frame
from .scene import Scene

__all__ = [
    "SurfacePaths",
    "surface_paths",
    "stratified_times",
    "flow",
    "sharp_frames",
    "mean_motion",
    "trajectories",
    "OUTPUTS",
    "outputs",
    "Exposure",
    "exposure",
]

_NAMED_TIMES = {"open": 0.0, "center": 0.5, "close": 1.0}


def _times(times, name: str = "times") -> np.ndarray:
    if times is None:
        return np.array([0.0, 0.5, 1.0])
    t = np.array(
        [_NAMED_TIMES.get(x, x) if isinstance(x, str) else x for x in np.atleast_1d(times)], dtype=object
    )
    t = as_array(t.astype(np.float64), name, np.float64, (None,))
    if ((t < 0.0) | (t > 1.0)).any():
        raise ValueError(f"{name}: shutter times must be in [0, 1]")
    return t


def stratified_times(scene: Scene, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """(times (N,), weights (N,)): N stratified shutter times ``(i + 0.5) / N`` and the
    shutter filter's integral over each stratum (summing to 1)."""
    n = as_int(samples, "samples", minimum=1, maximum=1 << 16)
    w = np.diff(scene.shutter_cdf(np.arange(n + 1) / n))
    return (np.arange(n) + 0.5) / n, w / w.sum()


def _camera_rays(scene: Scene, points: np.ndarray) -> np.ndarray:
    """(N,3) camera-space directions through pixel ``points`` (N,2) with view-axis length 1."""
    cam = scene.camera
    t = np.tan(cam.yfov / 2.0)
    x = (2.0 * points[:, 0] / cam.width - 1.0) * t * cam.aspect
    y = (1.0 - 2.0 * points[:, 1] / cam.height) * t
    return np.stack([x, y, -np.ones(len(points))], axis=1)


def _project(camera: Camera, world: np.ndarray, w: np.ndarray) -> np.ndarray:
    """(N,2) pixels of homogeneous world points (``world`` (N,3), ``w`` (N,) 1 for a point, 0 for
    a direction) seen by ``camera`` ([`Camera.project`][motionblur.raster.Camera.project]; a direction d is the point at d
    from this camera's eye, NaN behind the eye)."""
    points = np.where(w[:, None] > 0.0, world, camera.pose[:3, 3] + world)
    return camera.project(points)[0]


@dataclass(frozen=True)
class SurfacePaths:
    """Where the surfaces seen at N pixels at time ``source`` are at other shutter times.

    ``points`` (N,2) float64 pixels (x right, y down, pixel centres at +0.5); ``ids`` (N,) int32
    object seen (-1 background); ``depth`` (N,) float64 view-axis distance at ``source`` (inf
    for background); ``times`` (S,) float64; ``paths`` (N,S,2) float64 pixel positions at those
    times (NaN where the point is behind the camera then)."""

    points: NDArray[np.float64]
    ids: NDArray[np.int32]
    depth: NDArray[np.float64]
    source: float
    times: NDArray[np.float64]
    paths: NDArray[np.float64]


def _local_points(scene: Scene, world: np.ndarray, ids: np.ndarray, t: float) -> np.ndarray:
    """World points (N,3) seen on objects ``ids`` at ``t`` in their objects' own frames."""
    local = world.copy()
    for k in np.unique(ids[ids >= 0]):
        obj = scene.objects[int(k)]
        if obj.motion is not None and obj.motion.is_deforming:
            raise ValueError(f"scene: object {int(k)} deforms; its surface points have no rigid path")
        m = np.linalg.inv(obj.transform_at(t))
        sel = ids == k
        local[sel] = world[sel] @ m[:3, :3].T + m[:3, 3]
    return local


def _ray_depth(scene: Scene, k: int, t: float, eye: np.ndarray, rays: np.ndarray) -> np.ndarray:
    """(N,) the view-axis distance along ``rays`` (N,3, view-axis length 1) from ``eye`` to the
    nearest triangle of object ``k`` at time ``t`` (Moller-Trumbore), inf where none is hit."""
    obj = scene.objects[k]
    v = obj.world_vertices(t)[obj.mesh.faces]  # (F,3,3)
    e1, e2 = v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]
    out = np.full(len(rays), np.inf)
    for i, d in enumerate(rays):
        p = np.cross(d, e2)
        det = (e1 * p).sum(1)
        ok = np.abs(det) > 1e-12
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        s = eye - v[:, 0]
        u = (s * p).sum(1) * inv
        q = np.cross(s, e1)
        w = (q * d).sum(1) * inv
        dist = (q * e2).sum(1) * inv
        hit = ok & (u >= 0) & (w >= 0) & (u + w <= 1) & (dist > 0)
        if hit.any():
            out[i] = dist[hit].min()
    return out


def surface_paths(scene: Scene, points, times, *, source=None, frame: Frame | None = None) -> SurfacePaths:
    """Follow the surfaces seen at ``points`` (N,2) pixels at shutter time ``source`` (default
    the scene's reference time) to each of ``times`` (S,) (floats in [0, 1] or 'open', 'center',
    'close'). ``frame``: the sharp frame at ``source`` to read the object seen (ids) and, at
    pixel centres, its depth from (rendered when None); at other points the depth is found by
    casting the ray onto that object's triangles. Returns [`SurfacePaths`][motionblur.ground_truth.SurfacePaths]."""
    from .methods._sharp import sharp_frame

    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected a motionblur.Scene, got {type(scene).__name__}")
    src = scene.reference_t if source is None else float(_times(source, "source")[0])
    ts = _times(times)
    pts = as_array(points, "points", np.float64, (None, 2)).copy()
    w, h = scene.camera.width, scene.camera.height
    if len(pts) and not ((pts >= 0).all() and (pts[:, 0] < w).all() and (pts[:, 1] < h).all()):
        raise ValueError("points: every point must lie inside the image")
    if frame is None:
        frame = sharp_frame(scene, src, velocity=None)
    px = pts.astype(np.int64)
    depth = frame.depth[px[:, 1], px[:, 0]].astype(np.float64)
    ids = frame.ids[px[:, 1], px[:, 0]].astype(np.int32)
    pose = scene.camera_pose_at(src)
    rays = _camera_rays(scene, pts) @ pose[:3, :3].T
    off = (ids >= 0) & (np.abs(pts - px - 0.5) > 1e-9).any(axis=1)  # not a pixel centre: cast
    for k in np.unique(ids[off]):
        sel = off & (ids == k)
        depth[sel] = _ray_depth(scene, int(k), src, pose[:3, 3], rays[sel])
    ids[~np.isfinite(depth)] = -1
    far = ~np.isfinite(depth)
    world = np.where(far[:, None], rays, rays * np.where(far, 0.0, depth)[:, None] + pose[:3, 3])
    local = _local_points(scene, world, ids, src)
    weight = np.where(far, 0.0, 1.0)
    paths = np.empty((len(pts), len(ts), 2))
    # the points of each moving object, found once (a still object's points stay where they are)
    groups = [
        (k, np.flatnonzero(ids == k)) for k in np.unique(ids[ids >= 0]) if scene.objects[int(k)].is_moving
    ]
    moved = local.copy()
    for j, t in enumerate(ts):
        for k, idx in groups:
            m = scene.objects[int(k)].transform_at(float(t))
            moved[idx] = local[idx] @ m[:3, :3].T + m[:3, 3]
        paths[:, j] = _project(scene.camera_at(float(t)), moved, weight)
    return SurfacePaths(pts, ids, depth, src, ts, paths)


def _pixel_centres(scene: Scene) -> np.ndarray:
    h, w = scene.camera.height, scene.camera.width
    y, x = np.mgrid[0:h, 0:w] + 0.5
    return np.stack([x.ravel(), y.ravel()], axis=1)


def flow(scene: Scene, times=None, *, source=None) -> NDArray[np.float32]:
    """(S,H,W,2) float32 optical flow in pixels (+x right, +y down) from time ``source`` (default
    the scene's reference time) to each of ``times`` (default open, center, close): where the
    surface seen at each pixel centre at ``source`` is at that time, minus the pixel centre.
    Backward flow (from a time to ``source``) is ``flow(scene, [source], source=time)``."""
    h, w = scene.camera.height, scene.camera.width
    p = surface_paths(scene, _pixel_centres(scene), _times(times), source=source)
    d = p.paths - p.points[:, None, :]
    return np.ascontiguousarray(d.reshape(h, w, -1, 2).transpose(2, 0, 1, 3)).astype(np.float32)


def mean_motion(scene: Scene, samples: int = 64) -> NDArray[np.float32]:
    """(H,W,2) float32 the blur's mean motion per pixel: the shutter-weighted mean displacement,
    from its pixel centre at the reference time, of the surface seen there (``samples``
    stratified shutter times)."""
    h, w = scene.camera.height, scene.camera.width
    times, weights = stratified_times(scene, samples)
    p = surface_paths(scene, _pixel_centres(scene), times)
    d = ((p.paths - p.points[:, None, :]) * weights[None, :, None]).sum(axis=1)
    return d.reshape(h, w, 2).astype(np.float32)


def _flows(scene: Scene, ts: np.ndarray, sharp: list[Frame]) -> dict:
    """``flow``, ``flow_backward`` and ``mean_motion`` of [`outputs`][motionblur.ground_truth.outputs],
    from one sharp frame per time (``sharp``, at ``ts``): the surfaces seen at the reference time
    are followed once to the output times and the mean motion's times together."""
    h, w = scene.camera.height, scene.camera.width
    ref = scene.reference_t
    at_ref = [f for t, f in zip(ts, sharp) if t == ref]
    mm_times, weights = stratified_times(scene, MEAN_MOTION_SAMPLES)
    p = surface_paths(
        scene, _pixel_centres(scene), np.concatenate([ts, mm_times]), frame=at_ref[0] if at_ref else None
    )
    d = p.paths - p.points[:, None, :]
    back = [
        surface_paths(scene, p.points, [ref], source=float(t), frame=f).paths[:, 0] - p.points
        for t, f in zip(ts, sharp)
    ]
    as_image = lambda a: a.reshape(h, w, 2).astype(np.float32)  # noqa: E731
    return {
        "flow": np.stack([as_image(d[:, j]) for j in range(len(ts))]),
        "flow_backward": np.stack([as_image(b) for b in back]),
        "mean_motion": as_image((d[:, len(ts) :] * weights[None, :, None]).sum(axis=1)),
    }


def sharp_frames(scene: Scene, times=None, aa: int = 1) -> list[Frame]:
    """Sharp frames (rgba, depth, ids) at shutter ``times`` (default open, center, close), each the
    scene rasterized by the camera at that time with ``aa`` (1, 2 or 4) samples per pixel along
    each axis; ``stats["time"]`` is the time."""
    from .methods._sharp import sharp_frame

    out = []
    for t in _times(times):
        f = sharp_frame(scene, float(t), as_int(aa, "aa", minimum=1, maximum=4), velocity=None)
        f.stats["time"] = float(t)
        out.append(f)
    return out


def trajectories(scene: Scene, samples: int = 64) -> list[dict]:
    """Per object, its screen-space path over the shutter: a list (one dict per object, in
    ``scene.objects`` order) with ``name``, ``times`` (S,) stratified shutter times, ``origin``
    (S,2) the pixel position of the object's origin (its mesh's coordinate origin moved by its
    motion; NaN when behind the camera) and ``bbox`` (S,4) the pixel bounding box (x0, y0, x1,
    y1) of its projected vertices in front of the camera (NaN when none is)."""
    times, _ = stratified_times(scene, samples)
    cameras = [scene.camera_at(float(t)) for t in times]
    out = []
    for obj in scene.objects:
        origin, bbox = np.empty((len(times), 2)), np.full((len(times), 4), np.nan)
        for j, t in enumerate(times):
            origin[j] = cameras[j].project(obj.transform_at(float(t))[None, :3, 3])[0][0]
            q = cameras[j].project(obj.world_vertices(float(t)))[0]
            q = q[np.isfinite(q).all(axis=1)]
            if len(q):
                bbox[j] = [*q.min(0), *q.max(0)]
        out.append({"name": obj.name, "times": times, "origin": origin, "bbox": bbox})
    return out


#: Stratified shutter times of the mean motion that ``outputs=["flow"]`` gives (the midpoint
#: rule: its error falls as 1/N^2 on a smooth path; each time costs one projection of every pixel).
MEAN_MOTION_SAMPLES = 16

#: The ground-truth outputs [`render`][motionblur.render.render] gives with ``outputs=[...]``,
#: each with the methods that give it (None: every method; they are closed forms of the scene).
OUTPUTS: dict[str, tuple[str, ...] | None] = {
    "sharp": None,
    "flow": None,
    "trajectory": None,
    "exposure": ("analytic",),
}


def _check_outputs(names, method: str) -> list[str]:
    if isinstance(names, str) or not all(isinstance(n, str) for n in names):
        raise TypeError("outputs: expected a list of names such as ['sharp', 'flow']")
    out = []
    for n in names:
        if n not in OUTPUTS:
            raise ValueError(f"outputs: unknown output {n!r}; expected some of {', '.join(OUTPUTS)}")
        given_by = OUTPUTS[n]
        if given_by is not None and method not in given_by:
            raise ValueError(
                f"outputs: {n!r} is given by {', '.join(given_by)} only, not by method {method!r}"
            )
        out.append(n)
    return list(dict.fromkeys(out))


def outputs(scene: Scene, names, method: str, times=None) -> dict:
    """The ground-truth outputs ``names`` (from `OUTPUTS`) of
    ``scene`` for a frame rendered with ``method``, at shutter ``times`` (default open, center,
    close; S of them), as [`render`][motionblur.render.render] puts them on ``Frame.outputs``:

    - ``sharp``: ``sharp`` a list of S [`Frame`][motionblur.Frame]s (rgba, depth, ids) at the times;
    - ``flow``: ``flow`` (S,H,W,2) float32 forward flow in pixels from the reference time to each
      time, ``flow_backward`` (S,H,W,2) from each time back to the reference time (at the pixels
      of the sharp frame at that time), ``mean_motion`` (H,W,2) the blur's mean motion (from
      ``MEAN_MOTION_SAMPLES`` stratified times);
    - ``trajectory``: ``trajectory``, per object, its screen origin path and bounding box over
      the shutter ([`trajectories`][motionblur.ground_truth.trajectories]);
    - ``exposure`` (the analytic method only: it comes from the same render, which
      [`render`][motionblur.render.render] asks for it): ``exposure``, an
      [`Exposure`][motionblur.ground_truth.Exposure]; not made here.

    ``times`` (S,) is returned as ``times``. Raises ValueError naming ``outputs`` for an unknown
    name or one the method cannot give, and for deforming objects where a flow is asked."""
    names = _check_outputs(names, method)
    ts = _times(times, "output_times")
    out: dict = {"times": ts}
    if "sharp" in names or "flow" in names:
        sharp = sharp_frames(scene, ts)  # each drawn once: the output and the flows' sources
        out["sharp" if "sharp" in names else "_sharp"] = sharp
    if "flow" in names:
        out.update(_flows(scene, ts, sharp))
        out.pop("_sharp", None)
    if "trajectory" in names:
        out["trajectory"] = trajectories(scene)
    return out


def _exposure_of(planes: dict, n_objects: int) -> Exposure:
    ids = np.append(np.arange(n_objects, dtype=np.int32), np.int32(-1))
    out = [planes["fraction"], planes["first"], planes["last"], ids]
    for a in out:
        a.setflags(write=False)
    return Exposure(*out)


@dataclass(frozen=True)
class Exposure:
    """Per pixel and object, how long the object is the visible one there over the shutter.

    The K = N + 1 planes are the scene's N objects (ids 0..N-1, in ``scene.objects`` order)
    and, last, id -1: no surface at all (an empty background). ``fraction`` (H,W,K) float32 in
    [0, 1]: the shutter-weighted fraction of the shutter during which the object is visible,
    the mean over the pixel's samples (the planes of a pixel sum to 1); ``first`` and ``last``
    (H,W,K) float32 shutter times in [0, 1]: the earliest and latest instant it is visible at
    any of the pixel's samples, NaN where it never is; ``ids`` (K,) int32 the object id of each
    plane. The arrays are read-only."""

    fraction: NDArray[np.float32]
    first: NDArray[np.float32]
    last: NDArray[np.float32]
    ids: NDArray[np.int32]


#: The renderer of the exposure channel, handed over by the analytic method when `motionblur`
#: loads it (``fn(scene, aa, *, tolerance, segments, exposure=True) -> Frame``): ground truth sits
#: below the rendering methods ([`render`][motionblur.render.render] imports it for
#: ``outputs=``), so it is given the method rather than importing it (as ``render`` is given
#: its methods by ``register``).
_EXPOSURE_RENDERER: list[Callable[..., Frame]] = []


def _renders_exposure(fn: Callable[..., Frame]) -> Callable[..., Frame]:
    """Decorator: ``fn`` renders the exposure channel for [`exposure`][motionblur.ground_truth.exposure]."""
    _EXPOSURE_RENDERER[:] = [fn]
    return fn


def exposure(scene: Scene, aa: int = 1, *, tolerance: float = 0.01, segments=None) -> Exposure:
    """The exposure channel of ``scene`` from the analytic method (its exact covered times and
    visibility over time), rendered with ``aa`` (1, 2 or 4) samples per pixel along each axis;
    ``tolerance`` and ``segments`` as the analytic method has them (how the shutter is cut into
    segments of linear motion). Returns an [`Exposure`][motionblur.ground_truth.Exposure].

    Visible, at a sample and an instant, is the object of the frontmost surface there, whatever
    its alpha (a half-transparent object in front is the visible one; a triangle of alpha 0 at
    all its corners is not drawn at all), or where no moving surface is in front of it, the
    object of the static layer (still objects, rasterized once); id -1 where there is nothing.
    A sample's fraction is the shutter filter's weight of the times the object is visible (its
    integral over them: a ramp shutter counts late times more), and a pixel's is the mean over
    its samples. ``first`` and ``last`` are the earliest start and latest end over the pixel's
    samples of the stretches of time of positive length the object is visible, whatever the
    filter's weight there (a time the filter gives weight 0 still counts)."""
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected a motionblur.Scene, got {type(scene).__name__}")
    (analytic,) = _EXPOSURE_RENDERER  # set when motionblur loads motionblur.methods
    f = analytic(scene, aa, tolerance=tolerance, segments=segments, exposure=True)
    return _exposure_of(f.stats["exposure"], len(scene.objects))


from ._namespace import tidy  # noqa: E402  (dir() lists the API only; see motionblur._namespace)

tidy(__name__)
