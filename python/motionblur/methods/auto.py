"""The planner (method ``auto``): a frame whose measured error meets a tolerance, or the most
accurate frame that fits a time budget.

``auto`` certifies what it returns by measurement, not by prediction. Its candidates are the two
methods that measure their own distance from the exact time integral ([`motionblur.exact`][motionblur.exact])
while they render: accumulation, whose two interleaved halves of time samples give its error
(``stats["error_estimate"]``, the halves' RMS difference; its error falls as 1/N), and the
analytic method, exact to about `ANALYTIC_ERROR` at its defaults and to 1e-5 at
`motionblur.methods._estimate.EXACT_OPTIONS`.

With ``tolerance`` (RMSE against the exact integral, premultiplied linear RGBA):

1. a scene where nothing moves on screen is one sharp frame (its error is 0);
2. accumulation with [`first_samples`][motionblur.methods.auto.first_samples] samples measures
   the scene's error at that N: as many as a forecast from the scene's geometry
   (`motionblur.methods._sweep`: how far the moving outlines travel on screen, against what
   colour) says bring the error to `FIRST_AIM` x ``tolerance``, so that the first render is
   often the last; the forecast only picks N, the render's halves certify it;
3. since the error falls about as 1/N (`RATE`), the N that brings the halves' reading (the
   estimate, but at ``aa`` 4 before `_accumulate.resonance`, as the rules below were tuned) under
   ``tolerance`` x `SAFETY` (per ``aa``) is predicted and rendered, keeping the samples drawn (`_grids.next_grid`):
   accumulation's samples cut the shutter's mass into equal strata under any shutter, so an
   odd multiple of the count holds them, and so does the trapezoid grid (`_Trials._trapezoid`,
   the strata's ends instead of their middles, one sample more) of any even multiple, which
   then refines to any multiple of itself; a fresh render is taken when keeping them would
   draw over `REUSE_DRAWS` x its new samples. A frame that missed narrowly adds a quarter or a
   half of its strata's boundaries instead (`motionblur.methods._refine`, at ``aa`` 1 under
   the box shutter: about N / 4 or N / 2 samples more for 0.91x or 0.80x the error, where the
   trapezoid grid draws N + 1). With fewer than `SURE_SAMPLES` samples the aim is lower: their
   halves spread more. Again while the estimate says it missed (each step
   predicted from the last two measurements, at most `MAX_STEPS` steps);
4. where the analytic frame's predicted time (`ANALYTIC_FIT`, from the first render's time per
   sample, the segments, the moving triangles, the shutter and the camera) x `ANALYTIC_MARGIN`
   is under that of the samples accumulation would still draw, or N would exceed `MAX_SAMPLES`,
   or the tolerance is under what accumulation can certify cheaply, the analytic method
   renders instead (at the exact options below `ANALYTIC_ERROR` x 2).

With ``budget_ms``: accumulation with 4 samples measures the time per sample; the analytic
frame follows where its predicted time fits `BUDGET_SHARE` of the time left (it is more
accurate than any accumulation that fits); else accumulation grows, keeping the samples drawn
(`_grids.holds`: an odd multiple, or a trapezoid grid), to the most that fit `BUDGET_SHARE` of the
time left at the time per sample its last render took, measured against the clock at every step.

``Frame.stats["plan"]`` lists every render tried (method, options, ms, error estimate, and for
accumulation the halves' reading its step read) and why the last was kept;
``stats["error_estimate"]`` is the kept frame's own.
"""

from __future__ import annotations

import math
import time

import numpy as np

from .._validate import as_float
from ..raster import Frame
from ..render import METHODS, register
from ..scene import Scene
from . import _grids
from ._accumulate import HalfSums, add_stratified
from ._estimate import EXACT_OPTIONS
from ._grids import MAX_SAMPLES, REUSE_DRAWS, STRATIFIED, TRAPEZOID
from ._refine import refine
from ._segments import segment_times
from ._sharp import check_aa
from ._sweep import sweep_scale

