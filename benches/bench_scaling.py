"""Scaling: time against image size and against triangle count, one plot each.

Every method on an axis is timed at every point of that axis in the same run (best of N after a
warm-up; the calls of one point are interleaved round by round, so the load of a shared machine
falls on all methods alike), and drawn as one line of the axis's plot:

- size (``SIZES``, 320x240 to 3840x2160): the rasterizer on the 82k-face icosphere, opaque and
  transparent (alpha 0.5, exact order); the image kernels on an RGBA float32 frame whose every
  pixel is opaque (opaque motion blur over 101 px, horizontal and at 30 degrees, and the
  horizontal box blur), with a copy of the frame as the memory-bandwidth floor; and the scene
  methods on the 82k-face icosphere moving across the view (``render(scene, method, error_estimate=False)``,
  accumulation with 8 samples, ``opaque_image`` (a sharp frame blurred by the image kernels),
  and the analytic method when it is registered);
- triangles (``TRIANGLES``, 1.3k to 1.3M faces, icospheres of 3 to 8 subdivisions) at
  1024x768: the rasterizer, opaque and transparent, and the same scene methods on that sphere.

Adding a method: decorate a function with ``@method(axis, name)``. For ``"size"`` it takes
``(width, height)`` and returns a callable that renders once at that size; for ``"triangles"``
it takes ``(vertices, faces)`` of the icosphere (rendered at 1024x768) and returns that callable.
Set-up done by the function (meshes, images, scenes) is not timed. Nothing else changes: the
tables and plots pick the method up. ``@method(axis, name, needs="analytic")`` joins only when
``render`` knows the method ``analytic`` (it lands from another branch as
``render(scene, "analytic")``; until then the run says it left it out): a method of
``render`` is one decorated call of ``_scene_method``.

Writes out/bench/scaling.md, scaling_size.png and scaling_triangles.png.
Usage: python benches/bench_scaling.py [--quick]
"""

from __future__ import annotations

import math
import os
import platform
import sys
import time
from pathlib import Path

