"""The speed-against-error report: every registered method on every built-in and real-mesh scene.

Scenes: `motionblur.SCENES` (procedural, mostly convex) and
`motionblur.scenes_real.REAL_SCENES` (the bunny scan, the modelled ant, a torus and a
torus knot; translating, turning, coming toward the camera, one deforming). For each scene and
each method of `motionblur.METHODS` whose ``applies(scene)`` is true, every option set of
the method's ``sweep`` is rendered and timed (best of ``repeat`` after a warm-up), and measured
against **two references**:

- Mitsuba 3, time-sampled (K shutter times x spp): the physical ground truth. It casts shadows
  the rasterizer does not draw, so on the real-mesh scenes (a mover over a lit floor) every
  method carries that difference too;
- the method's own limit: the exact time integral ([`motionblur.exact`][motionblur.exact], the analytic method
  at a tight setting), or accumulation with ``limit_samples`` samples when given, on our
  rasterizer, at the same ``aa``: what a method would give with unlimited time, so the RMSE
  against it is the blur method's own error, without the renderers' differences.

References are cached under ``<out>/references/`` keyed by a hash of the scene and the
reference's settings ([`cache`][motionblur.evaluation.cache]). ``auto`` (the planner) gets one row per scene at its
default tolerance, and where it lands against the Pareto front (time at the error it reaches) is
reported. Outputs in ``<out>``:
``results.csv``, ``results.md`` (tables per scene, both references, the comparisons below),
``pareto_<scene>.png`` (error against time for both references, the front annotated),
``sheet_<scene>.png`` (labelled: the references and each method's most accurate option set
within a matched time, ``auto``'s) and ``html/index.html`` (a static page, [`html`][motionblur.evaluation.bench.html]).

Comparisons, measured in the same run: motion_volume against accumulation at equal error (and
re-timed in pairs), every method against accumulation at equal time, and accumulation with the
static layer drawn once against 16-pose pyrender accumulation (see `sweep`).

With a ``dask.distributed`` client (``client=``, or ``--dask local|ADDRESS`` on the command line)
the references and the errors are Dask tasks; the timings stay undisturbed ([`cluster`][motionblur.evaluation.cluster]).
"""

from __future__ import annotations

import json
import time
from contextlib import contextmanager
from dataclasses import dataclass, fields, replace
from pathlib import Path

import numpy as np

from .._optional import require_all
from ..methods.auto import DEFAULT_TOLERANCE, renders_shutter
from ..render import METHODS
from ..scene import Scene
from ..scenes_builtin import SCENES
from ..scenes_real import REAL_SCENES
from . import html, report
from . import reference as ref_mod
from .cluster import Dask, SceneRef, Serial, call_task, client_for, error_task, reference_task, timed_task
from .compare import equal_error, equal_time, front_row, landing, pareto_front
from .sweep import _label, _with_aa, paired_factor, paired_times, pyrender_comparison

__all__ = ["run", "main", "BenchOptions", "ALL_SCENES"]

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


@dataclass
class BenchOptions:
    """The settings of a report run ([`run`][motionblur.evaluation.bench.run] takes them as keywords too).

    ``width``, ``height``: pixels of the named scenes (a Scene passed in keeps its camera's);
    ``times`` (K) and ``spp``: Mitsuba's shutter times and samples per pixel per time; ``repeat``:
    timed renders per option set (best of, after a warm-up); ``methods``: restrict to these;
    ``sweeps``: optional ``{method: [options, ...]}`` replacing the registered sweeps; ``flip``:
    compute FLIP; ``pyrender_peer``: time 16-pose pyrender accumulation on the built-in scenes;
    ``save_images``: every image under ``images/``; ``aa``: spatial samples per pixel per axis
    given to every method that takes ``aa`` (and to the own-limit reference); ``limit_samples``:
    None (the own limit is [`motionblur.exact`][motionblur.exact]) or N for accumulation with N samples;
    ``auto``: add an ``auto`` row per scene; ``write_html``: the static page under ``html/``;
    ``seed``: Mitsuba's sampler seed."""

    width: int = 320
    height: int = 240
    times: int = 256
    spp: int = 4
    repeat: int = 3
    methods: list[str] | None = None
    sweeps: dict[str, list[dict]] | None = None
    flip: bool = True
    pyrender_peer: bool = True
    save_images: bool = False
    aa: int | None = 2
    limit_samples: int | None = None
    auto: bool = True
    write_html: bool = True
    seed: int = 0


