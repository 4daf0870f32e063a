"""``python -m motionblur demo``: the library's main job on one scene, small and quick.

Renders three built-in scenes at 320x240 -- the translating cube of the motion-volume paper, a
camera pan, and a bending arm (a deforming mesh) -- with every method that applies to each:
accumulation (N = 1, 4, 16, 64), motion volumes (1 and 4 segments, box and ramp filters), blur
shells, Kraus's opaque image blur, Chapman's camera blur, the McGuire/Guertin velocity filter,
the analytic method and ``auto`` at its default tolerance. Each image is measured against a
Mitsuba reference (K = 64 shutter times, cached), and ``out`` receives every image and the
references as PNGs (``images/``), a labelled side-by-side sheet per scene (``sheet_<scene>.png``:
the references and each method with its options, ms and two RMSEs: against Mitsuba, then against
the exact frame), ``results.csv``, ``results.md`` (the speed/error table), a Pareto plot per scene
and the static report page ``html/index.html`` (each image beside both references, with difference
images), whose path the run prints. Well under a minute.
"""

from __future__ import annotations

import time
from pathlib import Path

from . import bench

SWEEPS = {
    "accumulation": [{"samples": n} for n in (1, 4, 16, 64)],
    "motion_volume": [{"segments": s, "filter": f} for f in ("box", "ramp") for s in (1, 4)],
    "blur_shell": [{"subdivisions": s} for s in (4, 16)],
    "opaque_image": [{"aa": 2}],
    "camera_velocity": [{"samples": 8}, {"samples": None}],  # None: the line integral (default)
    "velocity": [{}],
    "analytic": [{"tolerance": 0.01}],
}

SCENES = ("cube", "pan", "bending_arm")


def run(out="out/demo", scenes=SCENES) -> int:
    if isinstance(scenes, str):
        scenes = [scenes]
    t0 = time.perf_counter()
    res = bench.run(
        out,
        scenes=list(scenes),
        width=320,
        height=240,
        times=64,
        spp=4,
        repeat=2,
        methods=[*SWEEPS, "auto"],
        sweeps=SWEEPS,
        pyrender_peer=False,
        save_images=True,
    )
    md = Path(res["paths"]["md"]).read_text()
    print(md)
    sheets = ", ".join(str(p) for k, p in res["paths"].items() if k.startswith("sheet_"))
    page = res["paths"].get("html")
    print(
        f"demo written to {out}/ in {time.perf_counter() - t0:.1f} s: sheets {sheets}, single images in {out}/images/"
        + (
            f"; the report page (every image beside both references, with difference images): {page}"
            if page
            else ""
        )
    )
    return 0
