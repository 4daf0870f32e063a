"""Production scale of the exact method (issue 27, section 1): the analytic frame at 1080p on a
dense mesh against accumulation with 256 samples in the same run, its peak memory at 4K, and its
time against resolution and face count, beside accumulation at the analytic frame's own error.

Mesh: the shipped Stanford bunny (5,998 faces) subdivided by trimesh (midpoint subdivision, each
level x4 faces: the same surface, more triangles): ``--level 2`` gives 95,968 faces; the faces
table runs from ``--min-level`` (-1: coarsened by vertex clustering to 1,481 faces) to
``--max-level`` (4: 1,535,488 faces). Motions,
each over a box shutter, over the static floor of the real-mesh scenes, lambert-lit:
``translate`` (across the view, 1.2 scene units) and ``turn`` (1.2 rad about the vertical while
moving 0.8 units across, five keyframes).

Target (issue 27): at 1920x1080 on meshes of 50k faces and more, translating and turning, the
analytic frame costs no more than accumulation with 256 samples, at an error no larger than
accumulation with 4096 samples; at 3840x2160 its peak memory is under 1 GB with the default
budget. Times are ``render(..., error_estimate=False)`` (the pilot error estimate, which renders
the scene twice more at 64x48, is left out of both methods and timed on its own), best of
``--repeat`` calls after a warm-up, the two methods interleaved per round (paired: the load of
the shared machine falls on both alike); the load average is printed. Errors are RMSE of the
premultiplied RGBA against the exact integral (``motionblur.methods._estimate.exact``: the
analytic method with tolerance 0.002 px and 4 Gauss points), at ``--error-size``.

Also printed: the analytic kernel's profile (thread time finding covered spans and resolving
samples, prim set-up, the Python side: segment rule and the straddled positions), and where a
target is missed, why.

``scaling`` (time against resolution and faces) and ``motion`` (time against the translation's
length and the turn's angle at ``--faces-size``): beside accumulation with 256 samples,
accumulation at the analytic frame's own error (its sample count extrapolated from its errors at
64 and 256 samples, its time taken as linear in the count), errors against the exact integral at
the same size.

Usage: python benches/bench_production.py [--quick] [--repeat 2] [--level 2] [--sections target,memory,scaling,motion] (scaling = resolution,faces)
Writes out/bench/production.md, production_resolution.png, production_faces.png and
production_motion.png.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("MPLBACKEND", "Agg")

import motionblur as mb  # noqa: E402
from motionblur.methods._estimate import exact  # noqa: E402
from motionblur.scene import DirectionalLight, Motion, Object, Scene, rotate, translate  # noqa: E402
from motionblur.scenes_real import _COLORS, FLOOR_Y, _camera, _floor, real_mesh  # noqa: E402

TARGET_SIZE = (1920, 1080)
MEMORY_SIZE = (3840, 2160)
MEMORY_TARGET = 1 << 30
SIZES = [(320, 240), (640, 360), (960, 540), (1920, 1080), (3840, 2160)]


def bunny(level: int) -> tuple[np.ndarray, np.ndarray]:
    """The shipped bunny (5,998 faces), normalised, subdivided ``level`` times (x4 faces each);
    a negative ``level`` coarsens it instead (`_clustered`: about 1/4 the faces a level)."""
    import trimesh

    v, f = real_mesh("bunny")
    if level < 0:
        return _clustered(np.asarray(v, np.float64), np.asarray(f), len(f) >> (-2 * level))
    m = trimesh.Trimesh(np.array(v), np.array(f), process=False)
    for _ in range(level):
        m = m.subdivide()
    return np.asarray(m.vertices), np.asarray(m.faces)


def _clustered(v: np.ndarray, f: np.ndarray, want: int) -> tuple[np.ndarray, np.ndarray]:
    """The mesh coarsened by vertex clustering to about ``want`` faces: vertices merged per cell
    of a cubic grid (their mean), faces that collapse or repeat dropped; the cell size is
    bisected on the face count (no quadric decimator is a dependency)."""
    lo_cell, hi_cell = 1e-4, 1.0
    best = (v, f)
    for _ in range(30):
        cell = (lo_cell * hi_cell) ** 0.5
        keys = np.floor((v - v.min(0)) / cell).astype(np.int64)
        _, rep, inv = np.unique(keys, axis=0, return_index=True, return_inverse=True)
        inv = inv.ravel()
        g = inv[f]
        g = g[(g[:, 0] != g[:, 1]) & (g[:, 1] != g[:, 2]) & (g[:, 0] != g[:, 2])]
        g = np.unique(g, axis=0)
        if len(g) > want:
            lo_cell = cell
        else:
            hi_cell, best = cell, (inv, g)
        if abs(len(g) - want) <= want // 50:
            best = (inv, g)
            break
    inv, g = best
    centres = np.zeros((inv.max() + 1, 3))
    np.add.at(centres, inv, v)
    centres /= np.bincount(inv)[:, None]
    return centres, g


def motion(kind: str, angle: float = 1.2, length: float = 1.2) -> Motion:
    """``translate``: ``length`` scene units across the view; ``turn``: ``angle`` radians about the
    vertical while moving 0.8 units across, five keys."""
    y = FLOOR_Y + 0.002
    if kind == "translate":
        return Motion.linear(translate((-0.15 - length / 2, y, 0.0)), translate((-0.15 + length / 2, y, 0.0)))
    ts = np.linspace(0.0, 1.0, 5)
    return Motion(
        ts, np.stack([translate((-0.5 + 0.8 * t, y, 0.0)) @ rotate(angle * t, (0, 1, 0)) for t in ts])
    )


def scene(mesh, kind: str, w: int, h: int, **shape) -> Scene:
    obj = Object(mesh, color=_COLORS["bunny"], shading="lambert", motion=motion(kind, **shape), name="bunny")
    light = DirectionalLight((-0.35, -1.0, -0.55), 1.0)
    return Scene([obj, _floor()], _camera(w, h), lights=[light], ambient=0.0, shutter="box")


def load() -> str:
    return "/".join(f"{x:.1f}" for x in os.getloadavg())


def paired(fns: dict, repeat: int) -> tuple[dict, dict]:
    """Best wall time (s) of each callable, interleaved round by round after one warm-up call
    each; and each one's last result."""
    out = {k: f() for k, f in fns.items()}
    best = dict.fromkeys(fns, float("inf"))
    for _ in range(repeat):
        for k, f in fns.items():
            t = time.perf_counter()
            out[k] = f()
            best[k] = min(best[k], time.perf_counter() - t)
    return best, out


