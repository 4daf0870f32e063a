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
2. accumulation with [`first_samples`][motionblur.methods.auto.first_samples] samples (what the
   easier tuning scenes need at that tolerance, 4 to 12) measures the scene's error at that N;
3. since the error falls about as 1/N (`RATE`), the N that brings the estimate under
   ``tolerance`` x `SAFETY` is predicted and rendered, keeping the samples drawn when N
   is an odd multiple of the last count (under a box shutter the next N is such a multiple
   unless that draws over `REUSE_DRAWS` x the new samples of a fresh render; with fewer
   than `SURE_SAMPLES` samples the aim is
   lower: their halves spread more), and again while the estimate says it missed (each
   step predicted from the last two measurements, at most `MAX_STEPS` steps);
4. where that N would cost more than the analytic frame (predicted from its segment count and
   accumulation's time per sample, only asked once N reaches `ANALYTIC_FROM`), or exceed
   `MAX_SAMPLES`, or the tolerance is under what accumulation can certify cheaply, the
   analytic method renders instead (at the exact options below `ANALYTIC_ERROR` x 2).

With ``budget_ms``: accumulation with 4 samples measures the time per sample; the analytic
frame follows where its predicted time fits `BUDGET_SHARE` of the time left (it is more
accurate than any accumulation that fits); else accumulation grows, keeping the samples drawn
under a box shutter (odd multiples), to the most that fit `BUDGET_SHARE` of the time left at
the time per sample its last render took, measured against the clock at every step.

``Frame.stats["plan"]`` lists every render tried (method, options, ms, error estimate) and why
the last was kept; ``stats["error_estimate"]`` is the kept frame's own.
"""

from __future__ import annotations

import math
import time

import numpy as np

from .._validate import as_float, as_int
from ..raster import Frame
from ..render import METHODS, register
from ..scene import Scene
from ._accumulate import HalfSums, sample_times
from ._estimate import EXACT_OPTIONS
from ._segments import segment_times

__all__ = [
    "auto",
    "layered_translucency",
    "renders_shutter",
    "DEFAULT_TOLERANCE",
    "SAFETY",
    "FIRST_SAMPLES",
    "FIRST_SCALE",
    "FIRST_MAX",
    "first_samples",
    "MAX_SAMPLES",
    "RATE",
    "SURE_SAMPLES",
    "MAX_STEPS",
    "ANALYTIC_ERROR",
    "ANALYTIC_FROM",
    "ANALYTIC_COST",
    "REUSE_DRAWS",
    "BUDGET_SHARE",
]

#: The default tolerance: RMSE against the exact time integral (premultiplied linear RGBA).
DEFAULT_TOLERANCE = 0.01
#: The share of the tolerance auto aims its estimate at (the estimate's own spread).
SAFETY = 0.85
#: Below this many samples the halves hold few samples each and their estimate spreads more:
#: the aim shrinks as sqrt(N / SURE_SAMPLES) (chosen on the tuning scenes: from 8 samples up the
#: 5th percentile of estimate / error there is 0.85, at 6 it is 0.69 and at 4 0.55).
SURE_SAMPLES = 8
#: Fewest time samples of the first accumulation render (two halves of 2).
FIRST_SAMPLES = 4
#: The first render's samples for tolerance ``tol``: ``FIRST_SCALE / tol`` rounded to even, at
#: least `FIRST_SAMPLES` and at most `FIRST_MAX`, about what the easier tuning scenes need at
#: that tolerance, so that the first render is often the last (`first_samples`).
FIRST_SCALE = 0.08
#: Most time samples of the first accumulation render.
FIRST_MAX = 12
#: The rate auto first assumes the error falls at, as N^-RATE (1 for an edge's coverage at one
#: point; slower where a pixel sees many edges), until two renders show their own.
RATE = 1.0
#: Most time samples auto gives accumulation.
MAX_SAMPLES = 1 << 12
#: Most accumulation renders after the first.
MAX_STEPS = 3
#: Sample count from which the analytic frame is timed as the alternative.
ANALYTIC_FROM = 512
#: The analytic frame's time over (its segments + 8) accumulation samples' (the largest ratio
#: on most tuning scenes; chosen there).
ANALYTIC_COST = 4.0
#: How many more new samples than a fresh render a refinement that keeps the drawn ones may
#: draw (`_next_count`; chosen on the tuning scenes).
REUSE_DRAWS = 1.5
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

    def _record(self, method: str, options: dict, frame: Frame, ms: float, est: float) -> Frame:
        frame.stats["error_estimate"] = est
        self.tried.append(
            {"method": method, "options": dict(options), "ms": round(ms, 3), "error_estimate": est}
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

    @property
    def reuses(self) -> bool:
        """Whether a finer grid keeps the samples drawn (a box shutter: see `accumulate`)."""
        return isinstance(self.scene.shutter, str) and self.scene.shutter == "box"

    def accumulate(self, n: int) -> Frame:
        """Accumulation with ``n`` stratified samples; under a box shutter the samples already
        drawn are kept when ``n`` is an odd multiple of the last count (their times are on the
        new grid) and only the others are drawn."""
        t0 = time.perf_counter()
        last = self.sums.samples if self.sums is not None else 0
        if not (self.reuses and last and n % last == 0 and (n // last) % 2 == 1):
            self.sums, last = HalfSums(self.scene, self.aa), 0
        times, weights = sample_times(self.scene, n)
        j = np.arange(n)
        if last:
            step = n // last
            self.sums.reweight(lambda t: (np.full(len(t), 1.0 / n), int(round(t[0] * n - 0.5)) % 2))
            j = j[(j % step) != step // 2]  # the new times only
        for half in (0, 1):
            sel = j[j % 2 == half]
            if len(sel):
                self.sums.add(times[sel], weights[sel], half)
        frame = self.sums.frame()
        ms = (time.perf_counter() - t0) * 1e3
        return self._record("accumulation", {"samples": n}, frame, ms, frame.stats["error_estimate"])

    @property
    def last(self) -> dict:
        """The last render of the frame itself (not a timing pilot)."""
        return [t for t in self.tried if "pilot" not in t["options"]][-1]

    def per_sample_ms(self) -> float:
        """Milliseconds per time sample of the accumulation renders so far."""
        acc = [t for t in self.tried if t["method"] == "accumulation" and "pilot" not in t["options"]]
        return sum(t["ms"] for t in acc) / max(
            1, self.sums.samples if self.sums else acc[-1]["options"]["samples"]
        )

    def analytic_ms(self) -> float:
        """The analytic frame's predicted time: `ANALYTIC_COST` x (its segments + 8) x the
        accumulation's time per sample (the segments by the analytic method's rule)."""
        scene = self.scene
        moving = scene.objects if scene.camera_moves else [o for o in scene.objects if o.is_moving]
        t0 = time.perf_counter()
        segments = len(segment_times(scene, moving, scene.camera)) - 1
        ms = (time.perf_counter() - t0) * 1e3
        self.tried.append(
            {"method": "analytic", "options": {"pilot": f"{segments} segments"}, "ms": round(ms, 3)}
        )
        return ANALYTIC_COST * (segments + 8) * self.per_sample_ms()


def _next_count(n: int, want: float, reuse: bool = True) -> int:
    """The sample count after ``n`` for an estimated need of ``want``: the smallest odd multiple
    of ``n`` at least ``want`` (whose grid keeps the ``n`` samples drawn, so it draws the others
    only) when ``reuse`` and that draws at most `REUSE_DRAWS` x as many new samples as ``want``
    rounded up to even does afresh (a render saved outweighs a few more samples, and the frame
    gets them too); else that even count, afresh."""
    odd = n * (2 * math.ceil((want / n - 1) / 2) + 1)
    fresh = 2 * math.ceil(want / 2)
    return int(min(MAX_SAMPLES, odd if reuse and odd - n <= REUSE_DRAWS * fresh else fresh))


def first_samples(tol: float) -> int:
    """The time samples of auto's first accumulation render at tolerance ``tol`` (see
    `FIRST_SCALE`): 8 at 0.01, 12 at 0.007 and below."""
    return int(min(FIRST_MAX, max(FIRST_SAMPLES, 2 * round(FIRST_SCALE / tol / 2))))


def _for_tolerance(trials: _Trials, tol: float) -> str:
    """Render until the estimate meets ``tol`` (see the module docs); returns why it stopped."""
    if tol < 2 * ANALYTIC_ERROR:
        trials.run("analytic", **EXACT_OPTIONS)
        return f"tolerance {tol:g} < 2 x {ANALYTIC_ERROR:g}: the exact integral"
    aim = tol * SAFETY
    trials.accumulate(first_samples(tol))
    analytic_ms = None
    rate = RATE
    for _ in range(MAX_STEPS + 1):
        est, n = trials.last["error_estimate"], trials.last["options"]["samples"]
        if est <= aim * min(1.0, math.sqrt(n / SURE_SAMPLES)):
            return f"accumulation-{n} estimates {est:.3g} <= {SAFETY} x tolerance"
        measured = [
            (t["options"]["samples"], t["error_estimate"])
            for t in trials.tried
            if t["method"] == "accumulation"
        ]
        if len(measured) >= 2 and measured[-2][1] > est > 0:  # the rate these two renders show
            (n0, e0), (n1, e1) = measured[-2:]
            rate = min(1.2, max(0.5, math.log(e0 / e1) / math.log(n1 / n0)))
        want = max(n * (est / aim) ** (1.0 / rate), n + 2)
        if want >= ANALYTIC_FROM:
            if analytic_ms is None:
                analytic_ms = trials.analytic_ms()
            if want > MAX_SAMPLES or analytic_ms < want * trials.per_sample_ms():
                trials.run("analytic")
                return (
                    f"accumulation would need {want:.0f} samples (about {want * trials.per_sample_ms():.0f} ms); "
                    f"the analytic frame, predicted {analytic_ms:.0f} ms, is exact to {ANALYTIC_ERROR:g}"
                )
        trials.accumulate(_next_count(n, want, trials.reuses))
    trials.run("analytic")
    return f"accumulation still estimated over the tolerance after {MAX_STEPS} steps: the analytic frame"


def _budget_step(trials: _Trials, room: float) -> tuple[int, int]:
    """``(n, drawn)``: the next accumulation's sample count when ``room`` more samples fit the
    budget, and how many it draws: the largest odd multiple of the samples drawn (keeping them,
    under a box shutter), else a fresh render of ``room`` samples when that is 25% more; ``(0,
    0)`` when neither fits."""
    last = trials.sums.samples if trials.sums is not None else 0
    if trials.reuses and last:
        most = MAX_SAMPLES // last
        k = min(2 * int(room / (2 * last)) + 1, most - (most + 1) % 2)  # odd, (k - 1) x last <= room
        if k >= 3:
            return k * last, (k - 1) * last
    n = min(MAX_SAMPLES, 2 * int(room // 2))
    return (n, n) if n >= 1.25 * last and n > last else (0, 0)


def _for_budget(trials: _Trials, budget: float) -> str:
    """The most accurate frame the budget allows (see the module docs); returns why."""
    start = time.perf_counter()

    def left() -> float:
        return budget - (time.perf_counter() - start) * 1e3

    trials.accumulate(FIRST_SAMPLES)
    est, drawn = trials.last["error_estimate"], FIRST_SAMPLES
    an = trials.analytic_ms()
    # where it fits, the analytic frame (about 1e-5 from the exact integral) is more accurate
    # than any accumulation that fits; unless the first render shows no error at all
    if an < BUDGET_SHARE * left() and est > 0.0:
        trials.run("analytic")
        return f"the analytic frame (predicted {an:.0f} ms) fits the {budget:g} ms budget"
    for _ in range(MAX_STEPS + 1):
        per = trials.last["ms"] / drawn  # the last render's time per sample it drew
        n, new = _budget_step(trials, BUDGET_SHARE * left() / max(per, 1e-6))
        if not n:
            break
        trials.accumulate(n)
        drawn = new
    n = trials.sums.samples
    return f"accumulation-{n}: the most samples that fit {budget:g} ms at the time per sample measured"


@register("auto", sweep=[{}, {"tolerance": 0.003}, {"tolerance": 0.03}], applies=lambda scene: True)
def auto(scene: Scene, tolerance=None, budget_ms=None, aa: int = 1) -> Frame:
    """A frame whose measured error meets a tolerance, or the most accurate one within a time budget.

    Options: ``tolerance`` RMSE against the exact time integral ([`motionblur.exact`][motionblur.exact];
    premultiplied linear RGBA), default `DEFAULT_TOLERANCE` (0.01); ``budget_ms`` instead,
    milliseconds per frame measured on this machine as it renders; ``aa`` 1, 2 or 4 samples per
    pixel along each axis. ``stats["plan"]``: ``goal``, ``tolerance`` or ``budget_ms``,
    ``tried`` (every render: method, options, ms, error estimate), ``kept`` (the method and
    options of the frame returned) and ``why`` (see [`motionblur.methods.auto`][motionblur.methods.auto]).
    """
    aa = as_int(aa, "aa")
    if tolerance is not None and budget_ms is not None:
        raise ValueError("tolerance, budget_ms: give one of them, not both")
    tol = DEFAULT_TOLERANCE if tolerance is None else as_float(tolerance, "tolerance")
    budget = None if budget_ms is None else as_float(budget_ms, "budget_ms")
    if not (tol > 0 and math.isfinite(tol)):
        raise ValueError(f"tolerance: must be finite and > 0, got {tol}")
    if budget is not None and not (budget > 0 and math.isfinite(budget)):
        raise ValueError(f"budget_ms: must be finite and > 0, got {budget}")
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
