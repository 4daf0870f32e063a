"""The rasterizer against real pyrender (offscreen OSMesa, FLAT): projection, depth, coverage, colour.

Tolerances (the issue's): depth within 1e-4 relative on pixels both cover, away from the
one-pixel silhouette band, where a grazing surface's depth changes by more than that within a
fraction of a pixel and Mesa's sub-pixel snapping differs from ours; coverage IoU >= 0.995 with
every disagreement inside the one-pixel silhouette band; FLAT colours within 1/255 (plus pyrender's
8-bit rounding) inside. A diff image goes to out/test-failures/ on failure.
"""

from __future__ import annotations

import numpy as np
import pyrender
import pytest
from _helpers import pyrender_peer as peer
from scipy import ndimage

import motionblur as mb
from motionblur import meshes

pytestmark = pytest.mark.pyrender  # every test here renders with pyrender


def _random_mesh(seed=3, n=40):
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-0.8, 0.8, (n, 1, 3))
    v = (centres + rng.normal(0, 0.35, (n, 3, 3))).reshape(-1, 3)
    return v, np.arange(3 * n).reshape(n, 3)


def _rotated_box():
    v, f = meshes.box((1.0, 1.5, 0.8))
    c, s = np.cos(0.6), np.sin(0.6)
    rot = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return v @ rot.T, f


CASES = {
    # name: (mesh, eye, yfov, znear, zfar, width, height, double_sided)
    "sphere": (meshes.icosphere(3), (0.5, 0.3, 3.0), 0.8, 0.5, 20.0, 160, 120, False),
    "sphere-wide": (meshes.icosphere(2), (-2.0, 1.0, 1.2), 1.4, 1.0, 8.0, 120, 90, False),
    "box": (_rotated_box(), (2.0, 1.5, 2.5), 0.6, 1.0, 10.0, 128, 96, False),
    "torus": (meshes.torus(), (0.0, 2.5, 2.0), 1.0, 1.0, 6.0, 120, 120, False),
    "random": (_random_mesh(), (0.3, -0.4, 3.5), 0.9, 1.5, 7.0, 140, 100, True),
}


def _compare(name, camera, v, f, rgba, double_sided, depth_rtol=1e-4):
    ours = mb.rasterize(camera, mb.Draw(v, f, rgba, cull_back=not double_sided))
    rgb, depth = peer.render([(v, f, rgba, double_sided)], camera)
    theirs = depth > 0
    mine = np.isfinite(ours.depth)
    assert (mine == (ours.ids >= 0)).all()
    union = (theirs | mine).sum()
    iou = (theirs & mine).sum() / union
    band = ndimage.binary_dilation(theirs) & ~ndimage.binary_erosion(theirs)
    inside = ndimage.binary_erosion(theirs & mine)
    both = theirs & mine
    rel = np.zeros(depth.shape)
    rel[both] = np.abs(ours.depth[both] - depth[both]) / depth[both]
    colour_err = np.abs(ours.rgba[..., :3] - rgb).max(axis=-1)
    ok = (
        iou >= 0.995
        and not ((theirs != mine) & ~band).any()
        and rel[inside].max() <= depth_rtol
        and colour_err[inside].max() <= 1.0 / 255.0 + 1e-6
    )
    if not ok:
        scale = max(depth.max(), 1e-9)
        path = peer.write_diff(f"raster-{name}-depth", np.where(mine, ours.depth, 0) / scale, depth / scale)
        peer.write_diff(f"raster-{name}-colour", ours.rgba, rgb)
        pytest.fail(
            f"{name}: IoU {iou:.5f}, {((theirs != mine) & ~band).sum()} coverage differences off the band, "
            f"depth rel {rel[inside].max():.2e}, colour {colour_err[inside].max() * 255:.2f}/255; see {path}"
        )
    return ours, iou


@pytest.mark.parametrize("name", list(CASES))
def test_depth_coverage_and_colour_match_pyrender(name):
    (v, f), eye, yfov, znear, zfar, w, h, double_sided = CASES[name]
    cam = mb.Camera(mb.look_at(eye, (0.0, 0.0, 0.0)), yfov, w, h, znear=znear, zfar=zfar)
    ours, iou = _compare(name, cam, v, f, (0.8, 0.4, 0.2, 1.0), double_sided)
    assert ours.coverage.sum() > 0.05 * w * h, "the scene must actually fill part of the image"


def test_projection_equals_pyrenders():
    for yfov, w, h, n, far in [
        (0.8, 160, 120, 0.05, 100.0),
        (1.3, 64, 200, 0.5, 7.0),
        (0.3, 1, 1, 1e-3, 1e4),
    ]:
        cam = mb.Camera(np.eye(4), yfov, w, h, znear=n, zfar=far)
        want = pyrender.PerspectiveCamera(yfov, znear=n, zfar=far, aspectRatio=w / h).get_projection_matrix(
            w, h
        )
        np.testing.assert_array_equal(cam.projection, want)
    cam = mb.Camera(np.eye(4), 0.8, 100, 50, znear=0.1, zfar=np.inf)
    want = pyrender.PerspectiveCamera(0.8, znear=0.1, zfar=None, aspectRatio=2.0).get_projection_matrix(
        100, 50
    )
    np.testing.assert_array_equal(cam.projection, want)


def test_a_floor_crossing_the_near_plane_matches_pyrender():
    """Hard case: triangles with vertices behind the camera are clipped the way OpenGL clips them."""
    v = np.array([[-30.0, -1.0, 30.0], [30.0, -1.0, 30.0], [30.0, -1.0, -30.0], [-30.0, -1.0, -30.0]])
    f = np.array([[0, 1, 2], [0, 2, 3]])
    pose = mb.look_at((0.0, 0.0, 0.0), (0.0, -0.3, -1.0))
    cam = mb.Camera(pose, 1.0, 128, 96, znear=0.5, zfar=50.0)
    ours, _ = _compare("floor", cam, v, f, (0.3, 0.7, 0.5, 1.0), False)
    assert ours.stats["clipped"] >= 1
    # The floor fills the lower part of the image up to the (clipped) far plane.
    assert np.isfinite(ours.depth[-1]).all()


def test_transparent_overlap_matches_pyrender_blending():
    """Two alpha-0.5 quads: pyrender sorts meshes by origin (back to front), as exact blending does."""
    quad = np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]])
    f = np.array([[0, 1, 2], [0, 2, 3]])
    near_offset, far_offset = np.array([0.3, 0.2, 0.5]), np.array([0.0, 0.0, -0.5])
    near, far = quad * [0.6, 0.6, 1] + near_offset, quad + far_offset
    pose = np.eye(4)
    cam = mb.Camera(mb.look_at((0.0, 0.0, 4.0), (0, 0, 0)), 0.7, 96, 96, znear=1.0, zfar=10.0)
    a, b = (0.2, 0.4, 0.9, 0.5), (0.9, 0.6, 0.1, 0.5)
    ours = mb.rasterize(cam, [mb.Draw(near, f, a), mb.Draw(far, f, b)], blend="exact")
    at = [pose.copy(), pose.copy()]
    at[0][:3, 3], at[1][:3, 3] = near_offset, far_offset
    meshes_at = [(near - near_offset, f, a, False, at[0]), (far - far_offset, f, b, False, at[1])]
    rgb, depth = peer.render(meshes_at, cam, alpha_mode="BLEND")
    inside = ndimage.binary_erosion(depth > 0, iterations=2)
    err = np.abs(ours.rgba[..., :3] - rgb).max(axis=-1)[inside]
    assert err.max() <= 1.5 / 255.0, f"blended colour differs by {err.max() * 255:.2f}/255"
