"""The demo (``python -m motionblur demo``): moved to :mod:`motionblur.evaluation.demo`. This old path is that module."""

import sys

from .evaluation import demo

sys.modules[__name__] = demo
