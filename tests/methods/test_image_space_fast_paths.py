"""The fast paths of the image-space methods, each against the slow path it replaces as oracle
(bit for bit):

* the sharp frame drawn over the static layer kept across frames (only the moving triangles
  rasterized) against `sharp_frame` (every object rasterized);
* ``camera_velocity``'s one-pass blur in the core against the composition it fuses
  (`motionblur.image.camera_velocity`, the moving objects' velocities, the float32 scale and
  clamp in numpy, `motionblur.image.velocity_blur`);
* the longest velocity in the core against numpy's float64 formula;
* ``velocity`` over the static layer's kept colour (the moving objects' window pasted in, the
  previous one put back) against the method's steps on the sharp frame drawn whole, and the
  core's reconstruction told the window where velocities are not 0 against it reading them all;
* ``opaque_image``'s coverage glow in one call of the core per object (``_core._coverage_blur``)
  and its velocity groups against the method's former numpy steps
  (``tests/_helpers/opaque_image_twin.py``), every option;
* the reconstruction filter's skipped taps (a big still frame around a small mover) against the
  same frame with the mover's motion removed where it cannot reach: the pixels out of reach do
  not change.

The reconstruction filter's skipping is also checked against its serial, unskipped twin in the
core's own tests (``src/image/reconstruct/tests.rs``, ``skipped_taps_give_the_bits_of_every_tap``).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from _helpers import opaque_image_twin, threads

import motionblur as mb
from motionblur import _core, image
from motionblur.evaluation.random_scenes import MEASURING_SEEDS, TUNING_SEEDS, random_scene
from motionblur.methods import image_space as ims
from motionblur.methods._layers import clear_static_cache
from motionblur.methods._sharp import require_box_shutter, sharp_frame, shutter_centroid
from motionblur.scenes_real import REAL_SCENES


def _same(a: mb.Frame, b: mb.Frame) -> bool:
    return all(
        np.array_equal(x, y)
        for x, y in ((a.rgba, b.rgba), (a.depth, b.depth), (a.ids, b.ids), (a.velocity, b.velocity))
    )


def _still_scenes():
    yield from (mb.SCENES[n](width=72, height=54) for n in ("cube", "curved", "airplane", "bending_arm"))
    yield from (random_scene(s, 64, 48) for s in list(MEASURING_SEEDS)[:12])


@pytest.mark.parametrize("aa", [1, 2])
def test_sharp_frame_over_the_kept_static_layer_is_the_full_sharp_frame(aa):
    used = 0
    for scene in _still_scenes():
        static = ims._static_part(scene, aa)
        if static is None:
            # refused: a moving camera, several shading modes, or a static object not opaque
            shadings = {o.shading for o in scene.objects}
            statics_opaque = all(
                float(np.min(o.rgba[..., 3])) >= 1.0 for o in scene.objects if not o.is_moving
            )
            assert scene.camera_moves or len(shadings) != 1 or not statics_opaque
            continue
        used += 1
        t = shutter_centroid(scene)
        for velocity in ("shutter", "since_open", None):
            assert _same(
                ims._sharp(scene, t, aa, velocity, static), sharp_frame(scene, t, aa, velocity=velocity)
            )
        # the cached layer (a second frame) gives the same bits as the freshly drawn one
        assert _same(
            ims._sharp(scene, t, aa, "shutter", ims._static_part(scene, aa)), sharp_frame(scene, t, aa)
        )
        clear_static_cache()
    assert used >= 6, used


def _camera_blur_numpy(scene, samples=16):
    """``camera_velocity``'s blur as it was composed before the core fused it."""
    t = shutter_centroid(scene)
    frame = sharp_frame(scene, t, 1, velocity="since_open")
    vel = image.camera_velocity(frame.depth, scene.camera_at(t), scene.camera_at(0.0))
    moving = np.isin(frame.ids, [k for k, o in enumerate(scene.objects) if o.is_moving])
    vel = np.where(moving[..., None], frame.velocity, vel) * np.float32(1.0 / t)
    vel = np.clip(vel, -image.MAX_VELOCITY, image.MAX_VELOCITY, out=vel)
    return image.velocity_blur(frame.rgba, vel, samples)


