"""The speed-against-error report: every registered method on every built-in and real-mesh scene.

Scenes: :data:`motionblur.SCENES` (procedural, mostly convex) and
:data:`motionblur.scenes_real.REAL_SCENES` (the bunny scan, the modelled ant, a torus and a
torus knot; translating, turning, coming toward the camera, one deforming). For each scene and
each method of :data:`motionblur.METHODS` whose ``applies(scene)`` is true, every option set of
the method's ``sweep`` is rendered and timed (best of ``repeat`` after a warm-up), and measured
against **two references**:

- Mitsuba 3, time-sampled (K shutter times x spp): the physical ground truth. It casts shadows
  the rasterizer does not draw, so on the real-mesh scenes (a mover over a lit floor) every
  method carries that difference too;
- the method's own limit: the exact time integral (:func:`motionblur.exact`, the analytic method
  at a tight setting), or accumulation with ``limit_samples`` samples when given, on our
  rasterizer, at the same ``aa``: what a method would give with unlimited time, so the RMSE
  against it is the blur method's own error, without the renderers' differences.

References are cached under ``<out>/references/`` keyed by a hash of the scene and the
reference's settings (:mod:`.cache`). ``auto`` (the planner) gets one row per scene at its
default tolerance, and where it lands against the Pareto front (time at the error it reaches) is
reported. Outputs in ``<out>``:
``results.csv``, ``results.md`` (tables per scene, both references, the comparisons below),
``pareto_<scene>.png`` (error against time for both references, the front annotated),
``sheet_<scene>.png`` (labelled: the references and each method's most accurate option set
within a matched time, ``auto``'s) and ``html/index.html`` (a static page, :mod:`.html`).

Comparisons, measured in the same run: motion_volume against accumulation at equal error (and
re-timed in pairs), every method against accumulation at equal time, and accumulation with the
static layer drawn once against 16-pose pyrender accumulation (see :mod:`.sweep`).

With a ``dask.distributed`` client (``client=``, or ``--dask local|ADDRESS`` on the command line)
the references and the errors are Dask tasks; the timings stay undisturbed (:mod:`.cluster`).
"""

from __future__ import annotations

import json
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from .._optional import require_all
from ..methods.auto import DEFAULT_TOLERANCE, renders_shutter
from ..render import METHODS
from ..scenes_builtin import SCENES
from ..scenes_real import REAL_SCENES
from . import html, report
from . import reference as ref_mod
from .cluster import Dask, SceneRef, Serial, call_task, client_for, error_task, reference_task, timed_task
from .compare import equal_error, equal_time, front_row, landing, pareto_front
from .sweep import _label, _with_aa, paired_factor, paired_times, pyrender_comparison

__all__ = ["run", "main", "ALL_SCENES"]

#: Every scene the report knows: the built-in ones, then the real-mesh ones.
ALL_SCENES = {**SCENES, **REAL_SCENES}
#: The option sets run on the real-mesh scenes (every shutter there is a box: the motion volume's
#: other filters are looks, not measurements; the analytic method takes 0.3-2 s a frame on them,
#: so three of its option sets): 22 runs a scene instead of 44, to keep ``make bench`` in time.
REAL_SWEEPS = {
    "accumulation": [{"samples": n} for n in (1, 2, 4, 8, 16, 32, 64, 128, 256)],
    "motion_volume": [{"segments": s, "filter": "box"} for s in (1, 2, 4, 8)]
    + [{"segments": 1, "filter": "box", "color_renders": n} for n in (1, 4)],
    "analytic": [{"gauss": "auto"}, {"gauss": 1}, {"aa": 1}],
    "blur_shell": [{"subdivisions": 4}, {"subdivisions": 16}],
    "opaque_image": [{"aa": 1}, {"aa": 2}],
}
#: The scenes of ``--quick``: two built-in, three real-mesh (concave, turning, deforming).
QUICK_SCENES = ("cube", "pan", "bunny_turn", "torus_toward", "knot_twist")


