"""The operator's hands over HTTP/JSON: state, E-stop, hold, mode, remote, servo, alarms, IO.

:func:`create_http_app` builds a FastAPI application (OpenAPI schema at
``/openapi.json``, interactive docs at ``/docs``) around a
:class:`~pymotoros.runtime.target.SimulatedController` (its
:class:`~pymotoros.controller.actions.ActionTarget` side). Its ``POST`` endpoints are
derived from the declared actions (:data:`~pymotoros.controller.actions.CONTROL_ACTIONS`):
one per action, its body a pydantic model built from the action's parameters (so the
OpenAPI schema shows their bounds, units and meaning), checked by the same declaration
as a scenario file's events: a bad value is a 422 with the same words. A rule between
parameters, or a refusal by the controller, is a 400; removing something that is not
there (``DELETE /api/workspace/NAME``), a 404 naming what is. Every endpoint is an
``async def`` so it runs on the simulator's event loop, between two interpolation ticks,
never in a worker thread: the controller is not thread-safe and does not need to be.

Every error answer, unknown paths and malformed bodies included, is a 4xx with a
JSON body ``{"error": "<what was wrong>"}``. Each POST answers with the state after
the action, in the same shape as ``GET /api/state``.
"""

from __future__ import annotations

import logging
from collections.abc import Awaitable, Callable, Sequence
from typing import Annotated, Any, ClassVar, Literal

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import BaseModel, ConfigDict, Field, create_model, model_validator
from pydantic_core import PydanticCustomError
from starlette.exceptions import HTTPException as StarletteHTTPException

from pymotoros import __version__
from pymotoros.controller.actions import (
    CONTROL_ACTIONS,
    ActionParamError,
    ActionRefusedError,
    ActionSpec,
    ActionTarget,
    ActionTargetMissingError,
    Param,
    actions_by_name,
)
from pymotoros.controller.api import ControllerSnapshot
from pymotoros.controller.scenario import with_scenario_of
from pymotoros.errors import PymotorosError
from pymotoros.runtime.action_endpoints import action_endpoint, path_values
from pymotoros.runtime.body_limit import BodyLimit
from pymotoros.runtime.csrf import CsrfGuard, NoFraming
from pymotoros.runtime.docs_page import install_offline_docs
from pymotoros.runtime.log_limit import api_refusal_allowed
from pymotoros.runtime.observers import CatchUpMiddleware, Observers
from pymotoros.runtime.pendant import install_pendant
from pymotoros.runtime.pendant.document import Ports, state_document
from pymotoros.runtime.snapshot_document import Answer, ErrorModel, document_model
from pymotoros.runtime.strict_json import StrictJsonRoute
from pymotoros.runtime.target import SimulatedController
from pymotoros.runtime.ticker import TickStats

__all__ = [
    "StateModel",
    "action_body_model",
    "create_http_app",
    "state_model",
    "state_model_for",
]

logger = logging.getLogger(__name__)

_STRICT = ConfigDict(extra="forbid", strict=True, frozen=True)

ACTION_PARAM_ERROR: str = "action_param"
"""The pydantic error type of a value the action's declaration refuses."""


# --------------------------------------------------------------------------- bodies


class ActionBody(BaseModel):
    """Base of every action's body: the declaration checks each value first, so the
    words of a refusal are the declaration's (the scenario file's), not pydantic's."""

    model_config = _STRICT
    spec: ClassVar[ActionSpec[ActionTarget]]

    @model_validator(mode="before")
    @classmethod
    def _declared_values(cls, data: Any) -> Any:
        if isinstance(data, dict):
            data = _as_documented(cls.spec, data)
            try:
                cls.spec.check_values({k: v for k, v in data.items() if cls.spec.param(k)})
            except ActionParamError as exc:
                message = {"message": str(exc)}
                raise PydanticCustomError(ACTION_PARAM_ERROR, "{message}", message) from exc
        return data


def _as_documented(spec: ActionSpec[ActionTarget], data: dict[str, Any]) -> dict[str, Any]:
    """The body as the OpenAPI document reads it, for the declaration's check:

    * ``3080.0`` for an integer parameter is 3080: JSON has one kind of number, and the
      document's ``"type": "integer"`` (JSON Schema) takes any number without a fraction,
      as a generated client or JavaScript may send it (a fraction stays refused, in the
      declaration's words);
    * ``null`` for an optional parameter whose default is none is the parameter left
      out (the document allows ``null`` there).
    """
    out = dict(data)
    for key, value in data.items():
        param = spec.param(key)
        if param is None:
            continue
        if value is None and not param.required and param.default is None:
            del out[key]
        elif param.kind == "int" and isinstance(value, float) and value.is_integer():
            out[key] = int(value)
    return out


