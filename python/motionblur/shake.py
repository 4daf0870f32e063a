"""Hand-held camera shake and the blur kernels it (or any motion) makes.

[`camera_shake`][motionblur.shake.camera_shake] draws a seeded 6-DoF hand-held trajectory over an exposure, in the spirit of
Boracchi and Foi (2012, "Modeling the performance of image restoration from motion blur"): the
camera's angular and linear velocities are random walks pulled back towards rest (an
Ornstein-Uhlenbeck process with a weak spring on the pose), with rare impulsive jerks, stepped at
1 ms. Rotation is about the camera's own centre and axes, so it dominates for distant content and
translation matters near the camera. A longer exposure with the same seed extends the same walk:
the trajectory of a short exposure is the start of a longer one's.

[`blur_kernels`][motionblur.shake.blur_kernels] gives the point-spread function of a scene at chosen pixels: the screen path,
weighted by the shutter, of the surface seen at each pixel at the scene's reference time (the path
the exact time integral sweeps that surface point along), splatted into a small image.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ._validate import as_array, as_float, as_int
from .scene import Motion, Scene

__all__ = ["camera_shake", "blur_kernels", "BlurKernels", "MAX_EXPOSURE", "STEP"]

STEP = 1e-3
"""Seconds between the random walk's steps."""
MAX_EXPOSURE = 10.0
"""Longest exposure [`camera_shake`][motionblur.shake.camera_shake] accepts, in seconds."""
_DAMPING = 8.0  # 1/s: velocities forget their past over about 1/8 s (hand tremor is 4-12 Hz)
_SPRING = 2.0  # 1/s^2: a weak pull of the pose back to where it started, so long walks stay bounded
_JERK_RATE = 2.0  # impulsive jerks per second
_JERK = 3.0  # a jerk's size, in units of the velocity's RMS
_ROLL = 0.5  # roll is steadier than yaw and pitch


def _axis_rotation(angle: float, axis: int) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    r = np.eye(3)
    r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
    return r


def _walk(seed: np.random.SeedSequence, steps: int, rms: np.ndarray) -> np.ndarray:
    """(steps + 1, 3) positions of a damped, spring-bound random walk whose velocity has
    stationary RMS ``rms`` (3,) per second, starting at 0 with a velocity drawn at that RMS.
    Each random stream has its own generator, so a longer walk starts as the shorter one."""
    start, noise, when, size = (np.random.default_rng(s) for s in seed.spawn(4))
    v = start.normal(size=3) * rms
    kicks = noise.normal(size=(steps, 3)) * rms * np.sqrt(2.0 * _DAMPING * STEP)
    jerks = when.random(steps) < _JERK_RATE * STEP
    kicks += np.where(jerks[:, None], size.normal(size=(steps, 3)) * rms * _JERK, 0.0)
    x = np.zeros((steps + 1, 3))
    for k in range(steps):
        v = v + (-_DAMPING * v - _SPRING * x[k]) * STEP + kicks[k]
        x[k + 1] = x[k] + v * STEP
    return x


def camera_shake(
    pose,
    *,
    exposure: float = 1.0 / 30.0,
    intensity: float = 1.0,
    seed: int = 0,
    keys: int | None = None,
    rotation: float = 0.1,
    translation: float = 0.01,
) -> Motion:
    """A seeded hand-held shake of the camera at ``pose`` over one exposure, for
    ``Scene(camera_motion=...)``.

    ``pose``: (4,4) float camera-to-world (the scene camera's ``pose``): the shake turns and moves
    the camera about its own centre and axes (x right, y up, z back). ``exposure``: the shutter's
    length in seconds, in (0, ``MAX_EXPOSURE``]; the shutter's normalised time [0, 1] spans it.
    ``intensity`` >= 0 scales the shake (0: no motion). ``rotation``: RMS angular speed in rad/s
    of yaw and pitch at intensity 1 (roll gets half); ``translation``: RMS speed in scene units per
    second at intensity 1. ``seed``: the same seed, pose and parameters give the same trajectory,
    and a longer ``exposure`` continues the same walk. ``keys`` >= 2 keyframes, evenly spaced over
    the shutter (the motion between them is interpolated as any [`Motion`][motionblur.shake.Motion]'s); the default,
    one per step of the walk up to 257, keeps every wiggle the walk has.

    Returns a rigid [`Motion`][motionblur.shake.Motion] whose ``transform_at(t) @ pose`` is the shaken pose at t.
    """
    pose = as_array(pose, "pose", np.float64, (4, 4))
    exposure = as_float(exposure, "exposure")
    if not 0.0 < exposure <= MAX_EXPOSURE:
        raise ValueError(f"exposure: must be in (0, {MAX_EXPOSURE:g}] seconds, got {exposure:g}")
    intensity = as_float(intensity, "intensity")
    if intensity < 0.0:
        raise ValueError(f"intensity: must be >= 0, got {intensity:g}")
    rotation, translation = as_float(rotation, "rotation"), as_float(translation, "translation")
    if rotation < 0.0 or translation < 0.0:
        raise ValueError("rotation, translation: must be >= 0")
    seed = as_int(seed, "seed", minimum=0)
    steps = int(np.ceil(exposure / STEP - 1e-9))
    keys = min(steps + 1, 257) if keys is None else as_int(keys, "keys", minimum=2, maximum=2049)
    turning, shifting = np.random.SeedSequence(seed).spawn(2)
    turn = _walk(turning, steps, intensity * rotation * np.array([1.0, 1.0, _ROLL]))
    shift = _walk(shifting, steps, intensity * translation * np.ones(3))
    clock = np.arange(steps + 1) * STEP
    times = np.linspace(0.0, 1.0, keys)
    inverse = np.linalg.inv(pose)
    mats = []
    for t in times * exposure:
        a = [np.interp(t, clock, turn[:, k]) for k in range(3)]
        local = np.eye(4)
        # yaw about the camera's y, then pitch about its x, then roll about its z
        local[:3, :3] = _axis_rotation(a[0], 1) @ _axis_rotation(a[1], 0) @ _axis_rotation(a[2], 2)
        local[:3, 3] = [np.interp(t, clock, shift[:, k]) for k in range(3)]
        mats.append(pose @ local @ inverse)
    return Motion(times, np.stack(mats))