def _box_shutter(scene) -> bool:
    try:
        require_box_shutter(scene, "camera_velocity")
    except ValueError:
        return False
    return True


def test_camera_velocity_in_one_pass_is_the_composition_it_fuses():
    scenes = [mb.SCENES["pan"](width=96, height=72), mb.SCENES["pan"](width=61, height=37)]
    scenes += [
        s
        for s in (random_scene(k, 80, 60) for k in list(MEASURING_SEEDS)[:24])
        if s.camera_moves and _box_shutter(s)
    ]
    assert any(s.moving_objects for s in scenes), "a moving camera with moving objects"
    for scene in scenes:
        for samples in (1, 4, 16):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ours = ims.camera_velocity(scene, samples=samples).rgba
            np.testing.assert_array_equal(ours, _camera_blur_numpy(scene, samples))


def test_camera_frame_blur_names_bad_input():
    scene = mb.SCENES["pan"](width=16, height=12)
    t = shutter_centroid(scene)
    f = sharp_frame(scene, t, 1, velocity="since_open")
    cam, start = scene.camera_at(t), scene.camera_at(0.0)
    options = {"camera": cam, "previous_camera": start, "scale": 2.0, "samples": 16}
    args = [f.rgba, f.depth, f.ids, f.velocity, [False] * len(scene.objects), options]
    bad = f.rgba.copy()
    bad[3, 4, 1] = np.nan
    with pytest.raises(ValueError, match="rgba"):
        _core._camera_frame_blur(bad, *args[1:])
    with pytest.raises(ValueError, match="depth"):
        _core._camera_frame_blur(f.rgba, np.zeros_like(f.depth), *args[2:])
    with pytest.raises(ValueError, match="ids"):
        _core._camera_frame_blur(f.rgba, f.depth, f.ids[:, :-1].copy(), *args[3:])
    with pytest.raises(ValueError, match="samples"):
        _core._camera_frame_blur(*args[:-1], {**options, "samples": 0})


def test_max_speed_is_numpys_float64_formula():
    rng = np.random.default_rng(3)
    for shape in ((1, 1, 2), (7, 5, 2), (300, 401, 2)):
        v = (rng.standard_normal(shape) * rng.choice([1e-3, 1.0, 300.0, 1e6])).astype(np.float32)
        want = float(np.sqrt((v.astype(np.float64) ** 2).sum(axis=-1)).max())
        assert _core._max_speed(v) == want
    # a window read in place: the value of its copy, NaN only when the NaN is inside it
    for win in ((0, 300, 0, 401), (17, 230, 3, 9), (299, 300, 0, 401), (40, 40, 5, 50), (0, 9, 395, 401)):
        y0, y1, x0, x1 = win
        assert _core._max_speed(v, win) == _core._max_speed(np.ascontiguousarray(v[y0:y1, x0:x1]))
    with pytest.raises(ValueError, match="within"):
        _core._max_speed(v, (0, 301, 0, 10))
    v[5, 7, 1] = np.nan
    assert np.isnan(_core._max_speed(v))
    assert np.isnan(_core._max_speed(v, (5, 6, 7, 8)))
    assert not np.isnan(_core._max_speed(v, (6, 300, 0, 401)))


def test_velocity_reads_its_longest_velocity_in_the_drawn_window_only():
    # velocity takes the longest velocity (its default tile and stats["max_velocity"]) from the
    # window the moving objects were drawn in over the static layer: it must be the whole
    # frame's, on scenes drawn that way, whole, and with the mover off screen (nothing drawn)
    seen = set()
    off = mb.SCENES["cube"](width=72, height=54)
    off.objects[0].motion = mb.Motion.linear(mb.translate((40.0, 0.0, 0.0)), mb.translate((41.0, 0.0, 0.0)))
    for scene in [*_still_scenes(), off]:
        box = isinstance(scene.shutter, str) and scene.shutter == "box"
        if scene.camera_moves or not scene.moving_objects or not box:
            continue
        tc = shutter_centroid(scene)
        frame = ims._sharp(scene, tc, 1, "shutter", ims._static_part(scene, 1))
        drawn = frame.stats["drawn"]
        whole_image = (0, scene.camera.height, 0, scene.camera.width)
        seen.add("whole" if drawn == whole_image else "none" if drawn is None else "window")
        whole = _core._max_speed(np.ascontiguousarray(frame.velocity, np.float32))
        assert ims._max_speed(np.ascontiguousarray(frame.velocity, np.float32), drawn) == whole
        assert mb.render(scene, "velocity", error_estimate=False).stats["max_velocity"] == whole
    assert {"window", "none"} <= seen, seen


