"""Differential test: every method against the exact time integral on random scenes nobody picked.

Hypothesis draws seeds of the *measuring* set of :mod:`motionblur.evaluation.random_scenes`
(meshes from the shipped procedural pool and held-out ones, rigid motions with full turns about
arbitrary axes, motion toward the camera, camera motion, five-key paths, deforming meshes, other
shutters, translucent objects) and renders each with every method that applies, at its default
options. Each frame must be finite, carry an error estimate, have its alpha mass within the
method's bound of the exact frame's, and be no farther from the exact frame than the method's
bound times the unblurred frame's distance (the sharp frame at mid-shutter; every bound is at
most 2: a blur worse than twice no blur at all is a wrong frame). A method may refuse a motion it
cannot model, with a ValueError that names the methods to use instead, and a frame clearly worse
than no blur must come with a :class:`motionblur.PoorBlurWarning`. ``auto`` must stay within 1.5x
its tolerance on every scene (and meets it on at least 95%: the README's measured table). ``make test`` runs a few examples (profile ``ci``), ``make fuzz`` many.

The bounds were read off the tuning seeds 0..29 at 64x48 (the worst seen, rounded up), except
the blur shell's alpha mass and the motion volume's bounds. The blur shell draws the object
opaque at mid-shutter with its two trails, so where the motion is much longer than the object
it adds about a quarter of the swept area beyond it: measuring seed 1,025,577 found +63% (with a
translucent object, whose trails then ignored its alpha), and tuning seeds 0..299 show up to
+95% with the trails fixed, so its mass bound is 100%. The motion volume's: tuning showed 0.75 and 3% of alpha mass, but measuring seeds found 1.6x the
unblurred frame's error under the paper's ramp shutter (with its PoorBlurWarning) and +22% mass
on a concave gear under camera motion (the convex outline), so it keeps the issue's general
bound. The README lists them beside each method.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

import motionblur as mb
from motionblur.evaluation.random_scenes import MEASURING_SEEDS, random_scene

pytestmark = pytest.mark.robustness

#: method -> (RMSE over the unblurred frame's RMSE, |alpha mass - exact's| / exact's), both
#: against mb.exact. Read off the tuning seeds; the README states them.
BOUNDS = {
    "accumulation": (0.5, 0.05),
    "analytic": (0.1, 0.01),
    "velocity": (1.3, 0.3),
    "opaque_image": (1.3, 0.3),
    "camera_velocity": (1.0, 0.1),
    "blur_shell": (2.0, 1.0),
    "motion_volume": (2.0, 0.6),
}
#: A frame this many times farther from the exact one than the unblurred frame must come with a
#: PoorBlurWarning (the estimates it is judged by are within 2x; 1.5 leaves room for that).
POOR = 1.5
#: RMSE under which a frame counts as exact whatever the ratio (float32 sums of a still scene).
FLOOR = 1e-4
W, H = 64, 48


def _rmse(a, b) -> float:
    return float(np.sqrt(np.mean(np.square(np.asarray(a, np.float64) - b))))


def test_every_registered_method_has_a_bound():
    assert set(BOUNDS) == set(mb.METHODS) - {"auto"}


@given(seed=st.integers(MEASURING_SEEDS.start, MEASURING_SEEDS.stop - 1))
@example(seed=1_025_577)  # a translucent cylinder's blur shell: trails as opaque as an opaque one's
def test_every_method_against_the_exact_integral_on_random_scenes(seed):
    scene = random_scene(seed, W, H)
    exact = mb.exact(scene).rgba.astype(np.float64)
    sharp = mb.render(scene, "accumulation", samples=1, error_estimate=False).rgba
    no_blur = _rmse(sharp, exact)
    mass = float(exact[..., 3].sum())
    for method, (ratio, mass_bound) in BOUNDS.items():
        if not mb.METHODS[method].applies(scene):
            continue
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                frame = mb.render(scene, method)
        except ValueError as exc:  # a refusal must say what to use instead
            assert "analytic" in str(exc) or "accumulation" in str(exc), (seed, method, exc)
            continue
        said = any(issubclass(w.category, mb.PoorBlurWarning) for w in caught)
        rgba = frame.rgba
        assert np.isfinite(rgba).all(), (seed, method)
        assert np.isfinite(frame.stats["error_estimate"]), (seed, method)
        err = _rmse(rgba, exact)
        assert err <= max(ratio * no_blur, FLOOR), (seed, method, err, no_blur)
        # a blur clearly worse than none says so (the pilot's estimate is within 2x)
        assert said or err <= max(POOR * no_blur, FLOOR), (seed, method, err, no_blur)
        off = abs(float(rgba[..., 3].sum()) - mass) / max(mass, 0.01 * W * H)
        assert off <= mass_bound, (seed, method, off)
    for tol in (0.01, 0.003):
        frame = mb.render(scene, "auto", tolerance=tol)
        # never above 1.5x on any frame; the share at or under the tolerance (95% asked) is the
        # README's table over many scenes, a property of a distribution, not of one example
        assert _rmse(frame.rgba, exact) <= tol * 1.5, (seed, tol, frame.stats["plan"])
