"""Issue 18's list of bad arguments: every one raises ValueError / TypeError naming the argument
and saying what is expected, instead of a bare message from numpy or Python, or a silent
wrong result. The rules are in ``motionblur._validate`` and the README's section Validation."""

from __future__ import annotations

import threading
from types import SimpleNamespace

import numpy as np
import pytest

import motionblur as mb
import motionblur.image as mbi
from motionblur import _core, metrics


def _cam(**kw):
    return mb.Camera(mb.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0)), kw.pop("yfov", 0.7), 32, 24, **kw)


def _scene(**kw):
    obj = mb.Object(mb.meshes.box(), motion=mb.Motion.linear((0, 0, 0), (0.5, 0, 0)))
    return mb.Scene([obj], _cam(), **kw)


# ---------------------------------------------------------------- errors that name nothing


@pytest.mark.parametrize(
    "call, exc, text",
    [
        (
            lambda: mb.DirectionalLight((0, 0, -1), intensity="x"),
            TypeError,
            "intensity: expected a float or an RGB",
        ),
        (lambda: mb.DirectionalLight((0, 0, -1), intensity=1j), TypeError, "intensity: expected a real"),
        (
            lambda: mb.DirectionalLight((0, 0, -1), intensity=[1, 2]),
            ValueError,
            "intensity: expected a float or",
        ),
        (lambda: mb.DirectionalLight((0, 0, -1), intensity=-1), ValueError, "intensity: must be >= 0"),
        (lambda: _scene(ambient="x"), TypeError, "ambient: expected a float or an RGB"),
        (lambda: _scene(ambient=np.nan), ValueError, "ambient: must be finite"),
        # finite in float64 but not in the core's float32 (make fuzz: the render raised instead)
        (lambda: _scene(ambient=3.4028235677973366e38), ValueError, "ambient: must be at most"),
        (lambda: mb.DirectionalLight((0, 0, -1), intensity=1e39), ValueError, "intensity: must be at most"),
        (lambda: mb.Scene(None, _cam()), TypeError, "objects: expected a sequence of motionblur.Object"),
        (lambda: mb.Scene([3], _cam()), TypeError, "objects: item 0 is a int"),
        (lambda: _scene(lights=3), TypeError, "lights: expected a sequence of motionblur.DirectionalLight"),
        (lambda: _scene(lights=["x"]), TypeError, "lights: item 0 is a str"),
        (
            lambda: mb.rasterize(_cam(), mb.Draw(*mb.meshes.box(), (1, 1, 1)), lights=[((0, 0, -1), 1j)]),
            TypeError,
            "lights: item 0 intensity: expected a real",
        ),
        (
            lambda: mb.rasterize(_cam(), mb.Draw(*mb.meshes.box(), (1, 1, 1)), lights=3),
            TypeError,
            "lights: expected a sequence",
        ),
        (
            lambda: mb.rasterize(_cam(), mb.Draw(*mb.meshes.box(), (1, 1, 1)), ambient="x"),
            TypeError,
            "ambient: expected a float or an RGB",
        ),
        (
            lambda: mb.ContourTable(mb.Mesh(*mb.meshes.box()), 4).edges(2**64),
            ValueError,
            "index: must be <= 3",
        ),
        (lambda: mb.ContourTable(mb.Mesh(*mb.meshes.box()), 4).edges(4), ValueError, "index: must be <= 3"),
        (
            lambda: mb.ContourTable(mb.Mesh(*mb.meshes.box()), 4).front_faces(-1),
            ValueError,
            "index: must be >= 0",
        ),
        (
            lambda: mb.ContourTable(mb.Mesh(*mb.meshes.box()), 4).edges(1.0),
            TypeError,
            "index: expected an integer",
        ),
        (
            lambda: metrics.psnr(np.zeros((2, 2, 4)), np.ones((2, 2, 4)), peak="x"),
            TypeError,
            "peak: expected",
        ),
        (
            lambda: metrics.psnr(np.zeros((2, 2, 4)), np.ones((2, 2, 4)), peak=np.nan),
            ValueError,
            "peak: must be finite",
        ),
        (
            lambda: metrics.psnr(np.zeros((2, 2, 4)), np.ones((2, 2, 4)), peak=-1),
            ValueError,
            "peak: must be > 0",
        ),
        (
            lambda: metrics.flip(np.zeros((2, 2, 4)), np.ones((2, 2, 4)), (0, 0)),
            ValueError,
            "background: expected shape",
        ),
        (
            lambda: metrics.flip(np.zeros((2, 2, 4)), np.ones((2, 2, 4)), "red"),
            TypeError,
            "background: expected a numeric",
        ),
    ],
)
def test_bad_scalars_and_containers_name_the_argument(call, exc, text):
    with pytest.raises(exc, match=text):
        call()


