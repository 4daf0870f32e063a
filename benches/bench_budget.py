"""``auto`` with a time budget, measured: does the frame arrive within the budget, and is it the
most accurate one that fits?

    python benches/bench_budget.py [--set measuring|tuning] [--scenes 8] [--first 0]
                                   [--sizes 96x72,192x144,320x240] [--budgets 10,40,160]

For each scene of :func:`motionblur.evaluation.random_scenes.random_scene` (the measuring set by
default), each size and each budget (milliseconds):

- ``auto`` with ``budget_ms`` is called `REPEAT` times; every call's wall time over the budget is
  kept (a user gets each call's time, so the worst call counts, not the best);
- its RMSE against :func:`motionblur.exact` (premultiplied linear RGBA, cached per scene);
- the most accurate render that fits: accumulation at the largest count of the grid (powers of
  two and their 1.5x, to 4096) and the analytic method, each timed best-of-3 in the same run,
  whose time is within the budget; auto's RMSE over that one's.

Writes ``results.md`` and ``rows.json`` to ``out/bench/budget/<set>``. Timings depend on the load:
the machine and its load average are printed with the table.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import numpy as np

import motionblur as mb
from motionblur.evaluation.random_scenes import MEASURING_SEEDS, TUNING_SEEDS, random_scene

OUT = Path("out/bench/budget")
REPEAT = 3
ACC_GRID = sorted({int(v) for k in range(13) for v in (2**k, 1.5 * 2**k) if v <= 4096})


def rmse(a, b) -> float:
    return float(np.sqrt(np.mean(np.square(np.asarray(a, np.float64) - b))))


def best_ms(fn, repeat: int = 3) -> tuple[float, object]:
    best, out = float("inf"), None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, (time.perf_counter() - t0) * 1e3)
    return best, out


def candidates(scene, ref) -> list[tuple[str, float, float]]:
    """(label, best-of-3 ms, RMSE) of accumulation on the grid (up to the first count over
    1 s) and of the analytic method."""
    out = []
    for n in ACC_GRID:
        ms, f = best_ms(lambda n=n: mb.render(scene, "accumulation", samples=n, error_estimate=False))
        out.append((f"accumulation-{n}", ms, rmse(f.rgba, ref)))
        if ms > 1000.0:
            break
    ms, f = best_ms(lambda: mb.render(scene, "analytic", error_estimate=False))
    out.append(("analytic", ms, rmse(f.rgba, ref)))
    return out


def budget_rows(scene, ref, seed, size, budgets) -> list[dict]:
    cands = candidates(scene, ref)
    rows = []
    for budget in budgets:
        mb.render(scene, "auto", budget_ms=budget)  # warm: the static layer, the caches
        times, frame = [], None
        for _ in range(REPEAT):
            t0 = time.perf_counter()
            frame = mb.render(scene, "auto", budget_ms=budget)
            times.append((time.perf_counter() - t0) * 1e3)
        fits = [c for c in cands if c[1] <= budget]
        best = min(fits, key=lambda c: c[2]) if fits else ("none", float("nan"), float("nan"))
        kept = frame.stats["plan"]["kept"]
        rows.append(
            {
                "seed": seed, "size": size, "budget_ms": budget, "ms": times,
                "measured": rmse(frame.rgba, ref), "kept": f"{kept['method']} {kept['options']}",
                "best_fit": best[0], "best_fit_ms": best[1], "best_fit_rmse": best[2],
            }
        )  # fmt: skip
    return rows


def summarise(rows: list[dict]) -> str:
    lines = [
        "| size | budget ms | frames | calls over budget | worst time / budget | median time / budget "
        "| auto RMSE / best fitting (median, worst) |",
        "|---|---|---|---|---|---|---|",
    ]
    for size in dict.fromkeys(r["size"] for r in rows):
        for budget in dict.fromkeys(r["budget_ms"] for r in rows):
            sel = [r for r in rows if r["size"] == size and r["budget_ms"] == budget]
            ratio = np.array([t / budget for r in sel for t in r["ms"]])
            acc = np.array([r["measured"] / r["best_fit_rmse"] for r in sel if r["best_fit_rmse"] > 0])
            acc_txt = f"{np.median(acc):.2f}, {acc.max():.2f}" if len(acc) else "n/a"
            lines.append(
                f"| {size} | {budget:g} | {len(sel)} | {int((ratio > 1).sum())} of {len(ratio)} "
                f"| {ratio.max():.2f} | {np.median(ratio):.2f} | {acc_txt} |"
            )
    # more budget buys accuracy: per scene and size, the error at each budget against the next
    pairs = better = 0
    for size in dict.fromkeys(r["size"] for r in rows):
        for seed in dict.fromkeys(r["seed"] for r in rows):
            errs = [r["measured"] for r in rows if r["size"] == size and r["seed"] == seed]
            pairs += len(errs) - 1
            better += sum(b <= a for a, b in zip(errs, errs[1:], strict=False))
    lines += ["", f"A larger budget gave an error no larger on {better} of {pairs} steps."]
    return "\n".join(lines)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--set", choices=("measuring", "tuning"), default="measuring")
    p.add_argument("--scenes", type=int, default=8)
    p.add_argument("--first", type=int, default=0, help="skip this many seeds of the set")
    p.add_argument("--sizes", default="96x72,192x144,320x240")
    p.add_argument("--budgets", default="10,40,160")
    args = p.parse_args()
    seeds = (MEASURING_SEEDS if args.set == "measuring" else TUNING_SEEDS)[
        args.first : args.first + args.scenes
    ]
    budgets = [float(b) for b in args.budgets.split(",")]
    out = OUT / args.set
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for size in args.sizes.split(","):
        w, h = map(int, size.split("x"))
        for seed in seeds:
            scene = random_scene(seed, w, h)
            ref = mb.exact(scene).rgba.astype(np.float64)
            rows += budget_rows(scene, ref, seed, size, budgets)
            print(f"{size} seed {seed}: done", flush=True)
    load = os.getloadavg()
    head = (
        f"# auto with budget_ms, {args.set} seeds {seeds.start}..{seeds.stop - 1}\n\n"
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"load average at the end {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f}\n\n"
    )
    (out / "rows.json").write_text(json.dumps(rows, indent=1, default=str))
    text = head + summarise(rows)
    (out / "results.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
