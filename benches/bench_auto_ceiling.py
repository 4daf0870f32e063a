"""How far ``auto``'s cost could fall: its plan against what any planner that certifies its frame
by accumulation's own estimate could pay, on seeded random scenes against the exact integral.

    python benches/bench_auto_ceiling.py [--set tuning|measuring] [--scenes 40] [--sizes 96x72,192x144]
        [--first-seed N] [--aa 1] [--tolerances 0.01,0.004,0.001]

Times are the process's CPU time at one thread (it sets one). For each scene where
something moves (no rolling shutter), against :func:`motionblur.exact` at the same ``aa``:

- every accumulation grid a planner asks for (stratified of N samples, auto's trapezoid grid of
  M strata, or N samples refined by a quarter or a half of their strata's boundaries) is
  rendered once, afresh (a refined grid after its stratified one), through auto's own trials
  (`_Trials.accumulate`): the halves' reading auto steers by (its estimate but at ``aa`` 4) and its measured RMSE are kept; the analytic frame (default and exact options) and
  the segment pilot too;
- time: accumulation at 1 to 256 samples (best of 3); a render that draws k new samples is
  charged the time of k interpolated, plus the estimate's overhead measured at 8 samples; the
  analytic frame and the pilot their measured times;
- three planners read the same renders:
  * **auto**: `motionblur.methods.auto._for_tolerance` itself, on the recorded estimates (the
    plan auto takes; its cost here is the model's, its error the measured one);
  * **doubling only**: the same without the refined grids (`_Trials.refines` off), as auto
    was before them;
  * **fixed first**: the same with the fixed first count (4 to 8) instead of the forecast;
  * **perfect next**: auto's first render, then the one next grid (holding the drawn samples or
    afresh, as `_next_grid` may choose) or the analytic frame that meets the tolerance, by the
    measured error, at the least time: any planner that starts as auto does and then knows every
    render's error;
  * **perfect first**: the first render at the fewest samples (even) whose measured error is at
    most 0.7x the tolerance (a perfect predictor of the need, with the margin the estimate's
    spread asks for), then auto's own steps: a planner with foresight that still certifies by
    the halves;
- the cheapest render that meets the tolerance, as in ``bench_error_control.py``: accumulation at
  1 to 4096 samples (powers of two and their 1.5x), the analytic frame, every other method's
  default; its time on the same model (accumulation) or measured (the others).

Prints, per size and tolerance, each planner's share of scenes that met the tolerance and its
time over the cheapest (median, p90, share within 1.5x). Writes ``results.md`` and
``rows.json`` to ``out/bench/auto_ceiling/<set><tag>``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

import motionblur as mb
from motionblur.evaluation.random_scenes import MEASURING_SEEDS, TUNING_SEEDS, random_scene
from motionblur.methods import _grids as grids
from motionblur.methods import auto as A
from motionblur.methods._refine import KINDS as REFINED_KINDS
from motionblur.methods._segments import segment_times
from motionblur.methods._sweep import sweep_scale
from motionblur.raster import over_background
from motionblur.threads import set_num_threads

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_error_control import ACC_GRID, other_renders, rmse  # noqa: E402  (the bench beside this one)

OUT = Path("out/bench/auto_ceiling")
TIMED = (1, 2, 4, 8, 16, 32, 64, 128, 256)
FORESIGHT = 0.7  # "perfect first": the first render's measured error at most this x the tolerance


def cpu_ms(fn, repeat: int = 3):
    best, out = math.inf, None
    for _ in range(repeat):
        t0 = time.process_time()
        out = fn()
        best = min(best, (time.process_time() - t0) * 1e3)
    return best, out


class Recorded:
    """One scene's renders, each made once: accumulation grids (estimate, measured error), the
    analytic frames, the other methods, and the time model."""

    def __init__(self, scene, aa: int) -> None:
        self.scene, self.aa = scene, aa
        self.ref = mb.exact(scene, aa=aa).rgba.astype(np.float64)
        self.grids: dict[tuple[int, str], tuple[float, float]] = {}
        self.times = [
            cpu_ms(lambda n=n: mb.render(scene, "accumulation", samples=n, error_estimate=False, aa=aa))[0]
            for n in TIMED
        ]
        with_estimate = cpu_ms(lambda: A._Trials(scene, aa).accumulate(8))[0]
        self.sweep_ms, self.sweep = cpu_ms(lambda: sweep_scale(scene))
        self.overhead = max(0.0, with_estimate - self.ms(8))
        self._analytic = None
        self._others: list[tuple[str, float, float]] | None = None

    def ms(self, n: int) -> float:
        """Accumulation of ``n`` samples, interpolated (extrapolated past the last timed)."""
        ns, ts = TIMED, self.times
        if n >= ns[-1]:
            return ts[-1] + (n - ns[-1]) * (ts[-1] - ts[-2]) / (ns[-1] - ns[-2])
        return float(np.interp(n, ns, ts))

    def grid(self, m: int, kind: str) -> tuple[float, float]:
        """(the halves' reading auto's plan reads, measured RMSE) of auto's grid of ``m`` strata
        of ``kind``."""
        key = (m, kind)
        if key not in self.grids:
            trials = A._Trials(self.scene, self.aa)
            if kind in REFINED_KINDS:  # refined: after the stratified grid it holds
                trials.accumulate(m)
            frame = trials.accumulate(m, kind)
            err = rmse(over_background(frame, self.scene.background).rgba, self.ref)
            self.grids[key] = (trials.tried[-1]["halves_reading"], err)
        return self.grids[key]

    def analytic(self) -> dict:
        if self._analytic is None:
            sc = self.scene
            moving = sc.objects if sc.camera_moves else [o for o in sc.objects if o.is_moving]
            pilot, segs = cpu_ms(lambda: len(segment_times(sc, moving, sc.camera)) - 1, 1)
            ms, f = cpu_ms(lambda: mb.render(sc, "analytic", error_estimate=False, aa=self.aa), 1)
            ems, g = cpu_ms(
                lambda: mb.render(sc, "analytic", error_estimate=False, aa=self.aa, **A.EXACT_OPTIONS), 1
            )
            self._analytic = {
                "pilot_ms": pilot, "segments": segs, "ms": ms, "err": rmse(f.rgba, self.ref),
                "exact_ms": ems, "exact_err": rmse(g.rgba, self.ref),
            }  # fmt: skip
        return self._analytic

    def others(self) -> list[tuple[str, float, float]]:
        """Every other method's default (the analytic frame apart: `analytic`)."""
        if self._others is None:
            skip = ("accumulation", "auto", "analytic")
            self._others = other_renders(self.scene, self.ref, self.aa, cpu_ms, skip)
        return self._others

    def cheapest(self, tol: float) -> tuple[str, float]:
        # the fewest samples that meet it: the grids past it are never rendered
        n = next((n for n in ACC_GRID if self.grid(n, grids.STRATIFIED)[1] <= tol), None)
        found = [] if n is None else [(f"accumulation-{n}", self.ms(n))]
        an = self.analytic()
        if an["err"] <= tol:
            found.append(("analytic", an["ms"]))
        found += [(m, ms) for m, ms, err in self.others() if err <= tol]
        return min(found, key=lambda x: x[1]) if found else ("none", math.nan)


