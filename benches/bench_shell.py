"""Blur-shell benchmark: silhouette update and build() from 10k to 1.3M faces, against the numpy
twin measured in the same run, and the shell's share of a frame (the paper claims about 1%).

Meshes: a 10k-face torus and icospheres of 82k, 328k and 1.3M faces, deformed every update
(a travelling wave plus a translation, so the silhouette changes and every normal is recomputed).

- update: ``BlurShell.update(vertices)`` (float32 conversion, face and vertex normals, facing,
  per-polygon silhouette edge, ring and state). Peer: the numpy twin's update (tests/_helpers/shell_twin.py,
  vectorised numpy, the same float32 arithmetic; both must give the same state, checked first).
- build: ``BlurShell.build()`` after the 10th update (only live strips are emitted).
- frame share: a 640x480 frame of our rasterizer drawing the mesh (opaque) and the shell (culling
  off, exact transparency); share = (update + build) / (update + build + rasterize).
  The paper (Jones and Keyser, tables 1-2) reports ~1% of frame time for the whole method.

Prints best-of-N milliseconds, ms per 100k faces and the ratios, writes out/bench/shell.md.
Usage: python benches/bench_shell.py [--quick]
"""

from __future__ import annotations

import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

import motionblur as mb
from motionblur import meshes

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "_helpers"))
from shell_twin import TwinShell  # noqa: E402


def best_ms(fn, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best * 1e3


def cpu_ms(fn, repeat: int) -> float:
    """Median CPU time of all threads (process time): on a busy shared machine this is steadier
    than wall time; on 2 idle cores the wall time is about half of it."""
    out = []
    for _ in range(repeat):
        c0 = time.process_time()
        fn()
        out.append(time.process_time() - c0)
    return float(np.median(out)) * 1e3


def frames(v: np.ndarray, k: int) -> list[np.ndarray]:
    r = np.linalg.norm(v, axis=1).max()
    return [
        v + 0.04 * r * np.sin(4.0 * v[:, 2:3] / r + 0.5 * i) * [1.0, 0.0, 0.0] + [0.03 * r * i, 0.0, 0.0]
        for i in range(k)
    ]


def measure(name: str, v: np.ndarray, f: np.ndarray) -> tuple:
    """One mesh: update, twin update, build, frame; prints and returns the table row."""
    n_updates = 12
    seq = frames(v, n_updates + 1)
    repeat = 3 if len(f) > 500_000 else 7
    # Same state as the twin first (small prefix of updates).
    shell = mb.BlurShell(f, subdivisions=10, hysteresis=3)
    twin = TwinShell(f, len(v), 10, 3)
    for p in seq[:3]:
        shell.update(p)
        twin.update(p)
    st = shell.state()
    assert np.array_equal(st["facing"], twin.facing) and np.array_equal(st["fade"], twin.fade), (
        "twin mismatch"
    )
    # Warm state: 10 updates, then time one more update (on a fresh copy of the state each
    # repeat would cost a rebuild; updating with the next frame repeatedly is the same work).
    shell = mb.BlurShell(f, subdivisions=10, hysteresis=3)
    for p in seq[:10]:
        shell.update(p)
    i = [10]

    def ours_update():
        shell.update(seq[i[0] % len(seq)])
        i[0] += 1

    t_up = best_ms(ours_update, repeat)
    c_up = cpu_ms(ours_update, repeat)
    j = [10]

    def peer_update():
        twin.update(seq[j[0] % len(seq)])
        j[0] += 1

    t_peer = best_ms(peer_update, max(2, repeat // 2))
    shell.reset()
    for p in seq[:11]:
        shell.update(p)
    t_build = best_ms(shell.build, repeat)
    sm = shell.build()
    # Frame: mesh + shell through our rasterizer at 640x480.
    r = np.linalg.norm(v, axis=1).max()
    centre = seq[10].mean(axis=0)
    cam = mb.Camera(mb.look_at(centre + [0.0, 0.6 * r, 3.2 * r], centre), 0.9, 640, 480)
    draws = [mb.Draw(seq[10], f, (0.8, 0.7, 0.6))]
    if not sm.is_empty:
        draws.append(sm.draw(object_id=1))
    t_rast = best_ms(lambda: mb.rasterize(cam, draws), max(2, repeat // 2))
    share = (t_up + t_build) / (t_up + t_build + t_rast)
    per = 1e5 / len(f)
    row = (
        name,
        len(f),
        t_up,
        t_up * per,
        t_build,
        t_build * per,
        t_peer,
        t_peer / t_up,
        len(sm),
        t_rast,
        share,
        c_up,
    )
    print(
        f"{name:<15} {len(f):>9} faces  update {t_up:7.2f} ms ({t_up * per:5.2f}/100k, cpu {c_up:6.2f} ms)  "
        f"build {t_build:6.2f} ms ({t_build * per:5.2f}/100k, {len(sm)} tris)  numpy twin update "
        f"{t_peer:8.2f} ms ({t_peer / t_up:5.1f}x)  raster {t_rast:7.2f} ms  shell share {100 * share:5.1f}%"
    )
    return row


def main() -> None:
    quick = "--quick" in sys.argv
    cores = os.cpu_count()
    usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else cores
    threads = os.environ.get("RAYON_NUM_THREADS", "default")
    header = (
        f"machine: {platform.machine()}, {cores} cores ({usable} usable, shared with other jobs: load "
        f"{os.getloadavg()[0]:.1f}), rayon threads {threads}, python {platform.python_version()}, numpy {np.__version__}"
    )
    print(header)
    cases = [("torus 10k", meshes.torus(n_major=100, n_minor=50)), ("icosphere 82k", meshes.icosphere(6))]
    if not quick:
        cases += [("icosphere 328k", meshes.icosphere(7)), ("icosphere 1.3M", meshes.icosphere(8))]
    rows = [measure(name, v, f) for name, (v, f) in cases]
    lines = [
        "# Blur-shell benchmark",
        "",
        header + ".",
        "Best of 3-7 runs. update = silhouette of motion + rings (normals recomputed every update); "
        "build = shell mesh after 11 updates (10 subdivisions, hysteresis 3); numpy ratio = numpy "
        "twin update / ours, same run; share = (update + build) / (update + build + our 640x480 "
        "rasterize of mesh + shell). update CPU = median process time of all threads per update (steadier "
        "than wall time on a shared machine; about twice the wall time on 2 idle cores). "
        "Target: < 1 ms per 100k faces; paper: ~1% of frame time.",
        "",
        "| mesh | faces | update ms | update ms/100k | update CPU ms | build ms | build ms/100k | numpy update ms "
        "| ratio | shell tris | raster ms | shell share |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    lines += [
        f"| {n} | {nf:,} | {u:.2f} | {up:.2f} | {cu:.2f} | {b:.2f} | {bp:.2f} | {p:.1f} | {r:.1f}x | {st:,} "
        f"| {ra:.1f} | {100 * sh:.1f}% |"
        for n, nf, u, up, b, bp, p, r, st, ra, sh, cu in rows
    ]
    out = Path("out/bench")
    out.mkdir(parents=True, exist_ok=True)
    (out / "shell.md").write_text("\n".join(lines) + "\n")
    print(f"wrote {out / 'shell.md'}")


if __name__ == "__main__":
    main()
