"""mb.Renderer: what the methods keep between frames lives on an object the caller holds; mb.render
uses the default one; clear() empties it; nothing of it is a module-level store."""

from __future__ import annotations

import gc
import subprocess
import sys

import numpy as np

import motionblur as mb
from motionblur.renderer import current_renderer, default_renderer


def _still_camera_scene():
    return mb.SCENES["cube"](64, 48)


def test_a_renderer_renders_what_render_does_and_keeps_its_own_stores():
    scene = _still_camera_scene()
    r = mb.Renderer()
    for method, options in [("accumulation", {"samples": 4}), ("motion_volume", {}), ("blur_shell", {})]:
        want = mb.render(scene, method, **options)
        got = r.render(scene, method, **options)
        np.testing.assert_array_equal(got.rgba, want.rgba)
        assert set(got.stats) == set(want.stats)
    again = r.render(scene, "motion_volume")
    assert again.stats["static_cached"] is True  # the second frame reuses the static layer
    assert len(r.static_layers) >= 1 and len(r.painters) >= 1 and len(r.shells) >= 1
    assert r is not default_renderer() and current_renderer() is default_renderer()
    r.clear()
    assert (len(r.static_layers), len(r.painters), len(r.shells), len(r.mesh_constants)) == (0, 0, 0, 0)
    assert r.render(scene, "motion_volume").stats["static_cached"] is False
    assert "Renderer(" in repr(r)


def test_a_reused_identity_never_finds_another_objects_entry():
    """The stores key on identities; an object collected and a new one made at the same address
    must render as itself (every entry holds, or weakly checks, what its key names)."""
    cam = mb.Camera(mb.look_at((0.0, 0.0, 4.0), (0.0, 0.0, 0.0)), 0.7, 48, 36)
    r = mb.Renderer()
    move = mb.Motion.linear(mb.translate((-0.4, 0, 0)), mb.translate((0.4, 0, 0)))
    for k in range(6):
        v, f = mb.meshes.icosphere(1, 0.2 + 0.1 * k)
        scene = mb.Scene(
            [mb.Object((v, f), (0.9, 0.3, 0.1), "lambert", move)], cam, [mb.DirectionalLight((0, 0, -1))]
        )
        got = r.render(scene, "accumulation", samples=4).rgba
        fresh = mb.Renderer().render(scene, "accumulation", samples=4).rgba
        np.testing.assert_array_equal(got, fresh)
        del scene
        gc.collect()


def test_no_module_level_render_store_and_no_import_side_effect():
    code = (
        "import os, sys; before = dict(os.environ); import motionblur as mb; "
        "s = mb.SCENES['cube'](32, 24); mb.render(s, 'motion_volume'); "
        "print(dict(os.environ) == before, 'motionblur._malloc' in sys.modules)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.split()
    assert out == ["True", "False"]
    from motionblur.methods import _layers, _painter, blur_shell, motion_volume

    for module in (_layers, _painter, blur_shell, motion_volume):
        stores = [
            n for n, v in vars(module).items() if isinstance(v, dict) and n.startswith("_") and n.isupper()
        ]
        assert stores == [], f"{module.__name__}: {stores}"
