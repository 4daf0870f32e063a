"""Fitting the ``auto`` planner's cost and error model from the report's measurements, and judging
where ``auto`` lands against each scene's Pareto front.

:func:`fit` takes the report's rows (each with ``scene``, ``method``, ``_opts``, ``ms`` and
``rmse_limit``, the RMSE against the method's own limit) and the features of each scene's moving
objects (:func:`scene_features`, measured as the planner measures them) and fits, per candidate
(method and option set, the option ``aa`` of the run left out), ridge regressions of log RMSE
and log time on the terms of :mod:`motionblur.methods._auto_model`; the residuals kept are the
leave-one-out ones (a scene's residual from the fit without it), with each scene's terms, so the
planner judges a prediction by how wrong the model was on the scenes most like the one it
plans (:meth:`~motionblur.methods._auto_model.Model.error_spread`); :func:`calibrate_margin` then picks how
many of those spreads the planner adds to a predicted error before trusting it (the smallest
that meets the tolerance on 95% of scenes when each scene is planned by the model fitted without
it). ``python -m motionblur bench --fit-auto`` calls both and writes
``motionblur/methods/auto_model.json``.

:func:`front_time` is the Pareto front's time at a given error (the fastest row at least as
accurate); :func:`landing` compares an ``auto`` row with it; :func:`leave_one_out` replays the
planner on each scene with the model fitted on the other scenes, reading the chosen candidate's
measured time and error from the rows (nothing is rendered).
"""

from __future__ import annotations

import json
import math
import time

import numpy as np

from ..methods._auto_model import Model, error_terms, time_terms
from ..methods._features import group_features

__all__ = [
    "fit", "fit_calibrated", "refit_from", "add_probes", "scene_features", "front_row", "front_time", "landing", "leave_one_out",
    "calibrate_margin", "candidate_key",
]  # fmt: skip

#: Ridge penalty on the standardised terms.
RIDGE = 1.0
#: Fewest scenes a candidate needs to be fitted.
MIN_ROWS = 4
_SKIP = ("auto",)


def add_probes(features: dict, rows, aa) -> dict:
    """``features`` ({scene: dict}) with ``probe_ms`` of each scene: the time of its
    accumulation row with one sample (at the run's ``aa``), as the planner measures it."""
    out = {}
    for scene, f in features.items():
        probe = [r["ms"] for r in rows if r["scene"] == scene and r["method"] == "accumulation"
                 and candidate_key(r, aa) == ("accumulation", '{"samples": 1}')]  # fmt: skip
        if not probe:
            raise ValueError(
                f"rows: scene {scene!r} has no accumulation row with samples=1 (the time model's probe)"
            )
        out[scene] = {**f, "probe_ms": min(probe)}
    return out


def scene_features(scene) -> dict:
    """The features of the scene's moving objects (all objects when the camera moves), one group."""
    objs = [(k, o) for k, o in enumerate(scene.objects) if o.is_moving or scene.camera_moves]
    return group_features(scene, objs or list(enumerate(scene.objects)))


def candidate_key(row: dict, aa) -> tuple[str, str]:
    """(method, options as sorted JSON) of a row, its ``aa`` left out when it is the run's."""
    opts = {k: v for k, v in row["_opts"].items() if not (k == "aa" and v == aa)}
    return row["method"], json.dumps(opts, sort_keys=True)