__all__ = [
    "auto",
    "layered_translucency",
    "STRATIFIED",
    "TRAPEZOID",
    "renders_shutter",
    "DEFAULT_TOLERANCE",
    "SAFETY",
    "FIRST_SAMPLES",
    "FIRST_SCALE",
    "FIRST_MAX",
    "FIRST_FIT",
    "FIRST_AIM",
    "FIRST_MOST",
    "first_samples",
    "MAX_SAMPLES",
    "RATE",
    "SURE_SAMPLES",
    "MAX_STEPS",
    "ANALYTIC_ERROR",
    "ANALYTIC_FIT",
    "MARGINAL_SAMPLE",
    "ANALYTIC_MARGIN",
    "REUSE_DRAWS",
    "BUDGET_SHARE",
]

#: The default tolerance: RMSE against the exact time integral (premultiplied linear RGBA).
DEFAULT_TOLERANCE = 0.01
#: The share of the tolerance auto aims its estimate at, per ``aa`` (the estimate's own spread):
#: the largest in steps of 0.05, at most 1, that kept every tuning scene under its tolerance in
#: the replay of auto's plans (``benches/bench_auto_ceiling.py``, tolerances 0.01, 0.004 and
#: 0.001). At ``aa`` 1, where the 5th percentile of estimate / error is 0.88-0.93 from 8
#: samples, 1 kept seeds 0-39 (96x72 and 192x144) but let one scene of 80 over at 0.01 and at
#: 0.001 at each size on seeds 40-119 (1.01-1.06), where 0.95 kept every one (at 2-4% more
#: time at the median); at ``aa`` 2 and 4, whose 5th percentile is 0.76-0.85, 0.95 (1 let one
#: scene in 40 to 1.2x).
SAFETY = {1: 0.95, 2: 0.95, 4: 0.95}
#: Below this many samples the halves hold few samples each and their estimate spreads more:
#: the aim shrinks as sqrt(N / SURE_SAMPLES) (chosen on the tuning scenes: at 8 stratified samples
#: the 5th percentile of estimate / error there is 0.85-0.89 (two sets of seeds), at 6 it is 0.69
#: and at 4 0.55).
SURE_SAMPLES = 8
#: Fewest time samples of the first accumulation render (two halves of 2).
FIRST_SAMPLES = 4
#: The first render's samples for tolerance ``tol``: ``FIRST_SCALE / tol`` rounded to even, at
#: least `FIRST_SAMPLES` and at most `FIRST_MAX`, about what the easier tuning scenes need at
#: that tolerance, so that the first render is often the last (`first_samples`).
FIRST_SCALE = 0.08
#: Most time samples of the first accumulation render (12 before the trapezoid grid: from 8 a
#: refinement to 17 or 33 keeps them; on tuning seeds 0-39 at 0.004 and 0.001 auto drew 0.89-0.97x
#: the samples of 12 first, mean over scenes).
FIRST_MAX = 8
#: The forecast of accumulation's error before anything renders, per ``aa``: RMSE of ``n``
#: stratified samples about ``exp(c[0]) * sweep^c[1] * n^c[2]``, ``sweep`` the scene's
#: `_sweep.sweep_scale`. Least squares on log RMSE over tuning scenes (seeds 0-119 at 96x72,
#: 0-79 at 192x144; 2 to 32 samples). At ``aa`` 1, fitted on the odd seeds and tried on the even
#: ones and back, 80% of the measured errors lie within 0.51-1.53x the forecast (on seeds
#: 120-299 at 96x72, not fitted on: 0.65-1.74x, median 1.08). At ``aa`` 2 and 4 the fit is to the
#: error estimate, which certifies the frame (at ``aa`` 4 it over-reads the error where N is
#: near the screen path in pixels): 80% within 0.51-1.86x (``aa`` 2) and 0.43-2.20x (``aa`` 4),
#: cross-fitted the same way. More spatial samples a pixel smooth each outline's step, so the
#: error falls faster with N (exponents -1.15 and -1.29 against -1.02).
FIRST_FIT = {
    1: (-1.858, 0.730, -1.022),
    2: (-1.810, 0.784, -1.153),
    4: (-1.550, 0.847, -1.286),
}
#: The share of the tolerance the first render's forecast error is aimed at (chosen on tuning
#: seeds 0-79 at 96x72 and 192x144 among 0.5 to 0.85: the least time over the cheapest render).
FIRST_AIM = 0.7
#: Most time samples of a first render the forecast picks.
FIRST_MOST = 256
#: The rate auto first assumes the error falls at, as N^-RATE (1 for an edge's coverage at one
#: point; slower where a pixel sees many edges), until two renders show their own.
RATE = 1.0
#: Most accumulation renders after the first.
MAX_STEPS = 3
#: The analytic frame's predicted time (ms): ``exp(c[0]) * ms^c[1] * n^c[2] * (segments + 1)^c[3]
#: * triangles^c[4] * exp(c[5] * other_shutter + c[6] * camera_moves)``, ``ms`` the first
#: accumulation render's time per sample and ``n`` its samples, ``segments`` by the analytic
#: method's rule, ``triangles`` those of the moving objects (all with a moving camera),
#: ``other_shutter`` 1 under a shutter other than the box. Least squares on log time over tuning
#: scenes (seeds 0-59 at 96x72, 0-39 at 192x144; CPU time, one thread): the prediction is within
#: a factor 0.33-1.9 of the time on 90% of them (leave-one-seed-out).
ANALYTIC_FIT = (-0.261, 0.927, 0.449, 0.753, 0.247, 0.32, 0.267)
#: The time of one more accumulation sample over the first render's time per sample (which
#: carries the frame's fixed costs; median on the same tuning scenes, 8 and 12 samples).
MARGINAL_SAMPLE = 0.6
#: The analytic frame replaces accumulation when its predicted time x this is under the
#: predicted time of the samples accumulation still needs (chosen on the same tuning scenes:
#: the lowest mean time over the cheaper of the two, simulated for 12 to 384 more samples).
ANALYTIC_MARGIN = 1.2
#: The share of the budget's remaining time a render is planned to take (the rest is margin
#: for the time per sample's spread).
BUDGET_SHARE = 0.8
#: The analytic method's error against the exact integral at its defaults (largest measured on
#: the tuning scenes, with margin): below twice this tolerance it runs at the exact options.
ANALYTIC_ERROR = 1e-4


