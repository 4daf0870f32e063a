"""The compiled resolve of a supersampled layer (methods._layers: resolve_arrays, paste) against numpy."""

from __future__ import annotations

import numpy as np
import pytest

from motionblur import _core
from motionblur.methods._layers import Layer, resolve_arrays


def _numpy_resolve(layer: Layer, s: int):
    h, w = layer.depth.shape[0] // s, layer.depth.shape[1] // s
    rgba = layer.rgba.reshape(h, s, w, s, 4).astype(np.float64).mean(axis=(1, 3))
    d = layer.depth.reshape(h, s, w, s).transpose(0, 2, 1, 3).reshape(h, w, s * s)
    k = d.argmin(axis=2)[..., None]  # the first nearest sample in row order
    i = layer.ids.reshape(h, s, w, s).transpose(0, 2, 1, 3).reshape(h, w, s * s)
    return rgba, np.take_along_axis(d, k, 2)[..., 0], np.take_along_axis(i, k, 2)[..., 0]


@pytest.mark.parametrize("s", [2, 4])
def test_resolve_matches_numpy_with_ties_and_empty_samples(s):
    rng = np.random.default_rng(s)
    h, w = 7 * s, 5 * s
    depth = rng.integers(0, 3, (h, w)).astype(np.float32)  # many ties
    depth[rng.random((h, w)) < 0.3] = np.inf
    layer = Layer(
        rng.random((h, w, 4), dtype=np.float32), depth, rng.integers(-1, 9, (h, w)).astype(np.int32)
    )
    copies = [a.copy() for a in (layer.rgba, layer.depth, layer.ids)]
    rgba, d, i = resolve_arrays(layer, s)
    want = _numpy_resolve(layer, s)
    np.testing.assert_allclose(rgba, want[0], rtol=1e-6, atol=1e-7)
    np.testing.assert_array_equal(d, want[1])
    np.testing.assert_array_equal(i, want[2])
    for a, c in zip((layer.rgba, layer.depth, layer.ids), copies):
        np.testing.assert_array_equal(a, c)
    # into a rectangle of a larger buffer: the rest untouched
    out = (
        np.full((20, 30, 4), 7, np.float32),
        np.full((20, 30), 7, np.float32),
        np.full((20, 30), 7, np.int32),
    )
    _core._resolve(layer, s, Layer(*out), (3, 4))
    np.testing.assert_array_equal(out[2][4:11, 3:8], want[2])
    assert (out[2][:4] == 7).all() and (out[2][:, :3] == 7).all() and (out[0][11:] == 7).all()
    with pytest.raises(ValueError, match="rectangle"):
        _core._resolve(layer, s, Layer(*out), (27, 0))
    with pytest.raises(ValueError, match="samples"):
        _core._resolve(Layer(layer.rgba[:, :-1], layer.depth[:, :-1], layer.ids[:, :-1]), s, Layer(*out))
