"""References (Mitsuba 3, pyrender): moved to [`motionblur.evaluation.reference`][motionblur.evaluation.reference]. This old path is that module."""

import sys

from .evaluation import reference

sys.modules[__name__] = reference
