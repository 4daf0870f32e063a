"""The rasterizer's ``background``: an opaque per-sample layer the frame starts from.

Drawing transparent (and opaque) draws over the background of opaque surfaces must give what
drawing those surfaces in the same call gives: bit-equal float32 here (the fragments of these
scenes are never within one ulp of a background depth). motion_volume uses it on a still camera
(the cached static layer of the volumes' window); its frames must equal the path that redraws
the static objects with the volumes (``exact_static`` with a non-opaque static layer).
"""

from __future__ import annotations

import textwrap
from types import SimpleNamespace

import numpy as np
import pytest
from _helpers.threads import digests, ticks_during

import motionblur as mb
from motionblur import _core, meshes
from motionblur.methods import motion_volume as mv_module
from motionblur.scene import translate


def _scene_draws():
    """Opaque floor and wall, a transparent sphere crossing the wall, a half-opaque torus."""
    floor_v, floor_f = meshes.box((4.0, 0.1, 3.0))
    wall_v, wall_f = meshes.box((4.0, 2.0, 0.1))
    sph_v, sph_f = meshes.icosphere(3, 0.5)
    tor_v, tor_f = meshes.torus(0.4, 0.12, 24, 10)
    statics = [
        mb.Draw(floor_v + (0, -0.6, 0), floor_f, (0.3, 0.3, 0.35), object_id=1),
        mb.Draw(wall_v + (0, 0.3, -0.2), wall_f, (0.6, 0.5, 0.4), object_id=2),
    ]
    alpha = np.linspace(0.2, 0.8, len(sph_v)).astype(np.float32)
    colours = np.c_[np.full((len(sph_v), 3), (0.9, 0.3, 0.1)), alpha]
    tor_rgba = np.c_[np.full((len(tor_v), 3), (0.1, 0.7, 0.3)), np.where(tor_v[:, 0] > 0, 1.0, 0.4)]
    moving = [
        mb.Draw(sph_v + (0.2, 0.1, -0.2), sph_f, colours, object_id=3, cull_back=False),
        mb.Draw(tor_v + (-0.7, 0.0, 0.5), tor_f, tor_rgba, object_id=4),
    ]
    return statics, moving


def _camera(w=96, h=72):
    return mb.Camera(mb.look_at((0.4, 0.7, 3.0), (0.0, 0.0, -0.2)), 0.8, w, h, znear=0.5, zfar=20.0)


def _same(a: mb.Frame, b: mb.Frame):
    np.testing.assert_array_equal(a.rgba, b.rgba)
    np.testing.assert_array_equal(a.depth, b.depth)
    np.testing.assert_array_equal(a.ids, b.ids)


@pytest.mark.parametrize("shading", ["flat", "lambert"])
def test_drawing_over_the_background_equals_drawing_everything_in_one_call(shading):
    statics, moving = _scene_draws()
    cam = _camera()
    light = dict(shading=shading, lights=[((-0.3, -1.0, -0.5), 0.9)], ambient=0.1)
    one_call = mb.rasterize(cam, statics + moving, **light)
    bg = mb.rasterize(cam, statics, **light)
    over = mb.rasterize(cam, moving, background=bg, **light)
    assert over.stats["triangles"] < one_call.stats["triangles"]
    _same(over, one_call)
    # the sphere crosses the wall: some of its pixels are partly hidden (wall id, blended colour)
    assert ((over.ids == 3) & (bg.ids == 2)).any()


def test_supersampled_background_is_given_per_sample():
    statics, moving = _scene_draws()
    cam = _camera(64, 48)
    fine = mb.Camera(cam.pose, cam.yfov, 128, 96, cam.znear, cam.zfar)
    bg = mb.rasterize(fine, statics)  # one sample per pixel of the 2x camera: the samples of cam
    got = mb.rasterize(cam, moving, samples=2, background=bg)
    _same(got, mb.rasterize(cam, statics + moving, samples=2))
    with pytest.raises(ValueError, match="background rgba"):
        mb.rasterize(cam, moving, samples=2, background=mb.rasterize(cam, statics))


