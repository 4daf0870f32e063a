"""The accumulation frame in one call (``_core._Painter.accumulate_still`` / ``accumulate_moving``,
``src/accumulate/frame.rs``) against its serial twin: the per-sample loop written in Python
with the painter's layer and the accumulation kernels, one call per sample. Exact: the twin
computes the sample rectangles in numpy in the order the core does, so the frames agree bit for
bit. Also: the same frame for any thread count, the GIL released, bad input named."""

from __future__ import annotations

import numpy as np
import pytest
from _helpers.threads import digests, ticks_during

import motionblur as mb
from motionblur import _core, meshes
from motionblur.methods._layers import Layer, composite, static_layer, supersampled, window_projection
from motionblur.methods._painter import Painter, box_corners
from motionblur.methods.accumulation import sample_times
from motionblur.raster import add_times_color
from motionblur.scene import rotate, translate


def _cam(w=64, h=48):
    return mb.Camera(mb.look_at((0.2, 0.4, 5.0), (0.0, 0.0, 0.0)), 0.7, w, h, znear=0.5, zfar=30.0)


def _scene(alpha: float = 1.0, lambert_pair: bool = True) -> mb.Scene:
    v, f = meshes.icosphere(2, 0.4)
    bv, bf = meshes.box((0.5, 0.5, 0.5))
    a = mb.Object(
        (v, f), (0.8, 0.3, 0.2), "lambert",
        mb.Motion.linear(translate((-1.2, 0, 0)) @ rotate(0.3, (0, 1, 0)), translate((1.0, 0.3, 0)) @ rotate(-0.5, (1, 1, 0))),
    )  # fmt: skip
    b = mb.Object(
        (bv, bf), (0.2, 0.6, 0.9), "lambert" if lambert_pair else "flat",
        mb.Motion([0.0, 0.5, 1.0], np.stack([translate((0, -1, 0)), rotate(1.0, (0, 0, 1)), translate((0.5, 0.8, -0.5))])),
    )  # fmt: skip
    pv = np.stack([v * 0.5 + (0.3 * t, 0.6, 0.5) for t in np.linspace(0.0, 1.0, 4)])
    d = mb.Object((pv[0], f), (0.3, 0.9, 0.4), "flat", mb.Motion.deforming(np.linspace(0.0, 1.0, 4), pv))
    wall = mb.Object((bv * (12, 8, 0.2) + (0, 0, -1.5), bf), (0.5, 0.5, 0.45, alpha), "flat")
    light = mb.DirectionalLight((-0.3, -1.0, -0.6), 1.0)
    return mb.Scene([a, b, d, wall], _cam(), [light], ambient=0.1)


def _rect(cam, pts):
    """The sample rectangle of points (numpy, in the core's order)."""
    xy, depth = cam.project(pts)
    if (depth <= 1e-9).any():
        return 0, 0, cam.width, cam.height
    x, y = xy[:, 0], xy[:, 1]
    x0, y0 = max(0, int(np.floor(x.min())) - 1), max(0, int(np.floor(y.min())) - 1)
    x1, y1 = min(cam.width, int(np.ceil(x.max())) + 1), min(cam.height, int(np.ceil(y.max())) + 1)
    return None if x0 >= x1 or y0 >= y1 else (x0, y0, x1, y1)


