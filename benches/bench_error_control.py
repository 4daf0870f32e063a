"""Error you can trust, measured: every method's error estimate against its measured error, and
``auto`` at several tolerances, on seeded random scenes against the exact time integral.

    python benches/bench_error_control.py [--set measuring|tuning] [--scenes 40] [--sizes 96x72,192x144]
        [--first-seed 1000120] [--repeat 5] [--timer cpu|wall] [--no-calibration] [--aa 2]

For each scene of :func:`motionblur.evaluation.random_scenes.random_scene` (the measuring set by
default: seeds and meshes never tuned on) and each size:

- the reference: :func:`motionblur.exact` (cached under ``out/bench/error_control``);
- calibration: every method that applies, at its default options (and accumulation at 4 and 64
  samples), rendered with ``render()``: estimate / measured RMSE (the analytic method's against
  the deeper ``motionblur.methods._estimate.limit``, which its estimate is of: its error is at
  the level of ``mb.exact``'s own; ``--methods`` keeps only the methods named, and auto's rows
  only when ``auto`` is among them);
- auto at tolerances 0.01, 0.004 and 0.001: measured RMSE / tolerance, its time, and the cheapest
  render that meets the tolerance on that scene among accumulation at 1 to 4096 samples (powers
  of two and their 1.5x), the analytic method and every other method's default (each timed
  best-of-``--repeat`` in the same run, the wall clock or, with ``--timer cpu``, the process's
  CPU time: steadier on a loaded machine with ``MOTIONBLUR_NUM_THREADS=1``), and auto's time over
  that one's; beside it, auto's time over the cheapest render with the error estimate ``render``
  gives it by default (accumulation's halves cost nothing; every other method's pilot is added):
  what a frame that states its error costs. Each render of the search is timed once a scene
  and serves every tolerance.

``--aa`` renders every frame, the reference and auto's with that many samples per pixel along
each axis (the estimates are of the error at the same ``aa``).

Writes ``results.md`` and ``rows.json`` to ``out/bench/error_control/<set>``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import time
import warnings
from pathlib import Path

import numpy as np

import motionblur as mb
from motionblur.evaluation import random_scenes
from motionblur.evaluation.random_scenes import MEASURING_SEEDS, TUNING_SEEDS, random_scene
from motionblur.methods import _estimate, _segments

TOLERANCES = (0.01, 0.004, 0.001)
OUT = Path("out/bench/error_control")
ACC_GRID = sorted({int(v) for k in range(13) for v in (2**k, 1.5 * 2**k) if v <= 4096})


def rmse(a, b) -> float:
    return float(np.sqrt(np.mean(np.square(np.asarray(a, np.float64) - b))))


TIMING = {"repeat": 3, "clock": time.perf_counter}


def best_ms(fn, repeat: int | None = None) -> tuple[float, object]:
    clock = TIMING["clock"]
    best, out = float("inf"), None
    for _ in range(repeat or TIMING["repeat"]):
        t0 = clock()
        out = fn()
        best = min(best, (clock() - t0) * 1e3)
    return best, out


def reference(scene, seed: int, size: str, kind: str = "exact", aa: int = 1) -> np.ndarray:
    # keyed by the build as well: a change to the kernel or the segment rule changes the reference
    build = b"".join(Path(m.__file__).read_bytes() for m in (mb._core, _segments, random_scenes))
    sampled = f"{size}" if aa == 1 else f"{size}aa{aa}"
    key = hashlib.sha1(f"{mb.__version__}{seed}{sampled}".encode() + build).hexdigest()[:12]
    path = OUT / "refs" / f"{seed}_{size}_{key}{'' if kind == 'exact' else '_' + kind}.npy"
    if path.exists():
        return np.load(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    ref = (mb.exact if kind == "exact" else _estimate.limit)(scene, aa=aa).rgba.astype(np.float64)
    np.save(path, ref)
    return ref


def calibration_rows(scene, ref, seed, size, methods=None, aa: int = 1) -> list[dict]:
    rows = []
    runs = [("accumulation", {"samples": 4}), ("accumulation", {}), ("accumulation", {"samples": 64})]
    runs += [
        (m, {}) for m in mb.METHODS if m not in ("accumulation", "auto") and mb.METHODS[m].applies(scene)
    ]
    for method, opts in runs:
        if methods is not None and method not in methods:
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                f = mb.render(scene, method, **opts, aa=aa)
        except ValueError as exc:  # a method that refuses the motion says so
            rows.append(
                {"seed": seed, "size": size, "method": method, "options": opts, "refused": str(exc)[:120]}
            )
            continue
        limit = "limit" + hashlib.sha1(repr(_estimate.LIMIT_OPTIONS).encode()).hexdigest()[:6]
        measured = rmse(f.rgba, reference(scene, seed, size, limit, aa) if method == "analytic" else ref)
        rows.append(
            {
                "seed": seed, "size": size, "method": method, "options": opts, "measured": measured,
                "estimate": f.stats["error_estimate"], "how": f.stats["error_estimate_how"].split(":")[0],
                "ms": f.stats["ms"], "estimate_ms": f.stats.get("estimate_ms"),
            }
        )  # fmt: skip
    return rows


def other_renders(
    scene, ref, aa: int, timed, skip=("accumulation", "auto")
) -> list[tuple[str, float, float]]:
    """``(method, ms, RMSE against ref)`` of every method not in ``skip`` that applies to
    ``scene``, at its defaults without an estimate, timed by ``timed(fn) -> (ms, frame)``; a
    method that refuses the motion (ValueError) is left out."""
    out = []
    for m in mb.METHODS:
        if m in skip or not mb.METHODS[m].applies(scene):
            continue
        try:
            ms, f = timed(lambda m=m: mb.render(scene, m, error_estimate=False, aa=aa))
        except ValueError:
            continue
        out.append((m, ms, rmse(f.rgba, ref)))
    return out


class Cheapest:
    """The renders that may meet a tolerance on one scene, each timed once (lazily) for all
    tolerances: accumulation on `ACC_GRID` and every other method's default."""

    def __init__(self, scene, ref, aa: int = 1) -> None:
        self.scene, self.ref, self.aa = scene, ref, aa
        self.acc: dict[int, tuple[float, float]] = {}  # n -> (ms, rmse)
        self.others: list[tuple[str, float, float]] | None = None
        self.estimates: dict[str, float] = {}  # method -> its pilot estimate's ms

    def _acc(self, n: int) -> tuple[float, float]:
        if n not in self.acc:
            ms, f = best_ms(
                lambda: mb.render(self.scene, "accumulation", samples=n, error_estimate=False, aa=self.aa)
            )
            self.acc[n] = (ms, rmse(f.rgba, self.ref))
        return self.acc[n]

    def _others(self) -> list[tuple[str, float, float]]:
        if self.others is None:
            self.others = other_renders(self.scene, self.ref, self.aa, best_ms)
        return self.others

    def __call__(self, tol: float, certified: bool = False) -> tuple[str, float]:
        """The cheapest render meeting ``tol`` (label, best-of-repeat ms); ``certified``: each
        render with the error estimate ``render`` gives it by default (accumulation's halves
        are free; every other method's pilot is added, `estimate_ms`)."""
        found = []
        for n in ACC_GRID:
            ms, err = self._acc(n)
            if err <= tol:
                found.append((f"accumulation-{n}", ms))
                break
        for m, ms, err in self._others():
            if err <= tol:
                found.append((m, ms + (self._estimate_ms(m) if certified else 0.0)))
        return min(found, key=lambda x: x[1]) if found else ("none", float("nan"))

    def _estimate_ms(self, method: str) -> float:
        """The pilot estimate's ms of ``method`` at its defaults (best of repeat, the clock's)."""
        if method not in self.estimates:
            self.estimates[method] = estimate_ms(self.scene, method, self.aa)
        return self.estimates[method]