def _jobs(scene, methods, aa, sweeps=None) -> list[tuple[str, dict]]:
    """The (method, options) runs of ``scene``. An option set naming another shutter ``filter``
    than the scene's renders a different shutter than the references integrate (the motion
    volume's ramp, triangle and gaussian looks on a box shutter): not a measurement, left out, as
    ``auto`` never chooses it."""
    out = []
    for mname, spec in METHODS.items():
        if mname == "auto" or (methods is not None and mname not in methods) or not spec.applies(scene):
            continue
        sweep = spec.sweep if sweeps is None else sweeps.get(mname, [])
        out += [(mname, _with_aa(spec.fn, o, aa)) for o in sweep if renders_shutter(o, scene)]
    return out


def _pyrender(scene, name, ref, repeat):
    return pyrender_comparison(name, scene, ref, repeat)


class _Phases:
    """Wall seconds spent in each phase of a run (``with phases("name"): ...`` adds to it)."""

    def __init__(self):
        self.seconds: dict[str, float] = {}
        self.start = time.perf_counter()

    @contextmanager
    def __call__(self, name: str):
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[name] = self.seconds.get(name, 0.0) + time.perf_counter() - t0

    def summary(self) -> str:
        total = time.perf_counter() - self.start
        parts = ", ".join(f"{k} {v:.0f} s" for k, v in sorted(self.seconds.items(), key=lambda kv: -kv[1]))
        return f"{total:.0f} s in all: {parts}"


