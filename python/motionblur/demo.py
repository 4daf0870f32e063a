"""``python -m motionblur demo``: the library's main job on one scene, small and quick.

Renders the translating-cube scene at 320x240 with accumulation (N = 1, 4, 16, 64) and motion
volumes (1 and 4 segments, box and ramp filters), measures each against a Mitsuba reference
(K = 64 shutter times, cached), and writes into ``out``: every image and the reference as PNGs
(``images/``), ``results.csv``, ``results.md`` and the Pareto plot. Well under a minute.
"""

from __future__ import annotations

import time
from pathlib import Path

from . import bench

SWEEPS = {
    "accumulation": [{"samples": n} for n in (1, 4, 16, 64)],
    "motion_volume": [{"segments": s, "filter": f} for f in ("box", "ramp") for s in (1, 4)],
}


def run(out="out/demo", scene: str = "cube") -> int:
    t0 = time.perf_counter()
    res = bench.run(
        out,
        scenes=[scene],
        width=320,
        height=240,
        times=64,
        spp=4,
        repeat=2,
        methods=list(SWEEPS),
        sweeps=SWEEPS,
        pyrender_peer=False,
        save_images=True,
    )
    md = Path(res["paths"]["md"]).read_text()
    print(md)
    print(f"demo written to {out}/ in {time.perf_counter() - t0:.1f} s (images in {out}/images/)")
    return 0