def estimate_ms(scene, method: str, aa: int = 1) -> float:
    """What the pilot error estimate adds to ``method`` at its defaults on ``scene``: ms (best of
    `TIMING`'s repeat, its clock) of the render with the estimate less the render without."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        on, _ = best_ms(lambda: mb.render(scene, method, aa=aa))
    off, _ = best_ms(lambda: mb.render(scene, method, error_estimate=False, aa=aa))
    return max(on - off, 0.0)


def auto_rows(scene, ref, seed, size, aa: int = 1) -> list[dict]:
    rows = []
    cheapest = Cheapest(scene, ref, aa)
    for tol in TOLERANCES:
        ms, f = best_ms(lambda tol=tol: mb.render(scene, "auto", tolerance=tol, aa=aa))
        label, cms = cheapest(tol)
        clabel, ccms = cheapest(tol, certified=True)
        kept = f.stats["plan"]["kept"]
        rows.append(
            {
                "seed": seed, "size": size, "tolerance": tol, "measured": rmse(f.rgba, ref), "ms": ms,
                "kept": f"{kept['method']} {kept['options']}", "cheapest": label, "cheapest_ms": cms,
                "cheapest_certified": clabel, "cheapest_certified_ms": ccms,
                "tried": [f"{t['method']} {t['options']}" for t in f.stats["plan"]["tried"]],
            }
        )  # fmt: skip
    return rows


def summarise(cal: list[dict], aut: list[dict]) -> str:
    lines = ["## Error estimates: estimate / measured RMSE against mb.exact (analytic: the limit)", ""]
    lines += [
        "| method | frames | in [0.5, 2] | below 0.5 | median | min | max |",
        "|---|---|---|---|---|---|---|",
    ]
    by: dict[str, list[float]] = {}
    for r in cal:
        if "measured" not in r:
            continue
        if r["measured"] < (1e-6 if r["method"] == "analytic" else 1e-5):  # nothing to estimate
            continue  # (the analytic method's limit is within about 1e-7 of its own)
        key = r["method"] + (f" {r['options']}" if r["options"] else "")
        by.setdefault(key, []).append(r["estimate"] / r["measured"])
    for key, v in sorted(by.items()):
        a = np.array(v)
        lines.append(
            f"| {key} | {len(a)} | {np.mean((a >= 0.5) & (a <= 2)):.0%} | {int((a < 0.5).sum())} | "
            f"{np.median(a):.2f} | {a.min():.2f} | {a.max():.2f} |"
        )
    refused = [r for r in cal if "refused" in r]
    lines += ["", f"Refused (raised a clear ValueError): {len(refused)} renders.", ""]
    lines += ["## auto: measured RMSE / tolerance, and time / the cheapest render meeting the tolerance", ""]
    lines += [
        "| size | tolerance | scenes | met | worst | median | time / cheapest (median, p90, worst) | "
        "time / cheapest with its estimate (median, p90, within 1.5x) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for size in sorted({r["size"] for r in aut}):
        for tol in TOLERANCES:
            sel = [r for r in aut if r["size"] == size and r["tolerance"] == tol]
            ratio = np.array([r["measured"] / tol for r in sel])
            cost = np.array([r["ms"] / r["cheapest_ms"] for r in sel if np.isfinite(r["cheapest_ms"])])
            cert = np.array(
                [
                    r["ms"] / r["cheapest_certified_ms"]
                    for r in sel
                    if np.isfinite(r.get("cheapest_certified_ms", np.nan))
                ]
            )
            certified = (
                f"{np.median(cert):.2f}, {np.percentile(cert, 90):.2f}, {np.mean(cert <= 1.5):.0%}"
                if len(cert)
                else "-"
            )
            lines.append(
                f"| {size} | {tol} | {len(sel)} | {np.mean(ratio <= 1):.0%} | {ratio.max():.2f} | "
                f"{np.median(ratio):.2f} | {np.median(cost):.2f}, {np.percentile(cost, 90):.2f}, {cost.max():.2f} | "
                f"{certified} |"
            )
    return "\n".join(lines) + "\n"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--set", choices=("measuring", "tuning"), default="measuring")
    p.add_argument("--scenes", type=int, default=12)
    p.add_argument("--sizes", default="96x72,192x144")
    p.add_argument("--first", type=int, default=0, help="skip this many seeds of the set")
    p.add_argument("--first-seed", type=int, default=None, help="the first seed (in the set) instead")
    p.add_argument("--tag", default="", help="a suffix for the output folder")
    p.add_argument("--repeat", type=int, default=3, help="best of this many timings")
    p.add_argument("--timer", choices=("wall", "cpu"), default="wall")
    p.add_argument("--no-calibration", action="store_true", help="auto's rows only")
    p.add_argument("--methods", default="", help="only these (comma-separated; auto: its rows)")
    p.add_argument("--aa", type=int, default=1, choices=(1, 2, 4), help="samples per pixel along each axis")
    args = p.parse_args()
    TIMING.update(repeat=args.repeat, clock=time.process_time if args.timer == "cpu" else time.perf_counter)
    pool = MEASURING_SEEDS if args.set == "measuring" else TUNING_SEEDS
    first = args.first if args.first_seed is None else pool.index(args.first_seed)
    seeds = pool[first : first + args.scenes]
    out = OUT / (args.set + args.tag)
    out.mkdir(parents=True, exist_ok=True)
    methods = set(args.methods.split(",")) if args.methods else None
    cal, aut = [], []
    for size in args.sizes.split(","):
        w, h = map(int, size.split("x"))
        for seed in seeds:
            scene = random_scene(seed, w, h)
            t0 = time.perf_counter()
            ref = reference(scene, seed, size, aa=args.aa)
            if not args.no_calibration:
                cal += calibration_rows(scene, ref, seed, size, methods, args.aa)
            if methods is None or "auto" in methods:
                aut += auto_rows(scene, ref, seed, size, args.aa)
            print(f"{size} seed {seed}: {time.perf_counter() - t0:.1f} s", flush=True)
    (out / "rows.json").write_text(json.dumps({"calibration": cal, "auto": aut}, indent=1, default=str))
    text = summarise(cal, aut)
    head = f"# {args.set} set, seeds {seeds.start}..{seeds.stop - 1}, aa={args.aa}, {args.timer} time best of {args.repeat}\n\n"
    (out / "results.md").write_text(head + text)
    print(text)


if __name__ == "__main__":
    main()
