"""Where the report's work runs: in this process, or as Dask tasks on a ``dask.distributed`` cluster.

The report does three kinds of work ([`bench`][motionblur.evaluation.bench] drives them, scene by scene):

- **references** ([`reference_task`][motionblur.evaluation.cluster.reference_task]): Mitsuba at K shutter times, and each method's own
  N -> infinity limit (accumulation with 1024 samples on our rasterizer); the slow part. Each is
  cached on disk keyed by a hash of the scene and the reference's settings ([`cache`][motionblur.evaluation.cache]), so a
  rerun renders nothing twice, and workers sharing the folder share the cache;
- **timed renders** ([`timed_task`][motionblur.evaluation.cluster.timed_task]): a method's frame, timed (best of ``repeat`` after one
  warm-up), returning the wall time, the image and the frame's plan (``auto``);
- **errors** ([`error_task`][motionblur.evaluation.cluster.error_task]): RMSE, PSNR, FLIP and coverage against both references.

[`Serial`][motionblur.evaluation.cluster.Serial] runs them in this process, one after another. [`Dask`][motionblur.evaluation.cluster.Dask] runs references and
errors as Dask tasks spread over the cluster's workers (``client.map``), and keeps timings
undisturbed: every timed render is a task pinned to one worker (the first, by address,
``workers=[w], allow_other_workers=False``) and submitted only after the previous one finished,
and only while no other task of the report runs (the references of the whole run are finished
before the first timing; a scene's errors are computed after its timings and waited for before
the next scene's timings start). So one render at a time runs anywhere on the cluster while a
timing is taken, as in the serial run. [`client_for`][motionblur.evaluation.cluster.client_for] makes the client of ``--dask local``
(a ``LocalCluster`` of processes, one thread each) or of a scheduler's address.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

import numpy as np

from .._optional import require
from ..methods._estimate import exact
from ..render import render
from ..scene import Scene
from . import metrics
from . import reference as ref_mod
from .cache import cached, reference_key

__all__ = [
    "SceneRef",
    "reference_task",
    "timed_task",
    "error_task",
    "call_task",
    "Serial",
    "Dask",
    "client_for",
]


class SceneRef:
    """A scene by name and size, built where a task runs (a Scene holds compiled meshes, which
    do not pickle): ``SceneRef("bunny_turn", 320, 240).build()``, cached per process so every
    task of one process renders the same Scene object (the static layers and plans methods keep
    across frames stay valid)."""

    def __init__(self, name: str, width: int, height: int):
        self.name, self.width, self.height = str(name), int(width), int(height)

    def build(self) -> Scene:
        key = (self.name, self.width, self.height)
        if key not in _BUILT:
            from ..scenes_builtin import SCENES
            from ..scenes_real import REAL_SCENES

            every = {**SCENES, **REAL_SCENES}
            if self.name not in every:
                raise ValueError(f"scene: unknown {self.name!r}")
            _BUILT[key] = every[self.name](width=self.width, height=self.height)
        return _BUILT[key]

    def __repr__(self) -> str:
        return f"SceneRef({self.name!r}, {self.width}, {self.height})"


_BUILT: dict[tuple, Scene] = {}


def _scene(s) -> Scene:
    return s.build() if isinstance(s, SceneRef) else s


def call_task(fn: Callable, scene, *args):
    """``fn(scene, *args)`` with a [`SceneRef`][motionblur.evaluation.cluster.SceneRef] built first (for timed comparisons)."""
    return fn(_scene(scene), *args)


def reference_task(scene: Scene, kind: str, settings: dict, folder: str) -> np.ndarray:
    """(H,W,4) float32 reference of ``scene``, from the cache ``folder`` or rendered into it.

    ``kind`` ``"mitsuba"``: settings ``times`` (K), ``spp``, ``seed``: [`reference.mitsuba`][motionblur.evaluation.reference.mitsuba];
    ``"limit"``: settings ``samples`` and ``aa``: the exact time integral on our rasterizer
    ([`motionblur.exact`][motionblur.exact]) when ``samples`` is None, else stratified accumulation with that
    many samples: the limit every method approaches (no shadows, our shading). ``scene``: a
    Scene or a [`SceneRef`][motionblur.evaluation.cluster.SceneRef]."""
    scene = _scene(scene)
    if kind == "mitsuba":
        key = reference_key(scene, kind, variant=ref_mod.mitsuba_variant(), **settings)

        def make():
            return ref_mod.mitsuba(
                scene, times=settings["times"], spp=settings["spp"], seed=settings["seed"]
            ).rgba

    elif kind == "limit":
        key = reference_key(scene, kind, **settings)

        def make():
            if settings.get("samples") is None:
                return exact(scene, aa=settings["aa"]).rgba
            return render(scene, "accumulation", samples=settings["samples"], aa=settings["aa"]).rgba

    else:
        raise ValueError(f"kind: expected 'mitsuba' or 'limit', got {kind!r}")
    return cached(folder, key, make)[0]


#: Seconds of timed renders after which a timing stops repeating (at least one render is timed).
TIMING_BUDGET_S = 1.5


def timed_task(scene: Scene, method: str, options: dict, repeat: int) -> tuple[float, np.ndarray, dict]:
    """``(ms, rgba (H,W,4) float32, plan)``: one warm-up render of ``method`` with ``options``
    (caches, first-call costs), then the best wall time of ``repeat`` renders (the method's own
    cost: without the pilot error estimate ``render`` adds by default), stopping early
    once the timed renders add up to `TIMING_BUDGET_S` (a render of over 0.75 s is timed
    once or twice: the load's share of its time is the smaller); ``plan`` is the frame's
    ``stats["plan"]`` (auto) or ``{}``."""
    scene = _scene(scene)
    render(scene, method, error_estimate=False, **options)
    best, frame, spent = float("inf"), None, 0.0
    for _ in range(max(1, int(repeat))):
        t0 = time.perf_counter()
        frame = render(scene, method, error_estimate=False, **options)
        dt = time.perf_counter() - t0
        best, spent = min(best, dt), spent + dt
        if spent > TIMING_BUDGET_S:
            break
    return best * 1e3, np.asarray(frame.rgba, np.float32), dict(frame.stats.get("plan", {}))


def error_task(rgba: np.ndarray, mitsuba: np.ndarray, limit: np.ndarray, flip: bool) -> dict:
    """Errors of ``rgba`` (H,W,4): ``rmse``, ``psnr``, ``flip`` (NaN unless ``flip``) and
    ``coverage_error`` against the Mitsuba reference, ``rmse_limit`` against the method's own
    limit (FLIP, the costly metric at 0.2 s an image, only against Mitsuba, the one the report's
    FLIP comparisons use)."""
    return {
        "rmse": metrics.rmse(rgba, mitsuba),
        "psnr": metrics.psnr(rgba, mitsuba),
        "flip": metrics.flip(rgba, mitsuba) if flip else float("nan"),
        "coverage_error": metrics.coverage_error(rgba, mitsuba),
        "rmse_limit": metrics.rmse(rgba, limit),
    }


class Serial:
    """Every task in this process, one after another."""

    name = "serial"

    def map(self, fn: Callable, *iterables) -> list:
        return [fn(*args) for args in zip(*iterables)]

    def timed(self, fn: Callable, jobs: Sequence[tuple]) -> list:
        return [fn(*job) for job in jobs]

    def close(self) -> None:
        pass


class Dask:
    """Tasks on the cluster of ``client`` (a ``dask.distributed.Client``); see the module docs
    for how timings stay undisturbed. ``close()`` closes the client (and a cluster it made)."""

    name = "dask"

    def __init__(self, client, owns: bool = False):
        self.client, self.owns = client, owns
        workers = sorted(client.scheduler_info()["workers"])
        if not workers:
            raise RuntimeError("the Dask cluster has no workers")
        self.timing_worker = workers[0]

    def map(self, fn: Callable, *iterables) -> list:
        args = [list(it) for it in iterables]
        if not args or not args[0]:
            return []
        futures = self.client.map(fn, *args, pure=False)
        return self.client.gather(futures)

    def timed(self, fn: Callable, jobs: Sequence[tuple]) -> list:
        out = []
        for job in jobs:  # one at a time, on one worker
            fut = self.client.submit(
                fn, *job, workers=[self.timing_worker], allow_other_workers=False, pure=False
            )
            out.append(fut.result())
        return out

    def close(self) -> None:
        if self.owns:
            cluster = getattr(self.client, "cluster", None)
            self.client.close()
            if cluster is not None:
                cluster.close()


def client_for(address: str, workers: int = 2):
    """A ``dask.distributed.Client``: ``"local"`` starts a ``LocalCluster`` of ``workers``
    processes with one thread each (each render uses every core through rayon); anything else
    is a scheduler address (``tcp://host:8786``)."""
    distributed = require("distributed", "the report on Dask (bench --dask)")
    if address == "local":
        cluster = distributed.LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
        )
        return distributed.Client(cluster)
    return distributed.Client(address)