def _velocity_oracle(scene: mb.Scene) -> np.ndarray:
    # the velocity method's steps on the sharp frame drawn whole (no static layer, no window)
    c = np.ascontiguousarray
    frame = sharp_frame(scene, shutter_centroid(scene), 1, velocity="shutter")
    vel = c(frame.velocity, np.float32)
    tile = max(8, int(np.ceil(0.5 * _core._max_speed(vel))))
    return _core._reconstruct(c(frame.rgba), c(frame.depth), vel, 16, tile, 0.02)


def test_velocity_over_the_kept_pasted_colour_is_the_sharp_frames():
    # velocity reads the sharp colour from the static layer's kept copy with the moving
    # objects' window pasted in, the previous frame's window put back first, and the core
    # reads the velocities in that window only: frames one after another over the same static
    # layer (the mover in other places, then off screen: nothing drawn, then back), and one
    # while another thread holds the kept copy (a fresh copy then), give the oracle's bits
    clear_static_cache()
    scene = mb.SCENES["cube"](width=72, height=54)
    mover = scene.objects[0]
    m = mover.motion
    statics = set()
    for dx in (0.0, 0.6, -0.8, 40.0, 0.3, 0.0):
        shift = mb.translate((dx, 0.0, 0.0))
        mover.motion = mb.Motion.linear(shift @ m.transform_at(0.0), shift @ m.transform_at(1.0))
        frame = mb.render(scene, "velocity", error_estimate=False)
        np.testing.assert_array_equal(frame.rgba, _velocity_oracle(scene))
        static = ims._static_part(scene, 1)
        statics.add(id(static))
    assert len(statics) == 1  # one static layer, kept: the windows followed each other in it
    with static._lock:
        np.testing.assert_array_equal(
            mb.render(scene, "velocity", error_estimate=False).rgba, _velocity_oracle(scene)
        )
    # the kept copy is the static colour again outside the last window
    y0, y1, x0, x1 = static._window
    kept = static._pasted.copy()
    kept[y0:y1, x0:x1] = static.rgba[y0:y1, x0:x1]
    np.testing.assert_array_equal(kept, static.rgba)


def test_reconstruction_of_a_moving_window_is_the_whole_frames():
    # the core told that every velocity outside a window is 0 reads only the window's and
    # gives the bits of reading them all: windows tight around the motion, loose, at the
    # edges, and empty (no motion); a window that is not inside the image is refused
    rng = np.random.default_rng(8)
    h, w = 90, 130
    rgba = rng.random((h, w, 4), dtype=np.float32)
    depth = (rng.random((h, w)) * 5 + 1).astype(np.float32)
    for win in ((30, 50, 40, 70), (0, 90, 0, 9), (20, 90, 100, 130), (0, 1, 0, 130), (10, 10, 5, 5)):
        y0, y1, x0, x1 = win
        vel = np.zeros((h, w, 2), np.float32)
        vel[y0:y1, x0:x1] = (rng.standard_normal((y1 - y0, x1 - x0, 2)) * 12).astype(np.float32)
        for samples, tile in ((16, 10), (8, 7)):
            want = _core._reconstruct(rgba, depth, vel, samples, tile, 0.02)
            np.testing.assert_array_equal(
                _core._reconstruct(rgba, depth, vel, samples, tile, 0.02, win), want
            )
    with pytest.raises(ValueError, match="moving"):
        _core._reconstruct(rgba, depth, vel, 16, 10, 0.02, (0, 91, 0, 10))
    with pytest.raises(ValueError, match="moving"):
        _core._reconstruct(rgba, depth, vel, 16, 10, 0.02, (5, 4, 0, 10))