_PYTHON_TYPES: dict[str, Any] = {
    "bool": bool,
    "int": int,
    "number": float,
    "str": str,
    "numbers": list[float],
    "tables": list[dict[str, Any]],
}


def _field(param: Param) -> tuple[Any, Any]:
    """A pydantic field for a declared parameter: its type, bounds and description."""
    bounds: dict[str, Any] = {"ge": param.ge, "gt": param.gt, "le": param.le}
    kind: Any
    if param.choices:
        kind = Literal[param.choices]
    elif param.kind == "numbers":  # the bounds hold for each number, the length for all
        kind = list[Annotated[float, Field(**bounds)]]
        bounds = {"min_length": param.length, "max_length": param.length}
    else:
        kind = _PYTHON_TYPES[param.kind]
    if param.kind == "str":
        bounds["max_length"] = param.max_length
    default: Any = ...
    if not param.required:
        if param.default is None:
            kind = kind | None
        default = param.default
    return kind, Field(default, description=param.description, **bounds)


def action_body_model(spec: ActionSpec[ActionTarget]) -> type[ActionBody] | None:
    """The JSON body of an action's endpoint (None: it takes no body)."""
    in_body = [p for p in spec.params if p.name not in spec.path_keys]
    if not in_body:
        return None
    name = "".join(part.capitalize() for part in spec.name.split("_")) + "Body"
    fields = {p.name: _field(p) for p in in_body}
    model: type[ActionBody] = create_model(name, __base__=ActionBody, **fields)  # type: ignore[call-overload]
    model.spec = spec
    return model


# --------------------------------------------------------------------------- answers


class LatenessModel(Answer):
    p50: float
    p99: float
    max: float


class TickModel(Answer):
    period_ms: float
    count: int
    overruns: int
    lateness_ms: LatenessModel


class PortsModel(Answer):
    motion: int | None
    state: int | None
    io: int | None


def state_model_for(snapshot_type: type[ControllerSnapshot]) -> type[Answer]:
    """The schema of ``GET /api/state`` for a snapshot type: its fields, types and
    docstrings (:func:`~pymotoros.runtime.snapshot_document.document_model`), then what
    the runtime adds (the loop's ``tick``, the listening ``ports``). Built once per type."""
    known = _STATE_MODELS.get(snapshot_type)
    if known is not None:
        return known
    model: type[Answer] = create_model(
        "StateModel",
        __base__=document_model(snapshot_type),
        tick=(TickModel, Field(description="the interpolation loop's counters")),
        ports=(
            PortsModel,
            Field(description="MotoROS's ports that accept connections (null: not listening)"),
        ),
    )
    _STATE_MODELS[snapshot_type] = model
    return model


_STATE_MODELS: dict[type, type[Answer]] = {}


StateModel = state_model_for(ControllerSnapshot)
"""``GET /api/state``'s schema, derived from :class:`ControllerSnapshot`."""


class IoValueModel(BaseModel):
    address: int
    value: int
    result_code: int


class FindingModel(Answer):
    """One client lint finding (``pymotoros.controller.lint``)."""

    code: str = Field(description="what the client did, e.g. fragmented-message")
    count: int = Field(description="how often, on this connection")
    first_s: float = Field(description="controller time (s) of the first occurrence")
    connection: str = Field(description='the client, "host:port"')
    reference: str = Field(description="section of the MotoROS 1.9.12 reference")
    text: str = Field(description="what happened, and what a real controller does with it")
    remedy: str = Field(description="what to change in the client")


class LintModel(Answer):
    findings: list[FindingModel]


def state_model(
    snapshot: ControllerSnapshot, tick: TickStats, ports: Ports = (None, None, None)
) -> Answer:
    """The ``GET /api/state`` document as its model (the one builder is
    :func:`~pymotoros.runtime.pendant.document.state_document`)."""
    model = state_model_for(type(snapshot))
    return model.model_validate(state_document(snapshot, tick, ports))


# --------------------------------------------------------------------------- errors


def _describe_validation(exc: RequestValidationError) -> str:
    parts = []
    for err in exc.errors():
        loc = [str(p) for p in err.get("loc", ()) if p != "body"]
        where = ".".join(loc) if loc else "body"
        kind = err.get("type", "")
        if kind == "json_invalid":
            parts.append(f"the body is not valid JSON ({err.get('msg', '')})")
        elif kind == "missing" and not loc:
            parts.append("a JSON body is required")
        elif not loc and kind in ("model_attributes_type", "dict_type"):
            parts.append("the body must be a JSON object (send Content-Type: application/json)")
        elif kind == "extra_forbidden":
            parts.append(f"unknown field {where!r}")
        elif kind == ACTION_PARAM_ERROR:  # the declaration's words, as in a scenario file
            parts.append(str(err.get("msg", "invalid")))
        else:
            parts.append(f"{where}: {err.get('msg', 'invalid')}")
    return "; ".join(parts) or "invalid request"