def _row(name, method, opts, ms, err, plan=None) -> dict:
    row = {"scene": name, "method": method, "options": _label(opts), "_opts": opts, "ms": ms, **err}
    if plan:
        row["_plan"] = plan
    return row


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
    client=None,
    limit_samples: int | None = None,
    auto: bool = True,
    write_html: bool = True,
    seed: int = 0,
) -> dict:
    """Run the report and write it to ``out``; returns ``{"rows", "comparisons", "auto", "paths", ...}``.

    ``scenes``: names from :data:`ALL_SCENES` (default all); ``sweeps``: optional ``{method:
    [options, ...]}`` replacing the registered sweeps; ``methods``: restrict to these; ``aa``:
    spatial samples per pixel per axis given to every method that takes ``aa`` (and to the
    own-limit reference); ``client``: a ``dask.distributed.Client`` (see :mod:`.cluster`);
    ``limit_samples``: None (the own limit is :func:`motionblur.exact`, the exact time integral)
    or N for accumulation with N samples instead; ``auto``: add an ``auto`` row per scene;
    ``save_images``: every image under ``images/``;
    ``write_html``: the static page under ``html/``.
    """
    names = list(ALL_SCENES) if scenes is None else list(scenes)
    unknown = [n for n in names if n not in ALL_SCENES]
    if unknown:
        raise ValueError(f"scenes: unknown {unknown}; expected names from {', '.join(ALL_SCENES)}")
    needed = ["mitsuba", "tqdm", "matplotlib", "PIL"] + ["flip_evaluator"] * bool(flip)
    needed += ["pyrender", "trimesh"] * bool(pyrender_peer)
    if any(n in REAL_SCENES for n in names):
        needed += ["pymeshfix", "pyvista", "fast_simplification"]
    require_all(needed, "the speed-against-error report")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    runner = Serial() if client is None else Dask(client)
    phases = _Phases()
    saved = {}
    if sweeps:
        for m, s in sweeps.items():
            saved[m] = METHODS[m].sweep
            METHODS[m].sweep = [dict(o) for o in s]
    refs_of = {name: SceneRef(name, width, height) for name in names}  # what tasks get: scenes do not pickle
    built = {name: refs_of[name].build() for name in names}
    cache = str(out / "references")
    mits_settings = {"times": times, "spp": spp, "seed": seed}
    limit_settings = {"samples": limit_samples, "aa": aa or 1}
    rows, frames, refs, comparisons, flip_comparisons, equal_times, paired, pyr = (
        [],
        {},
        {},
        {},
        {},
        {},
        {},
        [],
    )
    try:
        # 1. every reference of the run, as parallel tasks on a cluster
        kinds = [("mitsuba", mits_settings), ("limit", limit_settings)]
        jobs = [(refs_of[n], k, s, cache) for n in names for k, s in kinds]
        with phases("references"):
            images = runner.map(reference_task, *zip(*jobs))
        for i, n in enumerate(names):
            refs[n] = {"mitsuba": images[2 * i], "limit": images[2 * i + 1]}
        log(f"references: {len(jobs)} ({runner.name})")
        # 2. per scene: timings one at a time, then the errors as tasks
        for name in names:
            scene = built[name]
            todo = _jobs(scene, methods, aa, REAL_SWEEPS if name in REAL_SCENES and not sweeps else None)
            with phases("timed renders"):
                timed = runner.timed(timed_task, [(refs_of[name], m, o, repeat) for m, o in todo])
            with phases("errors"):
                errs = runner.map(
                    error_task, [t[1] for t in timed], [refs[name]["mitsuba"]] * len(timed),
                    [refs[name]["limit"]] * len(timed), [flip] * len(timed),
                )  # fmt: skip
            scene_rows = [_row(name, m, o, t[0], e) for (m, o), t, e in zip(todo, timed, errs)]
            for r, t in zip(scene_rows, timed):
                frames[(name, r["method"], r["options"])] = t[1]
            rows += scene_rows
            comparisons[name] = equal_error(scene_rows)
            equal_times[name] = equal_time(scene_rows)
            flip_comparisons[name] = equal_error(scene_rows, metric="flip") if flip else []
            with phases("paired re-timing"):
                paired[name] = runner.timed(
                    call_task, [(paired_factor, refs_of[name], scene_rows, "rmse", max(3, repeat))]
                )[0]
            if (
                pyrender_peer and name in SCENES
            ):  # pyrender draws lambert flat: no comparison on the lit real scenes
                with phases("pyrender"):
                    pyr += runner.timed(
                        call_task, [(_pyrender, refs_of[name], name, refs[name]["mitsuba"], repeat)]
                    )
            for r in scene_rows:
                log(f"  {name:<18} {r['method']:<14} {r['options']:<28} {r['ms']:9.2f} ms  "
                    f"RMSE {r['rmse']:.5f}  own limit {r['rmse_limit']:.5f}")  # fmt: skip
        # 3. auto: one row per scene
        with phases("auto"):
            auto_rows, landings = [], {}
            if auto and (methods is None or "auto" in methods):
                for name in names:
                    opts = _with_aa(METHODS["auto"].fn, {}, aa)
                    t = runner.timed(timed_task, [(refs_of[name], "auto", opts, max(repeat, 5))])[0]
                    e = runner.map(
                        error_task, [t[1]], [refs[name]["mitsuba"]], [refs[name]["limit"]], [flip]
                    )[0]
                    r = _row(name, "auto", opts, t[0], e, t[2])
                    frames[(name, "auto", r["options"])] = t[1]
                    auto_rows.append(r)
                    srows = [x for x in rows if x["scene"] == name]
                    lg = landing(srows, r, DEFAULT_TOLERANCE)
                    front = front_row(srows, r["rmse_limit"])
                    if front is not None:  # re-timed in pairs: both under the same load
                        jobs = [("auto", opts), (front["method"], front["_opts"])]
                        pa, pf = runner.timed(call_task, [(paired_times, refs_of[name], jobs)])[0]
                        lg.update(paired_auto_ms=pa, paired_front_ms=pf, paired_ratio=pa / pf)
                        lg["front"] = f"{front['method']} {front['options']}"
                    landings[name] = lg
                    log(f"  {name:<18} auto {r['ms']:9.2f} ms  own limit {r['rmse_limit']:.5f}  front {lg['front_ms']:.2f} ms  "
                        f"ratio {lg['ratio']:.2f}, re-timed in pairs {lg.get('paired_ratio', float('nan')):.2f}")  # fmt: skip
        rows += auto_rows
    finally:
        for m, s in saved.items():
            METHODS[m].sweep = s
    fronts, fronts_limit = [], []
    for name in names:
        sel = [r for r in rows if r["scene"] == name]
        fronts += pareto_front(sel)
        fronts_limit += pareto_front([{**r, "rmse": r["rmse_limit"]} for r in sel])
    settings = dict(width=width, height=height, times=times, spp=spp, repeat=repeat, aa=aa,
                    variant=ref_mod.mitsuba_variant(), limit_samples=limit_samples, runner=runner.name,
                    tolerance=DEFAULT_TOLERANCE, phases=phases.summary())  # fmt: skip
    paths = report.write(
        out, names, rows, fronts, settings, comparisons=comparisons, flip_comparisons=flip_comparisons,
        paired=paired, equal_times=equal_times, pyrender_rows=pyr, fronts_limit=fronts_limit,
        frames=frames, references=refs, landings=landings, save_images=save_images,
    )  # fmt: skip
    # the measurements with their option sets
    (out / "rows.json").write_text(json.dumps({
        "size": [width, height], "aa": aa,
        "applies": {n: {m: METHODS[m].applies(built[n]) for m in METHODS} for n in names},
        "rows": [{k: v for k, v in r.items() if k != "_plan"} for r in rows],
    }, default=str))  # fmt: skip
    if write_html:
        paths["html"] = html.write(out, names, rows, paths, refs, frames, settings)
    log(f"bench: {phases.summary()}")
    return {
        "rows": rows,
        "comparisons": comparisons,
        "flip_comparisons": flip_comparisons,
        "paired": paired,
        "equal_time": equal_times,
        "pyrender": pyr,
        "auto": landings,
        "paths": paths,
        "references": {n: {k: np.asarray(v) for k, v in r.items()} for n, r in refs.items()},
    }