@dataclass(frozen=True)
class BlurKernels:
    """Point-spread functions at N pixels ([`blur_kernels`][motionblur.shake.blur_kernels]).

    ``points`` (N,2) float64 pixel positions (x right, y down, pixel centres at +0.5);
    ``kernels`` (N,2R+1,2R+1) float32, each the shutter-weighted path splatted bilinearly with
    its centre cell at the point (row index is y), summing to 1 minus ``clipped``; ``paths``
    (N,S,2) float64 the screen position of the point's surface at the S shutter times ``times``
    (S,) with weights ``weights`` (S,) summing to 1; ``clipped`` (N,) float32 the weight that fell
    outside the kernel image; ``ids`` (N,) int32 the object seen (-1: background at infinity)."""

    points: NDArray[np.float64]
    kernels: NDArray[np.float32]
    paths: NDArray[np.float64]
    times: NDArray[np.float64]
    weights: NDArray[np.float64]
    clipped: NDArray[np.float32]
    ids: NDArray[np.int32]


def _grid_points(scene: Scene, grid) -> np.ndarray:
    gx, gy = (as_int(g, "grid", minimum=1, maximum=1024) for g in np.broadcast_to(grid, (2,)))
    w, h = scene.camera.width, scene.camera.height
    xs = (np.arange(gx) + 0.5) * w / gx
    ys = (np.arange(gy) + 0.5) * h / gy
    x, y = np.meshgrid(np.floor(xs) + 0.5, np.floor(ys) + 0.5)
    return np.stack([x.ravel(), y.ravel()], axis=1)


def _splat(
    path: np.ndarray, weights: np.ndarray, centre: np.ndarray, radius: int
) -> tuple[np.ndarray, float]:
    n = 2 * radius + 1
    k = np.zeros((n, n), np.float64)
    seen = np.isfinite(path).all(axis=1)  # a path point behind the camera is clipped weight
    d = path[seen] - centre + radius
    weights = weights[seen]
    x0, y0 = np.floor(d[:, 0]).astype(np.int64), np.floor(d[:, 1]).astype(np.int64)
    fx, fy = d[:, 0] - x0, d[:, 1] - y0
    for dx, dy, f in (
        (0, 0, (1 - fx) * (1 - fy)),
        (1, 0, fx * (1 - fy)),
        (0, 1, (1 - fx) * fy),
        (1, 1, fx * fy),
    ):
        xi, yi = x0 + dx, y0 + dy
        inside = (xi >= 0) & (xi < n) & (yi >= 0) & (yi < n)
        np.add.at(k, (yi[inside], xi[inside]), (weights * f)[inside])
    return k.astype(np.float32), float(max(0.0, 1.0 - k.sum()))


def blur_kernels(
    scene: Scene, points=None, *, grid=(4, 3), radius: int | None = None, samples: int = 256
) -> BlurKernels:
    """The motion blur's point-spread function of ``scene`` at chosen pixels.

    At each pixel, the surface seen there at ``scene.reference_t`` (from a sharp render's depth
    and ids; the background, where nothing is seen, counts as infinitely far) is followed over
    the shutter with its object's rigid motion and the camera's: its screen path at ``samples``
    stratified times, weighted by the shutter filter, splatted bilinearly into a
    (2R+1, 2R+1) image centred on the pixel. This is the path the exact time integral sweeps that
    surface point along; where other surfaces hide or uncover it during the shutter, the blurred
    image mixes several kernels and this one is the seen surface's alone.

    ``points``: (N,2) float pixel positions (x right, y down), or None for a ``grid`` (gx, gy) of
    evenly spread pixel centres. ``radius`` R in pixels (default: large enough to hold every
    path). Raises ValueError for a deforming object seen at a point (its surface points have no
    rigid path). Returns [`BlurKernels`][motionblur.shake.BlurKernels].
    """
    from .ground_truth import stratified_times, surface_paths

    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected a motionblur.Scene, got {type(scene).__name__}")
    pts = _grid_points(scene, grid) if points is None else points
    times, weights = stratified_times(scene, samples)
    found = surface_paths(scene, pts, times)
    pts, paths = found.points, found.paths
    if radius is None:
        reach = np.nanmax(np.abs(paths - pts[:, None, :]), initial=0.0)
        radius = int(np.ceil(reach)) + 1
    radius = as_int(radius, "radius", minimum=0, maximum=1024)
    out = [_splat(paths[i], weights, pts[i], radius) for i in range(len(pts))]
    kernels = (
        np.stack([k for k, _ in out]) if out else np.zeros((0, 2 * radius + 1, 2 * radius + 1), np.float32)
    )
    clipped = np.array([c for _, c in out], np.float32)
    return BlurKernels(pts, kernels, paths, times, weights, clipped, found.ids)


from ._namespace import tidy  # noqa: E402  (dir() lists the API only; see motionblur._namespace)

tidy(__name__)
