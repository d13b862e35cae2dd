"""Checks of what an error or an output says to the user."""

from __future__ import annotations


def assert_says(text: str, *parts: str) -> None:
    """Every one of ``parts`` is in ``text``: a message names what is wrong and what to do."""
    missing = [part for part in parts if part not in text]
    assert not missing, f"{missing} not in: {text}"
