"""The analytic method against accumulation with 64 to 4096 time samples (``--counts``), per
built-in scene (or real-mesh scene with ``--real``): wall clock and error, in the same run.

Every method renders each scene at the same size and supersampling, timed in the same run (best
of ``--repeat`` calls each, after one warm-up call), so the ratios are what counts on a shared
machine; the load average is printed before and after. Error is the RMSE of the premultiplied
RGBA against accumulation with ``--reference`` samples (16384, whose own error is about a quarter
of accumulation-4096's, so that an error below accumulation-4096's can be told apart from the
reference's noise; cached in out/bench/refs per build of the extension). Also prints the analytic kernel's counts (sample tests, spans, pieces,
tile splits) and its cover/resolve thread time.

The factor at equal error: when the analytic error is at or below that of the largest count
timed, the factor is reported as a bound, ``>= t(acc-4096) / t(analytic)``. Otherwise the sample count N
at which accumulation's error equals the analytic one is interpolated between the measured
counts on a log-log line (extrapolated below 64 along the 64-256 slope), accumulation's time at
N is interpolated linearly in N between the measured times (a frame costs a fixed part plus a
part per sample), and the factor is that time over the analytic one.

``--memory`` instead measures the peak resident memory of one frame of ``--memory-scene`` at
``--memory-size`` (each method in a fresh process: ``ru_maxrss`` of the child, minus the same
process's peak before the frame, so numpy, the scene and the extension are not counted).

Usage: python benches/bench_analytic.py [--size 320x240] [--aa 2] [--repeat 3] [--scenes a,b]
       [--real] [--reference 16384] [--counts 64,256,1024,4096] [--no-error]
       python benches/bench_analytic.py --memory [--memory-scene sphere80k] [--memory-size 1920x1080]
Writes out/bench/analytic.md (or analytic_memory.md).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from functools import partial
from pathlib import Path
from types import SimpleNamespace

import numpy as np

import motionblur as mb
from motionblur.evaluation.cluster import TIMING_BUDGET_S  # the report's rule: stop repeating after 1.5 s
from motionblur.scenes_builtin import SCENES
from motionblur.scenes_real import REAL_SCENES


def reference(scene, name: str, a: argparse.Namespace):
    """Accumulation with ``--reference`` samples, kept in out/bench/refs between runs of the same
    build of the extension (a deep reference takes minutes on the dense scenes)."""
    core = Path(mb._core.__file__).stat()
    build = f"{core.st_size:x}{int(core.st_mtime):x}"
    path = Path("out/bench/refs") / f"{name}_{a.size}_aa{a.aa}_{a.reference}_{build}.npz"
    if path.exists():
        with np.load(path) as z:
            return SimpleNamespace(rgba=z["rgba"])
    frame = mb.render(scene, "accumulation", samples=a.reference, aa=a.aa)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, rgba=frame.rgba)
    return frame


def best(fn, repeat: int) -> tuple[float, object]:
    out = fn()  # warm-up: static layers, segment rules, allocator
    t_best, spent = float("inf"), 0.0
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        dt = time.perf_counter() - t
        t_best, spent = min(t_best, dt), spent + dt
        if spent > TIMING_BUDGET_S:
            break
    return t_best, out


def rmse(a, b) -> float:
    return float(np.sqrt(np.mean((a.rgba - b.rgba) ** 2)))


def equal_error_factor(ta: float, ea: float, times: dict, err: dict) -> str:
    """Accumulation's time at the analytic error over the analytic time (see the module doc)."""
    ns = sorted(times)
    if not np.isfinite(ea) or any(not np.isfinite(err[n]) for n in ns):
        return "?"
    if ea <= err[ns[-1]]:
        return f">= {times[ns[-1]] / ta:.2f}"
    # the bracketing pair of measured counts (or the two lowest, to extrapolate below them)
    lo, hi = ns[0], ns[1]
    for a, b in zip(ns, ns[1:]):
        if err[b] <= ea <= err[a]:
            lo, hi = a, b
    slope = (np.log(err[hi]) - np.log(err[lo])) / (np.log(hi) - np.log(lo))
    if not slope < 0:
        return "?"
    n = lo * np.exp((np.log(ea) - np.log(err[lo])) / slope)
    per = (times[hi] - times[lo]) / (hi - lo)
    t_n = max(times[lo] + per * (n - lo), 0.0)
    return f"{t_n / ta:.2f} (N={n:.0f})"


def load() -> str:
    return " ".join(Path("/proc/loadavg").read_text().split()[:3]) if Path("/proc/loadavg").exists() else "?"


