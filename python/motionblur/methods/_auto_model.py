"""The cost and error model of the ``auto`` planner: per candidate (a method and an option set),
log RMSE and log time as linear functions of what the objects do on screen.

For a group of objects with features ``f`` (:mod:`._features`), candidate ``c`` predicts

- ``log(RMSE against the own-limit reference) = error_coef[c] . error_terms(f)`` with
  :func:`error_terms`: 1, log(1 + motion_px), log(tri_px), log(0.01 + rotation),
  log(0.02 + spread), concavity, log(0.02 + hollowness), log(coverage_px), deforming,
  camera_moves (the logs of rotation, spread and hollowness tell a convex translating object,
  where a motion volume is near exact, from one that turns or has holes);
- ``log(ms) = time_coef[c] . time_terms(f)`` with :func:`time_terms`: 1, log(probe_ms),
  log(faces), log(coverage_px), log(1 + motion_px), rotation, deforming, camera_moves, where
  ``probe_ms`` is the measured time of one accumulation sample of the same objects (the
  planner renders it once per scene; the report reads it from its ``samples=1`` row), which
  carries the scene's cost and the machine's speed;

each with the standard deviation of its fit's residuals (``error_sigma``, ``time_sigma``, in
log units). The error's spread is heteroscedastic (the motion volume is near exact on convex
translating objects and far off on hollow or turning ones), so a prediction is judged by the
local spread (:meth:`Model.error_spread`): the root mean square of the leave-one-out residuals
of the :data:`NEIGHBOURS` training scenes nearest in the error terms (standardised), never below
a quarter of the global one. Times are those of the machine, image size and ``aa`` of the fit (``size``,
``aa`` in the file); another ``aa`` scales the predicted time by the ratio of samples.

The coefficients are fitted by ridge regression (:mod:`motionblur.evaluation.autofit`) from the
report's rows and stored in ``auto_model.json`` beside this module; ``python -m motionblur
bench --fit-auto`` refits and rewrites it.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

__all__ = ["Model", "load_model", "error_terms", "time_terms", "MODEL_PATH", "NEIGHBOURS"]

#: Training scenes whose residuals give a prediction's local spread.
NEIGHBOURS = 5

#: Where the fitted model lives, inside the package.
MODEL_PATH = Path(__file__).with_name("auto_model.json")
_loaded: dict[str, Model] = {}
_ZERO = {k: 0.0 for k in ("motion_px", "tri_px", "faces", "rotation", "spread", "concavity", "hollowness",
                          "coverage_px", "deforming", "camera_moves", "probe_ms")}  # fmt: skip


def error_terms(f: dict) -> np.ndarray:
    """(10,) float64 terms of the error model for features ``f``."""
    return np.array([
        1.0, math.log1p(f["motion_px"]), math.log(max(f["tri_px"], 1e-3)), math.log(0.01 + f["rotation"]),
        math.log(0.02 + f["spread"]), f["concavity"], math.log(0.02 + f["hollowness"]),
        math.log(max(f["coverage_px"], 1.0)), f["deforming"], f["camera_moves"],
    ])  # fmt: skip


def time_terms(f: dict) -> np.ndarray:
    """(8,) float64 terms of the time model for features ``f`` (with ``probe_ms``)."""
    return np.array([
        1.0, math.log(max(f["probe_ms"], 1e-3)), math.log(max(f["faces"], 1.0)), math.log(max(f["coverage_px"], 1.0)),
        math.log1p(f["motion_px"]), f["rotation"], f["deforming"], f["camera_moves"],
    ])  # fmt: skip


class Model:
    """A fitted model: ``candidates`` (list of dicts: ``method``, ``options``, ``error_coef``,
    ``error_sigma``, ``time_coef``, ``time_sigma``, ``n`` rows fitted), ``margin`` (residual
    standard deviations added to the predicted log error when checking a tolerance), ``size``
    (W, H) and ``aa`` of the measurements, and ``fitted`` (where and when, words)."""

    def __init__(self, data: dict):
        self.data = data
        self.candidates = data["candidates"]
        ne, nt = len(error_terms(_ZERO)), len(time_terms(_ZERO))
        for c in self.candidates:
            if len(c["error_coef"]) != ne or len(c["time_coef"]) != nt:
                raise ValueError(
                    f"auto model: {c['method']} {c['options']} has {len(c['error_coef'])} error and "
                    f"{len(c['time_coef'])} time coefficients, this version's terms are {ne} and {nt}: "
                    "refit it (python -m motionblur bench --fit-auto)"
                )
        self.margin = float(data.get("margin", 1.0))
        self.aa = int(data.get("aa", 2))
        self._scale = None

    @property
    def reference_probe_ms(self) -> float:
        """The median ``probe_ms`` of the fit's scenes: the probe a plan for a tolerance uses
        (it times nothing, so its choice does not depend on the machine's load)."""
        return float(self.data.get("probe_ms", 1.0))

    def error_spread(self, c: dict, e: np.ndarray) -> float:
        """The local spread (log units) of candidate ``c``'s error model at terms ``e``."""
        terms = self.data.get("terms")
        if not terms or "error_loo" not in c:
            return float(c["error_sigma"])
        if self._scale is None:
            x = np.array(list(terms.values()))
            sd = x.std(axis=0)
            self._scale = np.where(sd > 1e-9, 1.0 / np.maximum(sd, 1e-9), 0.0)
        pts = np.array([terms[s] for s in c["scenes"]])
        d = np.linalg.norm((pts - e) * self._scale, axis=1)
        near = np.argsort(d, kind="stable")[:NEIGHBOURS]
        local = float(np.sqrt(np.mean(np.square(np.asarray(c["error_loo"])[near]))))
        return max(local, 0.25 * float(c["error_sigma"]))

    def methods(self) -> list[str]:
        return sorted({c["method"] for c in self.candidates})

    def predict(self, f: dict, aa: int = 0) -> list[tuple[dict, float, float]]:
        """``[(candidate, predicted log RMSE, predicted log ms)]`` for features ``f``."""
        e, t = error_terms(f), time_terms(f)
        scale = math.log((aa or self.aa) ** 2 / self.aa**2) if aa else 0.0
        return [
            (c, float(np.dot(c["error_coef"], e)), float(np.dot(c["time_coef"], t)) + scale)
            for c in self.candidates
        ]

    def choose(self, f: dict, tolerance, budget_ms, aa: int, applies: dict, margin: float, keep=None) -> dict:
        """The chosen candidate for features ``f``: ``{method, options, predicted_ms,
        predicted_rmse, reason}`` (see :mod:`motionblur.methods.auto`). With ``keep`` (a predicate
        on a candidate's options, e.g. that it renders the scene's shutter), the others are left out."""
        preds = [
            p
            for p in self.predict(f, aa)
            if applies.get(p[0]["method"], False) and (keep is None or keep(p[0]["options"]))
        ]
        e = error_terms(f)
        if not preds:
            raise ValueError("auto: no candidate of the model applies to this scene")

        def out(p, reason):
            c, le, lt = p
            return {
                "method": c["method"],
                "options": dict(c["options"]),
                "predicted_ms": round(math.exp(lt), 3),
                "predicted_rmse": round(math.exp(le), 6),
                "reason": reason,
            }

        if budget_ms is not None:
            lb = math.log(budget_ms)
            fits = [p for p in preds if p[2] + margin * p[0]["time_sigma"] <= lb]
            if fits:
                best = min(fits, key=lambda p: p[1])
                return out(
                    best, f"most accurate predicted within {budget_ms:g} ms ({len(fits)} of {len(preds)} fit)"
                )
            return out(
                min(preds, key=lambda p: p[2]), f"nothing predicted within {budget_ms:g} ms: the fastest"
            )
        lt = math.log(tolerance)
        meets = [p for p in preds if p[1] + margin * self.error_spread(p[0], e) <= lt]
        if meets:
            best = min(meets, key=lambda p: p[2])
            return out(
                best, f"cheapest predicted to meet RMSE {tolerance:g} ({len(meets)} of {len(preds)} do)"
            )
        return out(
            min(preds, key=lambda p: p[1]), f"none predicted to meet RMSE {tolerance:g}: the most accurate"
        )

    def save(self, path=MODEL_PATH) -> Path:
        path = Path(path)
        path.write_text(json.dumps(self.data, indent=1) + "\n")
        _loaded.pop(str(path), None)
        return path


def load_model(path=MODEL_PATH) -> Model:
    """The model stored at ``path`` (default: the package's), read once per process."""
    key = str(path)
    if key not in _loaded:
        _loaded[key] = Model(json.loads(Path(path).read_text()))
    return _loaded[key]
