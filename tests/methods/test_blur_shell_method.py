"""The blur_shell method against real Mitsuba 3 on the deforming scenes, and against many-sample
accumulation on rigid ones.

Property: blur shells approximate motion blur better than not blurring at all. The error (RMSE
over premultiplied RGBA) of ``render(scene, "blur_shell")`` against the reference must be at most
0.95 of the error of the unblurred frame at mid-shutter (the scene frozen at the shutter's middle,
the best single sharp frame), on 64x48 images, ours at aa = 2. The paper's frame (the mesh opaque
at shutter close, one trail from alpha 1: ``centred=False``) was worse than that sharp frame on
both deforming scenes (320x240 against 256-sample accumulation: bending arm 0.089 vs 0.064,
deforming propeller 0.124 vs 0.077): its ramp from alpha 1 over-covers every motion longer than
the object. The default frame is centred (the mesh at mid-shutter, a trail into the past and one
into the future, each from alpha 1/2): 0.056 and 0.058. A diff image goes to out/test-failures/
on failure.
"""

from __future__ import annotations

import numpy as np
import pytest
from _helpers import pyrender_peer as peer

import motionblur as mb
from motionblur import metrics, reference
from motionblur.methods.blur_shell import shell_times
from motionblur.render import METHODS

W, H = 64, 48


def sharp(scene: mb.Scene, tr: float = 0.5) -> mb.Frame:
    """The unblurred frame: every object frozen at ``tr`` (default mid-shutter), seen by the
    camera then."""
    objs = [
        mb.Object((o.world_vertices(tr), o.mesh.faces), o.color, o.shading, None, o.name)
        for o in scene.objects
    ]
    still = scene.with_(objects=objs, camera=scene.camera_at(tr), camera_motion=None)
    return mb.render(still, "accumulation", samples=1, aa=2)


def _check(name, ours, ref, bound, message):
    e = metrics.rmse(ours, ref)
    if not e <= bound:
        path = peer.write_diff(name, ours.rgba, ref.rgba)
        pytest.fail(f"{message}: rmse {e:.4f} > {bound:.4f}; see {path}")
    return e


@pytest.mark.parametrize("name", ["bending_arm", "deforming_propeller"])
@pytest.mark.mitsuba
def test_blur_shell_beats_the_unblurred_frame_against_mitsuba(name):
    scene = mb.SCENES[name](width=W, height=H)
    assert all(o.motion.is_deforming for o in scene.moving_objects)
    ref = reference.mitsuba(scene, times=32, spp=8)
    base = metrics.rmse(sharp(scene), ref)
    ours = mb.render(scene, "blur_shell", subdivisions=10, aa=2)
    assert ours.stats["shells"] == 2 and ours.stats["shell_triangles"] > 0  # past and future
    _check(
        f"blur_shell_{name}", ours, ref, 0.95 * base, f"{name}: blur_shell no better than the unblurred frame"
    )


@pytest.mark.parametrize("name", ["cube", "airplane", "pan"])
def test_blur_shell_beats_the_unblurred_frame_on_rigid_and_camera_motion(name):
    scene = mb.SCENES[name](width=W, height=H)
    ref = mb.render(scene, "accumulation", samples=128, aa=2)
    base = metrics.rmse(sharp(scene), ref)
    ours = mb.render(scene, "blur_shell", subdivisions=8, aa=2)
    _check(
        f"blur_shell_{name}", ours, ref, 0.98 * base, f"{name}: blur_shell no better than the unblurred frame"
    )


def test_exact_and_nearest_blends_and_speed_line_colour():
    scene = mb.SCENES["bending_arm"](width=W, height=H)
    near = mb.render(scene, "blur_shell", subdivisions=6)
    exact = mb.render(scene, "blur_shell", subdivisions=6, blend="exact")
    still = sharp(scene, near.stats["t"])
    # Both add coverage outside the sharp arm; exact blending compounds overlapping strips, so it
    # is never less opaque than the nearest-surface buffer.
    out = still.coverage < 0.5
    assert near.coverage[out].sum() > 5.0
    assert (exact.coverage >= near.coverage - 1e-5).all()
    assert exact.coverage.sum() > near.coverage.sum()
    red = mb.render(scene, "blur_shell", subdivisions=6, color=(1.0, 0.0, 0.0))
    trail = out & (red.coverage > 0.05)
    assert trail.any()
    assert (red.rgba[trail][:, 1] <= 1e-6).all()  # green: the arm's colour is gone from the trail