def speed_and_error(a: argparse.Namespace) -> list[str]:
    w, h = (int(v) for v in a.size.split("x"))
    counts = sorted(int(n) for n in a.counts.split(","))
    if len(counts) < 2 or not a.reference > counts[-1]:
        raise SystemExit("--counts: at least two sample counts, all below --reference")
    lines = [
        f"{a.size}, aa={a.aa}, best of {a.repeat} (wall clock; fewer once the calls add up to "
        f"{TIMING_BUDGET_S} s), {os.cpu_count()} cores; "
        f"load average at start {load()}",
        "",
        "| scene | analytic ms | "
        + "".join(f"acc-{n} ms | " for n in counts)
        + f"acc-{counts[-1]} / analytic | at equal error | RMSE analytic | "
        + "".join(f"RMSE acc-{n} | " for n in counts)
        + "tests | spans | pieces | splits | cover ms | resolve ms |",
        "|---|" + "---:|" * (2 * len(counts) + 10),
    ]
    print("\n".join(lines), flush=True)
    for name in a.scenes.split(","):
        scene = (SCENES | REAL_SCENES)[name](width=w, height=h)
        ta, fa = best(partial(mb.render, scene, "analytic", aa=a.aa), a.repeat)
        times, frames = {}, {}
        for n in counts:
            times[n], frames[n] = best(
                partial(mb.render, scene, "accumulation", samples=n, aa=a.aa), a.repeat
            )
        err = {"analytic": float("nan"), **{n: float("nan") for n in counts}}
        if not a.no_error:
            ref = reference(scene, name, a)
            err = {"analytic": rmse(fa, ref), **{n: rmse(frames[n], ref) for n in counts}}
        s = fa.stats
        factor = equal_error_factor(ta, err["analytic"], times, err)
        row = (
            f"| {name} | {1e3 * ta:.1f} | "
            + "".join(f"{1e3 * times[n]:.1f} | " for n in counts)
            + f"{times[counts[-1]] / ta:.2f} | {factor} | {err['analytic']:.2e} | "
            + "".join(f"{err[n]:.2e} | " for n in counts)
            + f"{s.get('tests', 0)} "
            f"| {s.get('spans', 0)} | {s.get('pieces', 0)} | {s.get('splits', 0)} "
            f"| {s.get('ms_cover', 0.0):.0f} | {s.get('ms_resolve', 0.0):.0f} |"
        )
        print(row, flush=True)
        lines.append(row)
    tail = f"\nload average at the end {load()}; RMSE against accumulation-{a.reference}"
    print(tail)
    return [*lines, tail]


_CHILD = """
import json, resource, sys
import motionblur as mb
name, w, h, method, kw = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4], json.loads(sys.argv[5])
scene = mb.SCENES[name](w, h)
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
frame = mb.render(scene, method, error_estimate=False, **kw)
after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({"before_kib": before, "peak_kib": after, "ms": frame.stats.get("ms_total", 0.0)}))
"""


def memory(a: argparse.Namespace) -> list[str]:
    w, h = (int(v) for v in a.memory_size.split("x"))
    runs = [
        ("analytic", {}),
        ("analytic", {"aa": 2}),
        ("accumulation", {"samples": 1}),
        ("accumulation", {"samples": 256}),
    ]
    lines = [
        f"{a.memory_scene} at {a.memory_size}: peak resident memory of one frame, each in a fresh "
        f"process; load average {load()}",
        "",
        "| method | options | process peak MiB | of which the frame MiB |",
        "|---|---|---:|---:|",
    ]
    print("\n".join(lines), flush=True)
    for method, kw in runs:
        out = subprocess.run(
            [sys.executable, "-c", _CHILD, a.memory_scene, str(w), str(h), method, json.dumps(kw)],
            capture_output=True, text=True, check=True,
        ).stdout  # fmt: skip
        r = json.loads(out.strip().splitlines()[-1])
        row = (
            f"| {method} | {kw} | {r['peak_kib'] / 1024:.0f} | "
            f"{(r['peak_kib'] - r['before_kib']) / 1024:.0f} |"
        )
        print(row, flush=True)
        lines.append(row)
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="320x240")
    ap.add_argument("--aa", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--real", action="store_true", help="every real-mesh scene instead")
    ap.add_argument("--reference", type=int, default=16384)
    ap.add_argument("--counts", default="64,256,1024,4096", help="accumulation sample counts to time")
    ap.add_argument("--no-error", action="store_true")
    ap.add_argument("--memory", action="store_true")
    ap.add_argument("--memory-scene", default="sphere80k")
    ap.add_argument("--memory-size", default="1920x1080")
    a = ap.parse_args()
    if a.real:
        a.scenes = ",".join(REAL_SCENES)
    lines = memory(a) if a.memory else speed_and_error(a)
    out = Path("out/bench")
    out.mkdir(parents=True, exist_ok=True)
    (out / ("analytic_memory.md" if a.memory else "analytic.md")).write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
