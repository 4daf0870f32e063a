"""The planner (method ``auto``): each object drawn by the cheapest method that meets a tolerance,
or the most accurate one that fits a time budget.

A scene pays only for what it needs. Per frame, ``auto``:

1. measures what each object does on screen (:mod:`._features`: screen motion in pixels,
   triangle size on screen, rotation, spread of motion, concavity, hollowness, swept area) and
   with ``budget_ms``, times one accumulation sample of it (the time model's probe of scene and
   machine; with a tolerance nothing is timed and the fit's median probe stands in, so the plan
   is the same on every run);
2. under a still camera, draws every object whose screen motion is under :data:`STILL_PX`
   pixels sharp, once, at the reference time (it joins the static layer);
3. groups the moving objects whose swept screen boxes overlap (a method composites overlapping
   blurs correctly only among the objects it draws itself), and plans each group: among the
   candidates of the cost and error model (every option set the report sweeps of analytic,
   motion volume, accumulation and the image-space blurs, where the method applies), the one
   with the least predicted time whose predicted RMSE against the own-limit reference
   (accumulation with 1024 samples), plus ``margin`` standard deviations of the model's
   residuals, is under ``tolerance``; or, given ``budget_ms``, the most accurate one whose
   predicted time fits the budget; the most accurate (fastest) candidate when none does;
4. renders: one call when every group chose the same thing; otherwise each group by its own
   method over the static scene, the results added as differences from the static frame
   (exact where the groups' boxes do not overlap, which is how the groups were made).

The model (:mod:`._auto_model`, ``auto_model.json`` beside this file) is fitted from the report's
measurements and refitted by ``python -m motionblur bench --fit-auto``. ``Frame.stats["plan"]``
says for each object what was chosen and why. The plan is kept with the scene object (up to 16
scenes), as a real-time loop keeps its static layer: rendering the same ``Scene`` again does not
plan again.
"""

from __future__ import annotations

import threading
import time

from .._validate import as_float, as_int
from ..raster import Frame
from ..render import METHODS, register
from ..scene import Object, Scene
from ._auto_model import Model, load_model
from ._features import group_features, screen_box

__all__ = ["auto", "plan", "renders_shutter", "STILL_PX", "DEFAULT_TOLERANCE"]

#: Objects moving less than this many pixels over the shutter are drawn sharp once.
STILL_PX = 0.5
#: The default tolerance: RMSE against the own-limit reference (premultiplied linear RGBA).
DEFAULT_TOLERANCE = 0.01
_PLANS: dict[int, tuple[Scene, tuple, dict]] = {}
_PLAN_CACHE = 16
_PLANS_LOCK = threading.Lock()


def renders_shutter(options: dict, scene: Scene) -> bool:
    """Whether a method run with ``options`` renders ``scene``'s shutter: False when the options
    name another ``filter`` than the scene's (the motion volume's ramp, triangle or gaussian looks
    on a box shutter). ``auto`` never chooses such a run, and the report does not measure it."""
    shutter = scene.shutter if isinstance(scene.shutter, str) else "weights"
    return options.get("filter", shutter) == shutter


def _overlap(a, b) -> bool:
    return a[0] <= b[2] and b[0] <= a[2] and a[1] <= b[3] and b[1] <= a[3]


def _groups(scene: Scene, moving) -> list[list[tuple[int, Object]]]:
    """The moving objects (pairs) joined where their swept screen boxes overlap."""
    boxes = [screen_box(scene, [p]) for p in moving]
    parent = list(range(len(moving)))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i in range(len(moving)):
        for j in range(i + 1, len(moving)):
            if _overlap(boxes[i], boxes[j]):
                parent[find(i)] = find(j)
    out: dict[int, list] = {}
    for i, p in enumerate(moving):
        out.setdefault(find(i), []).append(p)
    return list(out.values())


def _probe_ms(scene: Scene, aa: int) -> float:
    """Milliseconds of one accumulation sample of ``scene`` at ``aa`` (the second of two renders:
    the first builds the static layer): the time model's measure of the scene and the machine."""
    fn = METHODS["accumulation"].fn
    fn(scene, samples=1, aa=aa)
    t0 = time.perf_counter()
    fn(scene, samples=1, aa=aa)
    return (time.perf_counter() - t0) * 1e3


def _still(obj: Object, t: float) -> Object:
    return Object((obj.world_vertices(t), obj.mesh.faces), obj.color, obj.shading, None, obj.name)