def renders_shutter(options: dict, scene: Scene) -> bool:
    """Whether a method run with ``options`` renders ``scene``'s shutter: False when the options
    name another ``filter`` than the scene's (the motion volume's ramp, triangle or gaussian looks
    on a box shutter). The report does not measure such a run against the scene's integral."""
    shutter = scene.shutter if isinstance(scene.shutter, str) else "weights"
    return options.get("filter", shutter) == shutter


def layered_translucency(scene: Scene) -> bool:
    """Whether ``scene`` has translucent objects with another shading mode or (under a still
    camera) static objects: where accumulation once merged separate layers with one depth a
    pixel (a bias its halves could not see). It now draws such a scene's objects together at
    every sample, sorted by depth, so its limit is the exact integral and ``auto`` treats the
    scene like any other."""
    if not any(o.is_transparent for o in scene.objects):
        return False
    layers = {o.shading for o in scene.objects}
    return len(layers) > 1 or (not scene.camera_moves and any(not o.is_moving for o in scene.objects))


def _moves(scene: Scene) -> bool:
    return scene.camera_moves or any(o.is_moving for o in scene.objects)


class _Trials:
    """The renders auto tried, in order, each timed and with its error estimate."""

    def __init__(self, scene: Scene, aa: int) -> None:
        self.scene, self.aa, self.tried, self.frames = scene, aa, [], []
        self.sums: HalfSums | None = None
        self.grid: tuple[int, str] | None = None  # the strata of the samples drawn and the grid's kind
        self.segments: int | None = None  # the analytic method's segments, once its pilot ran
        # the stratified grids are drawn by residue so that they refine by boundaries
        # (`_refine`): at aa 1 under the box shutter, where their estimate is calibrated
        self.refines = aa == 1 and isinstance(scene.shutter, str) and scene.shutter == "box"
        self.effective: list[tuple[float, float]] = []  # (effective samples, estimate) per grid

    def _record(self, method: str, options: dict, frame: Frame, ms: float, est: float, **more) -> Frame:
        frame.stats["error_estimate"] = est
        self.tried.append(
            {"method": method, "options": dict(options), "ms": round(ms, 3), "error_estimate": est, **more}
        )
        self.frames.append(frame)
        return frame

    def run(self, method: str, **options) -> Frame:
        t0 = time.perf_counter()
        frame = METHODS[method].fn(self.scene, aa=self.aa, **options)
        ms = (time.perf_counter() - t0) * 1e3
        est = frame.stats.get("error_estimate", 0.0)
        if method == "analytic":
            est = 0.0 if options == EXACT_OPTIONS else ANALYTIC_ERROR
        elif not options.get("samples", 2) > 1:
            est = 0.0  # the one sharp frame of a scene where nothing moves
        return self._record(method, options, frame, ms, est)

    def accumulate(self, n: int, kind: str = STRATIFIED) -> Frame:
        """Accumulation with ``n`` samples of equal weight (`_accumulate.sample_times`), with the
        ``n + 1`` of the trapezoid grid of ``n`` strata (`TRAPEZOID`: see `_trapezoid`), or with
        ``n`` stratified samples and some of their strata's boundaries (a kind of
        `_refine.KINDS`). The samples already drawn are kept when the new grid holds them
        (`_grids.holds`: their times are among the new ones under any shutter, whose strata are of
        the shutter's mass) and only the others are drawn."""
        t0 = time.perf_counter()
        keep = self.grid is not None and _grids.holds((n, kind), self.grid)
        if not keep:
            self.sums = HalfSums(self.scene, self.aa)
        if kind == TRAPEZOID:
            self._trapezoid(n, keep)
        elif kind == STRATIFIED:
            self._stratified(n, keep)
        else:
            if self.sums is None or not keep:
                raise ValueError(f"kind: {kind!r} refines the stratified grid of {n} drawn before it")
            refine(self.sums, self.scene, n, kind)
        self.grid = (n, kind)
        frame = self.sums.frame()
        ms = (time.perf_counter() - t0) * 1e3
        options = {"samples": self.sums.samples, **({"grid": kind} if kind != STRATIFIED else {})}
        reading = self.sums.reading  # what the plan certifies by (`_accumulate.resonance` aside)
        self.effective.append((_grids.effective(self.grid), reading))
        est = frame.stats["error_estimate"]
        return self._record("accumulation", options, frame, ms, est, halves_reading=reading)

    def _stratified(self, n: int, keep: bool) -> None:
        """Accumulation's own ``n`` samples, the drawn ones (an ``n / last``-th of them) kept
        (`add_stratified`), drawn by residue where the grid may be refined."""
        assert self.sums is not None
        kept = self.grid[0] if keep and self.grid else 0
        add_stratified(self.sums, self.scene, n, kept, residues=self.refines)

    def _trapezoid(self, m: int, keep: bool) -> None:
        """The trapezoid grid of ``m`` strata of the shutter's mass: times ``W^-1(k / m)``, k = 0..m,
        weights 1/m but 1/(2m) at the two ends (a node at a gap closed mid-shutter is a sample
        at each end of the gap, `_grids.trapezoid_nodes`); its halves are the even and the odd k (the
        trapezoid and the midpoint rules of m / 2 strata). It holds any midpoint grid of
        ``m / (2 q)`` strata and trapezoid grid of ``m / q``, so a refinement may go to any
        multiple (the stratified grids only to odd ones)."""
        assert self.sums is not None
        times, weights, k = _grids.trapezoid_nodes(self.scene.shutter, m)
        held = self.sums.regrid(times, weights, k % 2) if keep else None
        if held is None:
            # nothing kept; where keeping failed, a drawn sample sits on a node split at a closed
            # gap (half its weight) among samples of full weight, which its part cannot hold
            if keep:
                self.sums = HalfSums(self.scene, self.aa)
            held = np.zeros(len(times), bool)
        self.sums.sampling = "trapezoid"
        sels = [(half, np.flatnonzero(~held & (k % 2 == half))) for half in (0, 1)]
        self.sums.add_all([(times[sel], weights[sel], half) for half, sel in sels if len(sel)])

    @property
    def renders(self) -> list[dict]:
        """The renders of the frame itself, in order (``tried`` without the pilots)."""
        return [t for t in self.tried if "pilot" not in t["options"]]

    @property
    def last(self) -> dict:
        """The last render of the frame itself (not a pilot)."""
        return self.renders[-1]

    def first_samples(self, tol: float) -> int:
        """The first accumulation render's samples at tolerance ``tol`` (`first_samples`), from
        the scene's forecast at its ``aa``, which is listed in ``tried`` as a pilot (its sweep,
        ms)."""
        t0 = time.perf_counter()
        sweep = sweep_scale(self.scene)
        n = first_samples(tol, sweep, self.aa)
        ms = (time.perf_counter() - t0) * 1e3
        self.tried.append(
            {
                "method": "accumulation",
                "options": {"pilot": f"forecast: sweep {sweep:.3g}, {n} samples"},
                "ms": round(ms, 3),
            }
        )
        return n

    @property
    def first_ms_per_sample(self) -> float:
        """The first accumulation render's milliseconds per sample (its fixed costs included)."""
        first = self.renders[0]
        return max(first["ms"], 1e-3) / first["options"]["samples"]

    def analytic_ms(self, segments: int | None = None) -> float:
        """The analytic frame's predicted time (`ANALYTIC_FIT`) from the first accumulation
        render; ``segments`` by the analytic method's rule unless given (its pilot runs once,
        listed in ``tried``; the count is kept in ``self.segments``)."""
        scene = self.scene
        moving = scene.objects if scene.camera_moves else [o for o in scene.objects if o.is_moving]
        if segments is None and self.segments is None:
            t0 = time.perf_counter()
            self.segments = len(segment_times(scene, moving, scene.camera)) - 1
            ms = (time.perf_counter() - t0) * 1e3
            self.tried.append(
                {"method": "analytic", "options": {"pilot": f"{self.segments} segments"}, "ms": round(ms, 3)}
            )
        segments = self.segments if segments is None else segments
        n = self.renders[0]["options"]["samples"]
        triangles = max(1, sum(len(o.mesh.faces) for o in moving))
        other = not (isinstance(scene.shutter, str) and scene.shutter == "box")
        c = ANALYTIC_FIT
        return math.exp(
            c[0] + c[1] * math.log(self.first_ms_per_sample) + c[2] * math.log(n)
            + c[3] * math.log(segments + 1) + c[4] * math.log(triangles) + c[5] * other
            + c[6] * scene.camera_moves
        )  # fmt: skip


