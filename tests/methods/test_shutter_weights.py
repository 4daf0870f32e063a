"""Custom shutter weights are honoured or refused, never replaced silently (every method).

A scene whose shutter is weights ``[0, 0, 1, 1]`` (all the exposure in the second half) is
rendered by every registered method on a scene it applies to. A method either gives a frame
different from the box shutter's (it integrates the weights) or raises ValueError naming
``shutter``; none may render the box frame. The motion volume's coverage model integrates the
named filters only: it refuses weights unless ``filter=`` chooses one, and its stats name the
filter it used.
"""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur.render import METHODS

WEIGHTS = [0.0, 0.0, 1.0, 1.0]


def _scene_for(method):
    for name in ("cube", "pan"):
        sc = mb.SCENES[name](64, 48)
        if METHODS[method].applies(sc):
            return sc
    raise AssertionError(f"no built-in scene for {method}")


@pytest.mark.parametrize("method", sorted(METHODS))
def test_weights_are_honoured_or_refused(method):
    sc = _scene_for(method)
    box = mb.render(sc, method)
    try:
        weighted = mb.render(sc.with_(shutter=WEIGHTS), method)
    except ValueError as e:
        assert "shutter" in str(e), e
        return
    assert not np.array_equal(weighted.rgba, box.rgba), f"{method} rendered the box shutter"
    assert weighted.stats.get("filter", "weights") != "box"


def test_motion_volume_refuses_weights_and_names_a_chosen_filter():
    sc = mb.SCENES["cube"](64, 48).with_(shutter=WEIGHTS)
    with pytest.raises(ValueError, match="shutter"):
        mb.render(sc, "motion_volume")
    f = mb.render(sc, "motion_volume", filter="triangle")
    assert f.stats["filter"] == "triangle"


def test_equal_weights_are_a_box_for_the_image_space_methods():
    sc = mb.SCENES["cube"](64, 48)
    for method in ("opaque_image", "velocity"):
        a = mb.render(sc, method)
        b = mb.render(sc.with_(shutter=[1.0, 1.0, 1.0]), method)
        np.testing.assert_array_equal(a.rgba, b.rgba)
