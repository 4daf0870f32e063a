"""The analytic kernel (`mb.rasterize_motion`) against exact oracles.

A square parallel to the image plane, translating parallel to it, covers a sample for a
closed-form interval of shutter time; a square spinning about the view axis covers it for a
fraction of the turn that a fine numpy sweep gives. Tolerances: 1e-5 where the oracle is a closed
form (float32 times and colours), 2e-3 for the spin (the oracle's own step, 1e-5 of a turn, and
the segments' chords, below 1e-3 px).
"""

from __future__ import annotations

import numpy as np
import pytest
from _helpers.threads import digests, ticks_during

import motionblur as mb

W, H, YFOV, DIST = 48, 36, 0.8, 5.0


def _cam(eye=(0.0, 0.0, DIST), target=(0.0, 0.0, 0.0), offset=(0.0, 0.0, 0.0)):
    o = np.asarray(offset, dtype=np.float64)
    return mb.Camera(mb.look_at(np.add(eye, o), np.add(target, o)), YFOV, W, H, znear=0.5, zfar=50.0)


def grid_square(h: float, n: int):
    """(V,3) points and (F,3) faces of a square of half-size h in z = 0 made of n x n quads."""
    u = np.linspace(-h, h, n + 1)
    xx, yy = np.meshgrid(u, u)
    v = np.stack([xx.ravel(), yy.ravel(), np.zeros(xx.size)], axis=1)
    r = n + 1
    f = []
    for j in range(n):
        for i in range(n):
            a = j * r + i
            f += [[a, a + 1, a + r + 1], [a, a + r + 1, a + r]]
    return v, np.array(f)


def on_plane(shape=(H, W)):
    """World (x, y) on z = 0 seen at each pixel centre of the default camera."""
    t = np.tan(YFOV / 2) * DIST
    iy, ix = np.mgrid[: shape[0], : shape[1]]
    xn = 2 * (ix + 0.5) / shape[1] - 1
    yn = 1 - 2 * (iy + 0.5) / shape[0]
    return xn * t * shape[1] / shape[0], yn * t


def translating(h, n, x0, x1, k=1):
    v, f = grid_square(h, n)
    xs = np.linspace(x0, x1, k + 1)
    pos = np.stack([v + (x, 0, 0) for x in xs])
    return mb.MovingDraw(pos, f, (1, 1, 1)), np.linspace(0, 1, k + 1)


def square_oracle(h, x0, x1, shutter="box"):
    x, y = on_plane()
    a = np.clip((x - h - x0) / (x1 - x0), 0, 1)
    b = np.clip((x + h - x0) / (x1 - x0), 0, 1)
    return np.where(np.abs(y) <= h, mb.shutter_cdf(shutter, b) - mb.shutter_cdf(shutter, a), 0.0)


@pytest.mark.parametrize("shutter", ["box", "triangle", "ramp", "gaussian"])
@pytest.mark.parametrize("n", [1, 6])
def test_a_translating_square_matches_the_closed_form(shutter, n):
    draw, times = translating(0.6, n, -1.5, 1.2)
    cov = mb.coverage(_cam(), [draw], times, shutter=shutter)
    want = square_oracle(0.6, -1.5, 1.2, shutter)
    assert np.abs(cov - want).max() < 1e-5
    assert want.max() > 0.3 and (want > 0).sum() > 200  # the oracle is not trivially empty


def test_motion_far_larger_than_the_screen_and_sub_pixel_motion():
    for x0, x1 in [(-40.0, 60.0), (0.2, 0.2 + 0.3 * 2 * np.tan(YFOV / 2) * DIST / H)]:
        draw, times = translating(0.5, 3, x0, x1)
        cov = mb.coverage(_cam(), [draw], times)
        assert np.abs(cov - square_oracle(0.5, x0, x1)).max() < 1e-5


def test_an_object_leaving_the_view_is_covered_only_while_inside():
    draw, times = translating(0.6, 2, 0.0, 9.0)  # leaves through the right edge
    cov = mb.coverage(_cam(), [draw], times)
    assert np.abs(cov - square_oracle(0.6, 0.0, 9.0)).max() < 1e-5


def test_segments_of_a_straight_motion_change_nothing():
    one = mb.coverage(_cam(), [translating(0.6, 3, -1.5, 1.2, 1)[0]], [0.0, 1.0])
    d, t = translating(0.6, 3, -1.5, 1.2, 7)
    assert np.abs(mb.coverage(_cam(), [d], t) - one).max() < 1e-5


