"""benches/bench_raster.py times the pyrender frame it means to: the bench's own scene, with the
bench's camera (``Camera``'s default ``zfar=inf``), covers the pixels our frame covers, opaque and
transparent. Passing ``zfar=inf`` to pyrender gave a NaN projection that drew nothing in a few
milliseconds, which the bench timed as pyrender's frame (issue 17: the ratios at 82k-328k faces
went from 0.4 to 1-2 with our times unchanged)."""

from __future__ import annotations

import runpy
from pathlib import Path

import numpy as np
import pytest
from _helpers import pyrender_peer  # noqa: F401  (OSMesa chosen before pyrender is imported)

import motionblur as mb
from motionblur import meshes

pytestmark = pytest.mark.pyrender

BENCH = Path(__file__).resolve().parents[2] / "benches" / "bench_raster.py"


@pytest.mark.parametrize("alpha", [1.0, 0.5])
def test_the_bench_peer_draws_our_pixels(alpha):
    import pyrender

    bench = runpy.run_path(str(BENCH), run_name="bench_loaded")
    w, h = bench["W"], bench["H"]
    camera = mb.Camera(mb.look_at((0.3, 0.4, 3.2), (0, 0, 0)), np.pi / 3, w, h)
    assert camera.zfar == np.inf  # the default the bench uses
    v, f = meshes.icosphere(3)
    rgba = (0.8, 0.5, 0.2, alpha)
    frame = mb.rasterize(camera, mb.Draw(v, f, rgba, cull_back=alpha == 1.0), blend="exact")
    renderer = pyrender.OffscreenRenderer(w, h)
    try:
        depth = renderer.render(
            bench["pyrender_scene"](v, f, rgba, camera, blend=alpha < 1.0), flags=pyrender.RenderFlags.FLAT
        )[1]
    finally:
        renderer.delete()
    assert (depth > 0).sum() > 0.1 * w * h
    bench["check_same_coverage"](frame, depth, "test")  # raises when they differ by > 1%
    with pytest.raises(RuntimeError, match="not the same image"):
        bench["check_same_coverage"](frame, np.zeros_like(depth), "test")
