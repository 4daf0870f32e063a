"""The cost and error model of the ``auto`` planner: per candidate (a method and an option set),
log RMSE and log time as linear functions of what the objects do on screen.

For a group of objects with features ``f`` (:mod:`._features`), candidate ``c`` predicts

- ``log(RMSE against the own-limit reference) = error_coef[c] . error_terms(f)`` with
  :func:`error_terms`: 1, log(1 + motion_px), log(tri_px), rotation, spread, concavity,
  log(coverage_px), deforming, camera_moves;
- ``log(ms) = time_coef[c] . time_terms(f)`` with :func:`time_terms`: 1, log(faces),
  log(coverage_px), log(1 + motion_px), rotation, deforming, camera_moves;

each with the standard deviation of its fit's residuals (``error_sigma``, ``time_sigma``, in
log units). Times are those of the machine, image size and ``aa`` of the fit (``size``,
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

__all__ = ["Model", "load_model", "error_terms", "time_terms", "MODEL_PATH"]

#: Where the fitted model lives, inside the package.
MODEL_PATH = Path(__file__).with_name("auto_model.json")
_loaded: dict[str, Model] = {}


def error_terms(f: dict) -> np.ndarray:
    """(9,) float64 terms of the error model for features ``f``."""
    return np.array([
        1.0, math.log1p(f["motion_px"]), math.log(max(f["tri_px"], 1e-3)), f["rotation"], f["spread"],
        f["concavity"], math.log(max(f["coverage_px"], 1.0)), f["deforming"], f["camera_moves"],
    ])  # fmt: skip


def time_terms(f: dict) -> np.ndarray:
    """(7,) float64 terms of the time model for features ``f``."""
    return np.array([
        1.0, math.log(max(f["faces"], 1.0)), math.log(max(f["coverage_px"], 1.0)), math.log1p(f["motion_px"]),
        f["rotation"], f["deforming"], f["camera_moves"],
    ])  # fmt: skip


class Model:
    """A fitted model: ``candidates`` (list of dicts: ``method``, ``options``, ``error_coef``,
    ``error_sigma``, ``time_coef``, ``time_sigma``, ``n`` rows fitted), ``margin`` (residual
    standard deviations added to the predicted log error when checking a tolerance), ``size``
    (W, H) and ``aa`` of the measurements, and ``fitted`` (where and when, words)."""

    def __init__(self, data: dict):
        self.data = data
        self.candidates = data["candidates"]
        self.margin = float(data.get("margin", 1.0))
        self.aa = int(data.get("aa", 2))

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

    def choose(self, f: dict, tolerance, budget_ms, aa: int, applies: dict, margin: float) -> dict:
        """The chosen candidate for features ``f``: ``{method, options, predicted_ms,
        predicted_rmse, reason}`` (see :mod:`motionblur.methods.auto`)."""
        preds = [p for p in self.predict(f, aa) if applies.get(p[0]["method"], False)]
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
        meets = [p for p in preds if p[1] + margin * p[0]["error_sigma"] <= lt]
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
