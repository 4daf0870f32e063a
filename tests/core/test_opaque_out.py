"""``motionblur.image.opaque_motion_blur(..., out=)``: the blur written into a caller's array gives
the bits of the new array it otherwise returns, on every path of the kernel (along rows, oblique
and vertical through the sheared crop, no blur at all), both composites, with and without a
base; every element of ``out`` is overwritten; bad ``out`` arrays are named, the inputs never
written."""

from __future__ import annotations

import numpy as np
import pytest

import motionblur.image as mi


def _img(seed: int, h: int = 37, w: int = 53) -> np.ndarray:
    rng = np.random.default_rng(seed)
    a = rng.random((h, w, 1), dtype=np.float32)
    a[rng.random((h, w)) < 0.3] = 0.0
    return np.concatenate([rng.random((h, w, 3), dtype=np.float32) * a, a], -1)


@pytest.mark.parametrize("direction", [(1.0, 0.0), (1.0, 0.4), (0.2, 1.0), (-1.0, 0.0)])
@pytest.mark.parametrize("mode", ["over", "under"])
@pytest.mark.parametrize("with_base", [False, True])
@pytest.mark.parametrize("length", [0.0, 9.0])
def test_out_gives_the_new_arrays_bits(direction, mode, with_base, length):
    rgba, base = _img(1), _img(2)
    kept = rgba.copy(), base.copy()
    b = base if with_base else None
    want = mi.opaque_motion_blur(rgba, direction, length, mode=mode, base=b)
    out = np.full_like(rgba, np.nan)
    got = mi.opaque_motion_blur(rgba, direction, length, mode=mode, base=b, out=out)
    assert got is out
    assert np.array_equal(out.view(np.uint32), want.view(np.uint32))
    assert np.array_equal(rgba, kept[0]) and np.array_equal(base, kept[1])


def test_a_frame_sized_out_gives_the_same_bits():
    # large enough for the kernel's non-temporal stores and the row pairs in AVX2
    rgba = _img(3, 300, 700)
    rgba[..., 3] = 1.0
    rgba[..., :3] = np.clip(rgba[..., :3], 0.0, 1.0)
    want = mi.opaque_motion_blur(rgba, (1, 0), 101, "over", rgba.copy())
    out = np.empty_like(rgba)
    mi.opaque_motion_blur(rgba, (1, 0), 101, "over", rgba.copy(), out=out)
    assert np.array_equal(out.view(np.uint32), want.view(np.uint32))


def test_bad_out_is_named():
    rgba, base = _img(1), _img(2)
    kept = rgba.copy()
    for bad, kind in [
        (np.zeros((37, 53, 4), np.float64), ValueError),
        (np.zeros((37, 52, 4), np.float32), ValueError),
        (np.zeros((53, 37, 4), np.float32).transpose(1, 0, 2), ValueError),
        (rgba, ValueError),
        (rgba[:, :, :], ValueError),
        (base, ValueError),
        ([[0.0]], TypeError),
    ]:
        with pytest.raises(kind, match="out"):
            mi.opaque_motion_blur(rgba, (1, 0), 5, base=base, out=bad)
    readonly = np.zeros_like(rgba)
    readonly.flags.writeable = False
    with pytest.raises(ValueError, match="out"):
        mi.opaque_motion_blur(rgba, (1, 0), 5, out=readonly)
    assert np.array_equal(rgba, kept)


def test_the_core_refuses_an_out_sharing_memory_by_name():
    # past the Python checks: the core's read-write borrow of out fails while rgba is borrowed
    from motionblur import _core

    rgba = _img(4)
    with pytest.raises(ValueError, match="out"):
        _core._opaque_motion_blur(rgba, None, (1.0, 0.0), 5.0, "over", rgba)
    with pytest.raises(ValueError, match="out"):
        _core._opaque_motion_blur(rgba, None, (1.0, 0.0), 5.0, "over", np.zeros((2, 2, 4), np.float32))