def _options(options: BenchOptions | None, keywords: dict) -> BenchOptions:
    """``options`` (default: the defaults) with ``keywords`` replacing its fields."""
    base = BenchOptions() if options is None else options
    if not isinstance(base, BenchOptions):
        raise TypeError(f"options: expected a BenchOptions, got {type(base).__name__}")
    unknown = sorted(set(keywords) - {f.name for f in fields(BenchOptions)})
    if unknown:
        raise TypeError(f"run() got unexpected keyword(s) {', '.join(unknown)}; see BenchOptions")
    return replace(base, **keywords)


def _scene_refs(scenes, width: int, height: int) -> dict[str, object]:
    """``{name: SceneRef or Scene}`` of ``scenes``: names from `ALL_SCENES`, Scenes (named
    ``scene_<i>`` in the order given) or a ``{name: Scene or known name}`` dict."""
    if scenes is None:
        return {n: SceneRef(n, width, height) for n in ALL_SCENES}
    if isinstance(scenes, (str, Scene)):
        scenes = [scenes]
    items = list(scenes.items()) if isinstance(scenes, dict) else [(None, s) for s in scenes]
    out: dict[str, object] = {}
    for i, (key, s) in enumerate(items):
        if isinstance(s, Scene):
            name = f"scene_{i}" if key is None else str(key)
            out[name] = s
        elif isinstance(s, str):
            if s not in ALL_SCENES:
                raise ValueError(
                    f"scenes: unknown {s!r}; expected names from {', '.join(ALL_SCENES)} or motionblur.Scene objects"
                )
            out[s if key is None else str(key)] = SceneRef(s, width, height)
        else:
            raise TypeError(
                f"scenes: expected scene names or motionblur.Scene objects, got {type(s).__name__}"
            )
    return out


def _built(ref) -> Scene:
    return ref.build() if isinstance(ref, SceneRef) else ref


def _needed(opts: BenchOptions, refs_of: dict) -> list[str]:
    """The optional packages this run needs."""
    needed = ["mitsuba", "tqdm", "matplotlib", "PIL"] + ["flip_evaluator"] * bool(opts.flip)
    needed += ["pyrender", "trimesh"] * bool(opts.pyrender_peer)
    if any(isinstance(r, SceneRef) and r.name in REAL_SCENES for r in refs_of.values()):
        needed += ["trimesh"]
    return needed


