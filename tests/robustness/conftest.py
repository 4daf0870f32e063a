"""Hypothesis profiles of the property-based robustness suite (marker ``robustness``).

``ci`` (the default, what ``make test`` runs): a few examples per property, derandomized so a
run is reproducible, well under a minute in all. ``fuzz`` (``make fuzz``, or
``MOTIONBLUR_FUZZ=fuzz``): many more examples from a random seed each run; hypothesis prints
the seed and the smallest failing example of any failure.
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

_quiet = [HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much]
settings.register_profile(
    "ci", max_examples=12, deadline=None, derandomize=True, suppress_health_check=_quiet
)
settings.register_profile(
    "fuzz",
    max_examples=int(os.environ.get("MOTIONBLUR_FUZZ_EXAMPLES", "400")),
    deadline=None,
    suppress_health_check=_quiet,
)
settings.load_profile(os.environ.get("MOTIONBLUR_FUZZ", "ci"))