def test_a_square_spinning_about_the_view_axis():
    h, turn, k = 0.9, 0.7, 64
    v, f = grid_square(h, 2)
    angles = np.linspace(0, turn, k + 1)
    rot = [np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]]) for a in angles]
    draw = mb.MovingDraw(np.stack([v @ r.T for r in rot]), f, (1, 1, 1))
    cov = mb.coverage(_cam(), [draw], np.linspace(0, 1, k + 1))
    x, y = on_plane()
    r, phi = np.hypot(x, y), np.arctan2(y, x)
    theta = np.linspace(0, turn, 20001)[:, None, None]
    inside = np.maximum(np.abs(r * np.cos(phi - theta)), np.abs(r * np.sin(phi - theta))) <= h
    want = inside.mean(axis=0)
    assert np.abs(cov - want).max() < 2e-3
    assert ((want > 0.02) & (want < 0.98)).sum() > 100 and want.max() == 1.0  # many partly covered


def test_a_camera_moving_with_the_object_sees_it_sharp():
    v, f = grid_square(0.6, 2)
    shift = np.linspace(0, 2.0, 3)
    draw = mb.MovingDraw(np.stack([v + (s, 0, 0) for s in shift]), f, (1, 1, 1))
    cams = [_cam(offset=(s, 0, 0)) for s in shift]
    cov = mb.coverage(cams, [draw], np.linspace(0, 1, 3))
    still = mb.coverage(_cam(), [mb.MovingDraw(np.stack([v] * 3), f, (1, 1, 1))], np.linspace(0, 1, 3))
    x, y = on_plane()
    want = ((np.abs(x) <= 0.6) & (np.abs(y) <= 0.6)).astype(float)
    assert np.abs(cov - want).max() < 1e-5 and np.abs(still - want).max() < 1e-5


def test_far_from_the_origin_the_image_is_the_same():
    draw, times = translating(0.6, 3, -1.5, 1.2)
    near = mb.coverage(_cam(), [draw], times)
    off = np.array([1e6, -1e6, 1e6])
    moved = mb.MovingDraw(draw.positions + off, draw.faces, (1, 1, 1))
    far = mb.coverage(_cam(offset=off), [moved], times)
    # positions near 1e6 hold about 1e-10 of a unit: far below a sample
    assert np.abs(far - near).max() < 1e-4