class _Run:
    """One report run's state, filled by its numbered steps ([`run`][motionblur.evaluation.bench.run])."""

    def __init__(self, out: Path, refs_of: dict, opts: BenchOptions, log, client):
        self.out, self.refs_of, self.opts, self.log = out, refs_of, opts, log
        self.names = list(refs_of)
        self.built = {n: _built(r) for n, r in refs_of.items()}
        self.runner = Serial() if client is None else Dask(client)
        self.phases = _Phases()
        self.rows: list[dict] = []
        self.frames: dict = {}
        self.refs: dict = {}
        self.comparisons: dict = {}
        self.flip_comparisons: dict = {}
        self.equal_times: dict = {}
        self.paired: dict = {}
        self.pyr: list = []
        self.landings: dict = {}

    def references(self) -> None:
        """1. Every reference of the run, as parallel tasks on a cluster."""
        o = self.opts
        cache = str(self.out / "references")
        kinds = [("mitsuba", {"times": o.times, "spp": o.spp, "seed": o.seed}),
                 ("limit", {"samples": o.limit_samples, "aa": o.aa or 1})]  # fmt: skip
        jobs = [(self.refs_of[n], k, s, cache) for n in self.names for k, s in kinds]
        with self.phases("references"):
            images = self.runner.map(reference_task, *zip(*jobs))
        for i, n in enumerate(self.names):
            self.refs[n] = {"mitsuba": images[2 * i], "limit": images[2 * i + 1]}
        self.log(f"references: {len(jobs)} ({self.runner.name})")

    def scene(self, name: str) -> None:
        """2. One scene: timings one at a time, then the errors as tasks, the comparisons."""
        o, ref, runner, refs = self.opts, self.refs_of[name], self.runner, self.refs[name]
        real = isinstance(ref, SceneRef) and ref.name in REAL_SCENES
        todo = _jobs(self.built[name], o.methods, o.aa, REAL_SWEEPS if real and not o.sweeps else None)
        with self.phases("timed renders"):
            timed = runner.timed(timed_task, [(ref, m, opts, o.repeat) for m, opts in todo])
        with self.phases("errors"):
            n = len(timed)
            errs = runner.map(
                error_task, [t[1] for t in timed], [refs["mitsuba"]] * n, [refs["limit"]] * n, [o.flip] * n
            )
        scene_rows = [_row(name, m, opts, t[0], e) for (m, opts), t, e in zip(todo, timed, errs)]
        for r, t in zip(scene_rows, timed):
            self.frames[(name, r["method"], r["options"])] = t[1]
        self.rows += scene_rows
        self.comparisons[name] = equal_error(scene_rows)
        self.equal_times[name] = equal_time(scene_rows)
        self.flip_comparisons[name] = equal_error(scene_rows, metric="flip") if o.flip else []
        with self.phases("paired re-timing"):
            self.paired[name] = runner.timed(
                call_task, [(paired_factor, ref, scene_rows, "rmse", max(3, o.repeat))]
            )[0]
        # pyrender draws lambert flat: no comparison on the lit real scenes, nor on a user's scene
        if o.pyrender_peer and isinstance(ref, SceneRef) and ref.name in SCENES:
            with self.phases("pyrender"):
                self.pyr += runner.timed(call_task, [(_pyrender, ref, name, refs["mitsuba"], o.repeat)])
        for r in scene_rows:
            self.log(f"  {name:<18} {r['method']:<14} {r['options']:<28} {r['ms']:9.2f} ms  "
                     f"RMSE {r['rmse']:.5f}  own limit {r['rmse_limit']:.5f}")  # fmt: skip

    def auto_row(self, name: str) -> dict:
        """3. ``auto`` on one scene: its row, and where it lands against the Pareto front."""
        o, ref, runner, refs = self.opts, self.refs_of[name], self.runner, self.refs[name]
        opts = _with_aa(METHODS["auto"].fn, {}, o.aa)
        t = runner.timed(timed_task, [(ref, "auto", opts, max(o.repeat, 5))])[0]
        e = runner.map(error_task, [t[1]], [refs["mitsuba"]], [refs["limit"]], [o.flip])[0]
        r = _row(name, "auto", opts, t[0], e, t[2])
        self.frames[(name, "auto", r["options"])] = t[1]
        srows = [x for x in self.rows if x["scene"] == name]
        lg = landing(srows, r, DEFAULT_TOLERANCE)
        front = front_row(srows, r["rmse_limit"])
        if front is not None:  # re-timed in pairs: both under the same load
            jobs = [("auto", opts), (front["method"], front["_opts"])]
            pa, pf = runner.timed(call_task, [(paired_times, ref, jobs)])[0]
            lg.update(paired_auto_ms=pa, paired_front_ms=pf, paired_ratio=pa / pf)
            lg["front"] = f"{front['method']} {front['options']}"
        self.landings[name] = lg
        self.log(f"  {name:<18} auto {r['ms']:9.2f} ms  own limit {r['rmse_limit']:.5f}  front {lg['front_ms']:.2f} ms  "
                 f"ratio {lg['ratio']:.2f}, re-timed in pairs {lg.get('paired_ratio', float('nan')):.2f}")  # fmt: skip
        return r

    def write(self) -> dict:
        """4. The report's files: tables, plots, ``rows.json`` and the page."""
        o, out, names, rows = self.opts, self.out, self.names, self.rows
        fronts, fronts_limit = [], []
        for name in names:
            sel = [r for r in rows if r["scene"] == name]
            fronts += pareto_front(sel)
            fronts_limit += pareto_front([{**r, "rmse": r["rmse_limit"]} for r in sel])
        sizes = {(s.camera.width, s.camera.height) for s in self.built.values()}
        width, height = sizes.pop() if len(sizes) == 1 else (o.width, o.height)
        settings = dict(width=width, height=height, times=o.times, spp=o.spp, repeat=o.repeat, aa=o.aa,
                        variant=ref_mod.mitsuba_variant(), limit_samples=o.limit_samples, runner=self.runner.name,
                        tolerance=DEFAULT_TOLERANCE, phases=self.phases.summary())  # fmt: skip
        paths = report.write(
            out, names, rows, fronts, settings, comparisons=self.comparisons, flip_comparisons=self.flip_comparisons,
            paired=self.paired, equal_times=self.equal_times, pyrender_rows=self.pyr, fronts_limit=fronts_limit,
            frames=self.frames, references=self.refs, landings=self.landings, save_images=o.save_images,
        )  # fmt: skip
        # the measurements with their option sets
        (out / "rows.json").write_text(json.dumps({
            "size": [width, height], "aa": o.aa,
            "applies": {n: {m: METHODS[m].applies(self.built[n]) for m in METHODS} for n in names},
            "rows": [{k: v for k, v in r.items() if k != "_plan"} for r in rows],
        }, default=str))  # fmt: skip
        if o.write_html:
            paths["html"] = html.write(out, names, rows, paths, self.refs, self.frames, settings)
        return paths


