"""Geometry benchmark: motionblur's Rust kernels against numpy + trimesh, measured in the same run.

Three jobs on icospheres of 82k, 328k and 1.3M faces (meshes.icosphere(6/7/8)):

- adjacency: build the edge adjacency from (V,3)/(F,3) arrays. Peer: trimesh
  ``Trimesh(process=False).face_adjacency`` (plus ``face_adjacency_edges``) on a fresh object.
  Ours: ``Mesh(v, f)`` (copy and validation included) and the adjacency build.
- contour, rigid: classify the faces and select and orient the contour edges for a new motion
  on a mesh kept across calls (a rigid object), so object-space face normals are cached on both
  sides (ours on the Mesh at the first call; the peer gets them precomputed), as is the
  adjacency (ours includes the face-neighbour table of a closed mesh, built on the first call
  and cached like trimesh's face_adjacency; best-of-N leaves that first call out on both
  sides). Peer: numpy dots and selection over trimesh's cached face_adjacency.
- contour, deformed: the same with face normals recomputed from new vertices every call (ours on
  a fresh ``Mesh.with_vertices`` copy, made before the clock starts; the peer recomputes its
  cross products).
- volume: a one-segment motion volume with vertex normals, ramp alpha and white colour.
  Peer: the same in numpy (normals by bincount, no vertex compaction) over cached adjacency.

Prints best-of-N wall and CPU milliseconds and ratios (peer / ours) and writes
out/bench/geometry.md. The machine has 2 cores, often shared with other jobs.
Usage: python benches/bench_geometry.py [--quick]
"""

from __future__ import annotations

import os
import platform
import sys
import time
from pathlib import Path

import numpy as np
import trimesh

import motionblur as mb
from motionblur import meshes


def best_ms(fn, repeat: int) -> tuple[float, float]:
    """Best wall-clock and best process CPU milliseconds (all threads) over ``repeat`` runs. On a
    shared machine the wall clock of our threaded code suffers most from other processes; the
    CPU time is the work done, comparable with the single-threaded peers."""
    wall = cpu = float("inf")
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall = min(wall, time.perf_counter() - t0)
        cpu = min(cpu, time.process_time() - c0)
    return wall * 1e3, cpu * 1e3


def np_normals(v, f):
    a = v[f[:, 0]]
    return np.cross(v[f[:, 1]] - a, v[f[:, 2]] - a)


def np_contour(v, f, adj, adj_edges, m, normals=None):
    """numpy twin: classification, selection and orientation (front face's winding); face
    normals recomputed unless given (a rigid object's cached ``normals``)."""
    front = (np_normals(v, f) if normals is None else normals) @ m >= 0.0
    sel = front[adj[:, 0]] != front[adj[:, 1]]
    a, e = adj[sel], adj_edges[sel]
    ff = np.where(front[a[:, 0]], a[:, 0], a[:, 1])
    t = f[ff]
    p, q = e[:, 0], e[:, 1]
    fwd = (
        ((t[:, 0] == p) & (t[:, 1] == q))
        | ((t[:, 1] == p) & (t[:, 2] == q))
        | ((t[:, 2] == p) & (t[:, 0] == q))
    )
    return np.where(fwd[:, None], e, e[:, ::-1]), front


def np_volume(v, f, adj, adj_edges, m):
    """numpy twin of a one-segment motion volume (leading, trailing, joining; rgba, normals)."""
    n_v = len(v)
    raw = np_normals(v, f)
    vn = np.stack(
        [np.bincount(f.ravel(), weights=np.repeat(raw[:, k], 3), minlength=n_v) for k in range(3)], 1
    )
    vn /= np.linalg.norm(vn, axis=1, keepdims=True)
    e, front = np_contour(v, f, adj, adj_edges, m)
    d = m / np.linalg.norm(m)
    x = v @ d
    alpha = max(0.1, 1.0 - np.linalg.norm(m) / (x.max() - x.min()))
    verts = np.concatenate([v + m, v])
    lead = f[front]
    trail = f[~front] + n_v
    a, b = e[:, 0], e[:, 1]
    a0, b0, a1, b1 = a + n_v, b + n_v, a, b
    join = np.concatenate([np.stack([a0, b0, b1], 1), np.stack([a0, b1, a1], 1)])
    faces = np.concatenate([lead, trail, join])
    rgba = np.ones((2 * n_v, 4), np.float32)
    rgba[n_v:, 3] = alpha
    normals = np.concatenate([vn, vn]).astype(np.float32)
    part = np.concatenate([np.zeros(len(lead)), np.ones(len(trail)), np.full(len(join), 2)]).astype(np.uint8)
    return verts, faces, rgba, normals, part


