"""Optional dependencies: import them on first use, and say what to install when they are missing.

The core (``pip install motionblur``) needs numpy only. The peers, metrics, file formats and
plots come with extras (``pip install "motionblur[reference]"`` ...); see the docs,
guide/install.md. `require` imports one such package or raises [`MissingDependencyError`][motionblur._optional.MissingDependencyError]
(a ``ModuleNotFoundError``) naming the pip package and the extra that brings it;
`require_all` checks all the packages of a task at once, before the task writes anything.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import sys
from types import ModuleType

__all__ = [
    "MissingDependencyError",
    "PACKAGES",
    "require",
    "require_all",
    "missing",
    "require_osmesa_pyopengl",
]

#: import name -> (pip package, extra that installs it, what it is used for)
PACKAGES: dict[str, tuple[str, str, str]] = {
    "mitsuba": ("mitsuba", "reference", "the Mitsuba 3 reference (motionblur.reference.mitsuba)"),
    "bpy": ("bpy", "blender", "the Blender Cycles reference (motionblur.reference.blender; Python 3.11)"),
    "tqdm": ("tqdm", "reference", "the progress bar of long references"),
    "flip_evaluator": ("flip-evaluator", "metrics", "the FLIP metric (motionblur.metrics.flip)"),
    "pyrender": ("pyrender", "pyrender", "the pyrender peer (motionblur.reference.pyrender)"),
    "trimesh": ("trimesh", "interop", "trimesh meshes and scenes"),
    "pygltflib": ("pygltflib", "interop", "glTF files (Scene.from_gltf)"),
    "OpenEXR": ("OpenEXR", "interop", "EXR files (Frame.save_exr, read_image)"),
    "PIL": ("pillow", "interop", "PNG files (Frame.save_png, read_image, the demo's sheets)"),
    "imageio_ffmpeg": ("imageio-ffmpeg", "video", "the MP4 preview of motionblur dataset (--preview mp4)"),
    "matplotlib": ("matplotlib", "bench", "the Pareto plots of the report"),
    "dask": ("dask[distributed]", "bench", "the report's references and errors as Dask tasks (bench --dask)"),
    "distributed": (
        "dask[distributed]",
        "bench",
        "the report's references and errors as Dask tasks (bench --dask)",
    ),
}


class MissingDependencyError(ModuleNotFoundError):
    """An optional package is not installed; the message names the pip package and the extra."""


def _advice(modules: list[str]) -> str:
    pips = sorted(
        {PACKAGES[m][0] for m in modules if m in PACKAGES} | {m for m in modules if m not in PACKAGES}
    )
    extras = sorted({PACKAGES[m][1] for m in modules if m in PACKAGES})
    line = f'pip install "motionblur[{",".join(extras)}]"' if extras else ""
    return f"{line} (or: pip install {' '.join(pips)})" if line else f"pip install {' '.join(pips)}"


def _installed(module: str) -> bool:
    if module in sys.modules:
        return sys.modules[module] is not None
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):
        return False


def missing(modules) -> list[str]:
    """The import names among ``modules`` that are not installed (nothing is imported)."""
    return [m for m in modules if not _installed(m)]


def require(module: str, purpose: str | None = None) -> ModuleType:
    """Import ``module`` (an import name of `PACKAGES`, or any other) and return it.

    Raises [`MissingDependencyError`][motionblur._optional.MissingDependencyError] when it is not installed, naming what needs it
    (``purpose``, default: the package's use), the pip package and the extra to install.
    """
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as exc:
        top = module.split(".")[0]
        if exc.name is not None and exc.name.split(".")[0] != top:
            raise  # the package is there but one of its own dependencies is not: pip's message is right
        pip, extra, use = PACKAGES.get(top, (top, "", top))
        raise MissingDependencyError(
            f"{purpose or use} needs the Python package {pip!r}, which is not installed: {_advice([top])}",
            name=top,
        ) from exc


def require_all(modules, task: str) -> None:
    """Raise one [`MissingDependencyError`][motionblur._optional.MissingDependencyError] listing every package of ``modules`` (import
    names) that is not installed, saying that ``task`` needs them; call it before the task
    writes anything."""
    gone = missing(modules)
    if gone:
        names = ", ".join(PACKAGES.get(m, (m,))[0] for m in gone)
        raise MissingDependencyError(
            f"{task} needs Python packages that are not installed ({names}): {_advice(gone)}",
            name=gone[0],
        )


def require_osmesa_pyopengl() -> None:
    """pyrender under OSMesa (``PYOPENGL_PLATFORM=osmesa``) needs PyOpenGL >= 3.1.5, whose OSMesa
    binding has ``OSMesaCreateContextAttribs``; pyrender 0.1.45 pins PyOpenGL 3.1.0. Raises
    ``RuntimeError`` with the command that upgrades it (pip then prints a resolver warning about
    pyrender's pin, which is expected)."""
    if os.environ.get("PYOPENGL_PLATFORM") != "osmesa":
        return
    opengl = require("OpenGL", "the pyrender peer")
    version = getattr(opengl, "__version__", "0")
    parts = tuple(int(p) if p.isdigit() else 0 for p in version.split(".")[:3])
    if parts < (3, 1, 5):
        raise RuntimeError(
            f"pyrender under OSMesa needs PyOpenGL >= 3.1.5 (installed: {version}; pyrender pins 3.1.0, "
            "whose OSMesa binding is broken): pip install 'pyopengl>=3.1.5' "
            "(pip then warns that pyrender requires PyOpenGL==3.1.0; that is expected)"
        )