async def _validation_error(request: Request, exc: Exception) -> JSONResponse:
    detail = _describe_validation(exc) if isinstance(exc, RequestValidationError) else str(exc)
    message = f"{request.method} {request.url.path}: {detail}"
    if api_refusal_allowed(request.scope, logger, logging.INFO):  # a flood: counted
        logger.info("control API refused a request: %s", message)
    return JSONResponse({"error": message}, status_code=422)


async def _http_error(request: Request, exc: Exception) -> JSONResponse:
    if not isinstance(exc, StarletteHTTPException):  # registered for that type only
        return JSONResponse({"error": str(exc)}, status_code=400)
    if exc.status_code == 404:
        message = f"no such endpoint: {request.method} {request.url.path} (see /docs)"
    elif exc.status_code == 405:
        allowed = (exc.headers or {}).get("Allow", "")
        message = f"method {request.method} not allowed on {request.url.path}"
        if allowed:
            message += f" (allowed: {allowed})"
    else:
        message = str(exc.detail)
    status = exc.status_code if 400 <= exc.status_code < 500 else 400
    return JSONResponse({"error": message}, status_code=status, headers=exc.headers)


async def _our_error(request: Request, exc: Exception) -> JSONResponse:
    """Our errors (a refused action, a bad scenario, an unreadable address) are the
    client's: 400; an action naming something that is not there (an obstacle to
    remove), 404. Any other exception is a bug in the simulator: 500."""
    message = f"{request.method} {request.url.path}: {exc}"
    if api_refusal_allowed(request.scope, logger, logging.INFO):  # a flood: counted
        logger.info("control API refused a request: %s", message)
    status = 404 if isinstance(exc, ActionTargetMissingError) else 400
    return JSONResponse({"error": message}, status_code=status)


# --------------------------------------------------------------------------- the app

_ERRORS: dict[int | str, dict[str, object]] = {
    400: {"model": ErrorModel, "description": "the controller refused the arguments"},
    422: {"model": ErrorModel, "description": "the body is malformed"},
}
_NOT_FOUND: dict[int | str, dict[str, object]] = {
    404: {"model": ErrorModel, "description": "nothing of that name (the error lists what is)"},
}

_TOO_LARGE: dict[int | str, dict[str, Any]] = {
    413: {"model": ErrorModel, "description": "the body is larger than the control API takes"},
}

StateFn = Callable[[], dict[str, Any]]


def create_http_app(
    controller: SimulatedController,
    tick_stats: Callable[[], TickStats],
    reset_tick_stats: Callable[[], None] | None = None,
    *,
    ports: Callable[[], Ports] | None = None,
    clients: Callable[[], dict[str, int]] | None = None,
    after_ticks: Callable[[int], Awaitable[None]] | None = None,
    observers: Observers | None = None,
    actions: Sequence[ActionSpec[ActionTarget]] = CONTROL_ACTIONS,
) -> FastAPI:
    """The control API of one simulated controller; ``actions``: the declared actions
    it serves (one endpoint each; a scenario's events may carry any of them)."""
    actions = with_scenario_of(actions)
    app = _new_app(observers)

    def state() -> dict[str, Any]:
        listening = ports() if ports is not None else (None, None, None)
        return state_document(controller.snapshot(), tick_stats(), listening)

    # the schema of the document this controller's snapshot type gives (a field a
    # subclass adds is in it too)
    answer = state_model_for(type(controller.snapshot()))
    install_pendant(app, controller, tick_stats, ports, clients, after_ticks, actions=actions)
    _install_state_routes(app, state, reset_tick_stats, answer)
    for spec in actions_by_name(actions).values():
        _install_action(app, spec, controller, state, answer)
    _install_read_io(app, controller)
    _install_lint(app, controller)
    return app


