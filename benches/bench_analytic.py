"""Wall-clock of the analytic method against accumulation with 256 time samples, per built-in scene.

Both at the same size and supersampling, timed in the same run (best of ``--repeat`` calls
each, after one warm-up call), so the ratio is what counts on a shared machine. Also prints the
analytic kernel's counts (sample tests, spans, pieces) and its cover/resolve thread time.

Usage: python benches/bench_analytic.py [--size 320x240] [--aa 2] [--repeat 3] [--scenes a,b]
       [--no-accumulation]
"""

from __future__ import annotations

import argparse
import time

import motionblur as mb
from motionblur.scenes_builtin import SCENES


def best(fn, repeat: int) -> tuple[float, object]:
    out = fn()  # warm-up: static layers, segment rules, allocator
    t_best = float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        t_best = min(t_best, time.perf_counter() - t)
    return t_best, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="320x240")
    ap.add_argument("--aa", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--no-accumulation", action="store_true")
    a = ap.parse_args()
    w, h = (int(v) for v in a.size.split("x"))
    print(f"{a.size}, aa={a.aa}, best of {a.repeat}; ratio = accumulation-256 time / analytic time")
    print(f"{'scene':22} {'analytic ms':>11} {'acc256 ms':>10} {'ratio':>6} {'tests':>10} {'spans':>9} "
          f"{'pieces':>9} {'cover ms':>9} {'resolve ms':>10}")
    for name in a.scenes.split(","):
        scene = SCENES[name](width=w, height=h)
        ta, fa = best(lambda: mb.render(scene, "analytic", aa=a.aa), a.repeat)
        tacc = float("nan")
        if not a.no_accumulation:
            tacc, _ = best(lambda: mb.render(scene, "accumulation", samples=256, aa=a.aa), a.repeat)
        s = fa.stats
        print(f"{name:22} {1e3 * ta:11.1f} {1e3 * tacc:10.1f} {tacc / ta:6.2f} {s.get('tests', 0):10d} "
              f"{s.get('spans', 0):9d} {s.get('pieces', 0):9d} {s.get('ms_cover', 0):9.1f} "
              f"{s.get('ms_resolve', 0):10.1f}", flush=True)


if __name__ == "__main__":
    main()