def test_blur_shell_rejects_bad_positions_naming_them():
    v, f = mb.meshes.box()
    shell = mb.BlurShell(f)
    with pytest.raises(ValueError, match=r"vertices: expected shape \(N,3\)"):
        shell.update(v[:, :2])
    with pytest.raises(TypeError, match="vertices: expected a numeric array"):
        shell.update("step")
    shell.update(v)
    with pytest.raises(ValueError, match="vertices: expected 8 rows"):
        shell.update(v[:5])
    with pytest.raises(TypeError, match="vertices: expected a numeric array"):
        shell.build("step")
    with pytest.raises(ValueError, match="n_vertices|vertices"):
        shell.update(v * 1e10)


def _sequence(render_at, **kw):
    return mb.Sequence(render_at, samples=2, **kw)


@pytest.mark.parametrize(
    "result, exc, text",
    [
        (lambda t: "frame", TypeError, "render_at: its result at t=0 is str"),
        (lambda t: None, TypeError, "render_at: its result at t=0 is NoneType"),
        (
            lambda t: np.zeros((4, 4, 3)),
            ValueError,
            r"render_at: its result at t=0: expected shape \(N,N,4\)",
        ),
        (lambda t: np.full((4, 4, 4), np.nan), ValueError, "render_at: its result at t=0: contains NaN"),
        (lambda t: np.zeros((4, 4, 4), complex), TypeError, "render_at: its result at t=0: expected a real"),
        (
            lambda t: np.zeros((4 + int(t), 4, 4)),
            ValueError,
            r"render_at: its result at t=1: expected shape \(4,4,4\)",
        ),
    ],
)
def test_sequence_checks_what_render_at_returns(result, exc, text):
    seq = _sequence(result)
    with pytest.raises(exc, match=text):
        seq.next()


def test_sequence_keeps_its_frames_for_good_renders_and_rejects_non_bool_keep_images():
    seq = _sequence(lambda t: np.full((2, 3, 4), t, np.float32), keep_images=True)
    np.testing.assert_array_equal(seq.next(), np.full((2, 3, 4), 0.5, np.float32))
    np.testing.assert_array_equal(seq.next(), np.full((2, 3, 4), 1.5, np.float32))
    for bad in ("no", 0, None):
        with pytest.raises(TypeError, match="keep_images: expected True or False"):
            _sequence(lambda t: np.zeros((2, 2, 4)), keep_images=bad)


def _frame(rgba):
    h, w = rgba.shape[:2]
    return mb.Frame(rgba, np.full((h, w), np.inf), -np.ones((h, w), np.int32), np.zeros((h, w, 2)))


def test_save_png_writes_png_only_and_never_non_finite_pixels(tmp_path):
    f = _frame(np.zeros((2, 3, 4), np.float32))
    for name in ("out.gif", "out.bmp", "out.jpg", "out"):
        with pytest.raises(ValueError, match="path: save_png writes PNG files only"):
            f.save_png(tmp_path / name)
        assert not (tmp_path / name).exists()
    with pytest.raises(TypeError, match="path: expected a str"):
        f.save_png(3)
    f.save_png(tmp_path / "UPPER.PNG")
    assert (tmp_path / "UPPER.PNG").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    for bad in (np.nan, np.inf, -np.inf):
        rgba = np.zeros((2, 3, 4), np.float32)
        rgba[1, 2, 0] = bad
        with pytest.raises(ValueError, match="rgba: 1 pixels are NaN or inf"):
            _frame(rgba).save_png(tmp_path / "bad.png")
        assert not (tmp_path / "bad.png").exists()


# ---------------------------------------------------------------- bad input accepted silently


@pytest.mark.parametrize(
    "image, exc, text",
    [
        (np.zeros((2, 2, 4), complex), TypeError, "image: expected a real array"),
        (np.zeros((2, 2, 4), object), TypeError, "image: expected a numeric array"),
        (np.zeros((0, 2, 4)), ValueError, "image: is empty"),
        (np.zeros((2, 2)), ValueError, r"image: expected an \(H,W,4\)"),
        ([[[0, 0, 0, 0]], [[0, 0]]], TypeError, "image: cannot be read"),
    ],
)
def test_metrics_reject_arrays_that_are_not_images(image, exc, text):
    with pytest.raises(exc, match=text):
        metrics.rmse(image, np.zeros((2, 2, 4)))


