"""Hypothesis settings shared by the fuzz tests: CI runs a fixed, derandomised set of examples; setting
SPECTRACE_FUZZ_EXAMPLES turns that into a random search of that many examples."""

import os

from hypothesis import settings

LONG_RUN_EXAMPLES = int(os.environ.get("SPECTRACE_FUZZ_EXAMPLES", "0"))


def fuzz_settings(examples: int, suppress_health_check, **options) -> settings:
    """`examples` derandomised examples in CI, or the long run's count drawn at random; no deadline."""
    return settings(
        max_examples=LONG_RUN_EXAMPLES or examples,
        deadline=None,
        derandomize=not LONG_RUN_EXAMPLES,
        suppress_health_check=suppress_health_check,
        **options,
    )
