"""``render(scene, method=..., **options) -> Frame`` and the registry of rendering methods.

Every method lives in its own module of `motionblur.methods` and registers itself with
[`register`][motionblur.render.register]::

    @register("accumulation", sweep=[{"samples": n} for n in (1, 4, 16)], applies=lambda scene: True)
    def accumulation(scene, samples=16, ...) -> Frame: ...

``sweep`` lists the option sets the speed-against-error report (`motionblur.evaluation`)
runs for the method on every built-in scene where ``applies(scene)`` is true. Importing
`motionblur` imports `motionblur.methods`, which registers every built-in method; this
module knows none of them. The layers the methods share are in `motionblur.methods._layers`.
"""

from __future__ import annotations

import inspect
import re
import textwrap
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from .raster import Frame, over_background
from .scene import Scene

__all__ = [
    "render",
    "register",
    "METHODS",
    "MethodSpec",
    "methods_for",
    "MethodNotApplicableWarning",
    "PoorBlurWarning",
]


#: The methods that model a rolling shutter (``Scene(rolling=R)``, R > 0): ``analytic``
#: exactly, ``accumulation`` per row (converging to it), ``auto`` by rendering the analytic
#: frame. [`render`][motionblur.render.render] refuses the others with a ValueError naming ``rolling``.
ROLLING_METHODS = frozenset({"analytic", "accumulation", "auto"})


#: Estimates under this RMSE are below what the pilot can tell apart (the exact reference's own
#: distance from the limit is of the order of 1e-5): a PoorBlurWarning needs an estimate above it.
POOR_BLUR_FLOOR = 1e-5
#: A frame whose alpha mass is this share or more away from the exact frame's (+0.5 is half as
#: much coverage again) comes with a PoorBlurWarning: its coverage, not only its colour, is
#: wrong. The pilot's ``stats["alpha_mass_estimate"]`` is read against it less `MASS_MARGIN`.
POOR_MASS = 0.5
#: The pilot's estimate of the alpha mass is measured against an accumulated reference, not the
#: exact frame: near `POOR_MASS` it was within 0.009 of the frame's own on tuning scenes (seeds
#: 0-299 at 64x48), and 0.004 off on a measuring scene where a warning at `POOR_MASS` itself let
#: a blur shell 50.2% over pass without one. The warning fires this much before the bound.
MASS_MARGIN = 0.02


class PoorBlurWarning(UserWarning):
    """The frame's error estimate is larger than the unblurred frame's (the sharp frame where the
    shutter's weight reaches half, as ``accumulation`` with one sample renders it: mid-shutter
    under the box; measured by the same pilot): on this scene the method blurs worse than not
    blurring at all; or its pilot puts the frame's alpha mass `POOR_MASS` or more away from the
    exact frame's, less `MASS_MARGIN` for the pilot's own error (a method that over- or
    under-covers: a motion volume filling a knot's holes).
    ``accumulation`` and ``analytic`` (or ``auto``) give the exact integral's approximation
    that converges."""


class MethodNotApplicableWarning(UserWarning):
    """[`render`][motionblur.render.render] was asked for a method whose ``applies(scene)`` is false: the method runs,
    but it does nothing useful for this scene (e.g. ``camera_velocity`` with a still camera gives
    the sharp frame)."""


@dataclass
class MethodSpec:
    """A registered method: its function ``fn(scene, **options) -> Frame``, the option sets
    ``sweep`` the benchmark runs, ``applies(scene) -> bool``, what the method ``needs`` of a scene
    (words, for the warning when it does not apply) and a one-line description; ``options``
    (read-only) and ``any_option`` are read from ``fn``'s signature once, when it is registered
    (``inspect.signature`` on every call took a tenth of a small frame's time)."""

    name: str
    fn: Callable[..., Frame]
    sweep: list[dict] = field(default_factory=list)
    applies: Callable[[Scene], bool] = lambda scene: True
    doc: str = ""
    needs: str = ""
    options: Mapping[str, inspect.Parameter] = field(init=False)
    any_option: bool = field(init=False)

    def __post_init__(self) -> None:
        self.options = MappingProxyType(_parameters(self.fn))
        self.any_option = any(p.kind == p.VAR_KEYWORD for p in inspect.signature(self.fn).parameters.values())


