"""Property-based robustness of the public API (hypothesis; marker ``robustness``).

Each property throws arrays and scalars of every kind at one entry point (NaN, inf, huge and
tiny values, wrong shapes and dtypes, empty, non-contiguous, Fortran-ordered, read-only,
degenerate geometry) and asserts :func:`_props.check`: a ValueError / TypeError / MemoryError
naming an argument, or a valid result; the caller's arrays unchanged; the same bits twice.
Sizes stay small here (huge ones are in ``test_huge.py``, in subprocesses).
"""

from __future__ import annotations

import numpy as np
import pytest
from _props import JUNK, arrays, check, finite, good_or_bad
from hypothesis import given
from hypothesis import strategies as st

import motionblur as mb
import motionblur.image as mbi
from motionblur import metrics

pytestmark = pytest.mark.robustness

BOX_V, BOX_F = mb.meshes.box()
SMALL = st.integers(1, 6)
MESH_NAMES = ("mesh", "vertices", "faces")


def _cam(w=16, h=12):
    return mb.Camera(mb.look_at((0.0, 0.3, 5.0), (0.0, 0.0, 0.0)), 0.7, w, h)


def _vertices():
    return arrays((SMALL, 3))


def _faces():
    return arrays((SMALL, 3), dtypes=st.sampled_from([np.int64, np.int32, np.uint8, np.float64, np.bool_]))


# ---------------------------------------------------------------- geometry


@given(v=good_or_bad(lambda: BOX_V * 1.0, _vertices()), f=good_or_bad(lambda: BOX_F.copy(), _faces()),
       motion=good_or_bad(lambda: np.array([1.0, 0.2, 0.0]), arrays((3,))))  # fmt: skip
def test_mesh_and_contour_edges(v, f, motion):
    mesh = check(lambda: mb.Mesh(v, f), (v, f), MESH_NAMES)
    if mesh is None:
        return
    edges = check(lambda: mb.contour_edges(mesh, motion), (motion,), ("motion",))
    if edges is not None:
        assert edges.ndim == 2 and edges.shape[1] == 2
        assert edges.size == 0 or (edges.min() >= 0 and edges.max() < len(mesh.vertices))


@given(
    keys=good_or_bad(
        lambda: np.stack([np.eye(4), mb.scene.translate((1.0, 0.0, 0.0))]), arrays((st.integers(1, 3), 4, 4))
    ),
    segments=good_or_bad(lambda: 2, JUNK),
    filt=good_or_bad(lambda: "box", JUNK),
    colors=good_or_bad(lambda: None, arrays((st.sampled_from([1, 8]), 4))),
    camera=good_or_bad(lambda: None, arrays((3,))),
    contour_line=good_or_bad(lambda: True, JUNK),
)
def test_motion_volume(keys, segments, filt, colors, camera, contour_line):
    mesh = mb.Mesh(BOX_V, BOX_F)
    vol = check(
        lambda: mb.motion_volume(
            mesh,
            keys,
            segments=segments,
            filter=filt,
            colors=colors,
            camera_position=camera,
            contour_line=contour_line,
        ),  # fmt: skip
        (keys, colors, camera),
        ("motion", "segments", "filter", "colors", "camera_position", "contour_line"),
    )
    if vol is not None:
        finite(vol.vertices, vol.rgba, vol.normals)
        assert vol.rgba.min() >= 0 and vol.rgba[:, 3].max() <= 1
        assert vol.faces.min() >= 0 and vol.faces.max() < len(vol.vertices)


@given(
    axis=good_or_bad(lambda: np.array([0.0, 0.0, 1.0]), arrays((3,))),
    angle=good_or_bad(lambda: 1.0, JUNK),
    center=good_or_bad(lambda: np.zeros(3), arrays((3,))),
    segments=good_or_bad(lambda: None, JUNK),
)
def test_spin_volume(axis, angle, center, segments):
    mesh = mb.Mesh(BOX_V, BOX_F)
    vol = check(
        lambda: mb.spin_volume(mesh, axis, angle, center=center, segments=segments),
        (axis, center),
        ("axis", "angle", "center", "segments"),
    )
    if vol is not None:
        finite(vol.vertices, vol.rgba, vol.normals)


@given(
    directions=good_or_bad(lambda: 8, st.one_of(JUNK, arrays((SMALL, 3)))),
    seed=good_or_bad(lambda: 0, JUNK),
    index=JUNK,
    motion=arrays((3,)),
)
def test_contour_table(directions, seed, index, motion):
    table = check(lambda: mb.ContourTable(mb.Mesh(BOX_V, BOX_F), directions, seed), (directions,),
                  ("directions", "seed"))  # fmt: skip
    if table is None:
        return
    check(lambda: table.edges(index), (), ("index",))
    check(lambda: table.front_faces(index), (), ("index",))
    check(lambda: table.lookup(motion), (motion,), ("motion",))