def plan(scene: Scene, tolerance=None, budget_ms=None, aa: int = 1, model: Model | None = None, margin=None):
    """``(scene to render, [(method, options, object indices)], plan dict)`` for ``scene`` (see
    the module docs); the plan dict is what ``Frame.stats["plan"]`` holds: per object name (or
    ``object<k>``) the method, options, predicted ms and RMSE and the reason."""
    model = model or load_model()
    margin = model.margin if margin is None else float(margin)
    goal = "budget" if budget_ms is not None else "tolerance"
    tol = DEFAULT_TOLERANCE if tolerance is None else as_float(tolerance, "tolerance")
    budget = None if budget_ms is None else as_float(budget_ms, "budget_ms")
    if tolerance is not None and budget_ms is not None:
        raise ValueError("tolerance, budget_ms: give one of them, not both")
    if not tol > 0 or (budget is not None and not budget > 0):
        raise ValueError("tolerance and budget_ms must be > 0")
    objects = list(scene.objects)
    info: dict[str, dict] = {}
    names = [o.name or f"object{k}" for k, o in enumerate(objects)]
    moving = []
    for k, o in enumerate(objects):
        if not (o.is_moving or scene.camera_moves):
            info[names[k]] = {"method": "static", "reason": "does not move: in the static layer, drawn once"}
            continue
        f = group_features(scene, [(k, o)])
        # Frozen in world space only under a still camera: under a moving one, an object still on
        # screen moves with the camera, and freezing it would smear it the other way.
        if f["motion_px"] < STILL_PX and not scene.camera_moves:
            objects[k] = _still(o, scene.reference_t)
            info[names[k]] = {
                "method": "static",
                "reason": f"moves {f['motion_px']:.2f} px < {STILL_PX} px on screen: drawn sharp once",
            }
        else:
            moving.append((k, o))
    prepared = (
        scene.with_(objects=objects) if any(a is not b for a, b in zip(objects, scene.objects)) else scene
    )
    choices = []
    for group in _groups(prepared, moving) if moving else []:
        sub = prepared.with_(objects=[o for k, o in enumerate(objects) if (k, o) in group or not o.is_moving])
        applies = {m: METHODS[m].applies(sub) for m in model.methods() if m in METHODS}
        # Only a time budget is worth a timed probe: a tolerance's plan must not depend on the
        # machine's load (the same scene gets the same plan on every run, in every process).
        probe = _probe_ms(sub, aa) if goal == "budget" else model.reference_probe_ms
        feats = {**group_features(prepared, group), "probe_ms": probe}
        pick = model.choose(
            feats, tol if goal == "tolerance" else None, budget, aa, applies, margin,
            lambda options: renders_shutter(options, scene),  # keep
        )  # fmt: skip
        choices.append((pick["method"], pick["options"], [k for k, _ in group]))
        for k, _ in group:
            info[names[k]] = {
                **pick,
                "group": [names[j] for j, _ in group],
                "features": {n: round(v, 4) for n, v in feats.items()},
            }
    return prepared, choices, {"goal": goal, "tolerance": tol if goal == "tolerance" else None,
                               "budget_ms": budget, "objects": info}  # fmt: skip


def _render_groups(scene: Scene, choices, aa: int) -> Frame:
    if len({(m, tuple(sorted(o.items()))) for m, o, _ in choices}) <= 1:
        m, opts, _ = choices[0]
        return METHODS[m].fn(scene, **_with_aa(m, opts, aa))
    grouped = {k for _, _, ks in choices for k in ks}
    static = scene.with_(objects=[o for k, o in enumerate(scene.objects) if k not in grouped])
    base = METHODS["accumulation"].fn(static, samples=1, aa=aa)
    keep = [k for k in range(len(scene.objects)) if k not in grouped]
    rgba, ids = base.rgba.astype("float64"), base.ids.copy()
    for m, opts, ks in choices:
        index = sorted(keep + ks)
        f = METHODS[m].fn(scene.with_(objects=[scene.objects[k] for k in index]), **_with_aa(m, opts, aa))
        rgba += f.rgba - base.rgba
        for local, k in enumerate(index):
            if k in ks:
                ids[f.ids == local] = k
    base.rgba = rgba.astype("float32")
    base.ids = ids
    return base


def _with_aa(method: str, opts: dict, aa: int) -> dict:
    import inspect

    if "aa" in opts or "aa" not in inspect.signature(METHODS[method].fn).parameters:
        return dict(opts)
    return {**opts, "aa": aa}


@register("auto", sweep=[{}, {"tolerance": 0.003}, {"tolerance": 0.03}], applies=lambda scene: True)
def auto(scene: Scene, tolerance=None, budget_ms=None, aa: int = 1, model=None) -> Frame:
    """Planned per object: the cheapest method predicted to meet a tolerance, or the most accurate within a budget.

    Options: ``tolerance`` RMSE against the own-limit reference (accumulation with 1024 samples;
    premultiplied linear RGBA), default :data:`DEFAULT_TOLERANCE` (0.01); ``budget_ms`` instead,
    milliseconds per frame on the machine the model was fitted on; ``aa`` 1, 2 or 4 samples per
    pixel along each axis, given to the chosen method; ``model`` the path of a model file (default
    the package's ``auto_model.json``; ``bench --fit-auto`` writes one). ``stats["plan"]``: per object the method,
    options, predicted ms and RMSE, and why (see :mod:`motionblur.methods.auto`).
    """
    aa = as_int(aa, "aa")
    key = id(scene)
    hit = _PLANS.get(key)
    args = (tolerance, budget_ms, aa, model)
    if hit is not None and hit[0] is scene and hit[1] == args:
        prepared, choices, info = hit[2]["scene"], hit[2]["choices"], hit[2]["plan"]
    else:
        prepared, choices, info = plan(scene, tolerance, budget_ms, aa, load_model(model) if model else None)
        with _PLANS_LOCK:  # renders in several threads share the plans
            if len(_PLANS) >= _PLAN_CACHE:
                _PLANS.pop(next(iter(_PLANS)))
            _PLANS[key] = (scene, args, {"scene": prepared, "choices": choices, "plan": info})
    if not choices:
        frame = METHODS["accumulation"].fn(prepared, samples=1, aa=aa)
    else:
        frame = _render_groups(prepared, choices, aa)
    frame.stats["plan"] = info
    return frame