def main() -> None:
    quick = "--quick" in sys.argv
    subs = (4, 5) if quick else (6, 7, 8)
    cores = os.cpu_count()
    usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else cores
    threads = os.environ.get("RAYON_NUM_THREADS", f"{usable} (rayon default)")
    header = (
        f"machine: {platform.machine()}, {cores} cores ({usable} usable), rayon threads {threads}, "
        f"python {platform.python_version()}, numpy {np.__version__}, trimesh {trimesh.__version__}"
    )
    print(header)
    rng = np.random.default_rng(0)
    rows = []
    for sub in subs:
        v, f = meshes.icosphere(sub)
        v = v * (1.0 + 0.01 * rng.standard_normal((len(v), 1)))  # not a perfect sphere
        repeat = 5 if len(f) < 500_000 else 3
        m = np.array([0.31, -0.12, 0.94])

        def ours_adj(v=v, f=f):
            mesh = mb.Mesh(v, f)
            mesh._core.build_adjacency()

        def peer_adj(v=v, f=f):
            tm = trimesh.Trimesh(v, f, process=False)
            tm.face_adjacency  # noqa: B018
            tm.face_adjacency_edges  # noqa: B018

        t_ours_adj = best_ms(ours_adj, repeat)
        t_peer_adj = best_ms(peer_adj, repeat)

        mesh = mb.Mesh(v, f)
        mesh._core.build_adjacency()
        tm = trimesh.Trimesh(v, f, process=False)
        adj, adj_edges = tm.face_adjacency, tm.face_adjacency_edges
        # Same answer first (sorted rows compare exactly).
        ref, _ = np_contour(v, f, adj, adj_edges, m)
        got = mb.contour_edges(mesh, m)
        key = np.sort(ref, axis=1)
        assert np.array_equal(ref[np.lexsort((key[:, 1], key[:, 0]))], got), "contour mismatch"
        vol = mb.motion_volume(mesh, m)
        pv = np_volume(v, f, adj, adj_edges, m)
        assert len(vol.faces) == len(pv[1]), "volume face count mismatch"

        # The contour job takes milliseconds: more runs, so that best-of-N sees a quiet moment of
        # the shared machine on both sides.
        rc = 4 * repeat
        normals = np_normals(v, f)
        t_ours_c = best_ms(lambda mesh=mesh, m=m: mb.contour_edges(mesh, m), rc)
        t_peer_c = best_ms(
            lambda v=v, f=f, a=adj, e=adj_edges, m=m, n=normals: np_contour(v, f, a, e, m, n), rc
        )
        copies = iter([mesh.with_vertices(v) for _ in range(rc + 1)])  # fresh normal caches
        t_ours_d = best_ms(lambda c=copies, m=m: mb.contour_edges(next(c), m), rc)
        del copies
        t_peer_d = best_ms(lambda v=v, f=f, a=adj, e=adj_edges, m=m: np_contour(v, f, a, e, m), rc)
        t_ours_v = best_ms(lambda mesh=mesh, m=m: mb.motion_volume(mesh, m), repeat)
        t_peer_v = best_ms(lambda v=v, f=f, a=adj, e=adj_edges, m=m: np_volume(v, f, a, e, m), repeat)
        for job, ours, peer, who in [
            ("adjacency", t_ours_adj, t_peer_adj, "trimesh"),
            ("contour, rigid (normals cached)", t_ours_c, t_peer_c, "numpy"),
            ("contour, deformed (normals recomputed)", t_ours_d, t_peer_d, "numpy"),
            ("motion volume, 1 segment", t_ours_v, t_peer_v, "numpy"),
        ]:
            rows.append((len(f), job, ours, peer, who))
            print(
                f"{len(f):>9} faces  {job:<38} ours {ours[0]:8.2f} ms ({ours[1]:8.2f} cpu)  "
                f"{who:<8}{peer[0]:9.2f} ms ({peer[1]:8.2f} cpu)  ratio {peer[0] / ours[0]:5.1f}x "
                f"(cpu {peer[1] / ours[1]:5.1f}x)"
            )
    lines = [
        "# Geometry benchmark",
        "",
        header + ".",
        "Best of 3-5 runs (12-20 for the contour job); ratio = peer time / motionblur time, measured in the same run "
        "(`python benches/bench_geometry.py`, run by `make bench`). Wall clock and process CPU "
        "time (all threads); the peers are single-threaded numpy/trimesh.",
        "",
        "| faces | job | motionblur ms (cpu) | peer | peer ms (cpu) | ratio wall | ratio cpu |",
        "|---:|---|---:|---|---:|---:|---:|",
    ]
    lines += [
        f"| {n:,} | {job} | {o[0]:.2f} ({o[1]:.2f}) | {who} | {p[0]:.2f} ({p[1]:.2f}) | "
        f"{p[0] / o[0]:.1f}x | {p[1] / o[1]:.1f}x |"
        for n, job, o, p, who in rows
    ]
    out = Path("out/bench")
    out.mkdir(parents=True, exist_ok=True)
    (out / "geometry.md").write_text("\n".join(lines) + "\n")
    print(f"wrote {out / 'geometry.md'}")


if __name__ == "__main__":
    main()