def first_samples(tol: float, sweep: float | None = None, aa: int = 1) -> int:
    """The time samples of auto's first accumulation render at tolerance ``tol``. With the scene's
    ``sweep`` (`_sweep.sweep_scale`; auto always passes it): the fewest even count whose
    forecast error at ``aa`` (1, 2 or 4 spatial samples per pixel along each axis; `FIRST_FIT`)
    is at most `FIRST_AIM` x ``tol``, and under `SURE_SAMPLES` at most that times
    ``sqrt(N / SURE_SAMPLES)``, the share auto holds so few samples' estimate to; 2 to
    `FIRST_MOST`. Without it (the rule before the
    forecast, kept for comparison): ``FIRST_SCALE / tol`` rounded to even, `FIRST_SAMPLES` to
    `FIRST_MAX` (4 at 0.02 and above, 6 at 0.0133, 8 at 0.01 and below)."""
    if sweep is None:
        return int(min(FIRST_MAX, max(FIRST_SAMPLES, 2 * round(FIRST_SCALE / tol / 2))))
    c0, c1, c2 = FIRST_FIT[check_aa(aa)]
    if not sweep > 0.0:
        return 2
    scale = math.exp(c0) * sweep**c1
    need = (FIRST_AIM * tol / scale) ** (1.0 / c2)
    n = int(min(FIRST_MOST, max(2, 2 * math.ceil(need / 2))))
    while n < SURE_SAMPLES and scale * n**c2 > FIRST_AIM * tol * _sure_share(n):
        n += 2
    return n