def test_a_transparent_surface_through_an_opaque_plane_is_cut_per_sample():
    """A transparent square tilted through an opaque plane at z = 0: in front of the plane it tints
    it, behind it it is hidden; the cut is a per-sample depth test (numpy twin: over by hand)."""
    cam = mb.Camera(mb.look_at((0.0, 0.0, 3.0), (0.0, 0.0, 0.0)), 0.6, 64, 64)
    plane_v = np.array([[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]], np.float64)
    quad_f = np.array([[0, 1, 2], [0, 2, 3]])
    tilted = np.array([[-0.6, -0.6, -0.5], [0.6, -0.6, 0.5], [0.6, 0.6, 0.5], [-0.6, 0.6, -0.5]])
    plane = mb.Draw(plane_v, quad_f, (0.2, 0.4, 0.6), object_id=0)
    glass = mb.Draw(tilted, quad_f, (1.0, 0.5, 0.0, 0.5), object_id=7)
    bg = mb.rasterize(cam, plane)
    got = mb.rasterize(cam, glass, background=bg)
    _same(got, mb.rasterize(cam, [plane, glass]))
    x = (np.arange(64) + 0.5) / 64 * 2 - 1  # NDC of pixel centres
    front = got.ids == 7
    assert front[32, 40] and not front[32, 24]  # the +x half is in front of the plane
    want = np.float32(0.5) * np.array([1.0, 0.5, 0.0, 1.0], np.float32) + np.float32(0.5) * bg.rgba[32, 40]
    np.testing.assert_allclose(got.rgba[32, 40], want, atol=1e-6)
    np.testing.assert_array_equal(got.rgba[32, 24], bg.rgba[32, 24])
    assert got.depth[32, 40] < bg.depth[32, 40]
    assert x[40] > 0 > x[24]


def test_an_empty_draw_list_returns_the_background():
    statics, _ = _scene_draws()
    cam = _camera(40, 30)
    bg = mb.rasterize(cam, statics)
    got = mb.rasterize(cam, [], background=(bg.rgba, bg.depth, bg.ids))
    _same(got, bg)
    assert not got.velocity.any()


def _old_exact_path(monkeypatch):
    """Force motion_volume's previous still-camera path (static objects redrawn with the
    volumes at sample resolution, resolved apart)."""
    monkeypatch.setattr(mv_module, "ONE_PASS", False)


@pytest.mark.parametrize("name", ["cube", "curved", "sphere80k", "airplane"])
def test_motion_volume_over_the_static_layer_equals_redrawing_the_statics(name, monkeypatch):
    sc = mb.SCENES[name](width=80, height=60)
    assert not sc.camera_moves
    for aa in (1, 2):
        new = mb.render(sc, "motion_volume", segments=2, filter="box", aa=aa)
        with monkeypatch.context() as m:
            _old_exact_path(m)
            old = mb.render(sc, "motion_volume", segments=2, filter="box", aa=aa)
        np.testing.assert_allclose(new.rgba, old.rgba, atol=1e-6, err_msg=f"aa={aa}")
        np.testing.assert_array_equal(new.ids, old.ids)
        np.testing.assert_allclose(new.depth, old.depth, rtol=1e-6)


def test_motion_volume_through_a_static_wall(monkeypatch):
    """The cube's volume passes through the wall: parts behind it are hidden per sample."""
    sc = mb.SCENES["cube"](width=96, height=72)
    cube = sc.objects[0]
    through = mb.Object(
        cube.mesh,
        cube.color,
        motion=mb.Motion.linear(translate((-1.2, 0.0, -2.6)), translate((0.9, 0.0, -1.2))),
    )
    sc = sc.with_(objects=[through, *sc.objects[1:]])
    new = mb.render(sc, "motion_volume", segments=1, filter="box", aa=2)
    with monkeypatch.context() as m:
        _old_exact_path(m)
        old = mb.render(sc, "motion_volume", segments=1, filter="box", aa=2)
    np.testing.assert_allclose(new.rgba, old.rgba, atol=1e-6)
    np.testing.assert_array_equal(new.ids, old.ids)
    static = mb.render(sc.with_(objects=list(sc.objects[1:])), "accumulation", samples=1)  # wall: id 1
    cut = (new.ids == 0) & (static.ids == 1)  # volume seen in front of the wall ...
    alone = mb.render(sc.with_(objects=[through]), "motion_volume", segments=1, filter="box", aa=2)
    behind = (alone.coverage > 0) & (new.ids == 2)  # ... and behind it, where only the wall shows
    hidden = behind & (np.abs(new.rgba - static.rgba).max(-1) == 0)
    assert cut.any() and hidden.any()