def test_reconstruction_out_of_reach_ignores_the_mover():
    # a 600x400 textured wall with a small block moving 40 pixels right: recolouring the block
    # leaves every pixel beyond its reach (its half velocity + 1 along the tap lines, a margin
    # more) with the same bits, the pixels whose taps the core skips there included, and
    # changes the streak near it
    h, w = 400, 600
    rng = np.random.default_rng(5)
    rgba = rng.random((h, w, 4), dtype=np.float32)
    rgba[..., 3] = 1.0
    depth = np.full((h, w), 10.0, np.float32)
    vel = np.zeros((h, w, 2), np.float32)
    depth[200:220, 300:320] = 4.0
    vel[200:220, 300:320] = (40.0, 0.0)
    other = rgba.copy()
    other[200:220, 300:320, :3] = (0.9, 0.1, 0.5)
    a = image.reconstruction_blur(rgba, depth, vel, samples=16, tile=20)
    b = image.reconstruction_blur(other, depth, vel, samples=16, tile=20)
    near = np.zeros((h, w), bool)
    near[200 - 2 : 220 + 2, 300 - 25 : 320 + 25] = True
    np.testing.assert_array_equal(a[~near], b[~near])
    assert np.abs(a[near] - b[near]).max() > 0.05
    # the tiles around the block gather (not a copy of the frame) where the block cannot reach
    gathered = np.zeros((h, w), bool)
    gathered[180:240, 280:340] = True
    assert not np.array_equal(a[gathered & ~near], rgba[gathered & ~near])


@pytest.mark.parametrize(
    "options",
    [
        {},
        {"groups": False},
        {"layers": False},
        {"aa": 2},
        {"glow": "opaque"},
        {"glow": "opaque", "groups": False},
    ],
)
def test_opaque_image_is_its_former_numpy_steps(options):
    # built-in scenes (a turning and a bending object: several velocity groups, oblique blurs),
    # the bunny over its floor (one group along a row: the core's row-by-row path) and random
    # scenes of tuning seeds; every frame array and the stats the same, bit for bit
    scenes = [mb.SCENES[n](width=72, height=54) for n in ("cube", "curved", "airplane", "bending_arm")]
    scenes += [REAL_SCENES["bunny_translate"](160, 96)]
    scenes += [random_scene(s, 64, 48) for s in list(TUNING_SEEDS)[:16]]
    seen = {"groups": 0, "front": 0, "scenes": 0}
    for scene in scenes:
        if not scene.moving_objects or scene.camera_moves:
            continue
        try:
            require_box_shutter(scene, "opaque_image")
        except ValueError:
            continue
        seen["scenes"] += 1
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            got = ims.opaque_image(scene, **options)  # (before render's background)
            want = opaque_image_twin.opaque_image(scene, **options)
        assert _same(got, want)
        for key in ("blurred", "masks", "front_pixels", "lengths"):
            assert got.stats[key] == want.stats[key], key
        seen["groups"] += got.stats["masks"] > got.stats["blurred"]
        seen["front"] += got.stats["front_pixels"] > 0
    assert seen["scenes"] >= 10, seen
    if options.get("groups", True):
        assert seen["groups"] >= 2, seen  # (the checks reached the several-group path)
    if options.get("layers", True):
        assert seen["front"] >= 1, seen


def test_object_pixels_are_numpys_mask_gathers_and_mean():
    # the mean along the first axis as numpy sums it (float64, pixel after pixel): random
    # velocities of every magnitude, windows of up to 250,000 pixels, objects of every share of
    # them; bit for bit
    rng = np.random.default_rng(5)
    for h, w in ((7, 9), (300, 420), (500, 500)):
        ids = rng.integers(-1, 3, (h, w)).astype(np.int32)
        vel = (rng.standard_normal((h, w, 2)) * rng.uniform(0.1, 900, (h, w, 1))).astype(np.float32)
        depth = rng.uniform(0.5, 40.0, (h, w)).astype(np.float32)
        for k in (-1, 0, 2):
            ids2 = np.where(rng.random((h, w)) < rng.random(), k, ids).astype(np.int32)
            y0, y1, x0, x1 = 1, h - 2, 2, w - 1
            mask, vs, zs, mean = _core._object_pixels(ids2, vel, depth, (y0, y1, x0, x1), k)
            want = ids2[y0:y1, x0:x1] == k
            assert mask.dtype == bool and np.array_equal(mask, want)
            assert vs.dtype == np.float64 and np.array_equal(vs, vel[y0:y1, x0:x1][want].astype(np.float64))
            assert np.array_equal(zs, depth[y0:y1, x0:x1][want])
            assert np.array_equal(np.array(mean), vs.mean(axis=0))


