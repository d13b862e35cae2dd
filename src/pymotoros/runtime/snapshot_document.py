"""The state document and its schema, derived from the controller's snapshot type.

:class:`~pymotoros.controller.api.ControllerSnapshot` is the one declaration of what an
observer sees. From a snapshot type this module derives, once:

* an encoder (:func:`document_encoder`): snapshot → plain dicts and lists, the body of
  ``GET /api/state``, the ``/ws/state`` feed and the pendant's document;
* a pydantic model (:func:`document_model`): the OpenAPI schema of the same document,
  each field described by the description in its metadata
  (:func:`~pymotoros.controller.values.described`), data next to the field.

So a field added to the snapshot, or to one of its parts (a group, the safety unit's
:class:`~pymotoros.controller.safety.SafetySnapshot`), appears in the document and its
schema with no other edit.

The rules: a dataclass is an object of its fields in declaration order; an enum is its
value; a tuple an array; None is null. A field's metadata may say ``omit`` (not in the
document) or ``inline`` (its fields join the parent object), see
:data:`~pymotoros.controller.values.OMIT` and :data:`~pymotoros.controller.values.INLINE`.
Where the JSON shape differs from the dataclass (the TCP's two speeds under
``speed_mm_s``; a fired event's parameters as keys of its own), a :class:`Form` in
:data:`FORMS` gives the encoder and the schema for that type.

The feed encodes the document 25 times a second on the loop that runs the interpolation
ticks, so the encoder is not a walk over ``dataclasses.fields`` at each call: the walk
is done once per type into a plan (the document's keys, one ``operator.attrgetter``
that reads every field's value at once, inline parts by their dotted path, and a
converter for only those values that are not their own JSON), composed into one
closure per dataclass. No source is generated or read: a call is two C-level calls and
a short loop over the converted fields (``docs/benchmarks.md``).
"""

from __future__ import annotations

import dataclasses
import enum
import inspect
import types
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from operator import attrgetter
from typing import Any, Final, Literal, Union

from pydantic import BaseModel, ConfigDict, Field, create_model

from pymotoros.controller.values import (
    AlarmInfo,
    FiredEventInfo,
    FsuLimits,
    GroupSnapshot,
    TcpSnapshot,
)
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
    """Each field's description, from its metadata
    (:func:`~pymotoros.controller.values.described`); a field without one is left out."""
    return {
        f.name: str(f.metadata["description"])
        for f in dataclasses.fields(cls)
        if "description" in f.metadata
    }


def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


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


Encode = Callable[[Any], Any]
"""A value → its JSON form (dicts, lists, scalars)."""

_ENCODERS: dict[type, Callable[[Any], dict[str, Any]]] = {}
_MODELS: dict[tuple[type, str | None], type[Answer]] = {}
_BUILDING: set[type] = set()


def _converter(tp: Any) -> Encode | None:
    """How a value of type ``tp`` becomes JSON; None when it already is (a scalar, a
    Literal): the encoder then takes the value as it is, with no call."""
    inner = _optional(tp)
    if inner is not None:
        present = _converter(inner)
        if present is None:
            return None
        return lambda v: None if v is None else present(v)
    conversion = _conversion(tp)
    if conversion is None:
        return None
    each, convert = conversion
    if each:
        return lambda v: list(map(convert, v))
    return convert


def _conversion(tp: Any) -> tuple[bool, Encode] | None:
    """A field's conversion as the encoder's loop applies it: (each, convert) converts
    every item of an array (``each``) or the value itself; None: no conversion. A null
    stays null, so ``X | None`` is converted as ``X``."""
    inner = _optional(tp)
    if inner is not None:
        tp = inner
    if tp in FORMS:
        return False, FORMS[tp].encode
    if _is_scalar(tp):
        return None
    if isinstance(tp, type) and issubclass(tp, enum.Enum):
        return False, attrgetter("value")
    item = _item_type(tp)
    if item is not None:
        convert = _converter(item)
        if convert is None:  # ``list`` alone: listed in one pass, unless it may be null
            return (False, list) if inner is None else (False, _array)
        return True, convert
    if isinstance(tp, type) and dataclasses.is_dataclass(tp):
        if tp in _BUILDING:  # a part that holds its own type: found at call time
            return False, lambda v: _ENCODERS[tp](v)
        return False, document_encoder(tp)
    raise TypeError(f"the state document cannot encode {tp!r} (add a Form to FORMS)")


