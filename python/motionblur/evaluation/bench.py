"""The speed-against-error report: every registered method on every built-in scene.

For each scene of :data:`motionblur.SCENES` and each method of :data:`motionblur.METHODS` whose
``applies(scene)`` is true, every option set of the method's ``sweep`` is rendered; the best of
``repeat`` wall-clock timings of :func:`motionblur.render` and the error against the Mitsuba
time-sampled reference (RMSE over premultiplied RGBA, PSNR, FLIP, signed coverage error) are
recorded. References are cached under ``<out>/references/`` (keyed by scene, size, K, spp, seed
and the Mitsuba variant). Outputs in ``<out>``: ``results.csv``, ``results.md`` (a table per
scene, the Pareto front marked, and the two comparisons below) and ``pareto_<scene>.png``
(error against time, log-log, the front drawn).

Comparisons, measured in the same run:

- motion_volume against accumulation at equal error: for each motion-volume option set, the time
  accumulation needs for the same RMSE, interpolated log-log between the two N that bracket it
  (if even N = 1 is better, its time is an upper bound and the factor is marked ``<=``; if even
  the largest N is worse, ``>=``). The factor is accumulation's time over motion_volume's.
- every method against accumulation at equal time (:func:`.compare.equal_time`): for each run of a
  method, accumulation's RMSE in the same time, interpolated log-log on accumulation's error
  against time, beside the method's own.
- accumulation with the static layer drawn once (N = 16) against 16-pose accumulation on pyrender
  (every object at every pose, :func:`.reference.pyrender`), on the same scene and size;
  ours at ``aa=1`` like pyrender under OSMesa, its static layer drawn once per frame (the cache
  cleared before every run).

In the sweeps the static layer is kept across frames (as a real-time loop keeps it while the
static objects and the camera do not change), for every method alike; timings are the best of
``repeat`` runs after one warm-up run.

:func:`run` is the whole report and :func:`main` its command line (``python -m motionblur
bench``); :mod:`.sweep` renders and times, :mod:`.compare` computes the comparisons from the
rows, :mod:`.report` writes the files.
"""

from __future__ import annotations

from pathlib import Path

from .._optional import require_all
from ..render import METHODS
from ..scenes_builtin import SCENES
from . import reference as ref_mod
from . import report
from .compare import equal_error, equal_time, pareto_front
from .sweep import paired_factor, pyrender_comparison, reference_for, sweep_scene

__all__ = ["run", "main"]


