"""Hypothesis settings for tests whose examples drive a robot: few, reproducible, no deadline."""

from __future__ import annotations

from hypothesis import HealthCheck, settings


def bounded_examples(max_examples: int) -> settings:
    """At most ``max_examples``, the same ones on every run (``derandomize``), without
    Hypothesis's per-example deadline (a move takes real or virtual seconds), and allowed
    beside function-scoped fixtures (the fixture's robot serves every example in turn)."""
    return settings(
        max_examples=max_examples,
        deadline=None,
        derandomize=True,
        suppress_health_check=[HealthCheck.function_scoped_fixture],
    )