def _array(value: Any) -> list[Any]:
    """An array that may be null (the encoder's loop passes a null by)."""
    return list(value)


_Plan = list[tuple[str, str, tuple[bool, Encode] | None]]
"""Per key of a document: the dotted attribute path of its value and its conversion."""


def _plan(cls: type, path: str = "") -> _Plan:
    """(key, dotted attribute path, conversion) of each field of ``cls`` in the document,
    ``inline`` parts expanded in place."""
    hints = _hints(cls)
    out: _Plan = []
    for f in dataclasses.fields(cls):
        how = _how(f)
        if how == "omit":
            continue
        if how == "inline":
            out += _plan(hints[f.name], f"{path}{f.name}.")
        else:
            out.append((f.name, path + f.name, _conversion(hints[f.name])))
    keys = [key for key, _, _ in out]
    if len(set(keys)) != len(keys):
        raise TypeError(f"{cls.__name__}: two fields give the document the same key: {keys}")
    return out


def _compose(plan: _Plan) -> Callable[[Any], dict[str, Any]]:
    """One closure for a plan: every value read by one ``attrgetter``, the dict built
    by ``zip``, then only the values that need it converted in place (a key keeps its
    place when its value is replaced; an array's items each by one ``map``)."""
    keys = tuple(key for key, _, _ in plan)
    if not keys:
        return lambda o: {}
    read = _reader([path for _, path, _ in plan])
    # arrays of plain values (joint positions, names) are listed in one C-level pass
    listed = [(key, path) for key, path, conversion in plan if conversion == (False, list)]
    conversions = tuple(
        (key, *conversion)
        for key, _, conversion in plan
        if conversion is not None and conversion != (False, list)
    )
    list_keys = tuple(key for key, _ in listed)
    read_lists = _reader([path for _, path in listed])
    if not conversions and not listed:
        return lambda o: dict(zip(keys, read(o)))  # noqa: B905 - one value per key

    def encode(o: Any) -> dict[str, Any]:
        doc = dict(zip(keys, read(o)))  # noqa: B905 - one value per key
        if listed:
            doc.update(zip(list_keys, map(list, read_lists(o))))  # noqa: B905
        for key, each, convert in conversions:
            value = doc[key]
            if value is None:
                continue
            if each:  # most arrays of parts are empty (alarms, events, contacts)
                doc[key] = list(map(convert, value)) if value else []
            else:
                doc[key] = convert(value)
        return doc

    return encode


def _reader(paths: list[str]) -> Callable[[Any], tuple[Any, ...]]:
    """One call that reads every path's value, as a tuple (``attrgetter`` of one path
    gives the value itself)."""
    if len(paths) > 1:
        return attrgetter(*paths)
    if paths:
        one = attrgetter(paths[0])
        return lambda o: (one(o),)
    return lambda o: ()


def document_encoder(cls: type) -> Callable[[Any], dict[str, Any]]:
    """The encoder of a snapshot type (a dataclass): an instance → its document. Built
    once per type; a type the rules cannot encode is a TypeError here, not at a call."""
    known = _ENCODERS.get(cls)
    if known is not None:
        return known
    _BUILDING.add(cls)
    try:
        encoder = _compose(_plan(cls))
    finally:
        _BUILDING.discard(cls)
    _ENCODERS[cls] = encoder
    return encoder


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
        out[f.name] = (kind, Field(default, description=f.metadata.get("description")))
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
