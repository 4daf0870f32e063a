"""References (Mitsuba 3, pyrender): moved to :mod:`motionblur.evaluation.reference`. This old path is that module."""

import sys

from .evaluation import reference

sys.modules[__name__] = reference
