"""Speed against error on the five built-in scenes, against Mitsuba, measured in one run.

Runs :func:`motionblur.evaluation.bench.run` (every registered method over its sweep on every built-in
scene, Mitsuba references cached in out/bench/references/), then prints the two comparisons of
the issue: motion_volume against accumulation at equal error, and accumulation with the static
layer drawn once (N = 16) against 16-pose accumulation on pyrender. Machine: see the report
header (2 shared cores here); all figures are ratios of timings taken in the same run.

Usage: python benches/bench_scenes.py [--quick] [bench options, see python -m motionblur bench --help]
Writes out/bench/results.md, results.csv and pareto_<scene>.png.
"""

from __future__ import annotations

import sys

from motionblur.evaluation.bench import main

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
