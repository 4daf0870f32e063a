"""The kernels' vector forms (AVX2, detected at run time) against their plain forms: the same bits
for the rasterizer (opaque, transparent, with and without velocity, 1 and 2 samples a side), the
opaque image blur at any angle (the rows path, the transposed and the sheared paths, every
composite) and the analytic method. ``_core._set_simd(False)`` forces the plain forms, as the
environment variable ``MOTIONBLUR_SIMD=0`` does from the first call."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

import motionblur as mb
import motionblur.image as mi
from motionblur import _core, meshes


def _both(render):
    """``render()`` with the vector forms allowed and forbidden (the switch restored after)."""
    before = _core._set_simd(True)
    try:
        vector = render()
        _core._set_simd(False)
        assert not _core._simd_enabled()
        plain = render()
    finally:
        _core._set_simd(before)
    return vector, plain


def _same_bits(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b):
        x, y = np.ascontiguousarray(x), np.ascontiguousarray(y)
        assert x.dtype == y.dtype and x.shape == y.shape
        assert x.tobytes() == y.tobytes()


def _image(h, w, seed, opaque):
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:h, 0:w]
    if opaque:
        a = np.ones((h, w))
    else:
        a = np.clip(0.3 * min(h, w) - np.hypot(x - 0.4 * w, y - 0.6 * h), 0, 1) * rng.uniform(0.5, 1, (h, w))
    c = rng.random((h, w, 3))
    return np.concatenate([c * a[..., None], a[..., None]], -1).astype(np.float32)


@pytest.mark.parametrize("opaque", [True, False])
def test_opaque_blur_is_the_same_in_both_forms(opaque):
    img = _image(61, 97, 1, opaque)
    base = _image(61, 97, 2, True) * np.float32(0.8)

    def render():
        out = []
        for d in [(1, 0), (-1, 0), (0, 1), (1, 0.577), (1, -0.3), (0.4, -1), (0.2, 1)]:
            for length in (3, 20, 101):
                out.append(mi.opaque_blur(img, d, length))
                for mode in ("over", "under"):
                    out.append(mi.opaque_motion_blur(img, d, length, mode=mode, base=base))
                out.append(mi.box_blur(img, d, length))
        return out

    _same_bits(*_both(render))


def test_rasterizer_is_the_same_in_both_forms():
    v, f = meshes.icosphere(3)
    moving = [
        mb.Draw(v, f, (0.8, 0.4, 0.2, 0.5), cull_back=False, previous_vertices=v * 1.05, object_id=3),
        mb.Draw(*meshes.torus(), (0.2, 0.4, 0.8, 1.0), object_id=4),
    ]
    still = [
        mb.Draw(v, f, (0.8, 0.4, 0.2, 0.5), cull_back=False),
        mb.Draw(*meshes.torus(), (0.2, 0.4, 0.8, 1.0)),
    ]
    cam = mb.Camera(mb.look_at((0.5, 0.6, 3.0), (0, 0, 0)), 0.9, 123, 77)

    def render():
        out = []
        for draws in (moving, still):
            for samples in (1, 2):
                fr = mb.rasterize(cam, draws, samples=samples, shading="lambert", lights=[((0, -1, -1), 1.0)])
                out += [fr.rgba, fr.depth, fr.ids, fr.velocity]
        return out

    _same_bits(*_both(render))


def test_analytic_method_is_the_same_in_both_forms():
    v, f = meshes.icosphere(2)
    draw = mb.MovingDraw(np.stack([v - (0.8, 0, 0), v + (0.8, 0.2, 0)]), f, (0.9, 0.5, 0.2))
    cam = mb.Camera(mb.look_at((0, 0, 4.0), (0, 0, 0)), 0.8, 64, 48)

    def render():
        fr = mb.rasterize_motion(cam, [draw], [0.0, 1.0], samples=2)
        return [fr.rgba, fr.depth, fr.ids, fr.velocity]

    _same_bits(*_both(render))


def test_the_environment_switches_the_vector_forms_off():
    script = "from motionblur import _core; print(_core._simd_enabled())"
    env = dict(os.environ, MOTIONBLUR_SIMD="0")
    r = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "False"
