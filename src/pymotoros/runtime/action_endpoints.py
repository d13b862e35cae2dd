"""One control API endpoint per declared action, each a plain function with its own signature.

FastAPI reads what an endpoint takes from the endpoint's parameters: a body whose type
is a pydantic model is the JSON body (its schema in the OpenAPI document), a parameter
marked ``Path`` is a part of the path. An action's body model is built at run time from
its declaration (:func:`pymotoros.runtime.http_api.action_body_model`), so the endpoint
is defined inside a small factory, one per shape (no body, a body, a body that may be
left out), and names the model in its annotation. The path's parameters come from a
dependency per parameter, each reading one typed value (its name in the path given by
``Path(alias=...)``), so an action may name any number of them.

This module must not use ``from __future__ import annotations``: FastAPI resolves a
string annotation in the module's globals, where a model built at run time is not.
"""

from collections.abc import Awaitable, Callable, Sequence
from typing import Annotated, Any

from fastapi import Depends, Path
from pydantic import BaseModel

__all__ = ["PathValues", "action_endpoint", "path_values"]

PathValues = Callable[..., Awaitable[dict[str, object]]]
"""A dependency giving the path's parameters by name, typed as declared."""

Act = Callable[[dict[str, object], BaseModel | None], dict[str, Any]]
"""What an endpoint does: with the path's values and the body, the state document after."""

Endpoint = Callable[..., Awaitable[dict[str, Any]]]


def path_values(keys: Sequence[tuple[str, type]]) -> PathValues:
    """The dependency reading ``keys`` (each a name in the path and its type: str, int or
    float) from the path; FastAPI checks each value's type and documents it. The first key
    and then the others, each a dependency of its own: the document lists them, and a
    request's errors name them, in the declaration's order."""
    if not keys:

        async def no_values() -> dict[str, object]:
            return {}

        return no_values
    (key, kind), *after = keys
    first, rest = _path_value(key, kind), path_values(after)

    async def values(
        one: Annotated[dict[str, object], Depends(first)],
        others: Annotated[dict[str, object], Depends(rest)],
    ) -> dict[str, object]:
        return {**one, **others}

    return values


def _path_value(key: str, kind: type) -> PathValues:
    """The dependency reading the one value ``key`` of type ``kind`` from the path."""
    if kind is int:

        async def int_value(value: Annotated[int, Path(alias=key)]) -> dict[str, object]:
            return {key: value}

        return int_value
    if kind is float:

        async def number_value(value: Annotated[float, Path(alias=key)]) -> dict[str, object]:
            return {key: value}

        return number_value
    if kind is not str:
        raise ValueError(f"a path carries a str, int or float, not {kind.__name__} ({key!r})")

    async def str_value(value: Annotated[str, Path(alias=key)]) -> dict[str, object]:
        return {key: value}

    return str_value


def action_endpoint(
    in_path: PathValues, model: type[BaseModel] | None, act: Act, *, body_optional: bool = False
) -> Endpoint:
    """The endpoint of one action: the path's values (``in_path``), the body of type
    ``model`` (None: the action takes none; ``body_optional``: it may be left out), then
    ``act``. (mypy cannot see a model built at run time as a type: hence its ignores.)"""
    if model is None:

        async def no_body(
            path: Annotated[dict[str, object], Depends(in_path)],
        ) -> dict[str, Any]:
            return act(path, None)

        return no_body
    if body_optional:

        async def optional_body(
            path: Annotated[dict[str, object], Depends(in_path)],
            body: model = None,  # type: ignore[valid-type]
        ) -> dict[str, Any]:
            return act(path, body)

        return optional_body

    async def with_body(
        path: Annotated[dict[str, object], Depends(in_path)],
        body: model,  # type: ignore[valid-type]
    ) -> dict[str, Any]:
        return act(path, body)

    return with_body