os.environ.setdefault("MPLBACKEND", "Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import motionblur as mb  # noqa: E402
import motionblur.image as mi  # noqa: E402
from motionblur import meshes  # noqa: E402
from motionblur.evaluation.cluster import TIMING_BUDGET_S  # noqa: E402  (the report's rule)
from motionblur.render import METHODS as RENDER_METHODS  # noqa: E402
from motionblur.scene import translate  # noqa: E402

SIZES = [(320, 240), (640, 480), (1280, 720), (1920, 1080), (3840, 2160)]
TRIANGLES = [3, 4, 5, 6, 7, 8]  # icosphere subdivisions: 1,280 to 1,310,720 faces
RASTER_SIZE = (1024, 768)
BLUR_LENGTH = 101

#: axis -> {method name: factory}; see the module docs.
METHODS: dict[str, dict] = {"size": {}, "triangles": {}}


#: (axis, name, render method) of the factories left out because ``render`` lacks the method.
LEFT_OUT: list[tuple[str, str, str]] = []


def method(axis: str, name: str, needs: str | None = None):
    """Registers a factory for ``axis`` ("size" or "triangles") under ``name``; with ``needs``,
    only when ``render`` knows that method (else it is listed in ``LEFT_OUT``)."""

    def register(factory):
        if needs is not None and needs not in RENDER_METHODS:
            LEFT_OUT.append((axis, name, needs))
        else:
            METHODS[axis][name] = factory
        return factory

    return register


def _camera(width: int, height: int) -> mb.Camera:
    return mb.Camera(mb.look_at((0.3, 0.4, 3.2), (0, 0, 0)), np.pi / 3, width, height)


_SPHERE = {}


def _sphere(sub: int):
    if sub not in _SPHERE:
        _SPHERE[sub] = meshes.icosphere(sub)
    return _SPHERE[sub]


def _opaque_frame(width: int, height: int) -> np.ndarray:
    """(H,W,4) float32 premultiplied, every alpha 1."""
    y, x = np.mgrid[0:height, 0:width]
    rng = np.random.default_rng(0)
    return np.stack(
        [
            0.5 + 0.5 * np.sin(x / 17.0),
            0.5 + 0.5 * np.cos(y / 23.0),
            rng.random((height, width)),
            np.ones((height, width)),
        ],
        -1,
    ).astype(np.float32)


def _raster(camera, v, f, alpha: float):
    draw = mb.Draw(v, f, (0.8, 0.5, 0.2, alpha), cull_back=alpha == 1.0)
    return lambda: mb.rasterize(camera, draw, blend="exact")


@method("size", "rasterize opaque, 82k faces")
def _raster_opaque_size(width, height):
    return _raster(_camera(width, height), *_sphere(6), 1.0)


@method("size", "rasterize transparent, 82k faces")
def _raster_transparent_size(width, height):
    return _raster(_camera(width, height), *_sphere(6), 0.5)


@method("size", "opaque motion blur, horizontal")
def _opaque_h(width, height):
    img = _opaque_frame(width, height)
    return lambda: mi.opaque_motion_blur(img, (1, 0), BLUR_LENGTH, "over", img)


@method("size", "opaque motion blur, 30 degrees")
def _opaque_30(width, height):
    img = _opaque_frame(width, height)
    d = (math.cos(math.radians(30)), math.sin(math.radians(30)))
    return lambda: mi.opaque_motion_blur(img, d, BLUR_LENGTH, "over", img)


@method("size", "box blur, horizontal")
def _box_h(width, height):
    img = _opaque_frame(width, height)
    return lambda: mi.box_blur(img, (1, 0), BLUR_LENGTH)


@method("size", "copy of the frame (bandwidth floor)")
def _copy(width, height):
    img = _opaque_frame(width, height)
    return lambda: np.copy(img)


def _moving_sphere(width: int, height: int, v, f) -> mb.Scene:
    """The icosphere (v, f) moving one radius to the right over the shutter, seen by the
    benchmark's camera at width x height."""
    sphere = mb.Object(
        mb.Mesh(v, f),
        color=(0.8, 0.5, 0.2),
        motion=mb.Motion.linear(translate((-0.5, 0, 0)), translate((0.5, 0, 0))),
    )
    return mb.Scene([sphere], _camera(width, height), shutter="box")


def _scene_method(render_method: str, label: str, **options):
    """Registers ``render(scene, render_method, **options)`` on both axes: the 82k-face sphere
    at every size, every sphere at 1024x768 (joins only when ``render`` knows the method)."""

    @method("size", f"{label}, 82k faces", needs=render_method)
    def by_size(width, height):
        scene = _moving_sphere(width, height, *_sphere(6))
        return lambda: mb.render(scene, render_method, error_estimate=False, **options)

    @method("triangles", label, needs=render_method)
    def by_triangles(v, f):
        scene = _moving_sphere(*RASTER_SIZE, v, f)
        return lambda: mb.render(scene, render_method, error_estimate=False, **options)


@method("triangles", "rasterize opaque")
def _raster_opaque_tris(v, f):
    return _raster(_camera(*RASTER_SIZE), v, f, 1.0)


@method("triangles", "rasterize transparent")
def _raster_transparent_tris(v, f):
    return _raster(_camera(*RASTER_SIZE), v, f, 0.5)


_scene_method("accumulation", "accumulation, 8 samples", samples=8)
# Kraus's image-space method: one sharp frame, then the opaque motion blur of the mover.
_scene_method("opaque_image", "opaque_image (image kernels)")
# The analytic method (another branch): joins both plots once render() knows it.
_scene_method("analytic", "analytic")


def paired_best_ms(fns: list, repeat: int) -> list[float]:
    """Best time (ms) of each callable after one warm-up call, calls interleaved by round; a
    callable whose timed calls add up to :data:`TIMING_BUDGET_S` sits out the later rounds."""
    for fn in fns:
        fn()
    best = [math.inf] * len(fns)
    spent = [0.0] * len(fns)
    for _ in range(repeat):
        for i, fn in enumerate(fns):
            if spent[i] > TIMING_BUDGET_S:
                continue
            t0 = time.perf_counter()
            fn()
            dt = time.perf_counter() - t0
            best[i], spent[i] = min(best[i], dt), spent[i] + dt
    return [b * 1e3 for b in best]


def run_axis(axis: str, points: list, labels: list[str], quick: bool) -> dict[str, list[float]]:
    """{method: [ms at each point]} for every method registered on ``axis``."""
    names = list(METHODS[axis])
    times: dict[str, list[float]] = {n: [] for n in names}
    for point, label in zip(points, labels):
        args = point if axis == "size" else _sphere(point)
        fns = [METHODS[axis][n](*args) for n in names]
        big = (point[0] * point[1] > 3_000_000) if axis == "size" else point >= 8
        repeat = 2 if quick else (3 if big else 7)
        for n, ms in zip(names, paired_best_ms(fns, repeat)):
            times[n].append(ms)
            print(f"{axis:<9} {label:>12}  {n:<38} {ms:9.2f} ms", flush=True)
    return times


def plot(axis: str, xs: list[float], labels: list[str], times: dict, xlabel: str, path: Path) -> None:
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    for name, ms in times.items():
        ax.plot(xs, ms, marker="o", label=name)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xticks(xs)
    ax.set_xticklabels(labels, rotation=30 if axis == "size" else 0)
    ax.minorticks_off()
    ax.set_xlabel(xlabel)
    ax.set_ylabel("best time per call, ms (log)")
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(f"motionblur: time against {xlabel}")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def table(times: dict, labels: list[str]) -> list[str]:
    head = f"| method | {' | '.join(labels)} |"
    rule = "|---|" + "---:|" * len(labels)
    return [head, rule] + [f"| {n} | {' | '.join(f'{t:.2f}' for t in ms)} |" for n, ms in times.items()]


def main() -> None:
    quick = "--quick" in sys.argv
    sizes = SIZES[:3] if quick else SIZES
    subs = TRIANGLES[:4] if quick else TRIANGLES
    header = (
        f"machine: {platform.machine()}, {os.cpu_count()} cores (shared), no GPU, "
        f"python {platform.python_version()}, numpy {np.__version__}"
    )
    print(header)
    for axis, name, needs in LEFT_OUT:
        print(f"left out: {axis} {name!r} (render() has no method {needs!r} yet)")
    size_labels = [f"{w}x{h}" for w, h in sizes]
    by_size = run_axis("size", sizes, size_labels, quick)
    tri_counts = [20 * 4**s for s in subs]
    tri_labels = [f"{n:,}" for n in tri_counts]
    by_tris = run_axis("triangles", subs, tri_labels, quick)
    out = Path("out/bench")
    out.mkdir(parents=True, exist_ok=True)
    plot(
        "size",
        [w * h for w, h in sizes],
        size_labels,
        by_size,
        "image size (pixels)",
        out / "scaling_size.png",
    )
    plot("triangles", tri_counts, tri_labels, by_tris, "triangles", out / "scaling_triangles.png")
    lines = [
        "# Scaling benchmark",
        "",
        header + ".",
        "Best time per call in ms (best of 3-7 after a warm-up, fewer once a method's calls add up "
        "to 1.5 s; the methods of one point interleaved round by round), `python benches/bench_scaling.py`, run by `make bench`. Plots: "
        "scaling_size.png, scaling_triangles.png.",
        "",
        "## Time against image size",
        "",
        f"Rasterizer: the 82k-face icosphere; image kernels: every pixel opaque, {BLUR_LENGTH}-pixel blur; "
        "scene methods: the 82k-face icosphere moving one radius across the view.",
        "",
        *table(by_size, size_labels),
        "",
        f"## Time against triangle count ({RASTER_SIZE[0]}x{RASTER_SIZE[1]})",
        "",
        *table(by_tris, tri_labels),
        *(
            [
                "",
                "Left out (render() lacks the method): "
                + ", ".join(sorted({n for _, _, n in LEFT_OUT}))
                + ".",
            ]
            if LEFT_OUT
            else []
        ),
    ]
    (out / "scaling.md").write_text("\n".join(lines) + "\n")
    print(f"wrote {out / 'scaling.md'}, scaling_size.png, scaling_triangles.png")


if __name__ == "__main__":
    main()