def test_a_transparent_static_object_keeps_the_redraw_path(monkeypatch):
    """The background holds opaque surfaces only: with a half-transparent wall the static objects
    are redrawn with the volumes (no background reaches the rasterizer), as before."""
    sc = mb.SCENES["cube"](width=64, height=48)
    wall = sc.objects[2]
    sc = sc.with_(objects=[*sc.objects[:2], mb.Object(wall.mesh, (*wall.color[:3], 0.5), name="wall")])
    seen = []
    raw = _core._rasterize

    def spy(*args):
        seen.append(len(args) > 2 and args[2] is not None)
        return raw(*args)

    monkeypatch.setattr(_core, "_rasterize", spy)
    new = mb.render(sc, "motion_volume", segments=2, filter="box", aa=2)
    assert seen and not any(seen)
    with monkeypatch.context() as m:
        _old_exact_path(m)
        old = mb.render(sc, "motion_volume", segments=2, filter="box", aa=2)
    np.testing.assert_array_equal(new.rgba, old.rgba)
    seen.clear()
    mb.render(sc.with_(objects=[*sc.objects[:2], wall]), "motion_volume", segments=2, filter="box", aa=2)
    assert any(seen), "with an opaque wall the volumes are drawn over the static layer"


# --- bad input


def _bg(h=8, w=8):
    return np.zeros((h, w, 4), np.float32), np.full((h, w), np.inf, np.float32), np.full((h, w), -1, np.int32)


@pytest.mark.parametrize(
    "change, exc, text",
    [
        (lambda b: (b[0][:4], b[1], b[2]), ValueError, "background rgba: expected shape"),
        (lambda b: (b[0], b[1][:, :3], b[2]), ValueError, "background depth: expected shape"),
        (lambda b: (b[0], b[1], b[2][None]), ValueError, "background ids: expected shape"),
        (
            lambda b: (b[0], np.where(np.eye(8, dtype=bool), np.nan, b[1]), b[2]),
            ValueError,
            "background depth",
        ),
        (lambda b: (b[0], np.zeros((8, 8), np.float32), b[2]), ValueError, "background depth: must be > 0"),
        (lambda b: (b[0], -b[1], b[2]), ValueError, "background depth: must be > 0"),
        (lambda b: (np.full((8, 8, 4), np.nan, np.float32), b[1], b[2]), ValueError, "background rgba"),
        (lambda b: (b[0].astype(str), b[1], b[2]), TypeError, "background rgba"),
        (lambda b: (b[0], b[1], b[2].astype(np.float32)), TypeError, "background ids"),
        (lambda b: b[:2], TypeError, "background"),
        (lambda b: 3.0, TypeError, "background"),
    ],
)
def test_bad_background_names_the_argument(change, exc, text):
    cam = mb.Camera(np.eye(4), 0.8, 8, 8)
    with pytest.raises(exc, match=text):
        mb.rasterize(cam, [], background=change(_bg()))


def test_the_core_rechecks_the_background():
    cam = mb.Camera(np.eye(4), 0.8, 8, 8)
    options = dict(
        view=cam.view, projection=cam.projection, width=8, height=8, samples=1, blend="exact", shading="flat",
        lights=[], ambient=(0.0, 0.0, 0.0),
    )  # fmt: skip

    def raster(rgba, depth, ids, x0, y0):
        layer = SimpleNamespace(rgba=rgba, depth=depth, ids=ids)
        return _core._rasterize([], {**options, "origin": (x0, y0)}, layer)

    rgba, depth, ids = _bg()
    big = _bg(16, 16)
    for bad in [
        (rgba[:, :4], depth, ids, 0, 0),
        (rgba, depth[:4], ids, 0, 0),
        (rgba, np.full((8, 8), np.nan, np.float32), ids, 0, 0),
        (rgba, np.zeros((8, 8), np.float32), ids, 0, 0),
        (np.full((8, 8, 4), np.inf, np.float32), depth, ids, 0, 0),
        (rgba, np.asfortranarray(np.ones((8, 8), np.float32)), ids, 0, 0),
        (*big, 9, 0),  # the window runs past the right edge
        (*big, 0, 9),
        (rgba, depth, ids, 1, 0),
    ]:
        with pytest.raises(ValueError, match="background"):
            raster(*bad)
    with pytest.raises(TypeError):
        raster(rgba.astype(np.float64), depth, ids, 0, 0)
    with pytest.raises(TypeError, match="origin"):  # a negative origin is no sample index
        raster(*big, -1, 0)
    raster(rgba, depth, ids, 0, 0)  # the right ones pass
    raster(*big, 8, 8)


