"""The rasterizer against plain numpy twins: watertight coverage, exact alpha, order independence,
velocity, lambert, supersampling, the hard cases, bad input and thread-count independence.

Tolerances are stated per test; "exact" means bit-equal float32.
"""

from __future__ import annotations

import textwrap
from types import SimpleNamespace

import numpy as np
import pytest
from _helpers.threads import digests

import motionblur as mb
from motionblur import meshes


def cover_count(camera, v, f, cull_back, eps=1e-3):
    """Numpy twin of coverage: how many faces contain each pixel centre, and a mask of pixels whose
    centre lies within ``eps`` pixels of some edge (where the fill rule, not geometry, decides)."""
    p, w = camera.project(v)
    assert (w > 0).all(), "the twin handles unclipped scenes only"
    ys, xs = np.mgrid[0 : camera.height, 0 : camera.width] + 0.5
    count = np.zeros(xs.shape, np.int32)
    ambiguous = np.zeros(xs.shape, bool)
    for a, b, c in p[f]:
        area = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
        if area == 0 or (cull_back and area > 0):  # y down: front faces have negative area
            continue
        s = -np.sign(area)
        inside = np.ones(xs.shape, bool)
        for q, r in ((a, b), (b, c), (c, a)):
            e = s * ((r[0] - q[0]) * (ys - q[1]) - (r[1] - q[1]) * (xs - q[0]))
            inside &= e < 0
            # Distance from the pixel centre to the segment q-r.
            d = r - q
            t = np.clip(((xs - q[0]) * d[0] + (ys - q[1]) * d[1]) / max(d @ d, 1e-300), 0, 1)
            ambiguous |= np.hypot(xs - q[0] - t * d[0], ys - q[1] - t * d[1]) < eps
        count += inside
    return count, ambiguous


def over_n(alpha, n):
    """float32 alpha after compositing n layers of ``alpha`` with premultiplied over."""
    out = np.float32(0)
    a = np.float32(alpha)
    for _ in range(n):
        out = a + (np.float32(1) - a) * out
    return out


def quad(size=1.0):
    v = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float64) * size
    return v, np.array([[0, 1, 2], [0, 2, 3]])


@pytest.mark.parametrize("eye", [(0.3, 0.2, 3.0), (-2.0, 1.5, 1.0), (0.0, -2.5, 0.7)])
def test_a_transparent_quad_has_no_seam_and_no_double_blend(eye):
    v, f = quad(0.9)
    cam = mb.Camera(mb.look_at(eye, (0.05, -0.02, 0.0)), 0.9, 97, 73)
    frame = mb.rasterize(cam, mb.Draw(v, f, (1.0, 1.0, 1.0, 0.5), cull_back=False))
    count, ambiguous = cover_count(cam, v, f, cull_back=False)
    alpha = frame.coverage
    assert set(np.unique(alpha)) <= {np.float32(0), np.float32(0.5)}, "a pixel was blended twice"
    inside_quad = count > 0  # either triangle
    sure = ~ambiguous
    np.testing.assert_array_equal(alpha[sure], np.where(inside_quad[sure], np.float32(0.5), 0))
    # The shared diagonal crosses the quad: pixels along it are no exception.
    assert inside_quad.sum() > 500


@pytest.mark.parametrize("cull_back", [False, True])
@pytest.mark.parametrize("eye", [(0.0, 0.0, 3.0), (2.0, 1.0, -1.5), (-1.0, -2.5, 0.5), (0.1, 2.8, 0.1)])
def test_a_transparent_closed_mesh_matches_the_analytic_alpha_exactly(eye, cull_back):
    v, f = meshes.icosphere(2)
    cam = mb.Camera(mb.look_at(eye, (0.0, 0.0, 0.0)), 0.9, 96, 72)
    a = 0.3
    frame = mb.rasterize(cam, mb.Draw(v, f, (0.2, 0.5, 0.9, a), cull_back=cull_back))
    count, ambiguous = cover_count(cam, v, f, cull_back)
    layers = 1 if cull_back else 2
    want = np.where(count > 0, over_n(a, layers), np.float32(0))
    sure = ~ambiguous
    np.testing.assert_array_equal(frame.coverage[sure], want[sure])
    # Everywhere (fill-rule pixels included) only 0 or exactly `layers` layers.
    assert set(np.unique(frame.coverage)) <= {np.float32(0), over_n(a, layers)}
    assert (count[sure] <= layers).all()


