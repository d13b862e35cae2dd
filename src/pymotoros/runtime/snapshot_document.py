"""The state document and its schema, derived from the controller's snapshot type.

:class:`~pymotoros.controller.api.ControllerSnapshot` is the one declaration of what an
observer sees. From a snapshot type this module derives, once:

* an encoder (:func:`document_encoder`): snapshot → plain dicts and lists, the body of
  ``GET /api/state``, the ``/ws/state`` feed and the pendant's document;
* a pydantic model (:func:`document_model`): the OpenAPI schema of the same document,
  each field described by its attribute's docstring in the declaration.

So a field added to the snapshot, or to one of its parts (a group, the safety unit's
:class:`~pymotoros.controller.safety.SafetySnapshot`), appears in the document and its
schema with no other edit.

The rules: a dataclass is an object of its fields in declaration order; an enum is its
value; a tuple an array; None is null. A field's metadata may say ``omit`` (not in the
document) or ``inline`` (its fields join the parent object), see
:data:`~pymotoros.controller.api.OMIT` and :data:`~pymotoros.controller.api.INLINE`.
Where the JSON shape differs from the dataclass (the TCP's two speeds under
``speed_mm_s``; a fired event's parameters as keys of its own), a :class:`Form` in
:data:`FORMS` gives the encoder and the schema for that type.

The feed encodes the document 25 times a second on the loop that runs the interpolation
ticks, so the encoder is not a walk over ``dataclasses.fields`` at each call: the walk
is done once per type and written as Python source (one function per dataclass, one
dict display each, as a hand-written builder would be), compiled once. Its cost per
call is that of the hand-written builder it replaced (``docs/benchmarks.md``).
"""

from __future__ import annotations

import ast
import dataclasses
import enum
import inspect
import itertools
import textwrap
import types
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Final, Literal, Union

from pydantic import BaseModel, ConfigDict, Field, create_model

from pymotoros.controller.api import (
    AlarmInfo,
    FiredEventInfo,
    GroupSnapshot,
    TcpSnapshot,
    snapshot_names,
)
from pymotoros.controller.safety import FsuLimits
from pymotoros.models.workspace import Obstacle

__all__ = [
    "FORMS",
    "SCHEMA_NAMES",
    "Answer",
    "ErrorModel",
    "Form",
    "document_encoder",
    "document_model",
    "field_docs",
]

_SCALARS: Final = (int, float, str, bool, type(None))


class ErrorModel(BaseModel):
    """Every error answer of the control API: ``{"error": "<what was wrong>"}``."""

    error: str


class Answer(BaseModel):
    """Base of every model of the state document: a key the model does not declare
    fails loudly (FastAPI checks each answer) instead of vanishing from the schema."""

    model_config = ConfigDict(extra="forbid")


class TcpSpeedModel(Answer):
    command: float
    feedback: float


class TcpModel(Answer):
    command: list[float] = Field(
        description="TCP of the active tool in base coordinates: x, y, z (m), rx, ry, rz "
        "(rad, R = Rz·Ry·Rx), from the command"
    )
    feedback: list[float] = Field(description="the same from the encoder feedback")
    speed_mm_s: TcpSpeedModel


def _tcp(tcp: TcpSnapshot) -> dict[str, Any]:
    return {
        "command": list(tcp.command),
        "feedback": list(tcp.feedback),
        "speed_mm_s": {"command": tcp.command_speed_mm_s, "feedback": tcp.feedback_speed_mm_s},
    }


def _event(e: FiredEventInfo) -> dict[str, Any]:
    doc: dict[str, Any] = {"t": e.t, "action": e.action, **dict(e.params)}
    if e.error:
        doc["error"] = e.error
    return doc


def _obstacle(o: Obstacle) -> dict[str, Any]:
    # the cell file's keys, only those the obstacle has (one shape; frame when given), so
    # what GET /api/state shows can be posted back to POST /api/workspace as it is; the
    # schema is therefore an object (as for a fired event), the keys in the field's doc
    return o.as_dict()