#: Every rendering method, by name (filled by ``@register`` when `motionblur.methods` loads).
METHODS: dict[str, MethodSpec] = {}


def register(name: str, sweep=(), applies: Callable[[Scene], bool] | None = None, needs: str = ""):
    """Decorator: register ``fn(scene, **options) -> Frame`` as method ``name`` (see the module
    docs). ``needs``: what ``applies`` asks of a scene, in words (``"a moving camera"``).
    [`render`][motionblur.render.render]'s docstring lists the method's options from ``fn``'s signature and the
    ``Options:`` paragraph of its docstring."""
    if not isinstance(name, str) or not name:
        raise TypeError("name: expected a non-empty string")

    def deco(fn):
        doc = (fn.__doc__ or "").strip().splitlines()
        METHODS[name] = MethodSpec(
            name=name,
            fn=fn,
            sweep=[dict(s) for s in sweep],
            applies=applies if applies is not None else (lambda scene: True),
            doc=doc[0] if doc else "",
            needs=str(needs),
        )
        render.__doc__ = _RENDER_DOC + _methods_doc()
        return fn

    return deco


def methods_for(scene: Scene) -> list[str]:
    """Names of the registered methods that apply to ``scene`` (``motionblur.methods_for``), in
    registration order; ``render`` warns (`MethodNotApplicableWarning`) for any other."""
    return [n for n, m in METHODS.items() if m.applies(scene)]