def _layers_scene():
    """Three overlapping transparent meshes with different colours and culling off."""
    draws = []
    for i, (c, off) in enumerate(
        [((0.9, 0.2, 0.1, 0.4), 0.0), ((0.1, 0.8, 0.3, 0.6), 0.3), ((0.2, 0.3, 0.9, 0.5), -0.4)]
    ):
        v, f = meshes.icosphere(2, radius=0.8)
        draws.append(mb.Draw(v + [off, 0.5 * off, -off], f, c, object_id=i, cull_back=False))
    return draws


def test_exact_blending_does_not_depend_on_submission_order():
    cam = mb.Camera(mb.look_at((0.4, 0.5, 3.0), (0, 0, 0)), 0.8, 80, 64)
    draws = _layers_scene()
    ref = mb.rasterize(cam, draws, blend="exact")
    rng = np.random.default_rng(7)
    shuffled = []
    for d in reversed(draws):
        perm = rng.permutation(len(d.faces))
        shuffled.append(mb.Draw(d.vertices, d.faces[perm], d.rgba[0], object_id=d.object_id, cull_back=False))
    other = mb.rasterize(cam, shuffled, blend="exact")
    np.testing.assert_array_equal(ref.rgba, other.rgba)
    np.testing.assert_array_equal(ref.depth, other.depth)
    np.testing.assert_array_equal(ref.ids, other.ids)
    # The test can fail: unsorted blending does depend on the order.
    u1 = mb.rasterize(cam, draws, blend="unsorted")
    u2 = mb.rasterize(cam, shuffled, blend="unsorted")
    assert np.abs(u1.rgba - u2.rgba).max() > 0.01
    # And with a single layer per pixel unsorted and exact agree.
    assert np.abs(u1.rgba - ref.rgba).max() > 0.01


def test_exact_blending_equals_a_numpy_depth_sorted_composite():
    """Numpy twin: per pixel, the layers' colours composited back to front in depth order."""
    cam = mb.Camera(mb.look_at((0.0, 0.0, 4.0), (0, 0, 0)), 0.7, 48, 48)
    v, f = quad(1.0)
    specs = [(0.3, (0.9, 0.1, 0.1, 0.5)), (-0.2, (0.1, 0.9, 0.1, 0.25)), (0.6, (0.1, 0.1, 0.9, 0.75))]
    draws = [
        mb.Draw(v * [1 - k * 0.2, 1, 1] + [0, 0, z], f, c, object_id=k) for k, (z, c) in enumerate(specs)
    ]
    frame = mb.rasterize(cam, draws)
    centre = frame.rgba[24, 24]
    out = np.zeros(4, np.float32)
    for _z, c in sorted(specs):  # far (small z) first
        c = np.asarray(c, np.float32)
        src = np.r_[c[:3] * c[3], c[3]].astype(np.float32)
        out = src + (np.float32(1) - src[3]) * out
    np.testing.assert_allclose(centre, out, rtol=0, atol=1e-6)
    assert frame.ids[24, 24] == 2, "the nearest transparent surface names the pixel"
    assert abs(frame.depth[24, 24] - (4.0 - 0.6)) < 1e-5


def test_opaque_output_does_not_depend_on_order():
    cam = mb.Camera(mb.look_at((1.0, 0.8, 3.0), (0, 0, 0)), 0.8, 80, 60)
    v, f = meshes.torus()
    v2, f2 = meshes.box((1.2, 0.4, 0.8))
    draws = [mb.Draw(v, f, (0.8, 0.3, 0.1), object_id=1), mb.Draw(v2, f2, (0.1, 0.3, 0.8), object_id=2)]
    ref = mb.rasterize(cam, draws)
    perm = np.random.default_rng(1).permutation(len(f))
    other = mb.rasterize(cam, [draws[1], mb.Draw(v, f[perm], (0.8, 0.3, 0.1), object_id=1)])
    for name in ("rgba", "depth", "ids"):
        np.testing.assert_array_equal(getattr(ref, name), getattr(other, name))
    assert {1, 2} <= set(np.unique(ref.ids))


