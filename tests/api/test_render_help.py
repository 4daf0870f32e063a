"""``help(motionblur.render)`` lists every method's options with defaults and units, built from
the methods' own docstrings, and asking for a method that does not apply to the scene warns."""

from __future__ import annotations

import dataclasses
import inspect
import pydoc
import warnings
from collections.abc import Mapping

import pytest

import motionblur as mb
from motionblur.render import METHODS, _options_paragraph, _parameters


def _options(name: str) -> Mapping[str, inspect.Parameter]:
    return _parameters(METHODS[name].fn)


def test_help_lists_every_option_of_every_method_with_its_default():
    text = pydoc.render_doc(mb.render, renderer=pydoc.plaintext)
    assert len(METHODS) >= 5
    for name, spec in METHODS.items():
        opts = _options(name)
        assert opts, name
        sig = ", ".join(f"{k}={p.default!r}" for k, p in opts.items())
        assert f"``{name}`` ({sig}): {spec.doc}" in text, name
        # the method's own words about its options (units, ranges) are there too
        para = _options_paragraph(spec.fn.__doc__)
        assert para and " ".join(para.split()[:12]) in " ".join(text.split()), name


def test_every_method_documents_each_of_its_options():
    for name, spec in METHODS.items():
        para = _options_paragraph(spec.fn.__doc__)
        missing = [k for k in _options(name) if f"``{k}``" not in para]
        assert not missing, f"{name}: the Options paragraph of its docstring does not describe {missing}"


def test_a_method_registered_later_appears_in_help():
    @mb.register("_test_only_method", needs="nothing at all")
    def _fn(scene, strength: float = 0.5):
        """A method of this test.

        Options: ``strength`` in [0, 1], unitless."""
        return mb.render(scene, "accumulation", samples=1)

    try:
        assert "``_test_only_method`` (strength=0.5): A method of this test." in mb.render.__doc__
        assert "``strength`` in [0, 1], unitless." in mb.render.__doc__
    finally:
        del METHODS["_test_only_method"]


def test_a_callable_object_without_a_hash_registers_and_renders():
    """A method may be any callable, a dataclass instance (``__eq__`` and no ``__hash__``) too:
    its options are read from its signature every call where they cannot be kept by the
    callable, and an unknown option is still refused by name."""

    @dataclasses.dataclass
    class Method:
        samples: int = 1

        def __call__(self, scene, strength: float = 0.5):
            """A method of this test.

            Options: ``strength`` in [0, 1], unitless."""
            return mb.render(scene, "accumulation", samples=self.samples)

    with pytest.raises(TypeError):
        hash(Method())
    mb.register("_test_unhashable")(Method())
    try:
        frame = mb.render(_still_scene(), "_test_unhashable", strength=0.3)
        assert frame.rgba.shape == (24, 32, 4)
        with pytest.raises(TypeError, match="colour"):
            mb.render(_still_scene(), "_test_unhashable", colour=1)
    finally:
        del METHODS["_test_unhashable"]


def _still_scene() -> mb.Scene:
    cam = mb.Camera(mb.look_at((0, 0, 4), (0, 0, 0)), 0.7, 32, 24)
    cube = mb.Object(mb.meshes.box((0.6, 0.6, 0.6)), motion=mb.Motion.linear([-0.5, 0, 0], [0.5, 0, 0]))
    return mb.Scene([cube], cam)


def test_a_method_that_does_not_apply_warns_and_says_why():
    scene = _still_scene()
    with pytest.warns(mb.MethodNotApplicableWarning, match=r"'camera_velocity'.*moving camera.*accumulation"):
        frame = mb.render(scene, "camera_velocity", samples=4)
    assert frame.rgba.shape == (24, 32, 4)  # it still runs: the sharp frame
    pan = mb.SCENES["pan"](32, 24)
    with pytest.warns(mb.MethodNotApplicableWarning, match="still camera"):
        mb.render(pan, "opaque_image")


def test_methods_for_names_the_methods_render_runs_without_a_warning():
    # mb.methods_for (the methods page's call) is the registry's own applies test: on a still
    # camera it names the object-space methods and not camera_velocity; on the pan the reverse
    still, pan = _still_scene(), mb.SCENES["pan"](32, 24)
    assert mb.methods_for is mb.render.__globals__["methods_for"]
    assert {"velocity", "opaque_image", "motion_volume"} <= set(mb.methods_for(still))
    assert "camera_velocity" not in mb.methods_for(still)
    assert "camera_velocity" in mb.methods_for(pan) and "velocity" not in mb.methods_for(pan)
    assert mb.methods_for(still) == [n for n in mb.METHODS if mb.METHODS[n].applies(still)]


@pytest.mark.parametrize("method", ["accumulation", "motion_volume", "opaque_image", "blur_shell"])
def test_methods_that_apply_do_not_warn(method):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mb.render(_still_scene(), method)


def test_an_unknown_option_names_the_methods_options():
    with pytest.raises(TypeError, match=r"no option 'sample'.*samples"):
        mb.render(_still_scene(), "accumulation", sample=4)