class Replay(A._Trials):
    """auto's trials on a `Recorded` scene: the same decisions, each render looked up."""

    def __init__(self, rec: Recorded, refines: bool = True) -> None:
        super().__init__(rec.scene, rec.aa)
        self.rec = rec
        self.refines = self.refines and refines

    def _log(self, method: str, options: dict, ms: float, est: float, err: float, **more) -> None:
        self.tried.append(
            {"method": method, "options": options, "ms": ms, "error_estimate": est, "err": err, **more}
        )

    def accumulate(self, n: int, kind: str = grids.STRATIFIED) -> None:
        grid = (n, kind)
        draws = grids.samples(grid) if self.grid is None else grids.draws(grid, self.grid)
        est, err = self.rec.grid(n, kind)
        self.grid = grid
        self.effective.append((grids.effective(grid), est))
        options = {"samples": grids.samples(grid), **({"grid": kind} if kind != grids.STRATIFIED else {})}
        ms = self.rec.ms(draws) + self.rec.overhead
        self._log("accumulation", options, ms, est, err, halves_reading=est)

    def run(self, method: str, **options) -> None:
        an = self.rec.analytic()
        exact = options == A.EXACT_OPTIONS
        est = 0.0 if exact else A.ANALYTIC_ERROR
        self._log(
            method, options, an["exact_ms" if exact else "ms"], est, an["exact_err" if exact else "err"]
        )

    def first_samples(self, tol: float) -> int:
        """auto's first count, its forecast's pilot charged its recorded time."""
        n = A.first_samples(tol, self.rec.sweep, self.aa)
        self.tried.append(
            {"method": "accumulation", "options": {"pilot": "forecast"}, "ms": self.rec.sweep_ms}
        )
        return n

    def analytic_ms(self, segments: int | None = None) -> float:
        if segments is None and self.segments is None:  # the pilot's recorded time, once
            an = self.rec.analytic()
            self.segments = an["segments"]
            self.tried.append({"method": "analytic", "options": {"pilot": "segments"}, "ms": an["pilot_ms"]})
        return A._Trials.analytic_ms(self, self.segments if segments is None else segments)


def outcome(trials: Replay) -> tuple[float, float]:
    kept = [t for t in trials.tried if "pilot" not in t["options"]][-1]
    return kept["err"], sum(t["ms"] for t in trials.tried)


def plan_auto(rec: Recorded, tol: float) -> tuple[float, float]:
    trials = Replay(rec)
    A._for_tolerance(trials, tol)
    return outcome(trials)


def plan_doubling(rec: Recorded, tol: float) -> tuple[float, float]:
    trials = Replay(rec, refines=False)
    A._for_tolerance(trials, tol)
    return outcome(trials)


def plan_fixed_first(rec: Recorded, tol: float) -> tuple[float, float]:
    trials = Replay(rec)
    trials.first_samples = A.first_samples  # the count without the forecast (and its pilot)
    A._for_tolerance(trials, tol)
    return outcome(trials)


