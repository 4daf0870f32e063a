"""motionblur: make objects and cameras look as if they moved while the shutter was open.

Conventions (docs: guide/conventions.md): vertices (V,3) float, faces (F,3) int counter-clockwise front;
images float32 (H,W,4) linear premultiplied RGBA, row 0 at the top; depth float32 (H,W) view-axis
distance, inf for background; the shutter spans normalised time [0, 1].

Importing the package loads the scene, the rasterizer and the rendering methods; the rest
(evaluation, interop, the built-in scenes, meshes, the analytic kernel's API, image filters) is
imported at its first use. Importing changes nothing in the process (see [`tune_malloc`][motionblur.tune_malloc]).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from . import (
    budget,
    methods,  # noqa: F401  (registers every built-in rendering method)
    threads,
)
from . import geometry as _geometry
from . import raster as _raster
from . import scene as _scene
from . import shell as _shell
from ._core import __version__
from ._namespace import tidy
from ._optional import MissingDependencyError
from .budget import memory_budget, set_memory_budget
from .geometry import *  # noqa: F403
from .raster import *  # noqa: F403
from .render import METHODS, MethodNotApplicableWarning, PoorBlurWarning, methods_for, register, render
from .renderer import Renderer
from .scene import *  # noqa: F403
from .shell import *  # noqa: F403
from .threads import get_num_threads, set_num_threads

if TYPE_CHECKING:  # what the names served at first use are, for type checkers and linters
    from . import (  # noqa: F401
        analytic,
        evaluation,
        ground_truth,
        image,
        interop,
        meshes,
        scenes_builtin,
        scenes_real,
        shake,
    )
    from ._malloc import tune_malloc
    from .analytic import MovingDraw, coverage, rasterize_motion
    from .evaluation import metrics, reference
    from .interop.images import read_image
    from .interop.mitsuba import to_mitsuba_dict
    from .methods._estimate import exact
    from .methods.accumulation import Sequence
    from .scenes_builtin import SCENES, builtin_scene
    from .shake import BlurKernels, blur_kernels, camera_shake

#: Names served at their first use: name -> (module, attribute; None for the module itself).
_LAZY: dict[str, tuple[str, str | None]] = {
    "analytic": (".analytic", None),
    "image": (".image", None),
    "interop": (".interop", None),
    "meshes": (".meshes", None),
    "evaluation": (".evaluation", None),
    "scenes_builtin": (".scenes_builtin", None),
    "scenes_real": (".scenes_real", None),
    "metrics": (".evaluation.metrics", None),
    "reference": (".evaluation.reference", None),
    "MovingDraw": (".analytic", "MovingDraw"),
    "coverage": (".analytic", "coverage"),
    "rasterize_motion": (".analytic", "rasterize_motion"),
    "read_image": (".interop.images", "read_image"),
    "to_mitsuba_dict": (".interop.mitsuba", "to_mitsuba_dict"),
    "exact": (".methods._estimate", "exact"),
    "Sequence": (".methods.accumulation", "Sequence"),
    "SCENES": (".scenes_builtin", "SCENES"),
    "builtin_scene": (".scenes_builtin", "builtin_scene"),
    "tune_malloc": ("._malloc", "tune_malloc"),
    "shake": (".shake", None),
    "ground_truth": (".ground_truth", None),
    "camera_shake": (".shake", "camera_shake"),
    "blur_kernels": (".shake", "blur_kernels"),
    "BlurKernels": (".shake", "BlurKernels"),
}

__all__ = [
    "__version__",
    "analytic",
    "budget",
    "memory_budget",
    "set_memory_budget",
    "threads",
    "get_num_threads",
    "set_num_threads",
    "image",
    "meshes",
    "interop",
    *_geometry.__all__,
    *_raster.__all__,
    *_shell.__all__,
]
__all__ += [
    "MovingDraw",
    "rasterize_motion",
    "coverage",
    *_scene.__all__,
    "render",
    "methods_for",
    "Renderer",
    "exact",
    "register",
    "METHODS",
    "Sequence",
    "SCENES",
    "builtin_scene",
    "metrics",
    "reference",
    "read_image",
    "to_mitsuba_dict",
    "MissingDependencyError",
    "MethodNotApplicableWarning",
    "PoorBlurWarning",
    "tune_malloc",
    "shake",
    "ground_truth",
    "camera_shake",
    "blur_kernels",
    "BlurKernels",
]


def __getattr__(name: str):
    if name in _LAZY:
        module, attr = _LAZY[name]
        value = importlib.import_module(module, __name__)
        if attr is not None:
            value = getattr(value, attr)
        globals()[name] = value  # once: the next lookup is an ordinary attribute
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


tidy(__name__, lazy=_LAZY)
