"""motionblur: make objects and cameras look as if they moved while the shutter was open.

Conventions (see the README): vertices (V,3) float, faces (F,3) int counter-clockwise front;
images float32 (H,W,4) linear premultiplied RGBA, row 0 at the top; depth float32 (H,W) view-axis
distance, inf for background; the shutter spans normalised time [0, 1].
"""

from __future__ import annotations

from . import (
    _malloc,  # noqa: F401  (keeps freed frame buffers in the process; see the module)
    analytic,
    budget,
    image,
    interop,
    meshes,
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
from .analytic import MovingDraw, coverage, rasterize_motion
from .budget import memory_budget, set_memory_budget
from .evaluation import metrics, reference
from .geometry import *  # noqa: F403
from .interop import read_image, to_mitsuba_dict
from .methods._estimate import exact
from .methods.accumulation import Sequence
from .raster import *  # noqa: F403
from .render import METHODS, MethodNotApplicableWarning, PoorBlurWarning, register, render
from .scene import *  # noqa: F403
from .scenes_builtin import SCENES, builtin_scene
from .shell import *  # noqa: F403
from .threads import get_num_threads, set_num_threads

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
]

tidy(__name__)