def plan_perfect_next(rec: Recorded, tol: float) -> tuple[float, float]:
    trials = Replay(rec)
    first = trials.first_samples(tol)
    est, err = rec.grid(first, grids.STRATIFIED)
    start = rec.ms(first) + rec.overhead + sum(t["ms"] for t in trials.tried)
    if err <= tol:
        return err, start
    best = (math.nan, math.inf)
    an = rec.analytic()
    for key, ms in (("err", an["ms"]), ("exact_err", an["exact_ms"])):
        if an[key] <= tol and start + ms < best[1]:
            best = (an[key], start + ms)
    start_grid = (first, grids.STRATIFIED)
    fresh = [(n, grids.STRATIFIED) for n in range(first + 2, grids.MAX_SAMPLES + 1, 2)]
    held = [(first * k, grids.STRATIFIED) for k in range(3, grids.MAX_SAMPLES // first + 1, 2)]
    held += [(first * k, grids.TRAPEZOID) for k in range(2, grids.MAX_SAMPLES // first, 2)]
    held += grids.refinements(start_grid) if trials.refines else []
    for grid in sorted(fresh + held, key=lambda g: grids.draws(g, start_grid)):
        cost = start + rec.ms(grids.draws(grid, start_grid)) + rec.overhead
        if cost >= best[1]:
            break  # sorted by draws: every later grid costs more
        if rec.grid(*grid)[1] <= tol:
            best = (rec.grid(*grid)[1], cost)
    return best


def plan_perfect_first(rec: Recorded, tol: float) -> tuple[float, float]:
    need = next(
        (
            n
            for n in range(2, grids.MAX_SAMPLES + 1, 2)
            if rec.grid(n, grids.STRATIFIED)[1] <= FORESIGHT * tol
        ),
        None,
    )
    trials = Replay(rec)
    trials.first_samples = lambda _tol: need if need is not None else grids.MAX_SAMPLES
    A._for_tolerance(trials, tol)
    return outcome(trials)


PLANNERS = {
    "auto": plan_auto,
    "doubling only": plan_doubling,
    "fixed first": plan_fixed_first,
    "perfect next": plan_perfect_next,
    "perfect first": plan_perfect_first,
}


def summarise(rows: list[dict]) -> str:
    lines = [
        "| size | tolerance | planner | scenes | met | time / cheapest: median | p90 | within 1.5x |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for size in dict.fromkeys(r["size"] for r in rows):
        for tol in dict.fromkeys(r["tolerance"] for r in rows):
            sel = [r for r in rows if r["size"] == size and r["tolerance"] == tol]
            for name in PLANNERS:
                met = np.mean([r[name]["err"] <= tol for r in sel])
                cost = np.array(
                    [r[name]["ms"] / r["cheapest_ms"] for r in sel if np.isfinite(r["cheapest_ms"])]
                )
                lines.append(
                    f"| {size} | {tol:g} | {name} | {len(sel)} | {met:.0%} | {np.median(cost):.2f} | "
                    f"{np.percentile(cost, 90):.2f} | {np.mean(cost <= 1.5):.0%} |"
                )
    return "\n".join(lines)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--set", choices=("measuring", "tuning"), default="tuning")
    p.add_argument("--scenes", type=int, default=40)
    p.add_argument("--sizes", default="96x72,192x144")
    p.add_argument("--first-seed", type=int, default=None, help="the first seed (in the set)")
    p.add_argument("--tolerances", default="0.01,0.004,0.001")
    p.add_argument("--aa", type=int, default=1, choices=(1, 2, 4))
    p.add_argument("--tag", default="")
    args = p.parse_args()
    set_num_threads(1)
    pool = MEASURING_SEEDS if args.set == "measuring" else TUNING_SEEDS
    first = 0 if args.first_seed is None else pool.index(args.first_seed)
    seeds = pool[first : first + args.scenes]
    tols = [float(t) for t in args.tolerances.split(",")]
    rows = []
    for size in args.sizes.split(","):
        w, h = map(int, size.split("x"))
        for seed in seeds:
            scene = random_scene(seed, w, h)
            if not A._moves(scene) or scene.rolling > 0.0:
                continue
            t0 = time.perf_counter()
            rec = Recorded(scene, args.aa)
            for tol in tols:
                label, cms = rec.cheapest(tol)
                row = {"seed": seed, "size": size, "tolerance": tol, "cheapest": label, "cheapest_ms": cms}
                for name, plan in PLANNERS.items():
                    err, ms = plan(rec, tol)
                    row[name] = {"err": err, "ms": ms}
                rows.append(row)
            print(f"{size} seed {seed}: {time.perf_counter() - t0:.1f} s", flush=True)
    out = OUT / (args.set + args.tag)
    out.mkdir(parents=True, exist_ok=True)
    (out / "rows.json").write_text(json.dumps(rows, indent=1))
    text = summarise(rows)
    head = f"# {args.set} set, seeds {seeds.start}..{seeds.stop - 1}, aa={args.aa}, CPU time (model)\n\n"
    (out / "results.md").write_text(head + text + "\n")
    print(text)


if __name__ == "__main__":
    main()