@dataclass(frozen=True, slots=True)
class Form:
    """A type whose JSON shape is not its fields': how to encode it, and its schema."""

    encode: Callable[[Any], Any]
    schema: Any


FORMS: Final[Mapping[type, Form]] = {
    TcpSnapshot: Form(_tcp, TcpModel),
    FiredEventInfo: Form(_event, dict[str, Any]),
    Obstacle: Form(_obstacle, dict[str, Any]),
}


SCHEMA_NAMES: Final[Mapping[type, str]] = {
    AlarmInfo: "AlarmModel",
    GroupSnapshot: "GroupModel",
    FsuLimits: "FsuModel",
}
"""The OpenAPI names the hand-written models had before the schema was derived (a client
generated from the schema keeps its class names); any other part is named after its
dataclass."""


def field_docs(cls: type) -> dict[str, str]:
    """Each field's docstring (the string literal after its annotation), the class's
    bases first; {} when the source is not available (then the schema has no
    descriptions, nothing else changes)."""
    docs: dict[str, str] = {}
    for klass in reversed(cls.__mro__):
        if not dataclasses.is_dataclass(klass):
            continue
        try:
            source = textwrap.dedent(inspect.getsource(klass))
        except (OSError, TypeError):
            continue
        tree = ast.parse(source)
        body = tree.body[0].body if tree.body and isinstance(tree.body[0], ast.ClassDef) else []
        for node, after in itertools.pairwise(body):
            if (
                isinstance(node, ast.AnnAssign)
                and isinstance(node.target, ast.Name)
                and isinstance(after, ast.Expr)
                and isinstance(after.value, ast.Constant)
                and isinstance(after.value.value, str)
            ):
                docs[node.target.id] = " ".join(inspect.cleandoc(after.value.value).split())
    return docs


def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls, localns=snapshot_names())