def test_metrics_reject_nan_references():
    ref = np.zeros((2, 2, 4))
    ref[0, 0, 0] = np.nan
    for fn in (metrics.rmse, metrics.psnr, metrics.coverage_error):
        with pytest.raises(ValueError, match="reference: contains NaN"):
            fn(np.zeros((2, 2, 4)), ref)
    assert metrics.psnr(np.zeros((2, 2, 4)), np.full((2, 2, 4), 0.1), peak=2.0) == pytest.approx(
        20 * np.log10(20)
    )


@pytest.mark.parametrize("bad", [1e19, 1e10, 1.0 + 1e-6, -1e-6, -1.0])
def test_image_kernels_reject_alpha_outside_zero_one(bad):
    alpha = np.zeros((8, 9), np.float32)
    alpha[3, 4] = bad
    rgba = np.zeros((8, 9, 4), np.float32)
    rgba[..., 3] = alpha
    good = np.zeros((8, 9, 4), np.float32)
    calls = [
        lambda: mbi.pyramid_glow(alpha, 2),
        lambda: mbi.glow(alpha, (1, 0), 3),
        lambda: mbi.glow(alpha, (1, 0.4), 3),
        lambda: mbi.pyramid_opaque_blur(rgba, 2),
        lambda: mbi.opaque_blur(rgba, (1, 0), 3),
        lambda: mbi.opaque_blur(rgba, (1, 0.3), 3),
        lambda: mbi.opaque_blur(rgba, (1, 0), 0),
        lambda: mbi.opaque_motion_blur(rgba, (0, 1), 3),
        lambda: mbi.opaque_motion_blur(rgba, (1, 1), 3, mode="under"),
    ]
    for call in calls:
        with pytest.raises(ValueError, match=r"(alpha|rgba): alpha must be in \[0, 1\]"):
            call()
    with pytest.raises(ValueError, match=r"base: alpha must be in \[0, 1\]"):
        mbi.opaque_motion_blur(good, (1, 0), 3, base=rgba)
    with pytest.raises(ValueError, match=r"base: alpha must be in \[0, 1\]"):
        mbi.opaque_motion_blur(good, (1, 0.5), 3, base=rgba)


def test_image_kernels_take_alpha_at_the_ends_of_the_range_and_linear_filters_take_any():
    rgba = np.zeros((8, 9, 4), np.float32)
    rgba[2:5, 3:6] = [0.5, 0.2, 0.1, 1.0]
    rgba[6, 1, 3] = -0.0
    for out in (
        mbi.opaque_motion_blur(rgba, (1, 0.2), 3),
        mbi.pyramid_opaque_blur(rgba, 2),
        mbi.opaque_blur(rgba, (0, 1), 2),
    ):
        assert np.isfinite(out).all() and out[..., 3].min() >= 0 and out[..., 3].max() <= 1
    assert np.isfinite(mbi.pyramid_glow(rgba[..., 3], 3)).all()
    hot = rgba.copy()
    hot[..., 3] *= 7.0  # a linear filter of a non-image: allowed, and linear
    np.testing.assert_allclose(
        mbi.box_blur(hot, (1, 0), 3)[..., 3], 7 * mbi.box_blur(rgba, (1, 0), 3)[..., 3], rtol=1e-6
    )


# ---------------------------------------------------------------- one coordinate range


def test_the_coordinate_range_is_the_cores_and_exported():
    assert mb.MAX_COORD == _core.MAX_COORD == mb.shell.MAX_COORD == 1e9


