"""The control API's body bound: the nesting check agrees with the real depth."""

from __future__ import annotations

import json
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from pymotoros.runtime.body_limit import nests_deeper_than

TEXT = st.text(alphabet='[]{}"\\ab', max_size=6)
"""Strings full of brackets, quotes and backslashes: the nesting check must ignore them."""

JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | TEXT,
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(TEXT, inner, max_size=3),
    max_leaves=40,
)


def depth(value: Any) -> int:
    if isinstance(value, list):
        return 1 + max((depth(v) for v in value), default=0)
    if isinstance(value, dict):
        return 1 + max((depth(v) for v in value.values()), default=0)
    return 0


@settings(max_examples=300, deadline=None)
@given(JSON, st.integers(min_value=0, max_value=8))
def test_nesting_check_matches_the_real_depth(value: Any, limit: int) -> None:
    body = json.dumps(value).encode()
    assert nests_deeper_than(body, limit) == (depth(value) > limit), body


def test_a_long_run_of_openings_is_deep_at_once() -> None:
    assert nests_deeper_than(b"[" * 100_000 + b"]" * 100_000, 32)
    assert not nests_deeper_than(b"[" * 32 + b"]" * 32, 32)
