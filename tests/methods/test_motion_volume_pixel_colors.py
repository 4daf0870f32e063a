"""The motion volume's per-pixel colours (``colors="pixel"``, the default): each pixel is the
volume's coverage alpha times the colour splatted from sharp renders along every point's own
image path. Measured against accumulation with many samples (the time-averaged image), against
the per-vertex colours (``colors="averaged"``), with a static occluder, a turning camera, several
colour renders, and the splat kernel's own input checks."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _helpers.threads import digests, ticks_during
from test_motion_volume_colors import _sphere_scene

import motionblur as mb
from motionblur import _core, meshes
from motionblur.evaluation.metrics import rmse
from motionblur.methods import _volume_colors as vc
from motionblur.scene import rotate

HERE = str(Path(__file__).parent)  # the scripts run in subprocesses import this module


def _errors(sc, **extra):
    ref = mb.render(sc, "accumulation", samples=128, aa=2).rgba
    pixel = mb.render(sc, "motion_volume", filter="box", aa=2, **extra)
    vertex = mb.render(sc, "motion_volume", filter="box", aa=2, colors="averaged")
    return pixel, vertex, rmse(pixel.rgba, ref), rmse(vertex.rgba, ref)


def test_a_shaded_sphere_gets_per_pixel_time_averaged_colours():
    """Measured 0.0010 against 0.0030 per vertex; the coverage alphas are the same."""
    pixel, vertex, e_pixel, e_vertex = _errors(_sphere_scene())
    assert pixel.stats["averaged"] == 1
    assert e_pixel < 0.6 * e_vertex, (e_pixel, e_vertex)
    np.testing.assert_allclose(pixel.rgba[..., 3], vertex.rgba[..., 3], atol=1e-6)
    a = pixel.rgba[..., 3]
    assert (pixel.rgba[..., :3] <= a[..., None] + 1e-5).all()  # premultiplied


def test_a_static_occluder_in_front_hides_the_streak_per_sample():
    """A static wall between the camera and part of the path: where the wall covers a pixel the
    frame is the wall, and the pixels along its edges (wall and streak in different samples)
    are composited per sample (measured 0.0009 against 0.0029 per vertex; per pixel it was
    0.0056)."""
    sc = _sphere_scene()
    v, f = meshes.box((0.6, 3.0, 0.1))
    wall = mb.Object((v + [0.5, 0.0, 1.5], f), color=(0.4, 0.4, 0.4))
    sc = sc.with_(objects=[*sc.objects, wall])
    pixel, _, e_pixel, e_vertex = _errors(sc)
    assert e_pixel < 0.6 * e_vertex, (e_pixel, e_vertex)
    alone = mb.render(sc.with_(objects=[wall]), "accumulation", samples=1, aa=2).rgba
    covered = alone[..., 3] >= 1.0
    assert covered.sum() > 100
    np.testing.assert_allclose(pixel.rgba[covered], alone[covered], atol=1e-6)


def test_a_turning_camera_sees_per_pixel_colours():
    """A still lambert sphere seen by a camera panning 0.3 rad: the splat follows each point's
    path through the turning view and keeps the lights where they are (measured 0.0006 against
    0.0018 per vertex)."""
    sc = _sphere_scene()
    pose = sc.camera.pose
    obj = sc.objects[0]
    sc = sc.with_(
        objects=[mb.Object(obj.mesh, color=obj.color, shading="lambert")],
        camera_motion=mb.Motion.linear(pose @ rotate(0.15, (0, 1, 0)), pose @ rotate(-0.15, (0, 1, 0))),
    )
    _, _, e_pixel, e_vertex = _errors(sc)
    assert e_pixel < 0.6 * e_vertex, (e_pixel, e_vertex)


def test_more_colour_renders_see_more_of_the_surface():
    sc = _sphere_scene(move=(2.4, 0.8, 0.0))
    ref = mb.render(sc, "accumulation", samples=128, aa=2).rgba
    errs = [
        rmse(mb.render(sc, "motion_volume", filter="box", aa=2, color_renders=k).rgba, ref) for k in (1, 3)
    ]
    assert errs[1] < errs[0], errs


@pytest.mark.parametrize("bad", [0, -1, 65, 1.5, "two", None])
def test_bad_color_renders_is_refused(bad):
    with pytest.raises((ValueError, TypeError), match="color_renders"):
        mb.render(_sphere_scene(), "motion_volume", color_renders=bad)


def test_splat_checks_its_input_and_leaves_it_alone():
    colors = np.ones((3, 4), np.float32)
    paths = np.full((3, 2, 2), 2.5, np.float32)  # still, on a pixel centre
    with pytest.raises(ValueError, match="colors"):
        _core._splat_paths(np.ones((3, 3), np.float32), paths, 8, 8)
    with pytest.raises(ValueError, match="paths"):
        _core._splat_paths(colors, np.zeros((2, 2, 2), np.float32), 8, 8)
    with pytest.raises(ValueError, match="paths"):
        _core._splat_paths(colors, np.zeros((3, 2, 3), np.float32), 8, 8)
    with pytest.raises(ValueError, match="colors"):
        _core._splat_paths(np.full((3, 4), np.nan, np.float32), paths, 8, 8)
    with pytest.raises(ValueError, match="size"):
        _core._splat_paths(colors, paths, 0, 8)
    with pytest.raises(ValueError, match="size"):
        _core._splat_paths(colors, paths, 1 << 20, 1 << 20)
    c0 = colors.copy()
    paths[1, 1] = np.nan  # a point behind the camera: its segment is dropped, nothing else
    p0 = paths.copy()
    out = _core._splat_paths(colors, paths, 8, 8)
    np.testing.assert_array_equal(colors, c0)
    np.testing.assert_array_equal(paths, p0)
    assert np.isfinite(out).all() and abs(out[..., 3].sum() - 2.0) < 1e-5


def _splat_inputs(n=20000, seed=3):
    rng = np.random.default_rng(seed)
    colors = rng.random((n, 4), dtype=np.float32)
    start = rng.random((n, 1, 2)) * [300, 200]
    paths = (start + np.cumsum(rng.normal(0, 15, (n, 5, 2)), axis=1)).astype(np.float32)
    return colors, paths


def test_splat_is_the_same_for_any_thread_count_and_releases_the_gil():
    script = (
        f"import hashlib, sys; sys.path.insert(0, {HERE!r})\n"
        "from test_motion_volume_pixel_colors import _splat_inputs\n"
        "from motionblur import _core\n"
        "c, p = _splat_inputs()\n"
        "print(hashlib.sha256(_core._splat_paths(c, p, 320, 240).tobytes()).hexdigest())\n"
    )
    assert len(set(digests(script))) == 1
    c, p = _splat_inputs()
    assert ticks_during(lambda: _core._splat_paths(c, p, 320, 240)) > 0


def _piece(seed=5, w=40, h=30, straight=True):
    """A sharp render (w x h pixels, two objects and empty pixels) with its maps: object 3
    translates across the image (a straight uniform path), object 8 moves towards the camera
    too (perspective: a non-uniform path) unless ``straight``."""
    rng = np.random.default_rng(seed)
    rgba = rng.random((h, w, 4), dtype=np.float32) * np.float32(0.8)
    rgba[..., 3] = np.where(rng.random((h, w)) < 0.2, 0.0, rgba[..., 3] + 0.1)
    rgba[..., :3] *= rgba[..., 3:]
    depth = (3.0 + rng.random((h, w))).astype(np.float32)
    ids = np.where(rng.random((h, w)) < 0.5, 3, 8).astype(np.int32)
    tan, aspect = 0.4, w / h
    ray = (2 * tan * aspect / w, -tan * aspect, -2 * tan / h, tan)
    proj = np.array([[1 / (tan * aspect), 0, 0, 0], [0, 1 / tan, 0, 0], [0, 0, -1, -0.2], [0, 0, -1, 0]])
    viewport = np.array([[w / 2, 0, 0, w / 2 + 4], [0, -h / 2, 0, h / 2 - 2], [0, 0, 1, 0], [0, 0, 0, 1]])
    maps = []
    for move in ((0.3, 0.1, 0.0), (0.2, -0.1, 0.0 if straight else 0.5)):
        steps = []
        for s in np.linspace(-0.5, 0.5, 9):
            t = np.eye(4)
            t[:3, 3] = np.multiply(move, s)
            steps.append(viewport @ proj @ t)
        maps.append(steps)
    return rgba, depth, ids, ray, np.float32(0.75), np.array([3, 8], np.int32), np.array(maps)


def _arg(piece) -> dict:
    """A piece as ``_core._scatter_pieces`` reads it: a dict of its parts."""
    return dict(zip(("rgba", "depth", "ids", "ray", "weight", "objects", "maps"), piece))


def _explicit(piece, w, h):
    """The same splat with every path made in numpy (the previous implementation's way)."""
    rgba, depth, ids, ray, weight, objects, maps = piece
    jj, ii = np.nonzero(rgba[..., 3] > 0)
    z = depth[jj, ii].astype(np.float64)
    q = np.stack(
        [z * (ray[0] * (ii + 0.5) + ray[1]), z * (ray[2] * (jj + 0.5) + ray[3]), -z, np.ones_like(z)], 1
    )
    slot = np.searchsorted(objects, ids[jj, ii])
    hom = np.einsum("npij,nj->npi", maps[slot], q)
    paths = (hom[..., :2] / hom[..., 3:]).astype(np.float32)
    return _core._splat_paths(np.ascontiguousarray(rgba[jj, ii] * weight), paths, w, h)


@pytest.mark.parametrize("straight", [True, False])
def test_scatter_pieces_is_the_splat_of_explicit_paths(straight):
    piece = _piece(straight=straight)
    before = [np.array(a, copy=True) for a in piece if isinstance(a, np.ndarray)]
    out = _core._scatter_pieces([_arg(piece)], 9, 48, 36)
    np.testing.assert_allclose(out, _explicit(piece, 48, 36), atol=2e-6)
    assert out[..., 3].sum() > 100.0
    for a, b in zip([a for a in piece if isinstance(a, np.ndarray)], before):
        np.testing.assert_array_equal(a, b)  # the caller's arrays are left alone


def test_scatter_pieces_checks_its_input():
    piece = _piece()

    def with_(k, v):
        p = list(piece)
        p[k] = v
        return [_arg(p)]

    for pieces, name in [
        (with_(0, piece[0][..., :3].copy()), "rgba"),
        (with_(1, piece[1][:-1].copy()), "depth"),
        (with_(2, piece[2][:, :-1].copy()), "ids"),
        (with_(6, piece[6][:1].copy()), "maps"),
        (with_(6, np.full_like(piece[6], np.nan)), "maps"),
        (with_(4, float("nan")), "weight"),
        (with_(3, (np.inf, 0.0, 0.0, 0.0)), "ray"),
    ]:
        with pytest.raises(ValueError, match=name):
            _core._scatter_pieces(pieces, 9, 48, 36)
    bad = piece[0].copy()
    bad[0, 0] = np.inf
    with pytest.raises(ValueError, match="rgba"):
        _core._scatter_pieces(with_(0, bad), 9, 48, 36)
    with pytest.raises(ValueError, match="points"):
        _core._scatter_pieces([_arg(piece)], 0, 48, 36)
    with pytest.raises(ValueError, match="size"):
        _core._scatter_pieces([_arg(piece)], 9, 0, 36)
    assert not _core._scatter_pieces([], 9, 8, 6).any()


def test_scatter_pieces_is_the_same_for_any_thread_count_and_releases_the_gil():
    script = (
        f"import hashlib, sys; sys.path.insert(0, {HERE!r})\n"
        "from test_motion_volume_pixel_colors import _arg, _piece\n"
        "from motionblur import _core\n"
        "ps = [_arg(_piece(seed=s, w=160, h=120, straight=s % 2 == 0)) for s in range(3)]\n"
        "print(hashlib.sha256(_core._scatter_pieces(ps, 9, 170, 130).tobytes()).hexdigest())\n"
    )
    assert len(set(digests(script))) == 1
    ps = [_arg(_piece(seed=s, w=160, h=120)) for s in range(3)]
    assert ticks_during(lambda: _core._scatter_pieces(ps, 9, 170, 130)) > 0


def test_vertex_colour_kernels_match_their_numpy_forms_and_check_input():
    from motionblur.methods._volume_colors import MIN_ALPHA

    rng = np.random.default_rng(2)
    cam = mb.Camera(mb.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0)), 0.7, 64, 48)
    pts = rng.normal(0, 1, (500, 3))
    img = rng.random((20, 30, 4), dtype=np.float32)
    img[..., 3] = np.where(rng.random((20, 30)) < 0.3, 0.0, img[..., 3])
    rgba = rng.random((500, 4), dtype=np.float32)
    p0, r0, i0 = pts.copy(), rgba.copy(), img.copy()
    xy, depth = cam.project(pts)
    x, y, front = xy[:, 0], xy[:, 1], depth > 1e-9
    b = _core._pixel_bounds(vc.to_pixels(cam), pts)
    np.testing.assert_allclose(b, [x.min(), y.min(), x.max(), y.max()], atol=1e-9)
    got = _core._sample_colors(img, vc.to_pixels(cam, 10, 12), pts, rgba)
    # the numpy form: each vertex takes its pixel's colour (fallback where empty or behind)
    h, w = img.shape[:2]
    near = img[np.clip((y - 12).astype(np.int64), 0, h - 1), np.clip((x - 10).astype(np.int64), 0, w - 1)]
    empty = (near[:, 3] < MIN_ALPHA) | ~front
    want = np.where(empty[:, None], rgba[:, :3], near[:, :3] / np.maximum(near[:, 3:], MIN_ALPHA))
    np.testing.assert_allclose(got[:, :3], want, rtol=1e-6)
    np.testing.assert_array_equal(got[:, 3], rgba[:, 3])
    behind = pts.copy()
    behind[0] = (0.0, 0.0, 9.0)
    assert _core._pixel_bounds(vc.to_pixels(cam), behind) is None
    for a, b0 in ((pts, p0), (rgba, r0), (img, i0)):
        np.testing.assert_array_equal(a, b0)
    with pytest.raises(ValueError, match="points"):
        _core._pixel_bounds(vc.to_pixels(cam), np.full((3, 3), np.nan))
    with pytest.raises(ValueError, match="points"):
        _core._pixel_bounds(vc.to_pixels(cam), pts[:, :2].copy())
    with pytest.raises(ValueError, match="map"):
        _core._sample_colors(img, np.eye(3), pts, rgba)
    with pytest.raises(ValueError, match="rgba"):
        _core._sample_colors(img, vc.to_pixels(cam), pts, rgba[:10].copy())
    # coverage times colour over the static layer, as the numpy form
    cov = rng.random((20, 30, 4), dtype=np.float32)
    under = rng.random((20, 30, 4), dtype=np.float32)
    a, w = cov[..., 3:], img[..., 3:]
    want = cov.copy()
    want[..., :3] = np.where(w >= MIN_ALPHA, img[..., :3] * (a / np.maximum(w, MIN_ALPHA)), cov[..., :3])
    want += (1.0 - a) * under
    np.testing.assert_allclose(_core._colored(cov, img, under), want, rtol=1e-6, atol=1e-7)
    with pytest.raises(ValueError, match="static_rgba"):
        _core._colored(cov, img, under[:5].copy())