def _sure_share(n: int) -> float:
    """The share of auto's aim a frame of ``n`` samples is held to: ``sqrt(n / SURE_SAMPLES)``
    under `SURE_SAMPLES`, else 1 (few samples' halves spread more)."""
    return min(1.0, math.sqrt(n / SURE_SAMPLES))


def _analytic_instead(trials: _Trials, draws: int) -> str | None:
    """Why the analytic frame replaces accumulation's next ``draws`` samples, or None: when its
    predicted time x `ANALYTIC_MARGIN` is under theirs (`MARGINAL_SAMPLE` x the first render's
    time per sample each). The segment pilot runs only when even a one-segment frame would be
    cheaper (`_Trials.analytic_ms` keeps its count)."""
    acc_ms = draws * MARGINAL_SAMPLE * trials.first_ms_per_sample
    if trials.segments is None and trials.analytic_ms(segments=1) * ANALYTIC_MARGIN >= acc_ms:
        return None
    predicted = trials.analytic_ms()
    if predicted * ANALYTIC_MARGIN >= acc_ms:
        return None
    return (
        f"accumulation would draw {draws} more samples (about {acc_ms:.1f} ms); the analytic frame, "
        f"predicted {predicted:.1f} ms, is exact to {ANALYTIC_ERROR:g}"
    )