def test_a_translucent_objects_trails_carry_its_alpha():
    """Off the sharp mesh the frame is the nearest shell surface alone, whose alpha is the
    covered fraction times the object's: an object of alpha 0.4 leaves trails 0.4x as opaque as
    the same object opaque (float32 products: 1e-6). Before, they were as opaque, and a
    translucent object's blur shell had up to three times the exact frame's alpha mass."""
    base = mb.SCENES["curved"](width=W, height=H).with_(background=(0.0, 0.0, 0.0, 0.0))

    def with_alpha(a):
        objs = [
            mb.Object(
                o.mesh, (*np.asarray(o.color)[:3], a if o.is_moving else 1.0), o.shading, o.motion, o.name
            )
            for o in base.objects
        ]
        return base.with_(objects=objs)

    opaque, clear = (mb.render(with_alpha(a), "blur_shell", error_estimate=False) for a in (1.0, 0.4))
    still = sharp(with_alpha(1.0), opaque.stats["t"])
    trail = (still.coverage == 0) & (opaque.coverage > 0.01)
    assert trail.sum() > 50
    np.testing.assert_allclose(clear.coverage[trail], 0.4 * opaque.coverage[trail], rtol=1e-5, atol=1e-6)
    exact = mb.exact(with_alpha(0.4))
    off = abs(clear.coverage.sum() - exact.coverage.sum()) / exact.coverage.sum()
    assert off <= 1.0, off  # the method's stated alpha-mass bound


def test_shell_times_follow_the_shutter_filter():
    scene = mb.SCENES["bending_arm"](width=W, height=H)
    np.testing.assert_allclose(shell_times(scene, 4), [0.0, 0.25, 0.5, 0.75, 1.0])
    ramp = scene.with_(shutter="ramp")
    t = shell_times(ramp, 8)
    w = ramp.shutter_cdf(t)
    np.testing.assert_allclose(w, np.linspace(0.0, 1.0, 9), atol=2e-3)
    assert t[0] == 0.0 and t[-1] == 1.0 and (np.diff(t) > 0).all()
    center = scene.with_(reference_time="center")
    assert shell_times(center, 4)[-1] == 0.5


def test_registered_with_sweep_and_applies():
    spec = METHODS["blur_shell"]
    assert spec.sweep and all("subdivisions" in s for s in spec.sweep)
    scene = mb.SCENES["bending_arm"](width=W, height=H)
    assert spec.applies(scene)
    static = scene.with_(objects=[mb.Object(o.mesh, o.color) for o in scene.objects])
    assert not spec.applies(static)
    # A static scene renders sharp: no shell.
    f = mb.render(static, "blur_shell")
    assert f.stats["shells"] == 0


@pytest.mark.parametrize(
    "opts, exc, text",
    [
        ({"subdivisions": 0}, ValueError, "subdivisions"),
        ({"hysteresis": -2}, ValueError, "hysteresis"),
        ({"initial_alpha": 2.0}, ValueError, "initial_alpha"),
        ({"color": (1.0, 0.0)}, ValueError, "color"),
        ({"blend": "add"}, ValueError, "blend"),
        ({"aa": 3}, ValueError, "aa"),
    ],
)
def test_bad_options_name_the_argument(opts, exc, text):
    scene = mb.SCENES["bending_arm"](width=W, height=H)
    with pytest.raises(exc, match=text):
        mb.render(scene, "blur_shell", **opts)


def test_blur_shell_frames_do_not_depend_on_the_thread_count():
    import hashlib
    import os
    import subprocess
    import sys

    script = (
        "import hashlib, motionblur as mb\n"
        "for name in ('bending_arm', 'deforming_propeller'):\n"
        "    f = mb.render(mb.SCENES[name](width=64, height=48), 'blur_shell', subdivisions=7, aa=2)\n"
        "    print(name, hashlib.sha256(f.rgba.tobytes() + f.depth.tobytes()).hexdigest())\n"
    )
    out = []
    for n in (1, 2):
        env = dict(os.environ, RAYON_NUM_THREADS=str(n))
        r = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        out.append(r.stdout)
    assert out[0] == out[1] and out[0].count("\n") == 2
    assert hashlib.sha256(b"").hexdigest() not in out[0]