def render(
    scene: Scene,
    method: str = "accumulation",
    *,
    aperture: float | None = None,
    focus_distance: float | None = None,
    error_estimate: bool = True,
    outputs: Sequence[str] = (),
    output_times: Any = None,
    **options: Any,
) -> Frame:
    """Render ``scene`` with the registered ``method`` (``accumulation``, ``motion_volume``, ...).

    Returns a [`Frame`][motionblur.render.Frame] of ``scene.camera`` size: ``rgba`` (H,W,4) float32 premultiplied
    linear RGBA composited over ``scene.background``, ``depth`` (H,W) float32, ``ids`` (H,W) int32
    (object index in ``scene.objects``, -1 background), ``velocity`` (H,W,2) and ``stats`` with
    ``method``, ``options`` and ``ms`` (wall time of the whole call). Unknown methods and options
    raise ValueError / TypeError; a method that does not apply to the scene (see
    [`methods_for`][motionblur.render.methods_for]) warns with [`MethodNotApplicableWarning`][motionblur.render.MethodNotApplicableWarning] and runs.

    Depth of field (any method): ``aperture`` is the thin lens's *radius* (not its diameter, not
    an f-number), exactly Mitsuba's ``thinlens`` ``aperture_radius``, and ``focus_distance`` the
    focal plane's distance along the view axis (Mitsuba's ``focus_distance``), both in scene
    units, > 0, both or neither. They blur the method's frame from its depth buffer with
    [`motionblur.image.lens_blur`][motionblur.image.lens_blur], a point at depth ``z`` spreading over a circle of
    confusion of radius ``H * aperture * |1 - focus_distance / z| / (2 * focus_distance *
    tan(yfov / 2))`` pixels; the reference is ``reference.mitsuba(..., aperture=,
    focus_distance=)`` with the same numbers. ``stats`` then has ``dof`` (the lens).

    Ground truth: ``outputs`` names channels to give with the frame on ``frame.outputs``
    (``"sharp"``, ``"flow"``, ``"trajectory"``, ``"exposure"``; what each holds and which method gives it:
    [`motionblur.ground_truth.outputs`][motionblur.ground_truth.outputs]) at the shutter times
    ``output_times`` (default open, center, close); ``stats["output_times"]`` lists them and
    ``stats["trajectory"]`` holds the trajectories. ``Frame.save_exr`` writes them as named
    channels.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected a motionblur.Scene, got {type(scene).__name__}")
    if not isinstance(error_estimate, bool):
        raise TypeError(f"error_estimate: expected True or False, got {type(error_estimate).__name__}")
    if not isinstance(method, str):
        raise TypeError(f"method: expected a string, got {type(method).__name__}")
    if method not in METHODS:
        raise ValueError(f"method: unknown method {method!r}; expected one of {', '.join(sorted(METHODS))}")
    spec = METHODS[method]
    if scene.rolling > 0.0 and method not in ROLLING_METHODS:
        raise ValueError(
            f"rolling: method {method!r} cannot model a rolling shutter (Scene(rolling={scene.rolling})); "
            f"the methods that do: {', '.join(sorted(ROLLING_METHODS))}"
        )
    if not spec.applies(scene):
        warnings.warn(
            f"method {method!r} does not apply to this scene"
            + (f" (it needs {spec.needs})" if spec.needs else "")
            + f"; methods that apply: {', '.join(methods_for(scene))}",
            MethodNotApplicableWarning,
            stacklevel=2,
        )
    bad = _unknown_options(spec, options)
    if bad:
        raise TypeError(
            f"options: method {method!r} has no option {', '.join(map(repr, bad))}; "
            f"its options: {', '.join(spec.options) or 'none'} (help(motionblur.render))"
        )
    lens = _lens(aperture, focus_distance)
    if outputs:
        from .ground_truth import _check_outputs

        outputs = _check_outputs(outputs, method)  # before rendering: a refusal costs nothing
    t0 = time.perf_counter()
    exposure = "exposure" in outputs  # the analytic method's own render gives it
    frame = spec.fn(scene, **options, exposure=True) if exposure else spec.fn(scene, **options)
    if lens is not None:
        frame = _with_depth_of_field(frame, scene, *lens)
    frame = over_background(frame, scene.background)
    blurred = frame if lens is None else None  # the motion blur alone, which the estimate is of
    frame.stats["method"] = method
    frame.stats["options"] = dict(options)
    frame.stats["ms"] = (time.perf_counter() - t0) * 1e3
    if error_estimate and "error_estimate" not in frame.stats and ESTIMATOR:
        frame.stats.update(ESTIMATOR[0](scene, method, options, blurred))
        _warn_if_poor(method, frame.stats)
    if lens is not None and "error_estimate" in frame.stats:
        frame.stats["error_estimate_how"] += " (of the motion blur before the lens)"
    if outputs:
        _add_outputs(frame, scene, method, outputs, output_times)
    return frame


def _warn_if_poor(method: str, stats: dict) -> None:
    """A PoorBlurWarning when the frame's estimates say its blur is worse than none or its alpha
    mass is `POOR_MASS` off the exact frame's (its estimate `POOR_MASS` - `MASS_MARGIN`)."""
    converge = "'accumulation', 'analytic' or 'auto' converge to it"
    est = stats.get("error_estimate", 0.0)
    if est > max(stats.get("unblurred_estimate", float("inf")), POOR_BLUR_FLOOR):
        warnings.warn(
            f"method {method!r}: estimated RMSE {est:.3g} against the exact integral is above the "
            f"unblurred frame's {stats['unblurred_estimate']:.3g} on this scene (its blur is worse "
            f"than none); {converge}",
            PoorBlurWarning,
            stacklevel=3,
        )
    mass = stats.get("alpha_mass_estimate", 0.0)
    if abs(mass) >= POOR_MASS - MASS_MARGIN:
        warnings.warn(
            f"method {method!r}: estimated alpha mass {mass:+.0%} off the exact integral's on this "
            f"scene (it {'over' if mass > 0 else 'under'}-covers); {converge}",
            PoorBlurWarning,
            stacklevel=3,
        )


