"""``mb.exact`` is the limit of accumulation: minimal scenes where it once was not.

Each scene is a few triangles under a moving camera (with a still camera every static object is
drawn by the rasterizer for both methods, and nothing differs). The bound: stratified
accumulation's error falls as 1/N, so accumulation with N/2 samples lies about twice as far from
the limit as with N, and their RMSE (``noise``) is about accumulation-N's own error (one to three
times it). ``RMSE(acc-N, exact) <= 2 * noise`` then holds when ``exact`` is the limit, and fails
when it sits off it (a plateau that stays while the noise shrinks). N is 1024, or 4096 where
the old error was within twice accumulation-1024's noise; the measured values are in each test.
"""

from __future__ import annotations

import numpy as np

import motionblur as mb
from motionblur.evaluation.random_scenes import hand_held_path
from motionblur.methods._estimate import EXACT_OPTIONS
from motionblur.methods.analytic import MAX_SEGMENTS, segment_times
from motionblur.scene import rotate, translate

N = 1024
QUAD = np.array([[0, 1, 2], [0, 2, 3]])


def _rmse(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(a.astype(np.float64) - b))))


def _limit_errors(scene: mb.Scene, n: int = N) -> tuple[float, float]:
    """(RMSE(acc-n, exact), RMSE(acc-n/2, acc-n)), every frame over the scene's background."""
    exact = mb.exact(scene).rgba
    acc, half = (mb.render(scene, "accumulation", samples=k).rgba for k in (n, n // 2))
    return _rmse(acc, exact), _rmse(half, acc)


def _camera() -> mb.Camera:
    return mb.Camera(mb.look_at((0, 0.3, 3), (0, -0.4, 0)), 0.8, 64, 48, znear=0.3, zfar=60)


def _hand_held(amount: float) -> mb.Motion:
    """Five keys of small turns and shifts (random_scenes' camera paths, seed 1)."""
    return hand_held_path(np.random.default_rng(1), amount)


def test_a_floor_cut_by_the_near_plane_keeps_its_vertex_colours():
    """Two triangles of a floor reaching behind the camera, a colour per corner, the camera
    sliding sideways. The rasterizer draws a face crossing the near plane as a fan of clipped
    triangles; it once interpolated two corners' colours (and normals) swapped there, so
    accumulation's limit was another image (RMSE 0.19 against exact, at every N); the analytic
    kernel clips per sample. Measured: 9.6e-6 against a bound of 2.5e-5."""
    floor = np.array([[-4.0, -1.0, 4.0], [4.0, -1.0, 4.0], [4.0, -1.0, -4.0], [-4.0, -1.0, -4.0]])
    colours = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], np.float32)
    scene = mb.Scene(
        [mb.Object((floor, QUAD), colours)],
        _camera(),
        camera_motion=mb.Motion.linear(translate((0, 0, 0)), translate((0.3, 0, 0))),
        background=(0, 0, 0, 1),
    )
    err, noise = _limit_errors(scene)
    assert err <= 2.0 * noise, f"{err:.2e} against noise {noise:.2e}"


def test_a_shutter_past_the_segment_cap_is_refined_evenly():
    """A big static floor whose near edge passes just in front of the camera, and a small quad
    turning a full turn on a curved five-key path, under a hand-held camera. The segment rule
    once measured a test point's chord error at its own image position: the floor's corners,
    far off the image and near the camera's plane, needed more than MAX_SEGMENTS segments at the
    exact tolerance, and the rule spent them all on the shutter's first half (depth first),
    leaving the quad's last key intervals whole: RMSE 1.1e-3 against accumulation at every N.
    Errors are now measured where they can be seen (within the image, beyond the near plane)
    and the worst piece is halved first. Measured: 6.0e-5 against a bound of 2.8e-4."""
    keys = np.linspace(0.0, 1.0, 5)
    path = np.array([[-0.6, 0, 0], [-0.2, 0.3, 0.2], [0.1, -0.1, 0], [0.4, 0.2, -0.3], [0.7, 0, 0]])
    turning = mb.Motion(
        keys, np.stack([translate(p) @ rotate(6.0 * t, (0.3, 1, 0.2)) for t, p in zip(keys, path)])
    )
    small = np.array([[-0.25, -0.25, 0], [0.25, -0.25, 0], [0.25, 0.25, 0], [-0.25, 0.25, 0]])
    floor = np.array([[-6.0, -1.0, 2.8], [6.0, -1.0, 2.8], [6.0, -1.0, -8.0], [-6.0, -1.0, -8.0]])
    scene = mb.Scene(
        [
            mb.Object((small, QUAD), (0.9, 0.6, 0.2), motion=turning),
            mb.Object((floor, QUAD), (0.35, 0.35, 0.38)),
        ],
        _camera(),
        camera_motion=_hand_held(2.0),
        background=(0.1, 0.05, 0.15, 1),
    )
    times = segment_times(scene, scene.objects, scene.camera, EXACT_OPTIONS["tolerance"])
    assert len(times) - 1 < MAX_SEGMENTS
    # every quarter of the shutter is cut: none is left whole for the others
    assert (np.histogram(times, bins=4, range=(0, 1))[0] >= 8).all()
    err, noise = _limit_errors(scene)
    assert err <= 2.0 * noise, f"{err:.2e} against noise {noise:.2e}"


def test_a_light_grazing_a_smooth_surface_is_integrated_exactly():
    """Two triangles folded along a ridge (vertex normals bending by 53 degrees across each)
    sliding under a still camera, larger than the view, lit nearly edge-on: on one triangle the
    light's ``max(0, n . l)`` turns off partway, a kink in each pixel's colour over time. The
    motion is one segment and the Gauss points of a piece saw the kink as smooth: RMSE 1.4e-4
    against accumulation at every N (within twice accumulation-1024's noise, hence N = 4096
    here). Pieces are now also cut where a light grazes the surface. Measured: 1.1e-5 against
    a bound of 3.8e-5."""
    ridge = np.array([[0.0, -3.0, 0.5], [0.0, 3.0, 0.5], [-3.0, 0.0, -1.0], [3.0, 0.0, -1.0]])
    scene = mb.Scene(
        [
            mb.Object(
                (ridge, [[0, 1, 2], [1, 0, 3]]),
                (0.9, 0.8, 0.7),
                "lambert",
                motion=mb.Motion.linear(translate((-0.5, 0, 0)), translate((0.5, 0, 0))),
            )
        ],
        mb.Camera(mb.look_at((0, 0, 3), (0, 0, 0)), 0.8, 64, 48, znear=0.3, zfar=60),
        lights=[mb.DirectionalLight((1.0, 0.0, -0.3), 1.0)],
        ambient=0.1,
        background=(0, 0, 0, 1),
    )
    err, noise = _limit_errors(scene, 4096)
    assert err <= 2.0 * noise, f"{err:.2e} against noise {noise:.2e}"