def _ridge(x: np.ndarray, y: np.ndarray, residuals: bool = False):
    """Coefficients on the raw terms (column 0 the constant) and the leave-one-out residual sd
    (and, with ``residuals``, the leave-one-out residuals themselves)."""
    mu, sd = x[:, 1:].mean(axis=0), x[:, 1:].std(axis=0)
    sd[sd < 1e-9] = np.inf  # a constant column gets no weight
    z = np.column_stack([np.ones(len(x)), (x[:, 1:] - mu) / sd])
    pen = RIDGE * np.eye(z.shape[1])
    pen[0, 0] = 0.0
    a = np.linalg.solve(z.T @ z + pen, z.T)
    beta = a @ y
    hat = np.einsum("ij,ji->i", z, a)
    loo = (y - z @ beta) / np.maximum(1.0 - hat, 1e-3)
    sigma = float(np.sqrt((loo**2).mean()))
    coef = np.concatenate([[beta[0] - (beta[1:] * mu / sd).sum()], beta[1:] / sd])
    return (coef, sigma, loo) if residuals else (coef, sigma)


def fit(rows, features: dict, aa: int, size, margin: float = 1.0, where: str = "") -> Model:
    """A :class:`~motionblur.methods._auto_model.Model` from report ``rows`` and ``features``
    ({scene: features dict}); candidates with fewer than :data:`MIN_ROWS` scenes are left out."""
    by: dict[tuple[str, str], list[dict]] = {}
    for r in rows:
        if r["method"] in _SKIP or r["scene"] not in features:
            continue
        e, t = r.get("rmse_limit", float("nan")), r["ms"]
        if not (math.isfinite(e) and math.isfinite(t) and t > 0):
            continue
        by.setdefault(candidate_key(r, aa), []).append(r)
    cands = []
    for (method, opts), rs in sorted(by.items()):
        if len(rs) < MIN_ROWS:
            continue
        fe = np.array([error_terms(features[r["scene"]]) for r in rs])
        ft = np.array([time_terms(features[r["scene"]]) for r in rs])
        ce, se, res = _ridge(fe, np.log([max(r["rmse_limit"], 1e-6) for r in rs]), residuals=True)
        ct, st = _ridge(ft, np.log([r["ms"] for r in rs]))
        cands.append({
            "method": method, "options": json.loads(opts), "n": len(rs),
            "error_coef": [round(float(c), 6) for c in ce], "error_sigma": round(se, 4),
            "scenes": [r["scene"] for r in rs], "error_loo": [round(float(x), 4) for x in res],
            "time_coef": [round(float(c), 6) for c in ct], "time_sigma": round(st, 4),
        })  # fmt: skip
    return Model({
        "version": 1, "fitted": where or time.strftime("%Y-%m-%d"), "size": list(size), "aa": int(aa),
        "margin": margin, "scenes": sorted(features), "candidates": cands,
        "terms": {n: [round(float(x), 5) for x in error_terms(f)] for n, f in sorted(features.items())},
        "probe_ms": round(float(np.median([f.get("probe_ms", 1.0) for f in features.values()])), 4),
    })  # fmt: skip


def front_row(rows, error: float, metric: str = "rmse_limit"):
    """The fastest row (``auto`` left out) whose ``metric`` is at most ``error``, or None."""
    ok = [r for r in rows if r["method"] not in _SKIP and r[metric] <= error * (1 + 1e-9)]
    return min(ok, key=lambda r: r["ms"]) if ok else None


def front_time(rows, error: float, metric: str = "rmse_limit") -> float:
    """The Pareto front's time at ``error``: the least ms of the rows (``auto`` left out) whose
    ``metric`` is at most ``error``; inf when none is."""
    ok = [r["ms"] for r in rows if r["method"] not in _SKIP and r[metric] <= error * (1 + 1e-9)]
    return min(ok) if ok else float("inf")


def landing(rows, auto_row: dict, tolerance: float, metric: str = "rmse_limit") -> dict:
    """``{ms, error, front_ms, ratio, meets}`` of one ``auto`` row on its scene's ``rows``:
    its time over the front's time at the error it reached, and whether it met ``tolerance``."""
    f = front_time(rows, auto_row[metric], metric)
    return {
        "ms": auto_row["ms"],
        "error": auto_row[metric],
        "front_ms": f,
        "ratio": auto_row["ms"] / f if math.isfinite(f) else float("nan"),
        "meets": auto_row[metric] <= tolerance,
    }