def run(
    out="out/bench",
    scenes=None,
    options: BenchOptions | None = None,
    *,
    log=print,
    client=None,
    **keywords,
) -> dict:
    """Run the report and write it to ``out``; returns ``{"rows", "comparisons", "auto", "paths", ...}``.

    ``scenes``: what to measure (default every scene of `ALL_SCENES`): names from it, your
    own [`motionblur.Scene`][motionblur.Scene] objects (``run(scenes=[my_scene])``, named ``scene_0``,
    ``scene_1`` ... in the report and rendered at their own camera's size), or a ``{name: Scene
    or known name}`` dict. ``options``: a [`BenchOptions`][motionblur.evaluation.bench.BenchOptions]; its fields may also be given as
    keywords (``width=160, times=32, methods=[...]``), which replace the ``options``' values.
    ``client``: a ``dask.distributed.Client`` (see [`cluster`][motionblur.evaluation.cluster]); ``log``: where progress lines go.

    The run's steps: 1. every reference (Mitsuba and the own limit); 2. per scene, every method's
    option sets timed and measured; 3. ``auto`` per scene against the Pareto front; 4. the files.
    """
    opts = _options(options, keywords)
    refs_of = _scene_refs(scenes, opts.width, opts.height)
    require_all(_needed(opts, refs_of), "the speed-against-error report")
    if opts.pyrender_peer:
        from .reference import _require_gl_platform

        _require_gl_platform()  # before any work: the pyrender peer needs a GL platform
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    state = _Run(out, refs_of, opts, log, client)
    saved = {}
    for m, s in (opts.sweeps or {}).items():
        saved[m] = METHODS[m].sweep
        METHODS[m].sweep = [dict(o) for o in s]
    try:
        state.references()
        for name in state.names:
            state.scene(name)
        auto_rows = []
        if opts.auto and (opts.methods is None or "auto" in opts.methods):
            with state.phases("auto"):
                auto_rows = [state.auto_row(name) for name in state.names]
        state.rows += auto_rows
    finally:
        for m, s in saved.items():
            METHODS[m].sweep = s
    paths = state.write()
    log(f"bench: {state.phases.summary()}")
    return {
        "rows": state.rows,
        "comparisons": state.comparisons,
        "flip_comparisons": state.flip_comparisons,
        "paired": state.paired,
        "equal_time": state.equal_times,
        "pyrender": state.pyr,
        "auto": state.landings,
        "paths": paths,
        "references": {n: {k: np.asarray(v) for k, v in r.items()} for n, r in state.refs.items()},
    }


def main(argv=None) -> int:
    import argparse

    p = argparse.ArgumentParser(prog="python -m motionblur bench", description=__doc__.splitlines()[0])
    p.add_argument("--out", default="out/bench")
    p.add_argument("--scenes", nargs="*", default=None, help=f"subset of {', '.join(ALL_SCENES)}")
    p.add_argument(
        "--scene", action="append", default=[], metavar="FILE",
        help="your own scene: a .glb or .gltf file (read with Scene.from_gltf at --size); repeatable",
    )  # fmt: skip
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
    if a.scene:
        files = {Path(f).stem: Scene.from_gltf(f, width=w, height=h) for f in a.scene}
        scenes = {**{n: n for n in scenes or []}, **files}
    opts = BenchOptions(width=w, height=h, times=a.times, spp=a.spp, repeat=a.repeat, flip=not a.no_flip,
                        aa=a.aa, pyrender_peer=not a.no_pyrender, save_images=a.images,
                        limit_samples=a.limit_samples)  # fmt: skip
    client = client_for(a.dask) if a.dask else None
    try:
        res = run(a.out, scenes, opts, client=client)
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