def test_crossing_the_near_plane_is_cut_in_time():
    # a big square flying from behind the near plane to behind the camera's back, facing it
    v, f = grid_square(0.4, 1)
    zs = np.linspace(4.8, 5.6, 9)  # the camera sits at z = 5, near plane at z = 4.5
    pos = np.stack([v + (0, 0, z) for z in zs]) * [1, 1, 1]
    draw = mb.MovingDraw(pos, f, (1, 1, 1), cull_back=False)
    times = np.linspace(0, 1, 9)
    cov = mb.coverage(_cam(), [draw], times)
    # while z < 4.5 the square is in front of the near plane: from t = 0 (z = 4.8 > 4.5) it is
    # already inside the near distance, so nothing is ever drawn
    assert cov.max() == 0.0
    zs = np.linspace(2.0, 4.9, 9)
    draw = mb.MovingDraw(np.stack([v + (0, 0, z) for z in zs]), f, (1, 1, 1), cull_back=False)
    cov = mb.coverage(_cam(), [draw], times)
    # the centre pixel is covered until the square passes z = 4.5 (distance 0.5): t = 2.5 / 2.9
    c = cov[H // 2, W // 2]
    assert abs(c - 2.5 / 2.9) < 1e-5


def test_degenerate_triangles_add_nothing_and_break_nothing():
    draw, times = translating(0.6, 2, -1.5, 1.2)
    p = draw.positions
    extra = np.stack([np.array([[0, 0, 0], [1, 1, 0], [2, 2, 0], [3, 3, 3]])] * len(times)).astype(float)
    pos = np.concatenate([p, extra], axis=1)
    nv = p.shape[1]
    bad = np.array([[nv, nv + 1, nv + 2], [nv, nv, nv + 3], [nv + 3, nv + 3, nv + 3]])
    d2 = mb.MovingDraw(pos, np.concatenate([draw.faces, bad]), (1, 1, 1))
    a = mb.coverage(_cam(), [draw], times)
    b = mb.coverage(_cam(), [d2], times)
    assert np.array_equal(a, b)


def test_bad_input_names_the_argument():
    draw, times = translating(0.6, 1, -1.5, 1.2)
    cam = _cam()
    cases = [
        (dict(times=[0.0, 0.5]), "times"),
        (dict(times=[0.0, 1.0, 1.0]), "draws|times"),
        (dict(gauss=9), "gauss"),
        (dict(gauss="many"), "gauss"),
        (dict(shutter="boxy"), "shutter"),
        (dict(shutter=[1.0, -1.0]), "shutter"),
        (dict(samples=3), "samples"),
        (dict(reference_time=2.0), "reference_time"),
        (dict(cameras=[cam, cam, cam]), "cameras"),
    ]
    for change, name in cases:
        args = dict(cameras=cam, draws=[draw], times=times)
        args.update(change)
        with pytest.raises((ValueError, TypeError), match=name):
            mb.rasterize_motion(**args)
    with pytest.raises(ValueError, match="positions"):
        mb.MovingDraw(np.full((2, 3, 3), np.nan), [[0, 1, 2]])
    with pytest.raises(ValueError, match="faces"):
        mb.MovingDraw(np.zeros((2, 3, 3)), [[0, 1, 5]])
    with pytest.raises(TypeError, match="draws"):
        mb.rasterize_motion(cam, ["not a draw"], times)


def test_the_callers_arrays_are_left_alone():
    v, f = grid_square(0.6, 2)
    pos = np.stack([v, v + (1, 0, 0)])
    keep = pos.copy(), f.copy()
    mb.rasterize_motion(_cam(), [mb.MovingDraw(pos, f, (1, 0, 0))], [0.0, 1.0], samples=2)
    assert np.array_equal(pos, keep[0]) and np.array_equal(f, keep[1])
    # the draw keeps read-only views: the caller's own float64 / int64 arrays stay writable
    f = np.ascontiguousarray(f, dtype=np.int64)
    draw = mb.MovingDraw(pos, f, np.ones((pos.shape[1], 4), np.float32))
    assert pos.flags.writeable and f.flags.writeable and not draw.positions.flags.writeable


def test_the_result_does_not_depend_on_the_thread_count():
    script = """
import hashlib, numpy as np, motionblur as mb
from core.test_analytic_kernel import translating, _cam
d, t = translating(0.6, 8, -1.5, 1.2, 3)
fr = mb.rasterize_motion(_cam(), [d], t, samples=2, shutter="gaussian")
print(hashlib.sha256(b"".join(a.tobytes() for a in (fr.rgba, fr.depth, fr.ids, fr.velocity))).hexdigest())
"""
    out = digests(script)
    assert len(set(out)) == 1, out


def test_the_gil_is_released():
    v, f = grid_square(0.6, 40)
    draw = mb.MovingDraw(np.stack([v, v + (2, 0, 0)]), f, (1, 1, 1))
    cam = mb.Camera(mb.look_at((0, 0, DIST), (0, 0, 0)), YFOV, 320, 240)
    assert ticks_during(lambda: mb.rasterize_motion(cam, [draw], [0.0, 1.0], samples=2)) > 3


def stacked(n: int):
    """One draw of n translucent quads, each wider than the view, stacked 0.02 apart in depth and
    translating by its own amount: every sample is covered by most of them at once."""
    v, f = grid_square(1.8, 1)
    pos, faces, rgba = [], [], []
    for i in range(n):
        z = (0, 0, -0.02 * i)
        pos.append(np.stack([v + (-0.6 + 0.01 * i, 0, 0) + z, v + (0.7 - 0.015 * i, 0.1, 0) + z]))
        faces.append(f + 4 * i)
        rgba.append(np.tile([(i % 3) / 2, (i % 5) / 4, (i % 7) / 6, 0.08], (4, 1)))
    return mb.MovingDraw(np.concatenate(pos, axis=1), np.concatenate(faces), np.concatenate(rgba))


def test_a_small_memory_budget_changes_no_bit_and_a_too_small_one_raises(monkeypatch):
    draw, args = stacked(40), dict(times=[0.0, 1.0], samples=1, shutter="triangle")
    whole = mb.rasterize_motion(_cam(), [draw], **args)
    assert whole.stats["splits"] == 0 and whole.stats["intervals"] > 20 * W * H
    splits = []
    for budget in (1 << 20, 1 << 17):
        monkeypatch.setattr(mb.analytic, "TILE_BUDGET_BYTES", budget)
        part = mb.rasterize_motion(_cam(), [draw], **args)
        for a, b in zip((part.rgba, part.depth, part.ids, part.velocity),
                        (whole.rgba, whole.depth, whole.ids, whole.velocity)):  # fmt: skip
            assert np.array_equal(a, b)
        for key in ("intervals", "pieces"):
            assert part.stats[key] == whole.stats[key], key
        splits.append(part.stats["splits"])
    assert 0 < splits[0] < splits[1], splits
    # one sample under 40 layers needs more than 4 KiB: a MemoryError naming it, and the session
    # goes on
    monkeypatch.setattr(mb.analytic, "TILE_BUDGET_BYTES", 4096)
    with pytest.raises(MemoryError, match=r"draws: sample \(\d+, \d+\) \(pixel .*TILE_BUDGET_BYTES"):
        mb.rasterize_motion(_cam(), [draw], **args)
    for bad, exc in ((0, ValueError), (1.5, TypeError)):
        monkeypatch.setattr(mb.analytic, "TILE_BUDGET_BYTES", bad)
        with pytest.raises(exc, match="TILE_BUDGET_BYTES"):
            mb.rasterize_motion(_cam(), [draw], **args)
    monkeypatch.undo()
    again = mb.rasterize_motion(_cam(), [draw], **args)
    assert np.array_equal(again.rgba, whole.rgba)