def _numpy_keys(v: np.ndarray) -> np.ndarray:
    # the keys of ims._velocity_groups, as it computes them
    sector = np.floor((np.arctan2(v[:, 1], v[:, 0]) + np.pi) / (2 * np.pi) * ims.VELOCITY_SECTORS)
    size = np.floor(np.log(np.maximum(np.hypot(v[:, 0], v[:, 1]), 1.0)) / np.log(ims.VELOCITY_RATIO))
    return (sector.astype(np.int64) % ims.VELOCITY_SECTORS) * (1 << 20) + size.astype(np.int64)


def test_one_velocity_group_only_when_numpys_keys_agree():
    # translations, turns of every spread, velocities a hair from a sector's edge or a size
    # bin's edge, along the axes, zero: whenever the core says one group, numpy's keys (its
    # own atan2 and log) are all one
    rng = np.random.default_rng(11)
    edges = -np.pi + np.arange(16) * np.pi / 8
    certain = 0
    for t in range(3000):
        n = int(rng.integers(1, 3000))
        a = rng.uniform(-np.pi, np.pi) + rng.standard_normal(n) * rng.uniform(0, 0.3) ** 3
        r = rng.uniform(0.2, 1200) * (1 + rng.standard_normal(n) * rng.uniform(0, 0.2) ** 2)
        kind = t % 5
        if kind == 1:
            a = np.full(n, edges[t % 16]) + rng.standard_normal(n) * 1e-13
        elif kind == 2:
            r = np.full(n, 1.5 ** (t % 12)) * (1 + rng.standard_normal(n) * 1e-14)
        v = np.stack([r * np.cos(a), r * np.sin(a)], -1)
        if kind == 3:
            v[:, 1] = 0.0
            v[:, 0] = np.abs(v[:, 0])
        elif kind == 4:
            v[:, rng.integers(0, 2)] = 0.0
        v = np.ascontiguousarray(v)
        if _core._one_velocity_group(v, ims.VELOCITY_SECTORS, ims.VELOCITY_RATIO):
            certain += 1
            k = _numpy_keys(v)
            assert k.min() == k.max(), (t, v[:4])
    assert certain > 600, certain  # (it does spare the keys often)
    # the bunny's translation at 1080p (lengths 517 to 611 pixels, one size bin): certain, so
    # the method skips the keys on it; at 320x180 its lengths straddle a bin: two groups
    for (w, h), masks in (((1920, 1080), 1), ((320, 180), 2)):
        sc = REAL_SCENES["bunny_translate"](w, h)
        f = ims._sharp(sc, 0.5, 1, "shutter", None)
        vs = f.velocity[f.ids == sc.objects.index(sc.moving_objects[0])].astype(np.float64)
        assert _core._one_velocity_group(vs, ims.VELOCITY_SECTORS, ims.VELOCITY_RATIO) == (masks == 1)
        assert ims.opaque_image(sc).stats["masks"] == masks


def test_fast_paths_same_for_any_thread_count():
    script = (
        "import hashlib, numpy as np, motionblur as mb\n"
        "from motionblur.scenes_real import REAL_SCENES\n"
        "h = hashlib.sha256()\n"
        "sc = REAL_SCENES['bunny_translate'](400, 240)\n"
        "for m in ('velocity', 'opaque_image'):\n"
        "    h.update(mb.render(sc, m, error_estimate=False).rgba.tobytes())\n"
        "h.update(mb.render(mb.SCENES['bending_arm'](200, 150), 'opaque_image', error_estimate=False).rgba.tobytes())\n"
        "h.update(mb.render(mb.SCENES['pan'](320, 240), 'camera_velocity', error_estimate=False).rgba.tobytes())\n"
        "print(h.hexdigest())\n"
    )
    d = threads.digests(script)
    assert len(set(d)) == 1, d