def test_opaque_surfaces_hide_transparent_ones_behind_them():
    cam = mb.Camera(mb.look_at((0.0, 0.0, 4.0), (0, 0, 0)), 0.7, 32, 32)
    v, f = quad(1.0)
    front = mb.Draw(v + [0, 0, 0.5], f, (0.2, 0.4, 0.6, 1.0), object_id=1)
    back = mb.Draw(v, f, (1.0, 1.0, 1.0, 0.5), object_id=2)
    frame = mb.rasterize(cam, [back, front])
    np.testing.assert_array_equal(frame.rgba[16, 16], np.float32([0.2, 0.4, 0.6, 1.0]))
    assert frame.ids[16, 16] == 1


def test_velocity_matches_a_numpy_twin():
    """A tilted quad translated between the previous and the current time: per pixel, the surface
    point seen now (ray-plane intersection) minus where it was, projected. Tolerance 1e-3 px."""
    v, f = quad(1.0)
    c, s = np.cos(0.7), np.sin(0.7)
    v = v @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]]).T
    shift = np.array([0.15, -0.1, 0.3])
    cam = mb.Camera(mb.look_at((0.2, 0.1, 3.0), (0, 0, 0)), 0.9, 64, 48)
    frame = mb.rasterize(cam, mb.Draw(v, f, (1, 1, 1), previous_vertices=v - shift, cull_back=False))
    ys, xs = np.nonzero(frame.ids == 0)
    # Ray through each pixel centre, intersected with the quad's plane.
    ndc = np.c_[(xs + 0.5) / 64 * 2 - 1, 1 - (ys + 0.5) / 48 * 2]
    inv = np.linalg.inv(cam.view_projection)
    far = np.c_[ndc, np.zeros(len(ndc)), np.ones(len(ndc))] @ inv.T  # a point on the ray (any zfar)
    far = far[:, :3] / far[:, 3:]
    eye = cam.pose[:3, 3]
    n = np.cross(v[1] - v[0], v[2] - v[0])
    t = ((v[0] - eye) @ n) / ((far - eye) @ n)
    point = eye + t[:, None] * (far - eye)
    now, _ = cam.project(point)
    before, _ = cam.project(point - shift)
    np.testing.assert_allclose(frame.velocity[ys, xs], now - before, atol=1e-3)
    assert np.abs(now - before).max() > 2.0
    static = mb.rasterize(cam, mb.Draw(v, f, (1, 1, 1), previous_vertices=v, cull_back=False))
    assert (static.velocity == 0).all()


def test_lambert_matches_a_numpy_twin():
    """A triangle with per-vertex normals and colours: numpy interpolates them perspective-correctly
    (ray-plane barycentrics), normalises and lights. Tolerance 1e-4."""
    v = np.array([[-1.0, -1.0, 0.0], [1.2, -0.8, -0.6], [-0.2, 1.1, 0.4]])
    f = np.array([[0, 1, 2]])
    nrm = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, 0.6, 0.8]])
    col = np.array([[1.0, 0.2, 0.2, 1.0], [0.2, 1.0, 0.2, 1.0], [0.2, 0.2, 1.0, 1.0]])
    lights = [((-0.3, -0.2, -1.0), 0.8), ((1.0, 0.0, -0.2), (0.2, 0.3, 0.4))]
    cam = mb.Camera(mb.look_at((0.3, 0.2, 3.0), (0, 0, 0)), 0.9, 64, 48)
    frame = mb.rasterize(cam, mb.Draw(v, f, col, normals=nrm), shading="lambert", lights=lights, ambient=0.1)
    ys, xs = np.nonzero(frame.ids == 0)
    ndc = np.c_[(xs + 0.5) / 64 * 2 - 1, 1 - (ys + 0.5) / 48 * 2]
    inv = np.linalg.inv(cam.view_projection)
    far = np.c_[ndc, np.zeros(len(ndc)), np.ones(len(ndc))] @ inv.T  # a point on the ray (any zfar)
    far = far[:, :3] / far[:, 3:]
    eye = cam.pose[:3, 3]
    pn = np.cross(v[1] - v[0], v[2] - v[0])
    t = ((v[0] - eye) @ pn) / ((far - eye) @ pn)
    p = eye + t[:, None] * (far - eye)
    area = np.linalg.norm(pn)
    lam = np.stack(
        [np.linalg.norm(np.cross(v[(k + 1) % 3] - p, v[(k + 2) % 3] - p), axis=1) / area for k in range(3)], 1
    )
    n = lam @ nrm
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    e = np.full((len(n), 3), 0.1)
    for d, k in lights:
        d = np.asarray(d) / np.linalg.norm(d)
        e += np.broadcast_to(k, (3,)) * np.maximum(0, -(n @ d))[:, None]
    want = (lam @ col)[:, :3] * e
    np.testing.assert_allclose(frame.rgba[ys, xs, :3], want, atol=1e-4)
    assert len(ys) > 300


