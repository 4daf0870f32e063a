"""The speed-against-error report: moved to :mod:`motionblur.evaluation` (:mod:`~.evaluation.bench`
runs it, :mod:`~.evaluation.sweep` renders and times, :mod:`~.evaluation.compare` compares,
:mod:`~.evaluation.report` writes). This old path keeps its names."""

from .evaluation.bench import main, run
from .evaluation.compare import equal_error, equal_time, pareto_front
from .evaluation.sweep import paired_factor as paired_factor
from .evaluation.sweep import reference_for, sweep_scene
from .render import METHODS as METHODS
from .scenes_builtin import SCENES as SCENES

__all__ = ["run", "sweep_scene", "reference_for", "pareto_front", "equal_error", "equal_time", "main"]