def _loo_models(rows, features: dict, aa: int, size) -> dict:
    """{scene: the model fitted without the scene's rows}."""
    out = {}
    for scene in features:
        others = {s: f for s, f in features.items() if s != scene}
        out[scene] = fit([r for r in rows if r["scene"] != scene], others, aa, size)
    return out


def leave_one_out(
    rows, features: dict, aa: int, size, tolerance: float, applies: dict, margin=None, models=None
) -> dict:
    """Per scene, the planner's choice with the model fitted on the other scenes, and where the
    chosen candidate's measured row lands (:func:`landing`); ``applies``: {scene: {method: bool}};
    ``margin`` overrides the models' own; ``models`` reuses :func:`_loo_models`' fits."""
    models = models or _loo_models(rows, features, aa, size)
    out = {}
    for scene in features:
        model = models[scene]
        if not model.candidates:
            continue
        pick = model.choose(
            features[scene], tolerance, None, aa, applies[scene], model.margin if margin is None else margin
        )
        key = (pick["method"], json.dumps(pick["options"], sort_keys=True))
        srows = [r for r in rows if r["scene"] == scene]
        hit = [r for r in srows if r["method"] not in _SKIP and candidate_key(r, aa) == key]
        if hit:
            out[scene] = {
                **landing(srows, hit[0], tolerance),
                "method": pick["method"],
                "options": pick["options"],
            }
    return out


#: Margins :func:`calibrate_margin` tries, in residual standard deviations.
MARGINS = (0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0)
#: Tolerances the margin is calibrated at (RMSE against the own limit).
CALIBRATION_TOLERANCES = (0.003, 0.01, 0.03)


def calibrate_margin(
    rows, features: dict, aa: int, size, applies: dict, target: float = 0.95
) -> tuple[float, dict]:
    """The smallest margin of :data:`MARGINS` with which the planner, replayed leave-one-scene-out,
    meets the tolerance on at least ``target`` of the scenes at every one of
    :data:`CALIBRATION_TOLERANCES`; the largest when none does. Returns ``(margin, {margin: the
    least share met over the tolerances})``."""
    models = _loo_models(rows, features, aa, size)
    met = {}
    for m in MARGINS:
        shares = []
        for t in CALIBRATION_TOLERANCES:
            hits = [
                x["meets"]
                for x in leave_one_out(rows, features, aa, size, t, applies, margin=m, models=models).values()
            ]
            shares.append(sum(hits) / len(hits) if hits else 0.0)
        met[m] = min(shares)
        if met[m] >= target:
            return m, met
    return MARGINS[-1], met


def fit_calibrated(rows, features: dict, aa: int, size, applies: dict, log=print) -> Model:
    """:func:`fit` with its margin set by :func:`calibrate_margin` (recorded in the model)."""
    features = add_probes(features, rows, aa)
    model = fit(rows, features, aa, size, where=f"{size[0]}x{size[1]} aa={aa}, {time.strftime('%Y-%m-%d')}")
    margin, met = calibrate_margin(rows, features, aa, size, applies)
    model.data["margin"] = model.margin = margin
    model.data["calibration"] = {str(k): round(v, 3) for k, v in met.items()}
    log(f"auto model: {len(model.candidates)} candidates from {len(rows)} rows, margin {margin} sd "
        f"(least share of scenes meeting the tolerance, leave-one-out, by margin: {model.data['calibration']})")  # fmt: skip
    return model


def refit_from(path, model_path=None):
    """Refit and save auto's model from a report's ``rows.json`` (nothing is rendered); returns
    the path written (default: the package's ``auto_model.json``)."""
    with open(path) as fh:
        data = json.load(fh)
    model = fit_calibrated(
        data["rows"], data["features"], int(data["aa"] or 1), data["size"], data["applies"]
    )
    return model.save(model_path) if model_path else model.save()