# ---------------------------------------------------------------- motion and scenes


@given(
    times=good_or_bad(lambda: np.array([0.0, 1.0]), arrays((st.integers(1, 3),))),
    transforms=good_or_bad(lambda: np.stack([np.eye(4), np.diag([2.0, 2.0, 2.0, 1.0])]), arrays((2, 4, 4))),
    t=JUNK,
)
def test_motion(times, transforms, t):
    motion = check(lambda: mb.Motion(times, transforms), (times, transforms), ("times", "transforms"))
    if motion is not None:
        m = check(lambda: motion.transform_at(t), (), ("t",))
        if m is not None:
            finite(m)


@given(
    direction=good_or_bad(lambda: (0.0, 0.0, -1.0), st.one_of(JUNK, arrays((3,)))),
    intensity=JUNK,
    ambient=JUNK,
    background=good_or_bad(lambda: (0.0, 0.0, 0.0, 0.0), st.one_of(JUNK, arrays((4,)))),
    reference_time=JUNK,
    shutter=good_or_bad(lambda: "box", st.one_of(JUNK, arrays((SMALL,)))),
)
def test_lights_and_scene_options(direction, intensity, ambient, background, reference_time, shutter):
    light = check(lambda: mb.DirectionalLight(direction, intensity), (direction, intensity),
                  ("direction", "intensity"))  # fmt: skip
    obj = mb.Object((BOX_V, BOX_F), motion=mb.Motion.linear((0, 0, 0), (0.3, 0, 0)))
    lights = [] if light is None else [light]
    scene = check(
        lambda: mb.Scene(
            [obj],
            _cam(),
            lights=lights,
            ambient=ambient,
            background=background,
            reference_time=reference_time,
            shutter=shutter,
        ),  # fmt: skip
        (ambient, background, shutter),
        ("ambient", "background", "reference_time", "shutter"),
    )
    if scene is not None:
        frame = check(lambda: mb.render(scene, "accumulation", samples=2), (), ("samples",))
        finite(frame.rgba, frame.velocity)


@given(
    objects=st.one_of(JUNK, st.just([])),
    lights=JUNK,
    camera_motion=JUNK,
)
def test_scene_containers(objects, lights, camera_motion):
    check(lambda: mb.Scene(objects, _cam(), lights=lights, camera_motion=camera_motion), (objects, lights),
          ("objects", "lights", "camera_motion"))  # fmt: skip


@given(
    method=st.sampled_from(
        ["accumulation", "motion_volume", "blur_shell", "opaque_image", "camera_velocity"]
    ),
    option=st.sampled_from(
        [
            "samples",
            "segments",
            "aa",
            "filter",
            "contour_line",
            "exact_static",
            "spin",
            "colors",
            "color_renders",
            "subdivisions",
            "layers",
            "dim",
            "jitter",
        ]
    ),  # fmt: skip
    value=JUNK,
)
def test_render_options(method, option, value):
    obj = mb.Object((BOX_V, BOX_F), color=(0.8, 0.3, 0.1), motion=mb.Motion.linear((0, 0, 0), (0.5, 0, 0)))
    scene = mb.Scene([obj], _cam())
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", mb.MethodNotApplicableWarning)
        frame = check(lambda: mb.render(scene, method, **{option: value}), (value,), ("options", option))
    if frame is not None:
        finite(frame.rgba, frame.velocity)


# ---------------------------------------------------------------- rasterizer


@given(
    v=good_or_bad(lambda: BOX_V * 1.0, _vertices()),
    f=good_or_bad(lambda: BOX_F.copy(), _faces()),
    rgba=good_or_bad(lambda: np.array([1.0, 0.5, 0.2, 0.5]), arrays((st.sampled_from([1, 8, 3, 4]),))),
    previous=good_or_bad(lambda: None, _vertices()),
    object_id=good_or_bad(lambda: 1, JUNK),
    samples=good_or_bad(lambda: 2, JUNK),
    blend=good_or_bad(lambda: "exact", JUNK),
    shading=good_or_bad(lambda: "lambert", JUNK),
)
def test_draw_and_rasterize(v, f, rgba, previous, object_id, samples, blend, shading):
    draw = check(lambda: mb.Draw(v, f, rgba, object_id=object_id, previous_vertices=previous),
                 (v, f, rgba, previous), ("vertices", "faces", "rgba", "previous_vertices", "object_id"))  # fmt: skip
    if draw is None:
        return
    frame = check(
        lambda: mb.rasterize(
            _cam(), draw, samples=samples, blend=blend, shading=shading, lights=[((0.0, -1.0, -1.0), 1.0)]
        ),  # fmt: skip
        (),
        ("samples", "blend", "shading", "vertices"),
    )
    if frame is not None:
        finite(frame.rgba, frame.velocity)
        assert frame.rgba[..., 3].min() >= 0 and frame.rgba[..., 3].max() <= 1