def run(
    out="out/bench",
    scenes=None,
    width: int = 320,
    height: int = 240,
    times: int = 256,
    spp: int = 4,
    repeat: int = 3,
    methods=None,
    sweeps=None,
    flip: bool = True,
    pyrender_peer: bool = True,
    save_images: bool = False,
    aa: int | None = 2,
    log=print,
) -> dict:
    """Run the report and write it to ``out``; returns ``{"rows", "comparisons", "pyrender", "paths"}``.

    ``scenes``: names from SCENES (default all); ``sweeps``: optional ``{method: [options, ...]}``
    replacing the registered sweeps (the demo's small version); ``methods``: restrict to these;
    ``aa``: spatial samples per pixel per axis given to every method that takes ``aa`` (2 by
    default: with one sample per pixel the aliasing of long static edges, about 0.017 RMSE on the
    cube scene, hides the motion-blur error the report is about). The pyrender comparison runs
    ours at ``aa=1``, as pyrender under OSMesa has no multisampling.
    """
    names = list(SCENES) if scenes is None else list(scenes)
    unknown = [n for n in names if n not in SCENES]
    if unknown:
        raise ValueError(f"scenes: unknown {unknown}; expected names from {', '.join(SCENES)}")
    # every optional package the run needs, checked before anything is written
    needed = ["mitsuba", "tqdm", "matplotlib"] + ["flip_evaluator"] * bool(flip)
    needed += ["PIL"] * bool(save_images) + ["pyrender", "trimesh"] * bool(pyrender_peer)
    require_all(needed, "the speed-against-error report")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    saved = {}
    if sweeps:
        for m, s in sweeps.items():
            saved[m] = METHODS[m].sweep
            METHODS[m].sweep = [dict(o) for o in s]
    rows, comparisons, flip_comparisons, pyr, paired, equal_times = [], {}, {}, [], {}, {}
    images = {} if save_images else None
    references = {}
    try:
        for name in names:
            scene = SCENES[name](width=width, height=height)
            ref, ref_ms = reference_for(name, scene, times, spp, out / "references")
            log(f"[{name}] reference {'cached' if ref_ms == 0 else f'{ref_ms / 1e3:.1f} s'}")
            if save_images:
                report.save_reference(out, name, ref)
                references[name] = ref
            scene_rows = sweep_scene(name, scene, ref, repeat, methods, flip, images, aa)
            rows += scene_rows
            comparisons[name] = equal_error(scene_rows)
            equal_times[name] = equal_time(scene_rows)
            flip_comparisons[name] = equal_error(scene_rows, metric="flip") if flip else []
            paired[name] = paired_factor(scene, scene_rows, "rmse", max(3, repeat))
            if pyrender_peer:
                pyr.append(pyrender_comparison(name, scene, ref, repeat))
            for r in scene_rows:
                log(f"  {r['method']:<14} {r['options']:<28} {r['ms']:9.2f} ms  RMSE {r['rmse']:.5f}")
    finally:
        for m, s in saved.items():
            METHODS[m].sweep = s
    fronts = []
    for name in names:
        fronts += pareto_front([r for r in rows if r["scene"] == name])
    settings = dict(
        width=width,
        height=height,
        times=times,
        spp=spp,
        repeat=repeat,
        aa=aa,
        variant=ref_mod.mitsuba_variant(),
    )
    paths = report.write(
        out,
        names,
        rows,
        fronts,
        settings,
        comparisons=comparisons,
        flip_comparisons=flip_comparisons,
        paired=paired,
        equal_times=equal_times,
        pyrender_rows=pyr,
        images=images,
        references=references,
    )
    return {
        "rows": rows,
        "comparisons": comparisons,
        "flip_comparisons": flip_comparisons,
        "paired": paired,
        "equal_time": equal_times,
        "pyrender": pyr,
        "paths": paths,
    }


def main(argv=None) -> int:
    import argparse

    p = argparse.ArgumentParser(prog="python -m motionblur bench", description=__doc__.splitlines()[0])
    p.add_argument("--out", default="out/bench")
    p.add_argument("--scenes", nargs="*", default=None, help=f"subset of {', '.join(SCENES)}")
    p.add_argument("--size", default="320x240", help="WxH")
    p.add_argument("--aa", type=int, default=2, help="spatial samples per pixel per axis for every method")
    p.add_argument("--times", type=int, default=256, help="Mitsuba shutter times K")
    p.add_argument("--spp", type=int, default=4, help="Mitsuba samples per pixel per time")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--no-flip", action="store_true")
    p.add_argument("--no-pyrender", action="store_true", help="leave out the pyrender comparison")
    p.add_argument("--images", action="store_true", help="save every image and a labelled sheet per scene")
    p.add_argument("--quick", action="store_true", help="160x120, K = 64, one timing")
    a = p.parse_args(argv)
    w, h = (int(x) for x in a.size.lower().split("x"))
    if a.quick:
        w, h, a.times, a.repeat = 160, 120, 64, 1
    res = run(
        a.out,
        a.scenes,
        w,
        h,
        a.times,
        a.spp,
        a.repeat,
        flip=not a.no_flip,
        aa=a.aa,
        pyrender_peer=not a.no_pyrender,
        save_images=a.images,
    )
    md = res["paths"]["md"].read_text()
    start = md.find("## Each method against")
    print(md[start if start >= 0 else md.index("## motion_volume against") :])
    print(f"written: {res['paths']['md']}, {res['paths']['csv']}, {a.out}/pareto_*.png")
    return 0