def test_supersampling_is_a_box_filter_of_the_finer_grid():
    """samples=4 equals a 4x larger render averaged over 4x4 blocks (same sample positions)."""
    v, f = meshes.icosphere(2)
    draw = mb.Draw(v, f, (0.9, 0.6, 0.3, 0.7))
    pose = mb.look_at((0.5, 0.4, 2.8), (0, 0, 0))
    coarse = mb.rasterize(mb.Camera(pose, 0.8, 40, 30), draw, samples=4)
    fine = mb.rasterize(mb.Camera(pose, 0.8, 160, 120), draw)
    blocks = fine.rgba.reshape(30, 4, 40, 4, 4)
    np.testing.assert_allclose(coarse.rgba, blocks.mean(axis=(1, 3)), rtol=0, atol=1e-6)
    np.testing.assert_array_equal(coarse.depth, fine.depth.reshape(30, 4, 40, 4).min(axis=(1, 3)))
    edge = (coarse.coverage > 0) & (coarse.coverage < 0.7 - 1e-6)
    assert edge.sum() > 20, "anti-aliased silhouette pixels exist"


# --- hard cases


def test_slivers_and_subpixel_triangles_stay_watertight():
    """A disc made of 500 needle-thin fan triangles and a grid of 0.3-pixel triangles."""
    n = 500
    ang = np.linspace(0, 2 * np.pi, n, endpoint=False)
    v = np.r_[[[0.05, 0.03, 0.0]], np.c_[np.cos(ang), np.sin(ang), np.zeros(n)]]
    f = np.c_[np.zeros(n, int), 1 + np.arange(n), 1 + (np.arange(n) + 1) % n]
    cam = mb.Camera(mb.look_at((0.0, 0.0, 3.0), (0, 0, 0)), 0.8, 90, 90)
    frame = mb.rasterize(cam, mb.Draw(v, f, (1, 1, 1, 0.5)))
    count, ambiguous = cover_count(cam, v, f, cull_back=True)
    assert set(np.unique(frame.coverage)) <= {np.float32(0), np.float32(0.5)}
    sure = ~ambiguous
    np.testing.assert_array_equal(frame.coverage[sure] > 0, count[sure] > 0)
    # Sub-pixel grid: 150 x 150 quads over ~45 pixels.
    k = 150
    g = np.linspace(-0.5, 0.5, k + 1)
    gx, gy = np.meshgrid(g, g)
    gv = np.c_[gx.ravel(), gy.ravel(), np.zeros(gx.size)]
    idx = np.arange((k + 1) ** 2).reshape(k + 1, k + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    gf = np.r_[np.c_[a, b, c], np.c_[a, c, d]]
    frame = mb.rasterize(cam, mb.Draw(gv, gf, (1, 1, 1, 0.5)))
    assert set(np.unique(frame.coverage)) <= {np.float32(0), np.float32(0.5)}
    inner = frame.coverage[35:55, 35:55]
    assert (inner == np.float32(0.5)).all()


def test_triangles_far_outside_the_viewport_and_huge_coordinates():
    cam = mb.Camera(mb.look_at((0.0, 0.0, 5.0), (0, 0, 0)), 0.8, 40, 30, zfar=1e7)
    # One triangle with corners thousands of screens away covers the whole image at depth 5.
    v = np.array([[-1e4, -1e4, 0.0], [1e4, -1e4, 0.0], [0.0, 1e4, 0.0]])
    frame = mb.rasterize(cam, mb.Draw(v, [[0, 1, 2]], (1, 1, 1, 0.5)))
    assert (frame.coverage == np.float32(0.5)).all()
    np.testing.assert_allclose(frame.depth, 5.0, rtol=1e-6)
    # Coordinates of 1e6: a quad 1e6 units away, 1e6 across.
    v, f = quad(3e5)
    frame = mb.rasterize(cam, mb.Draw(v + [0, 0, -1e6 + 5], f, (1, 1, 1)))
    ys, xs = np.nonzero(frame.ids == 0)
    assert 0 < len(ys) < 40 * 30
    np.testing.assert_allclose(frame.depth[ys, xs], 1e6, rtol=1e-6)
    # Triangles entirely outside the view do nothing.
    frame = mb.rasterize(cam, mb.Draw(v + [1e6, 0, 0], f, (1, 1, 1)))
    assert (frame.ids == -1).all() and frame.stats["triangles"] == 0


def test_vertices_behind_the_camera_do_not_wrap():
    """A triangle with one vertex behind the camera: the visible part is what the clipped
    triangle covers; a naive divide-by-w would wrap the corner through infinity."""
    cam = mb.Camera(np.eye(4), 1.0, 64, 48, znear=0.1)
    v = np.array([[-1.0, -0.5, -2.0], [1.0, -0.5, -2.0], [0.0, -0.5, 3.0]])  # third vertex behind
    frame = mb.rasterize(cam, mb.Draw(v, [[0, 1, 2]], (1, 1, 1), cull_back=False))
    ys, xs = np.nonzero(frame.ids == 0)
    assert len(ys) > 0
    # The floor at y = -0.5 is only visible below the horizon, and depth = 0.5 / slope there.
    assert (ys >= 24).all()
    yc = ys + 0.5
    slope = (yc / 48 * 2 - 1) * np.tan(0.5)
    np.testing.assert_allclose(frame.depth[ys, xs], 0.5 / slope, rtol=1e-5)
    assert frame.stats["clipped"] == 1


@pytest.mark.parametrize("cull_back", [True, False])
def test_clipped_triangles_interpolate_their_own_corners(cull_back):
    """A front face crossing the near plane, with a colour per corner: where it is seen, every
    pixel shows the colour of its surface point, as a triangle cut from the same plane wholly in
    front of the camera (its corners coloured by their barycentric coordinates) shows it. The
    clipped polygon is drawn as a fan of triangles whose corners are reordered to a positive
    area; their barycentric coordinates in the face once followed the corners but not the face's
    vertices, which swapped the colours of two corners."""
    cam = mb.Camera(mb.look_at((0, 0.5, 3), (0, -0.5, 0)), 0.9, 64, 48, znear=0.3)
    big = np.array([[-4.0, -1.0, 5.0], [4.0, -1.0, 5.0], [0.0, -1.0, -6.0]])  # the first two behind
    rgb = np.eye(3, dtype=np.float32)
    face = [[0, 1, 2]] if cull_back else [[0, 2, 1]]
    clipped = mb.rasterize(cam, mb.Draw(big, face, rgb, cull_back=cull_back))
    assert clipped.stats["clipped"] == 1
    # a triangle of the same plane in front of the camera, corners at barycentric coordinates lam
    lam = np.array([[0.4, 0.2, 0.4], [0.1, 0.4, 0.5], [0.05, 0.05, 0.9]])
    inner = mb.rasterize(cam, mb.Draw(lam @ big, face, lam.astype(np.float32), cull_back=cull_back))
    assert inner.stats["clipped"] == 0
    both = (inner.ids == 0) & (clipped.ids == 0)
    assert both.sum() > 200
    np.testing.assert_allclose(clipped.rgba[both], inner.rgba[both], atol=2e-6)


def test_one_pixel_and_4096_pixel_images():
    v, f = meshes.icosphere(4)
    draw = mb.Draw(v, f, (0.5, 0.5, 0.5))
    one = mb.rasterize(mb.Camera(mb.look_at((0, 0, 3), (0, 0, 0)), 0.8, 1, 1), draw)
    assert one.rgba.shape == (1, 1, 4) and one.ids[0, 0] == 0
    np.testing.assert_allclose(one.depth[0, 0], 2.0, rtol=1e-3)
    big = mb.rasterize(mb.Camera(mb.look_at((0, 0, 3), (0, 0, 0)), 0.8, 4096, 4096), draw)
    assert big.rgba.shape == (4096, 4096, 4)
    cov = big.coverage > 0
    # The sphere's disc: pi r^2 with r the projected radius (the 5120-face polygon is 0.3% smaller).
    r = 4096 / 2 / np.tan(0.4) * np.tan(np.arcsin(1 / 3))
    assert abs(cov.sum() / (np.pi * r * r) - 1) < 0.01
    assert big.ids[2048, 2048] == 0 and big.ids[0, 0] == -1


# --- bad input


@pytest.mark.parametrize(
    "make, exc, text",
    [
        (lambda: mb.Camera(np.eye(4), 0.8, 0, 10), ValueError, "width"),
        (lambda: mb.Camera(np.eye(4), 0.8, 10, 100000), ValueError, "height"),
        (lambda: mb.Camera(np.eye(4), 0.8, 16384, 16384), ValueError, "width"),
        (lambda: mb.Camera(np.eye(4), 0.8, 10, 10, znear=0.0), ValueError, "znear"),
        (lambda: mb.Camera(np.eye(4), 0.8, 10, 10, znear=-1.0), ValueError, "znear"),
        (lambda: mb.Camera(np.eye(4), 0.8, 10, 10, znear=1.0, zfar=0.5), ValueError, "zfar"),
        (lambda: mb.Camera(np.eye(4), 4.0, 10, 10), ValueError, "yfov"),
        (lambda: mb.Camera(np.full((4, 4), np.nan), 0.8, 10, 10), ValueError, "pose"),
        (lambda: mb.Camera(np.eye(3), 0.8, 10, 10), ValueError, "pose"),
        (lambda: mb.Camera(np.eye(4), 0.8, 10.5, 10), TypeError, "width"),
        (lambda: mb.Draw([[0, 0, np.nan]] * 3, [[0, 1, 2]], (1, 1, 1)), ValueError, "vertices"),
        (lambda: mb.Draw(np.zeros((3, 2)), [[0, 1, 2]], (1, 1, 1)), ValueError, "vertices"),
        (lambda: mb.Draw(np.zeros((3, 3)), [[0, 1, 3]], (1, 1, 1)), ValueError, "faces"),
        (lambda: mb.Draw(np.zeros((3, 3)), [[0, 1, -1]], (1, 1, 1)), ValueError, "faces"),
        (lambda: mb.Draw(np.zeros((3, 3)), [[0.0, 1.0, 2.0]], (1, 1, 1)), TypeError, "faces"),
        (lambda: mb.Draw(np.zeros((3, 3)), np.zeros((0, 3), int), (1, 1, 1)), ValueError, "faces"),
        (lambda: mb.Draw(np.zeros((3, 3)), [[0, 1, 2]], (1, 1)), ValueError, "rgba"),
        (lambda: mb.Draw(np.zeros((3, 3)), [[0, 1, 2]], np.ones((2, 4))), ValueError, "rgba"),
        (lambda: mb.Draw(np.zeros((3, 3)), [[0, 1, 2]], (1, 1, 1, 2)), ValueError, "rgba"),
        (
            lambda: mb.Draw(np.zeros((3, 3)), [[0, 1, 2]], (1, 1, 1), normals=np.ones((2, 3))),
            ValueError,
            "normals",
        ),
        (
            lambda: mb.Draw(np.zeros((3, 3)), [[0, 1, 2]], (1, 1, 1), previous_vertices=np.ones((4, 3))),
            ValueError,
            "previous_vertices",
        ),
        (lambda: mb.Draw(np.zeros((3, 3)), [[0, 1, 2]], (1, 1, 1), object_id=2**40), ValueError, "object_id"),
    ],
)
def test_bad_input_names_the_argument(make, exc, text):
    with pytest.raises(exc, match=text):
        make()


@pytest.mark.parametrize(
    "kwargs, exc, text",
    [
        ({"samples": 3}, ValueError, "samples"),
        ({"blend": "sorted"}, ValueError, "blend"),
        ({"blend": 1}, TypeError, "blend"),
        ({"shading": "phong"}, ValueError, "shading"),
        ({"lights": [((0, 0, 0), 1.0)]}, ValueError, "lights"),
        ({"lights": [((0, 0, 1), -1.0)]}, ValueError, "lights"),
        ({"lights": [1.0]}, TypeError, "lights"),
        ({"ambient": np.nan}, ValueError, "ambient"),
    ],
)
def test_bad_rasterize_options_name_the_argument(kwargs, exc, text):
    v, f = quad()
    cam = mb.Camera(np.eye(4), 0.8, 8, 8)
    with pytest.raises(exc, match=text):
        mb.rasterize(cam, mb.Draw(v, f, (1, 1, 1)), **kwargs)


def test_bad_draws_and_cameras_are_type_errors():
    v, f = quad()
    with pytest.raises(TypeError, match="camera"):
        mb.rasterize("camera", mb.Draw(v, f, (1, 1, 1)))
    with pytest.raises(TypeError, match="draws"):
        mb.rasterize(mb.Camera(np.eye(4), 0.8, 8, 8), [(v, f)])


def test_the_core_rechecks_what_reaches_it():
    """The binding checks shapes and indices itself (callers that bypass Draw get ValueError)."""
    from motionblur import _core

    cam = mb.Camera(np.eye(4), 0.8, 8, 8)
    v = np.zeros((3, 3))
    bad = SimpleNamespace(
        vertices=v, faces=np.array([[0, 1, 5]]), rgba=np.ones((1, 4), np.float32), normals=None, object_id=0,
        cull_back=True, previous_vertices=None,
    )  # fmt: skip
    options = dict(
        view=cam.view, projection=cam.projection, width=8, height=8, samples=1, blend="exact", shading="flat",
        lights=[], ambient=(0.0, 0.0, 0.0), origin=(0, 0),
    )  # fmt: skip
    with pytest.raises(ValueError, match="faces"):
        _core._rasterize([bad], options)
    with pytest.raises(ValueError, match="width"):
        _core._rasterize([], {**options, "width": 0})


def test_callers_arrays_are_never_written():
    v, f = meshes.icosphere(1)
    v = v.astype(np.float32)
    c = np.ones((len(v), 4), np.float32) * 0.5
    prev = v + 0.1
    before = [a.copy() for a in (v, f, c, prev)]
    draw = mb.Draw(v, f, c, previous_vertices=prev)
    mb.rasterize(mb.Camera(mb.look_at((0, 0, 3), (0, 0, 0)), 0.8, 16, 16), draw, shading="lambert")
    for a, b in zip((v, f, c, prev), before):
        np.testing.assert_array_equal(a, b)
    assert not draw.vertices.flags.writeable


def test_frame_from_arrays_and_png(tmp_path):
    rgba = np.zeros((4, 5, 4), np.float32)
    rgba[1, 2] = [0.25, 0.1, 0.0, 0.5]  # premultiplied: straight colour (0.5, 0.2, 0)
    frame = mb.Frame(rgba, np.full((4, 5), np.inf), -np.ones((4, 5), np.int64), np.zeros((4, 5, 2)))
    assert frame.ids.dtype == np.int32 and frame.depth.dtype == np.float32
    assert frame.coverage[1, 2] == 0.5
    path = tmp_path / "f.png"
    frame.save_png(path)
    from PIL import Image

    img = np.asarray(Image.open(path))
    assert img.shape == (4, 5, 4)
    srgb = lambda c: 1.055 * c ** (1 / 2.4) - 0.055  # noqa: E731
    np.testing.assert_array_equal(
        img[1, 2], np.round([srgb(0.5) * 255, srgb(0.2) * 255, 0, 127.5]).astype(np.uint8)
    )
    with pytest.raises(ValueError, match="depth"):
        mb.Frame(rgba, np.zeros((4, 4)), np.zeros((4, 5)), np.zeros((4, 5, 2)))


def test_frame_takes_ready_arrays_as_they_are_and_checks_the_others():
    rgba, depth = np.zeros((4, 5, 4), np.float32), np.full((4, 5), np.inf, np.float32)
    ids, vel = np.zeros((4, 5), np.int32), np.zeros((4, 5, 2), np.float32)
    frame = mb.Frame(rgba, depth, ids, vel)
    assert frame.rgba is rgba and frame.depth is depth and frame.ids is ids and frame.velocity is vel
    # strided, other dtypes, subclasses: converted to C-contiguous float32 / int32
    strided = mb.Frame(np.zeros((4, 10, 4), np.float32)[:, ::2], depth.astype(np.float64), ids, vel)
    assert strided.rgba.flags.c_contiguous and strided.depth.dtype == np.float32
    for args, err, name in (
        ((rgba[..., :3], depth, ids, vel), ValueError, "rgba"),
        ((rgba, depth[:, :4], ids, vel), ValueError, "depth"),
        ((rgba, depth, ids.astype(np.float32), vel), TypeError, "ids"),
        ((rgba, depth, ids, vel[..., :1]), ValueError, "velocity"),
        ((rgba[:0], depth[:0], ids[:0], vel[:0]), ValueError, "rgba"),
    ):
        with pytest.raises(err, match=name):
            mb.Frame(*args)


# --- threads


_THREAD_SCRIPT = textwrap.dedent(
    """
    import hashlib, numpy as np, motionblur as mb
    from motionblur import meshes
    v, f = meshes.icosphere(4)
    draws = [mb.Draw(v, f, (0.8, 0.4, 0.2, 0.5), cull_back=False, previous_vertices=v * 1.05, object_id=3),
             mb.Draw(*meshes.torus(), (0.2, 0.4, 0.8, 1.0), object_id=4)]
    cam = mb.Camera(mb.look_at((0.5, 0.6, 3.0), (0, 0, 0)), 0.9, 200, 150)
    h = hashlib.sha256()
    for samples in (1, 2):
        fr = mb.rasterize(cam, draws, samples=samples, shading="lambert", lights=[((0, -1, -1), 1.0)])
        for a in (fr.rgba, fr.depth, fr.ids, fr.velocity):
            h.update(np.ascontiguousarray(a).tobytes())
    print(h.hexdigest())
    """
)


def test_output_is_bit_identical_for_any_thread_count():
    got = digests(_THREAD_SCRIPT)
    assert len(got[0]) == 64
    assert got[0] == got[1] == got[2]


@pytest.mark.parametrize("size", [(1, 1), (640, 90), (33, 700)])
def test_a_resized_camera_equals_a_new_camera_of_that_size(size):
    cam = mb.Camera(mb.look_at((0.3, 1.0, 4.0), (0.0, 0.0, 0.0)), 0.8, 160, 120, znear=0.2, zfar=40.0)
    new = mb.Camera(cam.pose, cam.yfov, *size, znear=cam.znear, zfar=cam.zfar)
    got = cam.resized(*size)
    assert (got.width, got.height, got.aspect) == (new.width, new.height, new.aspect)
    for name in ("pose", "view", "projection", "view_projection"):
        np.testing.assert_array_equal(getattr(got, name), getattr(new, name))
        assert not getattr(got, name).flags.writeable
    assert (cam.width, cam.height) == (160, 120)  # the original is untouched


@pytest.mark.parametrize("size", [(0, 10), (10, -1), (1 << 20, 1 << 20)])
def test_a_resized_camera_checks_its_size(size):
    cam = mb.Camera(np.eye(4), 0.8, 16, 12)
    with pytest.raises(ValueError, match="width|height|pixels"):
        cam.resized(*size)


def test_unsorted_blending_tests_and_writes_depth_like_the_hardware():
    """The 1996 hardware composited in submission order but depth-tested each transparent
    fragment against the depth the earlier ones wrote: a far quad drawn after a near one is
    dropped where they overlap; drawn before it, both show, as in depth order."""
    cam = mb.Camera(mb.look_at((0.0, 0.0, 4.0), (0, 0, 0)), 0.7, 32, 32)
    v, f = quad(1.0)
    near = mb.Draw(v + [0, 0, 0.5], f, (0.9, 0.1, 0.1, 0.5), object_id=1)
    far = mb.Draw(v + [0, 0, -0.5], f, (0.1, 0.1, 0.9, 0.5), object_id=2)
    exact = mb.rasterize(cam, [far, near], blend="exact")
    back_to_front = mb.rasterize(cam, [far, near], blend="unsorted")
    np.testing.assert_array_equal(back_to_front.rgba, exact.rgba)
    front_first = mb.rasterize(cam, [near, far], blend="unsorted")
    alone = mb.rasterize(cam, [near], blend="unsorted")
    centre = (16, 16)
    np.testing.assert_array_equal(front_first.rgba[centre], alone.rgba[centre])
    assert front_first.ids[centre] == 1
    assert np.abs(front_first.rgba[centre] - exact.rgba[centre]).max() > 0.1


def test_camera_project_gives_pixels_and_view_depth():
    """Camera.project: the view axis lands on the image centre at its distance, y grows down, a
    point behind the eye has no pixel, and the bounds agree with the compiled core's."""
    from motionblur import _core
    from motionblur.methods._volume_colors import to_pixels

    cam = mb.Camera(mb.look_at((0.0, 0.0, 5.0), (0.0, 0.0, 0.0)), 0.7, 64, 48)
    xy, depth = cam.project([[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 6.0]])
    np.testing.assert_allclose(xy[0], [32.0, 24.0])
    np.testing.assert_allclose(depth, [5.0, 5.0, -1.0])
    assert xy[1, 1] < 24.0 and np.isnan(xy[2]).all()
    pts = np.random.default_rng(1).normal(0.0, 1.0, (200, 3))
    xy, _ = cam.project(pts)
    b = _core._pixel_bounds(to_pixels(cam), pts)
    np.testing.assert_allclose(b, [*xy.min(axis=0), *xy.max(axis=0)], atol=1e-9)