def rmse(a, b) -> float:
    return float(np.sqrt(np.mean((np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2)))


def analytic(s):
    return mb.render(s, "analytic", error_estimate=False)


def accumulation(n):
    return lambda s: mb.render(s, "accumulation", samples=n, error_estimate=False)


def profile(f, wall: float) -> str:
    st = f.stats
    # (the frame's own wall time: the best of the paired rounds is another render's)
    py = st.get("ms", wall * 1e3) - st["ms_total"]
    return (
        f"segments {st['segments']}, prims {st['prims']:,} (set up in {st.get('strips', 1)} strips of tile rows), sample tests {st['tests']:,}, spans "
        f"{st['spans']:,}, fragments {st['intervals']:,}, shaded pieces {st['pieces']:,}; thread time: "
        f"finding spans {st['ms_cover'] / 1e3:.2f} s, resolving and shading {st['ms_resolve'] / 1e3:.2f} s; "
        f"wall: prim set-up {st['ms_setup'] / 1e3:.2f} s, binning {st['ms_bin'] / 1e3:.2f} s, tiles "
        f"{st['ms_tiles'] / 1e3:.2f} s, Python side (segment rule, straddled positions, normals) "
        f"{py / 1e3:.2f} s"
    )


def target(mesh, a, lines: list[str]) -> None:
    w, h = TARGET_SIZE
    ew, eh = (int(v) for v in a.error_size.split("x"))
    lines += [
        f"## Target: {w}x{h}, {len(mesh[1]):,} faces, aa 1 (load {load()})",
        "",
        "| motion | analytic s | accumulation-256 s | ratio (target <= 1) | analytic RMSE | "
        f"acc-256 RMSE | acc-4096 RMSE (errors at {ew}x{eh}) | error target |",
        "|---|---:|---:|---:|---:|---:|---:|---|",
    ]
    print("\n".join(lines[-4:]), flush=True)
    notes = []
    for kind in ("translate", "turn"):
        s = scene(mesh, kind, w, h)
        t, out = paired(
            {"analytic": lambda s=s: analytic(s), "acc256": lambda s=s: accumulation(256)(s)}, a.repeat
        )
        se = scene(mesh, kind, ew, eh)
        ref = exact(se).rgba
        ea = rmse(analytic(se).rgba, ref)
        e256 = rmse(accumulation(256)(se).rgba, ref)
        e4096 = rmse(accumulation(4096)(se).rgba, ref)
        ratio = t["analytic"] / t["acc256"]
        row = (
            f"| {kind} | {t['analytic']:.2f} | {t['acc256']:.2f} | {ratio:.2f} "
            f"{'met' if ratio <= 1 else 'MISSED'} | {ea:.2e} | {e256:.2e} | {e4096:.2e} | "
            f"{'met' if ea <= e4096 else 'MISSED'} |"
        )
        print(row, flush=True)
        lines.append(row)
        notes.append(f"- {kind}: {profile(out['analytic'], t['analytic'])}")
        if ratio > 1:
            notes.append(
                f"  - time target missed by {ratio:.2f}x: the exact method shades every triangle that "
                "passes over a sample (the shaded pieces above) and tests every sample of every "
                "swept hull, so its cost grows with pixels x motion length / triangle size; "
                "accumulation's grows with samples x (faces + covered pixels)."
            )
    lines += ["", "Profile of the analytic frames:", *notes, ""]
    print("\n".join(notes), flush=True)


# The child's own peak: VmHWM of its memory map (ru_maxrss would carry the parent's peak over
# the exec on Linux).
_CHILD = """
import json, sys, time
sys.path.insert(0, sys.argv[1])
import bench_production as bp
def hwm():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1])
mesh = bp.bunny(int(sys.argv[2]))
w, h, kind = int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
s = bp.scene(mesh, kind, w, h)
before = hwm()
t = time.perf_counter()
f = bp.analytic(s)
dt = time.perf_counter() - t
after = hwm()
print(json.dumps({"before_kib": before, "peak_kib": after, "s": dt, "segments": f.stats["segments"],
                  "splits": f.stats["splits"], "strips": f.stats.get("strips", 1), "prims": f.stats["prims"]}))
"""


def memory(a, lines: list[str]) -> None:
    w, h = MEMORY_SIZE
    lines += [
        f"## Peak memory: analytic at {w}x{h}, default budget "
        f"({mb.budget.memory_budget() / 2**30:.0f} GiB), each in a fresh process (load {load()})",
        "",
        "| motion | segments | prims | strips | process peak MiB | of which the frame MiB | target < 1024 MiB | s |",
        "|---|---:|---:|---:|---:|---:|---|---:|",
    ]
    print("\n".join(lines[-4:]), flush=True)
    for kind in ("translate", "turn"):
        out = subprocess.run(
            [sys.executable, "-c", _CHILD, str(Path(__file__).parent), str(a.level), str(w), str(h), kind],
            capture_output=True, text=True, check=True,
        ).stdout  # fmt: skip
        r = json.loads(out.strip().splitlines()[-1])
        peak = r["peak_kib"] * 1024
        row = (
            f"| {kind} | {r['segments']} | {r['prims']:,} | {r['strips']} | {peak / 2**20:.0f} | {(r['peak_kib'] - r['before_kib']) / 1024:.0f} | "
            f"{'met' if peak < MEMORY_TARGET else 'MISSED'} | {r['s']:.1f} |"
        )
        print(row, flush=True)
        lines.append(row)
    lines.append("")


def scaling(mesh, a, lines: list[str], tables=("size", "faces")) -> dict:
    """The time-against-resolution (``size``) and time-against-faces (``faces``) tables."""
    res = {}
    if "size" in tables:
        res["size"] = _against_size(mesh, a, lines)
    if "faces" in tables:
        res["faces"] = _against_faces(a, lines)
    lines.append("")
    return res


def _against_size(mesh, a, lines: list[str]) -> list:
    sizes = SIZES[:-1] if a.quick else SIZES
    lines += [
        f"## Time against resolution: translate, {len(mesh[1]):,} faces (load {load()}); errors "
        "against the exact integral at each size; accumulation at the analytic frame's error "
        "extrapolated from its errors at 64 and 256 samples",
        "",
        f"| size | analytic s | accumulation-256 s | ratio | {_EQUAL_HEAD} |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    print("\n".join(lines[-4:]), flush=True)
    pts = []
    for w, h in sizes:
        s = scene(mesh, "translate", w, h)
        rep = 1 if w * h > 3e6 else a.repeat
        t, out = paired(
            {"analytic": lambda s=s: analytic(s), "acc256": lambda s=s: accumulation(256)(s)}, rep
        )
        eq = at_equal_error(s, t, out)
        row = f"| {w}x{h} | {t['analytic']:.2f} | {t['acc256']:.2f} | {t['analytic'] / t['acc256']:.2f} | {eq['cells']} |"
        print(row, flush=True)
        lines.append(row)
        pts.append((w * h, t["analytic"], t["acc256"], eq["t_eq"]))
    lines.append("")
    return pts


def _against_faces(a, lines: list[str]) -> list:
    fw, fh = (int(v) for v in a.faces_size.split("x"))
    lines += [
        f"## Time against faces: translate at {fw}x{fh} (load {load()}); the bunny from {a.min_level} "
        f"to {a.max_level} subdivisions (negative: coarsened by vertex clustering); errors and "
        "accumulation at equal error as above",
        "",
        f"| faces | analytic s | accumulation-256 s | ratio | shaded pieces | {_EQUAL_HEAD} |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    print("\n".join(lines[-4:]), flush=True)
    pts = []
    for lv in range(a.min_level, a.max_level + 1):
        m = bunny(lv)
        s = scene(m, "translate", fw, fh)
        t, out = paired(
            {"analytic": lambda s=s: analytic(s), "acc256": lambda s=s: accumulation(256)(s)}, a.repeat
        )
        eq = at_equal_error(s, t, out)
        row = (
            f"| {len(m[1]):,} | {t['analytic']:.2f} | {t['acc256']:.2f} | {t['analytic'] / t['acc256']:.2f} | "
            f"{out['analytic'].stats['pieces']:,} | {eq['cells']} |"
        )
        print(row, flush=True)
        lines.append(row)
        pts.append((len(m[1]), t["analytic"], t["acc256"], eq["t_eq"]))
    return pts


LENGTHS = (0.15, 0.3, 0.6, 1.2)  # scene units across the view (about 110 px a unit at 960x540)
ANGLES = (0.3, 0.6, 1.2, 2.4)  # radians about the vertical while moving


def equal_error(e64: float, e256: float, ea: float, t256: float) -> tuple[float, float]:
    """``(samples, seconds)`` of accumulation at the analytic frame's error ``ea``: the rate
    accumulation's error falls at, read from its errors at 64 and 256 samples (clamped to
    N^-0.5..N^-1.5), carried from 256 samples down to ``ea``; its time taken as linear in N."""
    rate = min(1.5, max(0.5, math.log(e64 / e256) / math.log(4.0))) if e64 > e256 > 0 else 1.0
    n = 256.0 * (e256 / ea) ** (1.0 / rate) if ea > 0 else math.inf
    return n, t256 * n / 256.0


# The columns `at_equal_error` fills.
_EQUAL_HEAD = "analytic RMSE | acc-256 RMSE | acc at equal error: samples, s | analytic / that"


def at_equal_error(s: Scene, t: dict, out: dict) -> dict:
    """Errors against the exact integral of one paired analytic / accumulation-256 run on ``s``
    (times ``t``, frames ``out``) and accumulation at the analytic frame's error (`equal_error`,
    from accumulation-64's error too): ``ea``, ``e256``, ``n_eq``, ``t_eq`` and the table
    ``cells`` of `_EQUAL_HEAD`."""
    ref = exact(s).rgba
    ea, e256 = rmse(out["analytic"].rgba, ref), rmse(out["acc256"].rgba, ref)
    e64 = rmse(accumulation(64)(s).rgba, ref)
    n_eq, t_eq = equal_error(e64, e256, ea, t["acc256"])
    cells = f"{ea:.1e} | {e256:.1e} | {n_eq:,.0f}, {t_eq:.1f} | {t['analytic'] / t_eq:.3f}"
    return {"ea": ea, "e256": e256, "n_eq": n_eq, "t_eq": t_eq, "cells": cells}


def _streak_px(s: Scene) -> float:
    """The longest screen path (pixels) of a mesh vertex over the shutter (33 times)."""
    obj = s.objects[0]
    v = np.asarray(obj.mesh.vertices, np.float64)[:: max(1, len(obj.mesh.vertices) // 2000)]
    pts = []
    for m in obj.motion.transforms_at(np.linspace(0.0, 1.0, 33)):
        pts.append(s.camera.project(v @ m[:3, :3].T + m[:3, 3])[0])
    steps = np.linalg.norm(np.diff(np.stack(pts), axis=0), axis=-1)
    return float(np.nanmax(steps.sum(axis=0)))


def motions(mesh, a, lines: list[str]) -> dict:
    """Time against motion length and turn angle, at ``--faces-size``, beside accumulation with
    256 samples and accumulation at the analytic frame's own error (`equal_error`)."""
    w, h = (int(v) for v in a.faces_size.split("x"))
    lines += [
        f"## Time against motion: {len(mesh[1]):,} faces at {w}x{h} (load {load()}); errors against "
        "the exact integral at the same size; accumulation at the analytic frame's error "
        "extrapolated from its errors at 64 and 256 samples",
        "",
        f"| motion | streak px | segments | analytic s | acc-256 s | ratio | {_EQUAL_HEAD} |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    print("\n".join(lines[-4:]), flush=True)
    res = {"length": [], "angle": []}
    cases = [("translate", {"length": v}) for v in LENGTHS] + [("turn", {"angle": v}) for v in ANGLES]
    for kind, shape in cases:
        s = scene(mesh, kind, w, h, **shape)
        t, out = paired({"analytic": lambda s=s: analytic(s), "acc256": lambda s=s: accumulation(256)(s)}, 1)
        eq = at_equal_error(s, t, out)
        label = (
            f"{kind} {shape.get('length', shape.get('angle'))}{' units' if kind == 'translate' else ' rad'}"
        )
        px = _streak_px(s)
        row = (
            f"| {label} | {px:.0f} | {out['analytic'].stats['segments']} | {t['analytic']:.2f} | "
            f"{t['acc256']:.2f} | {t['analytic'] / t['acc256']:.2f} | {eq['cells']} |"
        )
        print(row, flush=True)
        lines.append(row)
        res["length" if kind == "translate" else "angle"].append(
            (shape.get("length", shape.get("angle")), t["analytic"], t["acc256"], eq["t_eq"])
        )
    lines.append("")
    return res


def motion_plot(res: dict, out: Path) -> None:
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(9, 3.5))
    for ax, key, label in zip(
        axes, ("length", "angle"), ("translation (scene units)", "turn (rad)"), strict=True
    ):
        pts = np.array(res[key])
        ax.loglog(pts[:, 0], pts[:, 1], "o-", label="analytic")
        ax.loglog(pts[:, 0], pts[:, 2], "s-", label="accumulation-256")
        ax.loglog(pts[:, 0], pts[:, 3], "^--", label="accumulation at the analytic's error")
        ax.set_xticks(pts[:, 0], [f"{v:g}" for v in pts[:, 0]])
        ax.minorticks_off()
        ax.set_xlabel(label)
        ax.set_ylabel("seconds")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "production_motion.png", dpi=100)
    plt.close(fig)


def plots(res: dict, out: Path) -> None:
    try:
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plots")
        return
    for axis, label in (("size", "pixels"), ("faces", "faces")):
        if axis not in res:
            continue
        pts = np.array(res[axis])
        fig, ax = plt.subplots(figsize=(5, 3.5))
        ax.loglog(pts[:, 0], pts[:, 1], "o-", label="analytic")
        ax.loglog(pts[:, 0], pts[:, 2], "s-", label="accumulation-256")
        ax.loglog(pts[:, 0], pts[:, 3], "^--", label="accumulation at the analytic's error")
        ax.set_xlabel(label)
        ax.set_ylabel("seconds")
        ax.set_title(f"bunny translating: time against {label}")
        ax.legend()
        fig.tight_layout()
        fig.savefig(out / f"production_{'resolution' if axis == 'size' else 'faces'}.png", dpi=100)
        plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="no 4K point in the resolution table, 2 face levels")
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument(
        "--level", type=int, default=2, help="subdivisions of the target's bunny (2: 95,968 faces)"
    )
    ap.add_argument("--max-level", type=int, default=None, help="most subdivisions in the faces table")
    ap.add_argument("--min-level", type=int, default=-1, help="fewest (negative: coarsened, -1: 1,481 faces)")
    ap.add_argument("--faces-size", default="960x540")
    ap.add_argument("--error-size", default="480x270")
    ap.add_argument(
        "--sections",
        default="target,memory,scaling,motion",
        help="which tables, comma-separated (scaling: resolution and faces)",
    )
    a = ap.parse_args()
    if a.max_level is None:
        a.max_level = 2 if a.quick else 4
    mesh = bunny(a.level)
    lines = ["# The exact method at production scale (issue 27, section 1)", ""]
    print(lines[0], flush=True)
    sections = set(a.sections.split(","))
    if "target" in sections:
        target(mesh, a, lines)
    if "memory" in sections:
        memory(a, lines)
    out = Path("out/bench")
    out.mkdir(parents=True, exist_ok=True)
    tables = [k for k, name in (("size", "resolution"), ("faces", "faces")) if {name, "scaling"} & sections]
    if tables:
        plots(scaling(mesh, a, lines, tables), out)
    if "motion" in sections:
        motion_plot(motions(mesh, a, lines), out)
    lines.append(f"Load average at the end: {load()}")
    (out / "production.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