def _for_tolerance(trials: _Trials, tol: float) -> str:
    """Render until the estimate meets ``tol`` (see the module docs); returns why it stopped."""
    if tol < 2 * ANALYTIC_ERROR:
        trials.run("analytic", **EXACT_OPTIONS)
        return f"tolerance {tol:g} < 2 x {ANALYTIC_ERROR:g}: the exact integral"
    aim = tol * SAFETY[trials.aa]
    trials.accumulate(trials.first_samples(tol))
    rate = RATE
    for _ in range(MAX_STEPS + 1):
        est, n = trials.last["halves_reading"], trials.last["options"]["samples"]
        limit = aim * _sure_share(n)
        if est <= limit:
            return f"accumulation-{n}'s halves read {est:.3g} <= {limit / tol:.2g} x tolerance"
        measured = trials.effective  # (stratified samples' worth, estimate) of each grid
        if len(measured) >= 2 and measured[-2][1] > est > 0:  # the rate these two renders show
            (n0, e0), (n1, e1) = measured[-2:]
            rate = min(1.2, max(0.5, math.log(e0 / e1) / math.log(n1 / n0)))
        worth = measured[-1][0]
        want = max(worth * (est / aim) ** (1.0 / rate), worth + 1)
        if want > MAX_SAMPLES:
            trials.run("analytic")
            return f"accumulation would need {want:.0f} samples, over {MAX_SAMPLES}: the analytic frame"
        assert trials.grid is not None
        nxt = _grids.next_grid(trials.grid, want, trials.refines)
        why = _analytic_instead(trials, _grids.draws(nxt, trials.grid))
        if why is not None:
            trials.run("analytic")
            return why
        trials.accumulate(*nxt)
    trials.run("analytic")
    return f"accumulation still estimated over the tolerance after {MAX_STEPS} steps: the analytic frame"


