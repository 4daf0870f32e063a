"""Evaluation: how close each method comes to a physically correct render, and how fast.

- [`reference`][motionblur.evaluation.reference]: the same scene rendered by Mitsuba 3 (time-sampled, the ground truth) and
  by pyrender (the OpenGL peer);
- [`metrics`][motionblur.evaluation.metrics]: image errors (RMSE, PSNR, FLIP, coverage);
- [`bench`][motionblur.evaluation.bench]: the speed-against-error report (``python -m motionblur bench``), built from
  `sweep` (rendering and timing), `compare` (Pareto front, equal error, equal time)
  and `report` (tables, csv, plots);
- `demo`: its small version (``python -m motionblur demo``).
"""

from .._namespace import tidy  # noqa: E402  (dir() lists the API only; see motionblur._namespace)

tidy(__name__, walk=True)