def test_a_costly_splat_runs_on_a_coarser_grid_with_about_the_same_colours(monkeypatch):
    """Past the splat budget (area times image path) the colour renders and the splat run on a
    grid 2-8 times coarser, upsampled bilinearly: forced here on a small frame, the error
    against accumulation stays close to the pixel grid's and well below per-vertex colours."""
    from motionblur.methods import _volume_colors

    sc = _sphere_scene(width=128, height=96)
    ref = mb.render(sc, "accumulation", samples=128, aa=2).rgba
    fine = mb.render(sc, "motion_volume", filter="box", aa=2)
    vertex = mb.render(sc, "motion_volume", filter="box", aa=2, colors="averaged")
    steps = []
    grid_step = _volume_colors._grid_step
    monkeypatch.setattr(_volume_colors, "SPLAT_BUDGET", 1e4)
    monkeypatch.setattr(_volume_colors, "_grid_step", lambda *a: steps.append(grid_step(*a)) or steps[-1])
    coarse = mb.render(sc, "motion_volume", filter="box", aa=2, error_estimate=False)  # no pilot grid
    assert steps and min(steps) > 1, steps
    e_fine, e_coarse, e_vertex = (rmse(f.rgba, ref) for f in (fine, coarse, vertex))
    assert e_coarse < 1.5 * e_fine and e_coarse < 0.7 * e_vertex, (e_fine, e_coarse, e_vertex)
    np.testing.assert_allclose(coarse.rgba[..., 3], fine.rgba[..., 3], atol=1e-6)  # same coverage