def _optional(tp: Any) -> Any | None:
    """``X`` for ``X | None``, else None."""
    if typing.get_origin(tp) in (Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if len(args) == 1 and len(typing.get_args(tp)) == 2:
            return args[0]
        raise TypeError(f"the state document cannot encode the union {tp}")
    return None


def _item_type(tp: Any) -> Any | None:
    """The element type of ``tuple[X, ...]``, ``tuple[X, X]`` or ``list[X]``, else None."""
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if origin is list and args:
        return args[0]
    if origin is tuple and args:
        items = {a for a in args if a is not Ellipsis}
        if len(items) == 1:
            return items.pop()
        raise TypeError(f"the state document cannot encode the mixed tuple {tp}")
    return None


def _is_scalar(tp: Any) -> bool:
    return tp in _SCALARS or tp is Any or typing.get_origin(tp) is Literal


def _how(f: dataclasses.Field[Any]) -> str:
    return str(f.metadata.get("document", ""))


class _Encoder:
    """Writes the source of one encoder function per dataclass, then compiles them."""

    def __init__(self) -> None:
        self.namespace: dict[str, Any] = {}
        self.functions: dict[type, str] = {}
        self.sources: list[str] = []
        self._vars = itertools.count()

    def value(self, tp: Any, src: str) -> str:
        """A Python expression that encodes ``src``, of type ``tp``."""
        if tp in FORMS:
            name = f"_form_{FORMS[tp].encode.__name__.strip('_')}"
            self.namespace[name] = FORMS[tp].encode
            return f"{name}({src})"
        inner = _optional(tp)
        if inner is not None:
            code = self.value(inner, src)
            return src if code == src else f"(None if {src} is None else {code})"
        if _is_scalar(tp):
            return src
        if isinstance(tp, type) and issubclass(tp, enum.Enum):
            return f"{src}.value"
        item = _item_type(tp)
        if item is not None:
            var = f"v{next(self._vars)}"
            code = self.value(item, var)
            return f"list({src})" if code == var else f"[{code} for {var} in {src}]"
        if isinstance(tp, type) and dataclasses.is_dataclass(tp):
            return f"{self.function(tp)}({src})"
        raise TypeError(f"the state document cannot encode {tp!r} (add a Form to FORMS)")

    def items(self, cls: type, src: str) -> list[tuple[str, str]]:
        """(key, expression) of each field of ``cls`` in the document, ``inline`` parts
        expanded in place."""
        hints = _hints(cls)
        out: list[tuple[str, str]] = []
        for f in dataclasses.fields(cls):
            how = _how(f)
            if how == "omit":
                continue
            if how == "inline":
                out += self.items(hints[f.name], f"{src}.{f.name}")
            else:
                out.append((f.name, self.value(hints[f.name], f"{src}.{f.name}")))
        keys = [key for key, _ in out]
        if len(set(keys)) != len(keys):
            raise TypeError(f"{cls.__name__}: two fields give the document the same key: {keys}")
        return out

    def function(self, cls: type) -> str:
        if cls in self.functions:
            return self.functions[cls]
        name = f"_encode_{len(self.functions)}_{cls.__name__}"
        self.functions[cls] = name
        body = ", ".join(f"{key!r}: {code}" for key, code in self.items(cls, "o"))
        self.sources.append(f"def {name}(o):\n    return {{{body}}}\n")
        return name


_ENCODERS: dict[type, Callable[[Any], dict[str, Any]]] = {}
_MODELS: dict[tuple[type, str | None], type[Answer]] = {}


def document_encoder(cls: type) -> Callable[[Any], dict[str, Any]]:
    """The encoder of a snapshot type (a dataclass): an instance → its document. Built
    once per type; a type the rules cannot encode is a TypeError here, not at a call."""
    known = _ENCODERS.get(cls)
    if known is not None:
        return known
    encoder = _Encoder()
    name = encoder.function(cls)
    code = compile("\n".join(encoder.sources), f"<state document of {cls.__name__}>", "exec")
    exec(code, encoder.namespace)  # noqa: S102 - our own source, written from field names
    function: Callable[[Any], dict[str, Any]] = encoder.namespace[name]
    _ENCODERS[cls] = function
    return function


def _schema(tp: Any, name: str) -> Any:
    if tp in FORMS:
        return FORMS[tp].schema
    inner = _optional(tp)
    if inner is not None:
        return _schema(inner, name) | None
    if _is_scalar(tp):
        return tp
    if isinstance(tp, type) and issubclass(tp, enum.Enum):
        return Literal[tuple(m.value for m in tp)]
    item = _item_type(tp)
    if item is not None:
        return list[_schema(item, name)]  # type: ignore[misc]
    if isinstance(tp, type) and dataclasses.is_dataclass(tp):
        return document_model(tp)
    raise TypeError(f"no schema for {tp!r} in {name} (add a Form to FORMS)")


def _fields(cls: type) -> dict[str, tuple[Any, Any]]:
    hints = _hints(cls)
    docs = field_docs(cls)
    out: dict[str, tuple[Any, Any]] = {}
    for f in dataclasses.fields(cls):
        how = _how(f)
        if how == "omit":
            continue
        if how == "inline":
            out.update(_fields(hints[f.name]))
            continue
        kind = _schema(hints[f.name], cls.__name__)
        default: Any = ...
        if isinstance(f.default, _SCALARS) and not isinstance(f.default, enum.Enum):
            default = f.default
        out[f.name] = (kind, Field(default, description=docs.get(f.name)))
    return out


def document_model(cls: type, name: str | None = None) -> type[Answer]:
    """The pydantic model (OpenAPI schema) of a snapshot type's document, built once."""
    known = _MODELS.get((cls, name))
    if known is not None:
        return known
    model: type[Answer] = create_model(  # type: ignore[call-overload]
        name or SCHEMA_NAMES.get(cls, cls.__name__),
        __base__=Answer,
        __doc__=_first_line(cls),
        **_fields(cls),
    )
    _MODELS[cls, name] = model
    return model


def _first_line(cls: type) -> str | None:
    doc = inspect.getdoc(cls)
    if not doc or doc.startswith(f"{cls.__name__}("):  # the dataclass's generated signature
        return None
    return doc.split("\n\n")[0]