def main(argv=None) -> int:
    import argparse

    p = argparse.ArgumentParser(prog="python -m motionblur bench", description=__doc__.splitlines()[0])
    p.add_argument("--out", default="out/bench")
    p.add_argument("--scenes", nargs="*", default=None, help=f"subset of {', '.join(ALL_SCENES)}")
    p.add_argument(
        "--set", choices=["all", "builtin", "real"], default="all", help="which scenes (default all)"
    )
    p.add_argument("--size", default="320x240", help="WxH")
    p.add_argument("--aa", type=int, default=2, help="spatial samples per pixel per axis for every method")
    p.add_argument("--times", type=int, default=256, help="Mitsuba shutter times K")
    p.add_argument("--spp", type=int, default=4, help="Mitsuba samples per pixel per time")
    p.add_argument("--limit-samples", type=int, default=None,
                   help="N of an accumulation own-limit reference (default: the exact integral, motionblur.exact)")  # fmt: skip
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--no-flip", action="store_true")
    p.add_argument("--no-pyrender", action="store_true", help="leave out the pyrender comparison")
    p.add_argument("--images", action="store_true", help="save every image under images/")
    p.add_argument(
        "--dask", default=None, metavar="local|ADDRESS", help="references and errors as Dask tasks"
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help=f"160x120, K = 64, N = 256, one timing, no pyrender, scenes {' '.join(QUICK_SCENES)}",
    )
    a = p.parse_args(argv)
    w, h = (int(x) for x in a.size.lower().split("x"))
    if a.quick:
        w, h, a.times, a.repeat, a.no_pyrender = 160, 120, 64, 1, True
    scenes = a.scenes if a.scenes is not None or not a.quick else list(QUICK_SCENES)
    if scenes is None and a.set != "all":
        scenes = list(SCENES if a.set == "builtin" else REAL_SCENES)
    client = client_for(a.dask) if a.dask else None
    try:
        res = run(a.out, scenes, w, h, a.times, a.spp, a.repeat, flip=not a.no_flip, aa=a.aa,
                  pyrender_peer=not a.no_pyrender, save_images=a.images, client=client,
                  limit_samples=a.limit_samples)  # fmt: skip
    finally:
        if client is not None:
            Dask(client, owns=True).close()
    md = res["paths"]["md"].read_text()
    start = md.find("## auto against the Pareto front")
    print(md[start if start >= 0 else 0 :])
    print(
        f"written: {res['paths']['md']}, {res['paths']['csv']}, {a.out}/pareto_*.png, {res['paths'].get('html')}"
    )
    return 0