def serial_twin(scene: mb.Scene, n: int, aa: int):
    """The still-camera frame one sample at a time from Python: (window, rgba, depth, ids, calls)."""
    times, weights = sample_times(scene, n)
    ref = int(np.argmin(np.abs(times - scene.reference_t)))
    cam = supersampled(scene.camera, aa)
    moving = [(k, o) for k, o in enumerate(scene.objects) if o.is_moving]
    static = static_layer(scene, cam, [(k, o) for k, o in enumerate(scene.objects) if not o.is_moving], aa)
    painter = Painter(scene, moving, eye=cam.pose[:3, 3])
    rects = []
    for t in times:
        pts = []
        for _, o in moving:
            if o.motion.is_deforming:
                pts.append(o.world_vertices(t))
            else:
                m = o.transform_at(t)
                pts.append(box_corners(o.mesh) @ m[:3, :3].T + m[:3, 3])
        rects.append(_rect(cam, np.concatenate(pts)))
    found = np.array([r for r in rects if r is not None])
    x0, y0 = (found[:, :2].min(axis=0) // aa) * aa
    x1 = min(cam.width, -(-found[:, 2].max() // aa) * aa)
    y1 = min(cam.height, -(-found[:, 3].max() // aa) * aa)
    c = np.ascontiguousarray
    base = Layer(*(c(a[y0:y1, x0:x1]) for a in (static.layer.rgba, static.layer.depth, static.layer.ids)))
    has_static = bool(np.isfinite(base.depth).any())
    exact = not has_static or static.opaque
    acc = np.zeros((y1 - y0, x1 - x0, 4), np.float32)
    depth, ids = base.depth.copy(), base.ids.copy()
    calls = 0
    for i, (t, r) in enumerate(zip(times, rects)):
        w = np.float32(weights[i])
        if r is None:
            if not exact:
                acc += w * base.rgba
            continue
        proj = c(window_projection(cam.projection, cam.width, cam.height, r))
        layer = painter.layer(t, c(cam.view), proj, r[2] - r[0], r[3] - r[1])
        calls += 1
        sx0, sy0, sx1, sy1 = r[0] - x0, r[1] - y0, r[2] - x0, r[3] - y0
        sub = Layer(base.rgba[sy0:sy1, sx0:sx1], base.depth[sy0:sy1, sx0:sx1], base.ids[sy0:sy1, sx0:sx1])
        if i == ref:
            kept = composite(layer, sub)
            depth[sy0:sy1, sx0:sx1], ids[sy0:sy1, sx0:sx1] = kept.depth, kept.ids
        if exact:
            _core._accumulate(
                acc, layer.rgba, layer.depth, base.depth if has_static else None, float(w), (sx0, sy0)
            )
        else:
            full = base.rgba.copy()
            full[sy0:sy1, sx0:sx1] = composite(layer, sub).rgba
            acc += w * full
    if has_static and static.opaque:
        _core._over(acc, base.rgba)
    return (int(x0), int(y0), int(x1), int(y1)), acc, depth, ids, calls


def one_call(scene: mb.Scene, n: int, aa: int):
    times, weights = sample_times(scene, n)
    ref = int(np.argmin(np.abs(times - scene.reference_t)))
    cam = supersampled(scene.camera, aa)
    moving = [(k, o) for k, o in enumerate(scene.objects) if o.is_moving]
    static = static_layer(scene, cam, [(k, o) for k, o in enumerate(scene.objects) if not o.is_moving], aa)
    painter = Painter(scene, moving, eye=cam.pose[:3, 3])
    c = np.ascontiguousarray
    layer = static.layer
    return painter.core.accumulate_still(
        dict(times=times, weights=weights, reference=ref),
        dict(view=c(cam.view), projection=c(cam.projection), view_projection=c(cam.view_projection),
             width=cam.width, height=cam.height, aa=aa),
        Layer(c(layer.rgba), c(layer.depth), c(layer.ids)), static.opaque,
    )  # fmt: skip


@pytest.mark.parametrize("aa", [1, 2])
@pytest.mark.parametrize("alpha", [1.0, 0.5])
def test_one_call_equals_the_serial_loop(aa, alpha):
    sc = _scene(alpha)
    win, rgba, depth, ids, calls = one_call(sc, 13, aa)
    twin = serial_twin(sc, 13, aa)
    assert win == twin[0] and calls == twin[4] == 13
    np.testing.assert_array_equal(rgba, twin[1])
    np.testing.assert_array_equal(depth, twin[2])
    np.testing.assert_array_equal(ids, twin[3])
    assert rgba[..., 3].max() > 0.5  # the objects are in the frame


def test_moving_camera_equals_the_serial_loop():
    sc = _scene(lambert_pair=False).with_(
        camera_motion=mb.Motion.linear(np.eye(4), rotate(0.2, (0, 1, 0), (0.2, 0.4, 5.0)))
    )
    times, weights = sample_times(sc, 9)
    everything = list(enumerate(sc.objects))
    views = np.stack([sc.camera_at(t).view for t in times])
    painter = Painter(sc, everything)
    cam = sc.camera
    rgba, depth, ids = painter.core.accumulate_moving(
        dict(times=times, weights=weights, reference=4), views, cam.projection, cam.width, cam.height
    )
    acc = None
    for i, t in enumerate(times):
        layer = painter.layer(t, views[i], cam.projection, cam.width, cam.height)
        if acc is None:
            acc = layer.rgba * np.float32(weights[i])
        else:
            _core._accumulate(acc, layer.rgba, layer.depth, None, float(weights[i]))
        if i == 4:
            keep = layer
    np.testing.assert_array_equal(rgba, acc)
    np.testing.assert_array_equal(depth, keep.depth)
    np.testing.assert_array_equal(ids, keep.ids)


def test_offscreen_objects_give_no_window():
    v, f = meshes.icosphere(1)
    far = mb.Object((v + (80.0, 0, 0), f), motion=mb.Motion.linear((0, 0, 0), (1, 0, 0)))
    sc = mb.Scene([far], _cam())
    assert one_call(sc, 4, 1) is None
    fr = mb.render(sc, "accumulation", samples=4)
    assert fr.stats["window"] is None and fr.stats["draw_calls"] == 0 and fr.rgba.max() == 0


def test_the_frame_is_the_same_for_any_thread_count():
    script = (
        "import hashlib, numpy as np\n"
        "from methods.test_accumulation_frame import _scene\n"
        "import motionblur as mb\n"
        "f = mb.render(_scene(0.5), 'accumulation', samples=16, aa=2)\n"
        "g = mb.render(_scene(1.0), 'accumulation', samples=16)\n"
        "print(hashlib.sha256(f.rgba.tobytes() + f.depth.tobytes() + g.rgba.tobytes() + g.ids.tobytes()).hexdigest())\n"
    )
    assert len(set(digests(script))) == 1


def test_the_frame_releases_the_gil():
    v, f = meshes.icosphere(5, 0.5)
    ball = mb.Object((v, f), (0.8, 0.3, 0.2), motion=mb.Motion.linear((-1, 0, 0), (1, 0, 0)))
    sc = mb.Scene([ball], mb.Camera(mb.look_at((0, 0, 4.0), (0, 0, 0)), 0.7, 320, 240))
    assert ticks_during(lambda: mb.render(sc, "accumulation", samples=32)) > 0


def test_bad_requests_name_the_argument():
    sc = _scene()
    cam = sc.camera
    times, weights = sample_times(sc, 4)
    painter = Painter(sc, [(0, sc.objects[0])])
    bg = Layer(np.zeros((cam.height, cam.width, 4), np.float32), np.full((cam.height, cam.width), np.inf, np.float32),
               np.full((cam.height, cam.width), -1, np.int32))  # fmt: skip
    camera = dict(view=cam.view, projection=cam.projection, view_projection=cam.view_projection, width=cam.width,
                  height=cam.height, aa=1)  # fmt: skip

    def samples(weights, reference):
        return dict(times=times, weights=weights, reference=reference)

    with pytest.raises(ValueError, match="weights"):
        painter.core.accumulate_still(samples(weights[:3], 0), camera, bg, True)
    with pytest.raises(ValueError, match="reference"):
        painter.core.accumulate_still(samples(weights, 4), camera, bg, True)
    with pytest.raises(ValueError, match="background"):
        painter.core.accumulate_still(samples(weights, 0), camera, Layer(bg.rgba[1:], bg.depth, bg.ids), True)
    with pytest.raises(ValueError, match="views"):
        painter.core.accumulate_moving(samples(weights, 0), np.zeros((3, 4, 4)), cam.projection, 8, 8)
    v, f = meshes.box()
    obj = dict(id=0, shading="phong", vertices=v, faces=f, rgba=np.ones((1, 4), np.float32), normals=None,
               keyframes=None)  # fmt: skip
    with pytest.raises(ValueError, match="shading"):
        _core._Painter([obj], [], (0.0, 0.0, 0.0))


def test_the_painter_is_kept_across_frames_while_its_objects_stay_the_same():
    from motionblur.methods._painter import painter_for

    sc = _scene()
    moving = [(k, o) for k, o in enumerate(sc.objects) if o.is_moving]
    eye = sc.camera.pose[:3, 3]
    p = painter_for(sc, moving, eye)
    assert painter_for(sc, moving, eye) is p
    assert painter_for(sc, moving, eye + 1.0) is not p  # another eye: other faces turned away
    a = moving[0][1]
    first = mb.render(sc, "accumulation", samples=6).rgba
    a.motion = mb.Motion.linear(translate((0.5, 0, 0)), translate((-0.5, 0, 0)))
    assert painter_for(sc, moving, eye) is not p
    moved = mb.render(sc, "accumulation", samples=6).rgba
    fresh = _scene()
    fresh.objects[0].motion = a.motion
    np.testing.assert_array_equal(moved, mb.render(fresh, "accumulation", samples=6).rgba)
    assert not np.array_equal(first, moved)


def row_order_sum(squares):
    """The squares (h, ...) summed from 0 along each row in order, then the rows' sums from 0 in
    row order (``np.cumsum`` adds in order; ``np.sum`` pairwise would not be ``_halves``' bits)."""
    rows = np.cumsum(squares.reshape(squares.shape[0], -1), axis=1)[:, -1]
    return float(np.cumsum(rows)[-1])


def numpy_halves(sums, win, quartered=False):
    """`HalfSums.halves` in numpy, the arithmetic it replaces (the serial twin of
    ``_core._halves``): each half ``sum(m * part) / sum(m)`` (and, ``quartered``, each of its
    two quarters ``sum(m * part) * (1 / sum(m))``) in float64 from 0 in the parts' order, and
    the end term ``e = sum(end * part)`` of the parts with an end (coefficient ``end * m /
    total mass``), the difference of the halves plus ``e`` (and of each half's quarters plus
    ``2 e``) composited over the background and its squares summed in row order (with an end
    term, the difference's without it too), the frame by the halves' masses."""
    x0, y0, x1, y1 = win
    rows, cols = slice(y0, y1), slice(x0, x1)

    def mean(sel, reciprocal=False):
        mass = sum(float(p.weights.sum()) for p in sel)
        out = np.zeros((y1 - y0, x1 - x0, 4), np.float64)
        for p in sel:
            m, piece = float(p.weights.sum()), p.piece
            term = np.multiply(piece.base[0][rows, cols], m, dtype=np.float64)
            if piece.window is not None:
                wx0, wy0, wx1, wy1 = piece.window
                term[wy0 - y0 : wy1 - y0, wx0 - x0 : wx1 - x0] = np.multiply(
                    piece.drawn[0], m, dtype=np.float64
                )
            out += term
        if reciprocal:  # the sub-halves: only their difference's squares are kept
            out *= 1.0 / mass
        else:
            out /= mass
        return mass, out

    bg = np.asarray(sums.scene.background, np.float64)
    pre = np.concatenate([bg[:3] * bg[3], bg[3:]])

    def composited(a, b):
        diff = np.subtract(a, b, dtype=np.float64)
        add_times_color(diff, -diff[..., 3], pre)  # -alpha: a fresh array, read before the writes
        return diff

    (ma, a), (mb_, b) = (mean([p for p in sums.parts if p.half == j]) for j in (0, 1))
    frame = ((a * ma + b * mb_) / (ma + mb_)).astype(np.float32)
    total = sum(float(p.weights.sum()) for p in sums.parts)
    end = np.zeros_like(a)
    for p in sums.parts:
        if p.end:
            c = p.end * float(p.weights.sum()) / total
            term = np.multiply(p.piece.base[0][rows, cols], c, dtype=np.float64)
            if p.piece.window is not None:
                wx0, wy0, wx1, wy1 = p.piece.window
                term[wy0 - y0 : wy1 - y0, wx0 - x0 : wx1 - x0] = np.multiply(
                    p.piece.drawn[0], c, dtype=np.float64
                )
            end += term
    ends = any(p.end for p in sums.parts)
    diff = np.subtract(a, b, dtype=np.float64)
    square_sum = row_order_sum(np.square(composited(diff + end if ends else diff, 0.0)))
    plain_sum = row_order_sum(np.square(composited(diff, 0.0))) if ends else None
    sub_sum = None
    if quartered:
        # per pixel: half 0's quarters' difference, then half 1's, each channel in order
        subs = []
        for j in (0, 1):
            (_, qa), (_, qb) = (
                mean([p for p in sums.parts if p.half == j and p.quarter // 2 == s], reciprocal=True)
                for s in (0, 1)
            )
            subs.append(composited(qa - qb + 2.0 * end if ends else qa - qb, 0.0))
        sub_sum = row_order_sum(np.square(np.stack(subs, axis=2)))
    return (square_sum, sub_sum, plain_sum), frame, (ma, mb_)


@pytest.mark.parametrize(
    "case",
    [
        "opaque",
        "translucent wall",
        "aa 2",
        "moving camera",
        "background",
        "uneven halves",
        "quarters",
        "ends",
        "ends in quarters",
    ],
)
def test_the_halves_kernel_gives_the_numpy_arithmetics_bits(case):
    # The frame and the error estimate's sum of squares of both halves' difference (and of
    # each half's quarters) from one core pass (_core._halves) against the numpy arithmetic
    # they replace: bit for bit (each pixel's float64 operations and the squares' sums in the
    # same order), on a still camera over an opaque or a translucent static layer,
    # supersampled, a moving camera (every part its own whole frame), a coloured background,
    # halves of unequal mass (auto's reweighted parts), a grid drawn in quarters, and the
    # parts grid_parts makes with ends (aa 2, 4) of 12 and of 8 samples (their first and last sample apart, with
    # the end term; 8 in quarters).
    from motionblur.methods._accumulate import HalfSums, grid_parts

    scene = _scene(alpha=0.6 if case == "translucent wall" else 1.0)
    aa = 2 if case == "aa 2" else 1
    if case == "moving camera":
        scene = mb.Scene(
            scene.objects,
            scene.camera,
            scene.lights,
            camera_motion=mb.Motion.linear(np.eye(4), translate((0.3, 0.1, 0))),
        )
    if case == "background":
        scene = mb.Scene(scene.objects, scene.camera, scene.lights, background=(0.2, 0.4, 0.9, 0.7))
    sums = HalfSums(scene, aa)
    n = 8 if case == "ends in quarters" else 12
    times, weights = sample_times(scene, n)
    if case == "quarters":
        sums.add_all([(times[q::4], weights[q::4], q % 2, q) for q in range(4)])
    if case.startswith("ends"):
        sums.add_all([(times[k], weights[k], *rest) for k, *rest in grid_parts(n, ends=True)])
        assert {p.end for p in sums.parts} == {-1, 0, 1}
    for j, sel in enumerate((np.arange(12)[0::2], np.arange(12)[1::2])):
        if case == "quarters" or case.startswith("ends"):
            break
        if case == "uneven halves":
            sel = sel[: 2 + 2 * j]
        for part in np.array_split(sel, 2):  # two parts a half, as a refinement leaves them
            sums.add(times[part], weights[part], j)
    win = sums._window()
    assert win is not None
    got = sums.halves(win)
    quartered = case in ("quarters", "ends in quarters")
    want = numpy_halves(sums, win, quartered=quartered)
    assert got[1].dtype == np.float32 and got[1].shape == (win[3] - win[1], win[2] - win[0], 4)
    assert got[0][0] == want[0][0], "square sum"
    assert got[0][1] == want[0][1], "quarters' square sum"
    assert (got[0][1] is None) == (not quartered)
    assert got[0][2] == want[0][2], "plain square sum"
    assert (got[0][2] is None) == (not case.startswith("ends")), "the plain sum comes with the end term"
    assert np.array_equal(got[1].view(np.uint32), want[1].view(np.uint32)), "frame"
    assert got[2] == want[2]
    # a half whose parts differ shows in the difference (the kernel is not all zeros)
    assert got[0][0] > 1e-6 and (got[0][1] is None or got[0][1] > 1e-6)


def test_the_halves_kernel_names_bad_parts():
    base = np.zeros((4, 6, 4), np.float32)
    drawn = np.zeros((2, 2, 4), np.float32)
    with pytest.raises(ValueError, match="parts"):
        _core._halves([], (0, 0, 6, 4), (0.0, 0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="half"):
        _core._halves([(2, 1.0, base, None, None, None, 0.0)], (0, 0, 6, 4), (0.0, 0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="sub"):
        _core._halves([(0, 1.0, base, None, None, 2, 0.0)], (0, 0, 6, 4), (0.0, 0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="drawn"):
        _core._halves([(0, 1.0, base, (0, 0, 3, 2), drawn, None, 0.0)], (0, 0, 6, 4), (0.0, 0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="window"):
        _core._halves([(0, 1.0, base, (0, 0, 2, 2), None, None, 0.0)], (0, 0, 6, 4), (0.0, 0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="window"):
        _core._halves([(0, 1.0, base, None, None, None, 0.0)], (0, 0, 7, 4), (0.0, 0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="end"):
        _core._halves([(0, 1.0, base, None, None, None, float("nan"))], (0, 0, 6, 4), (0.0,) * 4)
    with pytest.raises(ValueError, match="base"):
        _core._halves(
            [(0, 1.0, base, None, None, None, 0.0), (1, 1.0, base[:3], None, None, None, 0.0)],
            (0, 0, 6, 4),
            (0.0,) * 4,
        )


@pytest.mark.parametrize("alpha", [1.0, 0.5])
def test_the_parts_call_gives_each_parts_own_frame(alpha):
    # accumulate_still_parts (an accumulation's halves in one hand-off to the pool, the static
    # layer cropped once for the union of their windows) against one accumulate_still call per
    # part: the same windows and bits, in order; with keep, depth and ids of that part only; a
    # bad part or keep named
    sc = _scene(alpha)
    cam = supersampled(sc.camera, 1)
    moving = [(k, o) for k, o in enumerate(sc.objects) if o.is_moving]
    static = static_layer(sc, cam, [(k, o) for k, o in enumerate(sc.objects) if not o.is_moving], 1)
    painter = Painter(sc, moving, eye=cam.pose[:3, 3])
    c = np.ascontiguousarray
    layer = Layer(c(static.layer.rgba), c(static.layer.depth), c(static.layer.ids))
    camera = dict(view=c(cam.view), projection=c(cam.projection), view_projection=c(cam.view_projection),
                  width=cam.width, height=cam.height, aa=1)  # fmt: skip
    times, weights = sample_times(sc, 9)
    parts = [
        dict(times=times[j::2].copy(), weights=weights[j::2] / weights[j::2].sum(), reference=0)
        for j in (0, 1)
    ]
    parts.append(dict(times=times[:3].copy(), weights=np.full(3, 1 / 3), reference=2))
    together = painter.core.accumulate_still_parts(parts, camera, layer, static.opaque)
    assert len(together) == len(parts)
    for got, p in zip(together, parts):
        want = painter.core.accumulate_still(p, camera, layer, static.opaque)
        assert got[0] == want[0] and got[4] == want[4]
        for a, b in zip(got[1:4], want[1:4]):
            assert a.dtype == b.dtype and np.array_equal(a.view(np.uint8), b.view(np.uint8))
    assert not np.array_equal(together[0][1], together[1][1])  # the halves differ
    # the third part's window is smaller than the union the static layer is cropped to
    assert together[2][0] != together[0][0]
    # keep: one part's depth and ids (the one HalfSums pastes), the others' None, colour the same
    kept = painter.core.accumulate_still_parts(parts, camera, layer, static.opaque, 1)
    for k, (got, want) in enumerate(zip(kept, together)):
        assert got[0] == want[0] and got[4] == want[4]
        assert np.array_equal(got[1].view(np.uint32), want[1].view(np.uint32))
        if k == 1:
            assert np.array_equal(got[2], want[2]) and np.array_equal(got[3], want[3])
        else:
            assert got[2] is None and got[3] is None
    with pytest.raises(ValueError, match="keep"):
        painter.core.accumulate_still_parts(parts, camera, layer, static.opaque, 3)
    with pytest.raises(ValueError, match="times"):
        painter.core.accumulate_still_parts(
            [parts[0], dict(parts[1], times=parts[1]["times"] + 2.0)], camera, layer, True
        )