def test_every_geometry_entry_point_rejects_coordinates_past_the_range():
    v, f = mb.meshes.box()
    far = v * 1e160
    mesh = mb.Mesh(v, f)
    over = 2 * mb.MAX_COORD
    far_shift = np.eye(4)
    far_shift[0, 3] = over
    calls = {
        "vertices": [
            lambda: mb.Mesh(far, f),
            lambda: mb.contour_edges(SimpleNamespace(vertices=far, faces=f), [1, 0, 0]),
            lambda: mb.Draw(far, f, (1, 1, 1)),
            lambda: mb.Motion.deforming([0.0, 1.0], np.stack([v, far])),
            lambda: mesh.with_vertices(far),
        ],
        "motion": [
            lambda: mb.motion_volume(mesh, np.stack([np.eye(4), np.diag([1e103, 1e103, 1e103, 1])])),
            lambda: mb.motion_volume(mesh, [over, 0, 0]),
            lambda: mb.contour_edges(mesh, [over, 0, 0]),
            lambda: mb.ContourTable(mesh, 4).lookup([over, 0, 0]),
        ],
        "center": [lambda: mb.spin_volume(mesh, [0, 0, 1], 1.0, center=[1e200, 0, 0])],
        "camera_position": [lambda: mb.motion_volume(mesh, [1, 0, 0], camera_position=[0, 0, over])],
        "eye": [lambda: mb.look_at([0, 0, over], [0, 0, 0])],
        "pose": [lambda: mb.Camera(far_shift, 0.7, 8, 8)],
        "offset": [lambda: mb.scene.translate([over, 0, 0])],
        "transforms": [lambda: mb.Motion([0.0, 1.0], np.stack([np.eye(4), far_shift]))],
    }
    for name, fns in calls.items():
        for call in fns:
            with pytest.raises(
                ValueError, match=f"{name}: .*(coordinate range|MAX_COORD|outside the accepted)"
            ):
                call()
    # the rasterizer and the shell had their own bounds (1e15, 1e9): now the same one
    d = mb.Draw(v * 0.9e9, f, (1, 1, 1))
    mb.rasterize(_cam(), d)
    shell = mb.BlurShell(f)
    shell.update(v * 0.9e9)
    with pytest.raises(ValueError, match="vertices"):
        shell.update(v * 2.1e9)


def test_volumes_that_leave_the_range_are_refused_and_those_inside_are_kept():
    mesh = mb.Mesh(*mb.meshes.box())
    big = np.stack([np.eye(4), np.diag([0.9e9, 0.9e9, 0.9e9, 1.0])])
    with pytest.raises(ValueError, match="motion: the volume leaves the coordinate range"):
        mb.motion_volume(mb.Mesh(mesh.vertices + 2.0, mesh.faces), big)
    vol = mb.motion_volume(mesh, np.stack([np.eye(4), np.diag([1e8, 1e8, 1e8, 1.0])]))
    assert np.abs(vol.vertices).max() <= 0.5e8 + 1
    with pytest.raises(ValueError, match="center: the (volume|spin about it) leaves the coordinate range"):
        mb.spin_volume(mesh, [0, 0, 1], np.pi, center=[0.9e9, 0, 0])
    # the contour of a mesh near the range's end is the contour of the unit mesh
    v, f = mb.meshes.box()
    np.testing.assert_array_equal(
        mb.contour_edges(mb.Mesh(v * 1e8, f), [1, 0.3, 0.2]), mb.contour_edges(mb.Mesh(v, f), [1, 0.3, 0.2])
    )


@pytest.mark.parametrize("scale", [1e-120, 1e-10, 2e9, 1e120])
def test_motion_says_which_scales_it_takes_and_why(scale):
    with pytest.raises(
        ValueError,
        match=r"transforms: keyframe 1 scales by about .*outside the accepted uniform scales \[1e-09, 1e\+09\]",
    ):
        mb.Motion([0.0, 1.0], np.stack([np.eye(4), np.diag([scale, scale, scale, 1.0])]))


@pytest.mark.parametrize("scale", [1e-9, 1e-3, 1e3, 1e9])
def test_motion_takes_every_scale_in_the_range(scale):
    m = mb.Motion([0.0, 1.0], np.stack([np.eye(4), np.diag([scale, scale, scale, 1.0])]))
    assert m.transform_at(1.0)[0, 0] == pytest.approx(scale)


def test_camera_field_of_view_has_a_stated_range():
    for yfov in (1e-45, 0.0, -0.1, np.pi, np.pi - 1e-9):
        with pytest.raises(ValueError, match=r"yfov: must be in \[1e-06, pi - 1e-06\] radians"):
            _cam(yfov=yfov)
    narrow = _cam(yfov=mb.raster.MIN_YFOV)
    frame = mb.render(_scene().with_(camera=narrow), "accumulation", samples=2)
    assert np.isfinite(frame.velocity).all() and np.isfinite(frame.rgba).all()
    # a camera pan seen through the narrowest lens: streaks longer than any image, clamped
    pan = mb.SCENES["pan"](32, 24)
    c = pan.camera
    pan = pan.with_(camera=mb.Camera(c.pose, mb.raster.MIN_YFOV, c.width, c.height))
    for method in ("camera_velocity", "accumulation", "motion_volume"):
        frame = mb.render(pan, method)
        assert np.isfinite(frame.velocity).all() and np.isfinite(frame.rgba).all(), method


