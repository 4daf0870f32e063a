"""Colours of motion volumes: the time-averaged colour the camera sees, per volume vertex or per
pixel (used by `motionblur.methods.motion_volume`).

The paper's volume carries the object's own surface colours, the joining surfaces those of the
contour. A motion-blurred pixel instead shows the shutter-average of the surfaces passing over
it. Two estimates of that average are made here from sharp renders of the moving objects:

- `averaged_colors` (``colors="averaged"``): one sharp render at mid-shutter, box-blurred
  along the image path of the object's centroid (exact for a translation seen orthographically),
  sampled at the volume's vertices.
- `scattered` (``colors="pixel"``): K sharp renders, at the middle of K equal pieces of the
  shutter, each pixel carried back to its 3D point (from the depth buffer) and splatted along the
  image path that point follows during its piece (``_core._scatter_pieces``, the paths made and
  splatted in Rust as ``_core._splat_paths`` splats them). Every point blurs by
  its own motion (nearer points faster under perspective, rotation, several objects), and the
  surfaces hidden at one piece's middle are seen at another's.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from .. import _core, image
from ..raster import Camera, Draw
from ..scene import Object, Scene
from ._layers import raster_layer, window_projection
from ._painter import Painter, box_corners, mesh_constant

#: Stand-in for an object drawn unlit: colours already shaded (``raster_layer`` groups by it).
UNLIT = SimpleNamespace(shading="flat")

#: Path points per piece of the shutter in `scattered` (4 straight segments: perspective
#: speed changes and rotation follow them).
PATH_STEPS = 4

#: Splat work (sources x pixels of path) a colour render may cost before `scattered` works
#: on a coarser grid: it grows with the object's area times its image motion, so a long streak
#: at a large size (1080p) would cost far more than its accumulation; one grid step ``s`` divides
#: it by ``s^3`` (s^2 sources, paths s times shorter in grid pixels).
SPLAT_BUDGET = 8e6

#: Below this time-averaged alpha a pixel's scattered colour is not trusted.
MIN_ALPHA: float = _core.MIN_ALPHA


def uniform(obj: Object) -> bool:
    """Flat shading and one colour: the time-averaged colour is that colour."""
    c = obj.rgba
    return obj.shading == "flat" and (c.ndim == 1 or bool((c == c[0]).all()))


def place(obj: Object, m: np.ndarray) -> np.ndarray:
    return obj.mesh.vertices @ m[:3, :3].T + m[:3, 3]


def to_pixels(cam: Camera, x0: float = 0.0, y0: float = 0.0) -> np.ndarray:
    """(4,4) float64 taking a world point (x, y, z, 1) to homogeneous pixel coordinates
    ``(X, Y, ., W)`` of ``cam``'s image shifted by (x0, y0): the pixel is (X/W, Y/W) (as
    `Camera.project` gives, minus the shift), in front of the camera where W > 1e-9."""
    viewport = np.array(
        [
            [0.5 * cam.width, 0.0, 0.0, 0.5 * cam.width - x0],
            [0.0, -0.5 * cam.height, 0.0, 0.5 * cam.height - y0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )
    return viewport @ cam.view_projection


def sample(img: np.ndarray, x, y, front, fallback: np.ndarray) -> np.ndarray:
    """Straight RGB (N,3) float32 at image positions ``x``, ``y`` (N,) (pixel centres at +0.5) of
    the premultiplied ``img`` (H,W,4), bilinear, clamped to its edge; ``fallback`` (N,3) where
    the sampled alpha is below `MIN_ALPHA` or the point is behind the camera."""
    h, w = img.shape[:2]
    flat = img.reshape(-1, 4)
    px, py = np.where(front, x, 0.5) - 0.5, np.where(front, y, 0.5) - 0.5  # no image behind the eye
    i0 = np.clip(np.floor(px), 0, max(w - 2, 0)).astype(np.int64)
    j0 = np.clip(np.floor(py), 0, max(h - 2, 0)).astype(np.int64)
    i1, j1 = np.minimum(i0 + 1, w - 1), np.minimum(j0 + 1, h - 1)
    fx = np.clip(px - i0, 0.0, 1.0)[:, None]
    fy = np.clip(py - j0, 0.0, 1.0)[:, None]

    def at(j, i):  # gathered in float32, weighted in float64
        return flat[j * w + i].astype(np.float64)

    s = (at(j0, i0) * (1 - fx) + at(j0, i1) * fx) * (1 - fy) + (at(j1, i0) * (1 - fx) + at(j1, i1) * fx) * fy
    keep = (s[:, 3] < MIN_ALPHA) | ~front
    return np.where(keep[:, None], fallback, s[:, :3] / np.maximum(s[:, 3:], MIN_ALPHA)).astype(np.float32)


def averaged_colors(
    scene: Scene, k: int, obj: Object, keys: np.ndarray, mid: np.ndarray, vol
) -> np.ndarray | None:
    """Straight RGB (N,3) float32 for the N volume vertices: the time-averaged colour the camera
    sees at each one's image, or None (leave the volume's own colours). ``keys`` (S+1,4,4) the
    object's apparent placements, ``mid`` (4,4) its placement at mid-shutter.

    The object alone is rendered sharp (shaded, one sample a pixel) at ``mid`` as the camera at
    the reference time sees it, inside the volume's pixel window, and box-blurred along the image
    path of its centroid from shutter open to close: for a translation seen orthographically that
    blurred layer is exactly the time average of the object's image (the window reaches beyond the
    view by the image path, at most one image size, so an object leaving the view still colours
    its streak). Each vertex takes the blurred colour at its image (`sample`)."""
    cam = scene.camera_at(scene.reference_t)
    c = obj.mesh.vertices.mean(axis=0)
    ends, depth = cam.project(np.array([m[:3, :3] @ c + m[:3, 3] for m in (keys[0], keys[-1])]))
    if not (depth > 1e-9).all():
        return None
    dx, dy = (float(v) for v in ends[1] - ends[0])
    xy, depth = cam.project(vol.vertices)
    x, y, front = xy[:, 0], xy[:, 1], depth > 1e-9
    win = _grown_window(cam, x, y, front, abs(dx), abs(dy))
    if win is None:
        return None
    x0, y0, x1, y1 = win
    proj = window_projection(cam.projection, cam.width, cam.height, win)
    wcam = cam.resized(x1 - x0, y1 - y0)
    draw = Draw(place(obj, mid), obj.mesh.faces, obj.rgba, object_id=k)
    sharp = raster_layer(wcam, scene, [(obj, draw)], projection=proj).rgba
    length = float(np.hypot(dx, dy))
    if length >= 1.0:
        sharp = image.box_blur(sharp, (dx, dy), length)
    return sample(sharp, x - x0, y - y0, front, vol.rgba[:, :3])


def _grown_window(cam: Camera, x, y, front, mx: float, my: float):
    """The pixel box of the points (x, y), cut to the view grown by (mx, my) pixels and at most one
    image size beyond each side (the whole view when a point is behind the camera); None when
    empty."""
    if front.all():
        mx, my = min(mx + 1.0, cam.width), min(my + 1.0, cam.height)
        x0 = int(max(np.floor(x.min()) - 1, -mx))
        y0 = int(max(np.floor(y.min()) - 1, -my))
        x1 = int(min(np.ceil(x.max()) + 1, cam.width + mx))
        y1 = int(min(np.ceil(y.max()) + 1, cam.height + my))
    else:
        x0, y0, x1, y1 = 0, 0, cam.width, cam.height
    if x1 <= x0 or y1 <= y0:
        return None
    return x0, y0, x1, y1


def _centroid(mesh) -> np.ndarray:
    return mesh.vertices.mean(axis=0)


def _bounds(cam: Camera, point_sets, limit):
    """The pixel box (x0, y0, x1, y1) of the points of ``point_sets`` under ``cam``, cut to
    ``limit`` (all of ``limit`` when a point is behind the camera); None when empty."""
    pts = np.concatenate(point_sets)
    xy, depth = cam.project(pts)
    if not (depth > 1e-9).all():
        return tuple(limit)
    x, y = xy[:, 0], xy[:, 1]
    box = (
        max(int(np.floor(x.min())) - 1, limit[0]),
        max(int(np.floor(y.min())) - 1, limit[1]),
        min(int(np.ceil(x.max())) + 1, limit[2]),
        min(int(np.ceil(y.max())) + 1, limit[3]),
    )
    return box if box[0] < box[2] and box[1] < box[3] else None


def scattered(scene: Scene, cam: Camera, movers, keys_of, win, pieces: int) -> np.ndarray:
    """The time-averaged premultiplied image (H,W,4) float32 of the objects ``movers`` (pairs
    (index, Object)) inside the pixel window ``win`` (x0, y0, x1, y1) of ``cam`` (one sample a
    pixel), from ``pieces`` sharp renders.

    ``keys_of(obj, n)`` gives the object's apparent placements (n+1,4,4) at the times i/n. The
    shutter is cut into ``pieces`` equal pieces weighted by the shutter filter; for each, the
    movers are rendered sharp together (so they hide each other as at that time) at the piece's
    middle, in the window grown by their image motion; every covered pixel is carried to its 3D
    point by its depth and splatted with its premultiplied colour along the image path of that
    point through the piece (`PATH_STEPS` straight segments). Per piece only its layer and
    one (4,4) map per mover and path time (camera point at the piece's middle to output pixel)
    are made here; the sources and their paths are made and splatted by
    ``_core._scatter_pieces`` (a uniform straight path as one segment cut at its points)."""
    x0, y0, x1, y1 = win
    n = pieces * 2 * PATH_STEPS  # placements: piece p spans [2 p S, 2 (p + 1) S], middle (2 p + 1) S
    keys = [keys_of(o, n) for _, o in movers]
    corners = [mesh_constant(o.mesh, "corners", box_corners) for _, o in movers]
    # the sources: what passes the output window during the shutter (its bounds grown by the
    # movers' image motion, at most one image size beyond the view)
    reach = np.zeros(2)
    for (_, o), ks in zip(movers, keys):
        c = mesh_constant(o.mesh, "centroid", _centroid)
        path, depth = cam.project(ks[:, :3, :3] @ c + ks[:, :3, 3])
        if (depth > 1e-9).all():
            reach = np.maximum(reach, path.max(axis=0) - path.min(axis=0))
        else:
            reach = np.array([cam.width, cam.height], float)
    grown = (
        int(max(x0 - np.ceil(reach[0]) - 1, -cam.width)),
        int(max(y0 - np.ceil(reach[1]) - 1, -cam.height)),
        int(min(x1 + np.ceil(reach[0]) + 1, 2 * cam.width)),
        int(min(y1 + np.ceil(reach[1]) + 1, 2 * cam.height)),
    )
    cdf = scene.shutter_cdf(np.arange(pieces + 1) / pieces)
    step = _grid_step(cam, corners, keys, n, pieces, float(reach.max()))
    # the painter accumulation draws with: object-space draws, faces turned away the whole shutter dropped
    painter = Painter(scene, movers, eye=None if scene.camera_moves else cam.pose[:3, 3])
    objects = np.array([k for k, _ in movers], np.int32)
    tan = np.tan(cam.yfov / 2.0)
    world_to_window = np.diag([1.0 / step, 1.0 / step, 1.0, 1.0]) @ to_pixels(cam, x0, y0)
    work = []
    for p in range(pieces):
        weight = float(cdf[p + 1] - cdf[p])
        if weight <= 0.0:
            continue
        mid = (2 * p + 1) * PATH_STEPS
        rwin = _bounds(cam, [b @ ks[mid][:3, :3].T + ks[mid][:3, 3] for b, ks in zip(corners, keys)], grown)
        if rwin is None:
            continue
        # Drawn where they are at that time, seen by the camera of that time (the apparent
        # placements seen by the reference camera give the same image but turn the objects
        # against the lights when the camera turns).
        tm = mid / n
        pose = scene.camera_pose_at(tm)
        if step > 1:  # whole grid cells
            rwin = (
                rwin[0],
                rwin[1],
                rwin[0] + _up(rwin[2] - rwin[0], step),
                rwin[1] + _up(rwin[3] - rwin[1], step),
            )
        proj = window_projection(cam.projection, cam.width, cam.height, rwin)
        rw, rh = (rwin[2] - rwin[0]) // step, (rwin[3] - rwin[1]) // step
        lay = painter.layer(tm, np.linalg.inv(pose), proj, rw, rh)
        # pixel (i, j) at depth z: camera-space z (ray0 (i + 0.5) + ray1, ray2 (j + 0.5) + ray3, -1)
        ray = (
            2.0 * step * tan * cam.aspect / cam.width,
            (2.0 * rwin[0] / cam.width - 1.0) * tan * cam.aspect,
            -2.0 * step * tan / cam.height,
            (1.0 - 2.0 * rwin[1] / cam.height) * tan,
        )
        # per object and path time: camera point at the piece's middle -> its object's local
        # point -> its apparent placement at that time -> output pixel (homogeneous)
        steps = slice(2 * p * PATH_STEPS, 2 * (p + 1) * PATH_STEPS + 1)
        maps = np.stack(
            [
                world_to_window @ ks[steps] @ (np.linalg.inv(o.transform_at(tm)) @ pose)
                for (_, o), ks in zip(movers, keys)
            ]
        )
        work.append(
            {"rgba": lay.rgba, "depth": lay.depth, "ids": lay.ids, "ray": ray, "weight": np.float32(weight),
             "objects": objects, "maps": maps}
        )  # fmt: skip
    if not work:
        return np.zeros((y1 - y0, x1 - x0, 4), np.float32)
    if step == 1:
        return _core._scatter_pieces(work, 2 * PATH_STEPS + 1, x1 - x0, y1 - y0)
    coarse = _core._scatter_pieces(
        work, 2 * PATH_STEPS + 1, _up(x1 - x0, step) // step, _up(y1 - y0, step) // step
    )
    return _upsampled(coarse, step, x1 - x0, y1 - y0)


def _up(n: int, step: int) -> int:
    return -(-n // step) * step


def _grid_step(cam: Camera, corners, keys, n: int, pieces: int, reach: float) -> int:
    """The grid step of `scattered`'s colour renders and splat: 1 (pixels) unless the
    movers' projected area at mid-shutter times their image path per piece exceeds
    `SPLAT_BUDGET`, then the smallest step that brings it under."""
    mid = n // 2
    box = _bounds(
        cam,
        [b @ ks[mid][:3, :3].T + ks[mid][:3, 3] for b, ks in zip(corners, keys)],
        (0, 0, cam.width, cam.height),
    )
    if box is None:
        return 1
    work = (box[2] - box[0]) * (box[3] - box[1]) * (reach / pieces + 1.0)
    step = 1
    while work / step**3 > SPLAT_BUDGET and step < 8:
        step += 1
    return step


def _upsampled(img: np.ndarray, step: int, w: int, h: int) -> np.ndarray:
    """(h, w, 4) float32: ``img`` on a grid ``step`` times coarser (cell (i, j) covers pixels
    [i step, (i + 1) step)), interpolated bilinearly at the pixel centres (clamped at the edges)."""

    def axis(n_out: int, n_in: int):
        c = (np.arange(n_out) + 0.5) / step - 0.5
        i0 = np.clip(np.floor(c).astype(np.int64), 0, n_in - 1)
        i1 = np.minimum(i0 + 1, n_in - 1)
        f = np.clip(c - np.floor(c), 0.0, 1.0).astype(np.float32)
        return i0, i1, f

    j0, j1, fy = axis(h, img.shape[0])
    i0, i1, fx = axis(w, img.shape[1])
    rows = img[j0] * (1.0 - fy)[:, None, None] + img[j1] * fy[:, None, None]
    return np.ascontiguousarray(
        rows[:, i0] * (1.0 - fx)[None, :, None] + rows[:, i1] * fx[None, :, None], np.float32
    )