def _add_outputs(frame: Frame, scene: Scene, method: str, names, times) -> None:
    """Put the ground-truth ``names`` at ``times`` on ``frame.outputs`` (and their times and
    trajectories in its stats, which EXR headers carry)."""
    from .ground_truth import outputs as ground_truth

    t0 = time.perf_counter()
    out = ground_truth(scene, names, method, times)
    if "exposure" in names:
        from .ground_truth import _exposure_of

        out["exposure"] = _exposure_of(frame.stats.pop("exposure"), len(scene.objects))
    frame.stats["output_times"] = [float(t) for t in out.pop("times")]
    if "trajectory" in out:
        frame.stats["trajectory"] = [
            {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in tr.items()}
            for tr in out["trajectory"]
        ]
    frame.outputs.update(out)
    frame.stats["outputs_ms"] = (time.perf_counter() - t0) * 1e3


#: The pilot estimator ``fn(scene, method, options, frame) -> dict`` that
#: [`render`][motionblur.render.render] calls when a method did not measure its own error (set by
#: `motionblur.methods._estimate`); ``frame`` is the one rendered (over the background), None
#: under a lens.
ESTIMATOR: list[Callable[[Scene, str, dict, Frame | None], dict]] = []


_RENDER_DOC = render.__doc__ or ""


def _lens(aperture, focus_distance) -> tuple[float, float] | None:
    """(aperture, focus_distance) checked, or None when both are None."""
    if aperture is None and focus_distance is None:
        return None
    if aperture is None or focus_distance is None:
        missing = "aperture" if aperture is None else "focus_distance"
        raise ValueError(f"{missing}: depth of field needs both aperture and focus_distance")
    from ._validate import as_float

    a, f = as_float(aperture, "aperture"), as_float(focus_distance, "focus_distance")
    for name, v in (("aperture", a), ("focus_distance", f)):
        if not (np.isfinite(v) and v > 0):
            raise ValueError(f"{name}: must be finite and > 0 (scene units), got {v}")
    return a, f


def _with_depth_of_field(frame: Frame, scene: Scene, aperture: float, focus: float) -> Frame:
    """The frame blurred by the thin lens of radius ``aperture`` focused at ``focus``."""
    from .image import lens_blur

    depth = np.where(np.isfinite(frame.depth) & (frame.depth > 0), frame.depth, np.inf).astype(np.float32)
    rgba = lens_blur(frame.rgba, depth, aperture, focus, scene.camera.yfov)
    out = Frame(rgba, frame.depth, frame.ids, frame.velocity)
    out.stats.update(frame.stats)
    out.stats["dof"] = {"aperture": aperture, "focus_distance": focus}
    return out


def _parameters(fn) -> dict[str, inspect.Parameter]:
    """The options of a method function: its parameters after ``scene``."""
    params = list(inspect.signature(fn).parameters.values())[1:]
    return {p.name: p for p in params if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)}


def _unknown_options(spec: MethodSpec, options: dict) -> list[str]:
    """The names in ``options`` that method ``spec`` has no option of."""
    if spec.any_option:
        return []
    return [k for k in options if k not in spec.options]


def _options_paragraph(doc: str) -> str:
    """The ``Options:`` paragraph of a method's docstring (up to the next blank line or
    ``Returns``), whitespace collapsed."""
    text = inspect.cleandoc(doc or "")
    m = re.search(r"Options:(.*?)(?:\n\s*\n|$)", text, re.S)
    return " ".join(m.group(1).split()) if m else ""


def _methods_doc() -> str:
    """The part of [`render`][motionblur.render.render]'s docstring listing every registered method, its options with
    their defaults, and what its docstring says of them (units included)."""
    lines = [
        "",
        "    Methods and their options (from each method's docstring; defaults in the signature):",
        "",
    ]
    for name in sorted(METHODS):
        spec = METHODS[name]
        sig = ", ".join(
            f"{p.name}={p.default!r}" if p.default is not p.empty else p.name for p in spec.options.values()
        )
        lines.append(f"    ``{name}`` ({sig}): {spec.doc}")
        if spec.needs:
            lines.append(f"        Applies to scenes with {spec.needs}.")
        para = _options_paragraph(spec.fn.__doc__ or "")
        if para:
            lines += textwrap.wrap(para, 92, initial_indent="        ", subsequent_indent="        ")
        lines.append("")
    return "\n".join(lines)