def _budget_grid(grid: tuple[int, str], room: float) -> tuple[int, str] | None:
    """The next accumulation grid (strata, kind) when ``room`` more samples fit the
    budget: of the grids that hold the samples drawn (`_holding_grid`) and draw at most
    ``room`` new ones, the one with the most samples; else a fresh even count, when it has at
    least 1.25x the samples drawn; None when neither fits."""
    # draws are whole samples: at most floor(room), added to the drawn ones exactly
    whole = math.floor(room) if math.isfinite(room) else MAX_SAMPLES
    best = _grids.holding_grid(grid, most=whole + _grids.samples(grid), largest=True)
    fresh = 2 * int(min(room, MAX_SAMPLES) // 2)  # a fresh render draws all its samples
    if fresh >= 1.25 * _grids.samples(grid) and fresh > (_grids.samples(best) if best else 0):
        return (fresh, STRATIFIED)
    return best


def _for_budget(trials: _Trials, budget: float) -> str:
    """The most accurate frame the budget allows (see the module docs); returns why."""
    start = time.perf_counter()

    def left() -> float:
        return budget - (time.perf_counter() - start) * 1e3

    trials.accumulate(FIRST_SAMPLES)
    est, drawn = trials.last["error_estimate"], FIRST_SAMPLES
    an = trials.analytic_ms()
    # where it fits, the analytic frame (within ANALYTIC_ERROR of the exact integral, 1e-6 to
    # 1e-4 measured) is more accurate than any accumulation that fits; unless the first render
    # shows no error at all
    if an < BUDGET_SHARE * left() and est > 0.0:
        trials.run("analytic")
        return f"the analytic frame (predicted {an:.0f} ms) fits the {budget:g} ms budget"
    share = MARGINAL_SAMPLE  # the first render's time per sample carries the frame's fixed costs
    for _ in range(MAX_STEPS + 1):
        assert trials.grid is not None
        per = share * trials.last["ms"] / drawn  # the last render's time per sample it drew
        share = 1.0
        grid = _budget_grid(trials.grid, BUDGET_SHARE * left() / max(per, 1e-6))
        if grid is None:
            break
        drawn = _grids.draws(grid, trials.grid)
        trials.accumulate(*grid)
    n = trials.last["options"]["samples"]
    return f"accumulation-{n}: the most samples that fit {budget:g} ms at the time per sample measured"


@register("auto", sweep=[{}, {"tolerance": 0.003}, {"tolerance": 0.03}], applies=lambda scene: True)
def auto(scene: Scene, tolerance=None, budget_ms=None, aa: int = 1) -> Frame:
    """A frame whose measured error meets a tolerance, or the most accurate one within a time budget.

    Options: ``tolerance`` RMSE against the exact time integral ([`motionblur.exact`][motionblur.exact];
    premultiplied linear RGBA), default `DEFAULT_TOLERANCE` (0.01); ``budget_ms`` instead,
    milliseconds per frame measured on this machine as it renders; ``aa`` 1, 2 or 4 samples per
    pixel along each axis. ``stats["plan"]``: ``goal``, ``tolerance`` or ``budget_ms``,
    ``tried`` (every render: method, options, ms, error estimate; accumulation's also
    ``halves_reading``), ``kept`` (the method and options of the frame returned) and ``why``
    (see [`motionblur.methods.auto`][motionblur.methods.auto]).
    """
    aa = check_aa(aa)
    if tolerance is not None and budget_ms is not None:
        raise ValueError("tolerance, budget_ms: give one of them, not both")
    tol = DEFAULT_TOLERANCE if tolerance is None else as_float(tolerance, "tolerance")
    budget = None if budget_ms is None else as_float(budget_ms, "budget_ms")
    if not (tol > 0 and math.isfinite(tol)):
        raise ValueError(f"tolerance: must be finite and > 0, got {tol}")
    if budget is not None and not (budget > 0 and math.isfinite(budget)):
        raise ValueError(f"budget_ms: must be finite and > 0, got {budget}")
    if budget is not None and scene.rolling > 0.0:
        raise ValueError(
            "budget_ms: auto does not plan a time budget under a rolling shutter (it renders the "
            "exact analytic frame there); use tolerance, or render 'analytic' or 'accumulation'"
        )
    trials = _Trials(scene, aa)
    if not _moves(scene):
        trials.run("accumulation", samples=1)
        why = "nothing moves on screen: one sharp frame"
    elif scene.rolling > 0.0:
        trials.run("analytic", **EXACT_OPTIONS)
        why = "a rolling shutter: the analytic frame, the one method that models it (exactly)"
    elif budget is not None:
        why = _for_budget(trials, budget)
    else:
        why = _for_tolerance(trials, tol)
    frame = trials.frames[-1]
    frame.stats["error_estimate_how"] = f"auto: {trials.last['method']}'s own estimate"
    frame.stats["plan"] = {
        "goal": "budget" if budget is not None else "tolerance",
        "tolerance": None if budget is not None else tol,
        "budget_ms": budget,
        "tried": trials.tried,
        "kept": {"method": trials.last["method"], "options": trials.last["options"]},
        "why": why,
    }
    return frame
