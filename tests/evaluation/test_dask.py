"""The report on Dask: a small sweep on a real LocalCluster of processes gives the same errors as
the serial run, and references are cached on disk keyed by the scene, so nothing renders twice."""

from __future__ import annotations

import numpy as np
import pytest

import motionblur as mb
from motionblur.evaluation import bench, cache, cluster

SWEEPS = {"accumulation": [{"samples": 1}, {"samples": 4}], "motion_volume": [{"segments": 1, "filter": "box"}],
          "analytic": [{"aa": 1}]}  # fmt: skip
KW = dict(scenes=["cube", "knot_twist"], width=40, height=30, times=4, spp=1, repeat=1, methods=[*SWEEPS, "auto"],
          sweeps=SWEEPS, flip=True, pyrender_peer=False, limit_samples=16, write_html=False, log=lambda *a: None)  # fmt: skip


@pytest.mark.mitsuba
@pytest.mark.dask
def test_a_sweep_on_a_local_cluster_gives_the_serial_errors(tmp_path):
    serial = bench.run(tmp_path / "serial", **KW)
    client = cluster.client_for("local", workers=2)
    try:
        assert len(client.scheduler_info()["workers"]) == 2
        runner = cluster.Dask(client)
        pids = runner.map(_pid, range(6))
        distributed = bench.run(tmp_path / "dask", client=client, **KW)
    finally:
        cluster.Dask(client, owns=True).close()
    assert len(set(pids)) == 2  # the tasks ran in two other processes
    key = ("scene", "method", "options")
    a = {tuple(r[k] for k in key): r for r in serial["rows"]}
    b = {tuple(r[k] for k in key): r for r in distributed["rows"]}
    assert a.keys() == b.keys() and len(a) == 9  # 5 on the cube, 4 on the knot (no motion volume)
    for k in a:
        for err in ("rmse", "rmse_limit", "flip", "flip_limit", "coverage_error"):
            assert a[k][err] == pytest.approx(b[k][err], rel=1e-9, abs=1e-12), (k, err)
    for name in KW["scenes"]:
        for kind in ("mitsuba", "limit"):
            np.testing.assert_array_equal(
                serial["references"][name][kind], distributed["references"][name][kind]
            )


def _pid(_):
    import os

    return os.getpid()


def test_references_are_cached_by_a_hash_of_the_scene_and_settings(tmp_path, monkeypatch):
    scene = mb.SCENES["cube"](24, 18)
    calls = []
    real = mb.render

    def counting(*a, **k):
        calls.append(a[1])
        return real(*a, **k)

    monkeypatch.setattr(cluster, "render", counting)
    first = cluster.reference_task(scene, "limit", {"samples": 8, "aa": 1}, str(tmp_path))
    again = cluster.reference_task(mb.SCENES["cube"](24, 18), "limit", {"samples": 8, "aa": 1}, str(tmp_path))
    assert calls == ["accumulation"]  # the equal scene, built anew, hits the cache
    np.testing.assert_array_equal(first, again)
    cluster.reference_task(scene, "limit", {"samples": 16, "aa": 1}, str(tmp_path))
    assert len(calls) == 2 and len(list(tmp_path.glob("limit_*.npy"))) == 2
    # any change to the scene changes its hash
    h = cache.scene_hash(scene)
    cube = scene.objects[0]
    changed = [
        scene.with_(objects=[mb.Object(cube.mesh, (0.1, 0.2, 0.3), motion=cube.motion), *scene.objects[1:]]),
        scene.with_(
            objects=[
                mb.Object(cube.mesh, cube.color, motion=mb.Motion.linear([0, 0, 0], [1, 0, 0])),
                *scene.objects[1:],
            ]
        ),  # fmt: skip
        scene.with_(shutter="triangle"),
        scene.with_(camera=mb.Camera(scene.camera.pose, 0.71, 24, 18, znear=0.5, zfar=30.0)),
        scene.with_(objects=scene.objects[:-1]),
    ]
    assert len({h, *(cache.scene_hash(s) for s in changed)}) == 1 + len(changed)
    assert cache.scene_hash(mb.SCENES["cube"](24, 18)) == h