def test_look_at_takes_any_up_length_and_raises_for_a_degenerate_one():
    ref = mb.look_at([0, 0, 5], [0, 0, 0], [0, 1, 0])
    for up in ([0, 1e300, 0], [0, 1e-300, 0], [0, 3, 0]):
        np.testing.assert_allclose(mb.look_at([0, 0, 5], [0, 0, 0], up), ref, atol=1e-15)
    for up, text in (
        ([0, 0, 0], "up: must not be zero"),
        ([0, 0, 1e300], "up: must not be parallel"),
        ([0, np.inf, 0], "up: contains NaN"),
    ):
        with pytest.raises(ValueError, match=text):
            mb.look_at([0, 0, 5], [0, 0, 0], up)


def test_light_directions_of_any_length_give_the_same_light():
    a = mb.DirectionalLight([0, 0, -1])
    for d in ([0, 0, -1e300], [0, 0, -1e-300]):
        np.testing.assert_array_equal(mb.DirectionalLight(d).direction, a.direction)


# ---------------------------------------------------------------- booleans: one rule


def test_every_boolean_option_raises_for_a_non_bool():
    sc = _scene()
    mesh = mb.Mesh(*mb.meshes.box())
    calls = {
        "exact_static": lambda b: mb.render(sc, "motion_volume", exact_static=b),
        "contour_line": lambda b: mb.render(sc, "motion_volume", contour_line=b),
        "layers": lambda b: mb.render(sc, "opaque_image", layers=b),
        "cull_back": lambda b: mb.Draw(*mb.meshes.box(), (1, 1, 1), cull_back=b),
        "visible_only": lambda b: mb.motion_volume(mesh, [1, 0, 0], visible_only=b),
        "unit": lambda b: mesh.face_normals(unit=b),
        "keep_images": lambda b: mb.Sequence(lambda t: np.zeros((1, 1, 4)), 1, keep_images=b),
    }
    for name, call in calls.items():
        for bad in ("no", 1, None):
            with pytest.raises(TypeError, match=f"{name}: expected True or False"):
                call(bad)
        call(np.bool_(False))


# ---------------------------------------------------------------- threads


def test_a_blur_shell_shared_by_threads_gives_what_one_thread_gives():
    pos, faces = mb.meshes.bending_arm(9)
    serial = mb.BlurShell(faces, subdivisions=4)
    for p in pos:
        serial.update(p)
    expect = serial.build(pos[-1])
    shared = mb.BlurShell(faces, subdivisions=4)
    shared.update(pos[0])
    errors = []
    barrier = threading.Barrier(4)

    def builder():
        barrier.wait()
        try:
            for _ in range(40):
                shared.build(pos[0])
                shared.state()
        except Exception as exc:  # noqa: BLE001 - the test reports whatever a thread raised
            errors.append(exc)

    def updater():
        barrier.wait()
        try:
            for p in pos[1:]:
                shared.update(p)
        except Exception as exc:  # noqa: BLE001
            errors.append(exc)

    threads = [threading.Thread(target=fn) for fn in (builder, builder, builder, updater)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    got = shared.build(pos[-1])
    for name in ("vertices", "faces", "rgba", "step"):
        np.testing.assert_array_equal(getattr(got, name), getattr(expect, name))


def test_one_scene_rendered_from_several_threads_gives_the_same_bits():
    """The methods share kept state across calls (static layers, painters): threads rendering
    one scene at once neither fail nor see each other's frames."""
    sc = mb.SCENES["cube"](48, 36)
    methods = ("accumulation", "motion_volume", "opaque_image")
    expect = {m: mb.render(sc, m).rgba.tobytes() for m in methods}
    errors, differ = [], []

    def run():
        try:
            for _ in range(3):
                for m in methods:
                    if mb.render(sc, m).rgba.tobytes() != expect[m]:
                        differ.append(m)
        except Exception as exc:  # noqa: BLE001 - the test reports whatever a thread raised
            errors.append(exc)

    threads = [threading.Thread(target=run) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors and not differ, (errors, differ)