def test_a_window_of_a_larger_background_is_read_in_place():
    """raw_layer over a window of a kept layer (origin x0, y0) equals the copied window."""
    from motionblur.methods._layers import Layer, raw_layer, window_projection

    statics, moving = _scene_draws()
    cam = _camera(96, 72)
    bg = mb.rasterize(cam, statics)
    layer = Layer(bg.rgba, bg.depth, bg.ids)
    x0, y0, x1, y1 = 20, 12, 76, 52
    proj = window_projection(cam.projection, 96, 72, (x0, y0, x1, y1))
    run = dict(draws=moving, shading="flat", lights=[], ambient=(0.0, 0.0, 0.0))
    window = Layer(bg.rgba[y0:y1, x0:x1], bg.depth[y0:y1, x0:x1], bg.ids[y0:y1, x0:x1])
    copied = raw_layer(x1 - x0, y1 - y0, cam.view, proj, background=window, **run)
    in_place = raw_layer(
        x1 - x0, y1 - y0, cam.view, proj, background=layer, background_origin=(x0, y0), **run
    )
    for a, b in zip((copied.rgba, copied.depth, copied.ids), (in_place.rgba, in_place.depth, in_place.ids)):
        np.testing.assert_array_equal(a, b)
    full = mb.rasterize(cam, statics + moving)
    np.testing.assert_array_equal(in_place.rgba, full.rgba[y0:y1, x0:x1])


def test_callers_background_arrays_are_never_written():
    statics, moving = _scene_draws()
    cam = _camera(48, 36)
    bg = mb.rasterize(cam, statics)
    rgba, depth, ids = bg.rgba.astype(np.float64), bg.depth.copy(), bg.ids.copy()
    before = [a.copy() for a in (rgba, depth, ids, bg.rgba)]
    out = mb.rasterize(cam, moving, background=(rgba, depth, ids))
    out2 = mb.rasterize(cam, moving, background=bg)
    out.rgba[:] = 7.0
    out.depth[:] = 7.0
    out.ids[:] = 7
    for a, b in zip((rgba, depth, ids, bg.rgba), before):
        np.testing.assert_array_equal(a, b)
    assert not np.shares_memory(out2.rgba, bg.rgba) and not np.shares_memory(out2.depth, bg.depth)


_THREAD_SCRIPT = textwrap.dedent(
    """
    import hashlib, numpy as np, motionblur as mb
    from motionblur import meshes
    v, f = meshes.box((3.0, 2.0, 0.2))
    sv, sf = meshes.icosphere(4)
    cam = mb.Camera(mb.look_at((0.5, 0.6, 3.0), (0, 0, 0)), 0.9, 200, 150)
    fine = mb.Camera(cam.pose, cam.yfov, 400, 300)
    glass = mb.Draw(sv, sf, (0.8, 0.4, 0.2, 0.5), cull_back=False, object_id=3)
    h = hashlib.sha256()
    for samples, c in ((1, cam), (2, fine)):
        bg = mb.rasterize(c, mb.Draw(v, f, (0.2, 0.4, 0.8), object_id=4))
        fr = mb.rasterize(cam, glass, samples=samples, background=bg)
        for a in (fr.rgba, fr.depth, fr.ids):
            h.update(np.ascontiguousarray(a).tobytes())
    for name in ("cube", "curved"):  # the volumes over a window of the kept static layer
        fr = mb.render(mb.SCENES[name](width=96, height=72), "motion_volume", segments=2, aa=2)
        for a in (fr.rgba, fr.depth, fr.ids):
            h.update(np.ascontiguousarray(a).tobytes())
    print(h.hexdigest())
    """
)


def test_background_output_is_bit_identical_for_any_thread_count():
    got = digests(_THREAD_SCRIPT)
    assert len(got[0]) == 64
    assert got[0] == got[1] == got[2]


def test_the_gil_is_released_while_rasterizing_over_a_background():
    """A Python thread keeps ticking while rasterize runs in another thread: with the GIL held
    it could tick only between the calls."""
    v, f = meshes.icosphere(5)
    cam = mb.Camera(mb.look_at((0.0, 0.0, 2.6), (0, 0, 0)), 0.9, 640, 480)
    fine = mb.Camera(cam.pose, cam.yfov, 1280, 960)
    bg = mb.rasterize(fine, mb.Draw(*meshes.box((3.0, 3.0, 0.1)), (0.3, 0.3, 0.3)))
    glass = mb.Draw(v, f, (0.8, 0.4, 0.2, 0.4), cull_back=False)
    assert ticks_during(lambda: mb.rasterize(cam, glass, samples=2, background=bg)) >= 6