def _new_app(observers: Observers | None) -> FastAPI:
    """The application with its middleware (CSRF, catch-up, body limit) and error answers."""
    app = FastAPI(
        title="pymotoros control API",
        version=__version__,
        docs_url=None,  # /docs is served offline by install_offline_docs below
        redoc_url=None,  # /redoc too (ReDoc from the installed files, not a CDN)
        description=(
            "The operator of the virtual controller: pendant keys, E-stop, mode switch, "
            'alarms and forced IO. Errors are 4xx with {"error": "..."}.'
        ),
        responses=_TOO_LARGE,  # any route: the body limit answers before the route
    )
    app.router.route_class = StrictJsonRoute  # a JSON body naming a key twice: 422
    install_offline_docs(app)
    app.add_middleware(CsrfGuard)  # the pendant's buttons: refuse other sites' POSTs
    app.add_middleware(NoFraming)  # no other site may frame the pendant or /docs
    if observers is not None:  # idle batching: every request sees an up-to-date controller
        app.add_middleware(CatchUpMiddleware, observers=observers)
    app.add_middleware(BodyLimit)  # outermost: no body read beyond MAX_BODY_BYTES
    app.add_exception_handler(RequestValidationError, _validation_error)
    app.add_exception_handler(StarletteHTTPException, _http_error)
    app.add_exception_handler(PymotorosError, _our_error)
    return app


def _install_state_routes(
    app: FastAPI,
    state: StateFn,
    reset_tick_stats: Callable[[], None] | None,
    answer: type[Answer] = StateModel,
) -> None:
    @app.get("/api/state", response_model=answer, tags=["state"])
    async def get_state() -> dict[str, Any]:
        """Operator state, alarms, groups (command/feedback positions, queue, tool), loop timing."""
        return state()

    @app.post("/api/tick/reset", response_model=answer, tags=["state"])
    async def reset_tick() -> dict[str, Any]:
        """Forget the loop's lateness samples and overrun count (e.g. after a warm-up)."""
        if reset_tick_stats is not None:
            reset_tick_stats()
        return state()


def _install_action(
    app: FastAPI,
    spec: ActionSpec[ActionTarget],
    controller: SimulatedController,
    state: StateFn,
    answer: type[Answer] = StateModel,
) -> None:
    """``spec.method spec.path``: the body (and the path's parameters) checked by the
    declaration, then the action (the endpoint: runtime/action_endpoints.py)."""
    model = action_body_model(spec)
    path_keys = spec.path_keys

    def act(in_path: dict[str, object], body: BaseModel | None) -> dict[str, Any]:
        given = {} if body is None else body.model_dump(exclude_unset=True)
        for key in path_keys:
            try:
                spec.check_value(key, in_path[key])
            except ActionParamError as exc:
                error = {"type": ACTION_PARAM_ERROR, "loc": ("path", key), "msg": str(exc)}
                raise RequestValidationError([error]) from exc
            given[key] = in_path[key]
        logger.info("operator: %s %s", spec.name, given)
        spec.perform(controller, given)
        return state()

    # with its key in the path, an action whose body is all optional may omit it
    optional = bool(path_keys) and not any(
        p.required for p in spec.params if p.name not in path_keys
    )
    in_path = path_values([(key, _PATH_TYPES[_param(spec, key).kind]) for key in path_keys])
    app.add_api_route(
        spec.path,
        action_endpoint(in_path, model, act, body_optional=optional),
        methods=[spec.method],
        response_model=answer,
        responses=_ERRORS | _NOT_FOUND if spec.method == "DELETE" else _ERRORS,
        tags=[spec.tag],
        summary=spec.doc.split(":")[0].rstrip("."),
        description=spec.doc,
        name=spec.name,
    )


_PATH_TYPES: dict[str, type] = {"str": str, "int": int, "number": float}
"""What a path can carry (an action's other kinds go in the body)."""


def _param(spec: ActionSpec[ActionTarget], key: str) -> Param:
    param = spec.param(key)
    if param is None or param.kind not in _PATH_TYPES:
        raise ValueError(f"action {spec.name!r}: {key!r} in {spec.path} is not a str or number")
    return param


def _install_read_io(app: FastAPI, controller: SimulatedController) -> None:
    @app.get("/api/io/{address}", response_model=IoValueModel, responses=_ERRORS, tags=["io"])
    async def read_io(address: int) -> IoValueModel:
        """Read a bit, or an M-register (address 1000000 + n), as a client would."""
        if address >= 1_000_000:
            read = controller.read_mregister(address)
        else:
            read = controller.read_io_bit(address)
        if read.result_code != 0:
            raise ActionRefusedError(f"address {address}: {read.result_code.meaning}")
        return IoValueModel(address=address, value=read.value, result_code=int(read.result_code))


def _install_lint(app: FastAPI, controller: SimulatedController) -> None:
    @app.get("/api/lint", response_model=LintModel, tags=["lint"])
    async def get_lint() -> dict[str, Any]:
        """What clients did that a real controller answers differently, or that works only
        by luck: one finding per code and connection (issue 31)."""
        return controller.lint.document()

    @app.delete("/api/lint", response_model=LintModel, tags=["lint"])
    async def clear_lint() -> dict[str, Any]:
        """Forget every finding (answers the empty list)."""
        controller.lint.clear()
        return controller.lint.document()