@given(
    pose=good_or_bad(lambda: mb.look_at((0, 0, 5), (0, 0, 0)), arrays((4, 4))),
    yfov=good_or_bad(lambda: 0.7, JUNK),
    width=good_or_bad(lambda: 8, JUNK),
    height=good_or_bad(lambda: 6, JUNK),
    znear=good_or_bad(lambda: 0.05, JUNK),
    zfar=good_or_bad(lambda: float("inf"), JUNK),
    eye=good_or_bad(lambda: (0.0, 0.0, 5.0), arrays((3,))),
    up=good_or_bad(lambda: (0.0, 1.0, 0.0), arrays((3,))),
)
def test_camera_and_look_at(pose, yfov, width, height, znear, zfar, eye, up):
    p = check(lambda: mb.look_at(eye, (0.0, 0.0, 0.0), up), (eye, up), ("eye", "target", "up"))
    if p is not None:
        finite(p)
        np.testing.assert_allclose(p[:3, :3].T @ p[:3, :3], np.eye(3), atol=1e-9)
    cam = check(lambda: mb.Camera(pose, yfov, width, height, znear=znear, zfar=zfar), (pose,),
                ("pose", "yfov", "width", "height", "znear", "zfar"))  # fmt: skip
    if cam is not None and cam.width * cam.height <= 4096:
        frame = check(lambda: mb.rasterize(cam, mb.Draw(BOX_V, BOX_F, (1, 1, 1), previous_vertices=BOX_V + 0.1)),
                      (), ())  # fmt: skip
        finite(frame.rgba, frame.velocity)


# ---------------------------------------------------------------- image space

IMG = (st.integers(1, 9), st.integers(1, 9), 4)
PLANE = (st.integers(1, 9), st.integers(1, 9))


