"""Evaluation: how close each method comes to a physically correct render, and how fast.

- :mod:`.reference`: the same scene rendered by Mitsuba 3 (time-sampled, the ground truth) and
  by pyrender (the OpenGL peer);
- :mod:`.metrics`: image errors (RMSE, PSNR, FLIP, coverage);
- :mod:`.bench`: the speed-against-error report (``python -m motionblur bench``), built from
  :mod:`.sweep` (rendering and timing), :mod:`.compare` (Pareto front, equal error, equal time)
  and :mod:`.report` (tables, csv, plots);
- :mod:`.demo`: its small version (``python -m motionblur demo``).
"""

from .._namespace import tidy  # noqa: E402  (dir() lists the API only; see motionblur._namespace)

tidy(__name__, walk=True)
