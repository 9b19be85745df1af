"""Hypothesis settings for the file-input property tests.

The suite runs a modest number of examples so it stays fast; the acceptance run asks for
more through the environment, once:

    SILBRIDGE_HYPOTHESIS_EXAMPLES=10000 .venv/bin/python -m pytest -q tests/fuzz

No example database is kept (database=None): a crash is reported with the falsifying
file text in the failure. (Hypothesis still caches constants in .hypothesis/, which holds
its own .gitignore.)
"""

from __future__ import annotations

import os
import sys

from hypothesis import HealthCheck, settings

_EXAMPLES = int(os.environ.get("SILBRIDGE_HYPOTHESIS_EXAMPLES", "200"))

settings.register_profile(
    "silbridge-files", max_examples=_EXAMPLES, deadline=None, database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                           HealthCheck.filter_too_much])
settings.load_profile("silbridge-files")

sys.path.insert(0, os.path.dirname(__file__))     # fuzz_mutate, as tests/mavlink does