@st.composite
def _image(draw):
    """A premultiplied image, valid more often than not, or anything."""
    if draw(st.booleans()):
        h, w = draw(st.integers(1, 9)), draw(st.integers(1, 9))
        a = draw(st.sampled_from([0.0, 0.5, 1.0]))
        img = np.zeros((h, w, 4), np.float32)
        img[: h // 2 + 1, : w // 2 + 1] = [0.3 * a, 0.2 * a, 0.1 * a, a]
        return img
    return draw(arrays(IMG))


@given(
    rgba=_image(),
    direction=good_or_bad(lambda: (1.0, 0.3), st.one_of(JUNK, arrays((2,)))),
    length=good_or_bad(lambda: 3.0, JUNK),
    levels=good_or_bad(lambda: 2, JUNK),
    mode=good_or_bad(lambda: "over", JUNK),
)
def test_image_kernels(rgba, direction, length, levels, mode):
    names = ("rgba", "alpha", "direction", "length", "width", "levels", "mode", "base")
    alpha = rgba[..., 3] if isinstance(rgba, np.ndarray) and rgba.ndim == 3 and rgba.shape[-1] == 4 else rgba
    for call in (
        lambda: mbi.box_blur(rgba, direction, length),
        lambda: mbi.opaque_blur(rgba, direction, length),
        lambda: mbi.opaque_motion_blur(rgba, direction, length, mode=mode),
        lambda: mbi.glow(alpha, direction, length),
        lambda: mbi.pyramid_blur(rgba, levels),
        lambda: mbi.pyramid_glow(alpha, levels),
        lambda: mbi.pyramid_opaque_blur(rgba, levels),
    ):
        out = check(call, (rgba,), names)
        if out is not None:
            finite(out)


@given(
    rgba=_image(),
    depth=good_or_bad(lambda: None, arrays(PLANE)),
    velocity=good_or_bad(lambda: None, arrays((st.integers(1, 9), st.integers(1, 9), 2))),
    samples=good_or_bad(lambda: 4, JUNK),
    focal=good_or_bad(lambda: 3.0, JUNK),
)
def test_depth_and_velocity_kernels(rgba, depth, velocity, samples, focal):
    shape = rgba.shape[:2] if isinstance(rgba, np.ndarray) and rgba.ndim == 3 else (4, 4)
    d = np.full(shape, 3.0, np.float32) if depth is None else depth
    vel = np.ones((*shape, 2), np.float32) if velocity is None else velocity
    names = ("rgba", "depth", "velocity", "samples", "focal_depth", "yfov", "layers", "focus_distance")
    out = check(lambda: mbi.velocity_blur(rgba, vel, samples=samples), (rgba, vel), names)
    if out is not None:
        finite(out)
    out = check(lambda: mbi.depth_of_field(rgba, d, focal, 0.05, 2.0, 0.7), (rgba, d), names)
    if out is not None:
        finite(out)
    out = check(lambda: mbi.lens_blur(rgba, d, 0.2, focal, 0.7), (rgba, d), names)
    if out is not None:
        finite(out)


# ---------------------------------------------------------------- metrics, shells, frames


@given(image=arrays(IMG), reference=arrays(IMG), peak=JUNK)
def test_metrics(image, reference, peak):
    names = ("image", "reference", "peak")
    for call in (
        lambda: metrics.rmse(image, reference),
        lambda: metrics.psnr(image, reference, peak=peak),
        lambda: metrics.coverage(image),
        lambda: metrics.coverage_error(image, reference),
    ):
        out = check(call, (image, reference), names)
        assert out is None or not np.isnan(out)


@given(
    first=good_or_bad(lambda: BOX_V * 1.0, _vertices()),
    second=good_or_bad(lambda: BOX_V + 0.3, _vertices()),
    normals=good_or_bad(lambda: None, _vertices()),
    subdivisions=good_or_bad(lambda: 3, JUNK),
    alpha=good_or_bad(lambda: 1.0, JUNK),
)
def test_blur_shell(first, second, normals, subdivisions, alpha):
    shell = check(lambda: mb.BlurShell(BOX_F, subdivisions=subdivisions, initial_alpha=alpha), (),
                  ("subdivisions", "initial_alpha"))  # fmt: skip
    if shell is None:
        return
    names = ("vertices", "normals")
    for p in (first, second):
        try:
            shell.update(p, normals)
        except (ValueError, TypeError) as exc:
            assert str(exc).split(":")[0] in names, exc
    out = check(lambda: shell.build(second, normals), (second, normals), names)
    if out is not None:
        finite(out.vertices, out.rgba)


@given(rgba=arrays(IMG), name=st.sampled_from(["f.png", "f.PNG", "f.gif", "f", "f.png.bmp", "f.jpg"]))
def test_frame_save_png(tmp_path_factory, rgba, name):
    path = tmp_path_factory.mktemp("png") / name
    frame = check(
        lambda: mb.Frame(
            rgba, np.zeros(rgba.shape[:2]), np.zeros(rgba.shape[:2], np.int32), np.zeros((*rgba.shape[:2], 2))
        ),  # fmt: skip
        (rgba,),
        ("rgba", "depth", "ids", "velocity"),
    )
    if frame is None:
        return
    check(lambda: frame.save_png(path), (rgba,), ("path", "rgba"))
    if path.exists():
        assert path.suffix.lower() == ".png" and path.read_bytes()[:4] == b"\x89PNG"


@given(
    fn=st.sampled_from(
        ["icosphere", "box", "torus", "cylinder", "uv_sphere", "bending_arm", "spinning_propeller"]
    ),
    a=JUNK,
    b=JUNK,
)
def test_procedural_meshes(fn, a, b):
    names = ("subdivisions", "radius", "extents", "major", "minor", "n_major", "n_minor", "height", "sections",
             "rings", "n_lat", "n_lon", "times", "blades", "length", "angle")  # fmt: skip
    out = check(lambda: getattr(mb.meshes, fn)(a), (a,), names)
    if out is None:
        out = check(lambda: getattr(mb.meshes, fn)(), (), ())
    positions, faces = out
    finite(positions)
    mb.Mesh(positions.reshape(-1, 3), faces)  # every face index is valid for the vertices
    if fn != "box":
        first = 1 if fn in ("icosphere", "bending_arm", "spinning_propeller") else 0.5
        check(lambda: getattr(mb.meshes, fn)(first, b), (b,), names)


@given(
    shutter=good_or_bad(lambda: "triangle", st.one_of(JUNK, arrays((SMALL,)))),
    t=st.one_of(JUNK, arrays((SMALL,))),
)
def test_shutter_cdf(shutter, t):
    w = check(lambda: mb.scene.shutter_cdf(shutter, t), (shutter, t), ("shutter", "t"))
    if w is not None:
        finite(w)
        assert (w >= 0).all() and (w <= 1 + 1e-12).all()
