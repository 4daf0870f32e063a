"""Image error metrics: moved to [`motionblur.evaluation.metrics`][motionblur.evaluation.metrics]. This old path is that module."""

import sys

from .evaluation import metrics

sys.modules[__name__] = metrics
