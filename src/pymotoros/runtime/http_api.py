"""The operator's hands over HTTP/JSON: state, E-stop, hold, mode, remote, servo, alarms, IO.

:func:`create_http_app` builds a FastAPI application (OpenAPI schema at
``/openapi.json``, interactive docs at ``/docs``) around a
:class:`~pymotoros.runtime.target.SimulatedController` (its
:class:`~pymotoros.controller.api.OperatorPanel` and
:class:`~pymotoros.controller.api.FaultInjection` sides). Every endpoint is an ``async def``
so it runs on the simulator's event loop, between two interpolation ticks, never in
a worker thread: the controller is not thread-safe and does not need to be.

Every error answer, unknown paths and malformed bodies included, is a 4xx with a
JSON body ``{"error": "<what was wrong>"}``. Each POST answers with the state after
the action, in the same shape as ``GET /api/state``.
"""

from __future__ import annotations

import logging
from collections.abc import Awaitable, Callable
from typing import Any, Literal

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import BaseModel, ConfigDict, Field
from starlette.exceptions import HTTPException as StarletteHTTPException

from pymotoros import __version__
from pymotoros.controller.api import ControllerSnapshot, PendantMode, TcpSnapshot
from pymotoros.controller.scenario import parse_scenario
from pymotoros.runtime.body_limit import BodyLimit
from pymotoros.runtime.csrf import CsrfGuard
from pymotoros.runtime.docs_page import install_offline_docs
from pymotoros.runtime.log_limit import api_refusal_allowed
from pymotoros.runtime.observers import CatchUpMiddleware, Observers
from pymotoros.runtime.pendant import install_pendant
from pymotoros.runtime.strict_json import StrictJsonRoute
from pymotoros.runtime.target import SimulatedController
from pymotoros.runtime.ticker import TickStats

__all__ = ["StateModel", "create_http_app", "state_model"]

logger = logging.getLogger(__name__)

_STRICT = ConfigDict(extra="forbid", strict=True, frozen=True)


# --------------------------------------------------------------------------- bodies


class EstopBody(BaseModel):
    model_config = _STRICT
    pressed: bool = Field(description="true presses the pendant E-stop, false releases it")


class OnOffBody(BaseModel):
    model_config = _STRICT
    on: bool


class ModeBody(BaseModel):
    model_config = _STRICT
    mode: Literal["teach", "play"]


class AlarmBody(BaseModel):
    model_config = _STRICT
    code: int = Field(ge=0, le=9999, description="alarm number, e.g. 4107")
    subcode: int = Field(default=0, ge=0, description="alarm subcode")
    text: str = Field(default="", max_length=128, description="alarm text shown on the pendant")


class IoFailureBody(BaseModel):
    model_config = _STRICT
    reads: bool = Field(default=False, description="client IO reads fail with 1004")
    writes: bool = Field(default=False, description="client IO writes fail with 1005")


class IoBody(BaseModel):
    model_config = _STRICT
    address: int = Field(
        ge=0,
        description="bit address (e.g. 20010), or 1000000 + n for M-register n",
    )
    value: int = Field(ge=0, le=0xFFFF, description="0/1 for a bit, 0..65535 for an M-register")


class PflBody(BaseModel):
    model_config = _STRICT
    event: Literal["contact", "clamping"] = Field(
        description="contact: PFL stop; clamping: PFL stop, then retreat with PFL escape"
    )
    retreat_ms: int | None = Field(
        default=None, ge=1, description="clamping only: how much of the last motion to retreat"
    )
    stop_ms: int | None = Field(
        default=None, ge=0, le=60_000, description="how long PFL stop stays on (default 500)"
    )


class FsuBody(BaseModel):
    model_config = _STRICT
    joint_speed_pct: int | None = Field(
        default=None, ge=1, le=100, description="share of each axis's maximum speed"
    )
    tcp_speed_mm_s: float | None = Field(
        default=None, gt=0, description="TCP speed limit (needs the kinematics model)"
    )
    off: bool = Field(default=False, description="switch every FSU speed limit off")


# --------------------------------------------------------------------------- answers


class AlarmModel(BaseModel):
    code: int
    subcode: int
    text: str


class TcpSpeedModel(BaseModel):
    command: float
    feedback: float


class TcpModel(BaseModel):
    command: list[float] = Field(
        description="TCP of the active tool in base coordinates: x, y, z (m), rx, ry, rz "
        "(rad, R = Rz·Ry·Rx), from the command"
    )
    feedback: list[float] = Field(description="the same from the encoder feedback")
    speed_mm_s: TcpSpeedModel


class GroupModel(BaseModel):
    name: str
    joint_names: list[str]
    command_rad: list[float]
    feedback_rad: list[float]
    command_pulse: list[int]
    queue: int = Field(description="increments queued for the group")
    tool: int
    tcp: TcpModel | None = Field(default=None, description="null: no kinematic chain")


class LatenessModel(BaseModel):
    p50: float
    p99: float
    max: float


class TickModel(BaseModel):
    period_ms: float
    count: int
    overruns: int
    lateness_ms: LatenessModel


class ScenarioBody(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)
    events: list[dict[str, Any]] = Field(
        description="timed events, the keys of a scenario file's [[events]] tables"
    )


class FsuModel(BaseModel):
    joint_speed_pct: int | None
    tcp_speed_mm_s: float | None


class PortsModel(BaseModel):
    motion: int | None
    state: int | None
    io: int | None


class StateModel(BaseModel):
    mode: Literal["play", "teach"]
    remote: bool
    servo: bool
    estop: bool
    hold: bool
    alarms: list[AlarmModel]
    motion_ready: bool
    groups: list[GroupModel]
    tick: TickModel
    fsu: FsuModel = Field(
        default_factory=lambda: FsuModel(joint_speed_pct=None, tcp_speed_mm_s=None),
        description="the FSU speed limits in force (null: off)",
    )
    pfl: Literal["off", "idle", "stop", "escape"] = Field(
        default="off", description="the PFL function: off (not in this cell), idle, stop, escape"
    )
    events: list[dict[str, Any]] = Field(
        default_factory=list,
        description='scenario events fired: {"t": seconds since boot, "action": ..., params}',
    )
    motoros: str = Field(
        default="running",
        description="MotoROS's start-up: running, what it waits for, or why it halted",
    )
    ports: PortsModel = Field(
        default_factory=lambda: PortsModel(motion=None, state=None, io=None),
        description="MotoROS's ports that accept connections (null: not listening)",
    )


class ErrorModel(BaseModel):
    error: str


class IoValueModel(BaseModel):
    address: int
    value: int
    result_code: int


def _tcp_model(tcp: TcpSnapshot | None) -> TcpModel | None:
    if tcp is None:
        return None
    return TcpModel(
        command=list(tcp.command),
        feedback=list(tcp.feedback),
        speed_mm_s=TcpSpeedModel(command=tcp.command_speed_mm_s, feedback=tcp.feedback_speed_mm_s),
    )


def state_model(
    snapshot: ControllerSnapshot,
    tick: TickStats,
    ports: tuple[int | None, int | None, int | None] = (None, None, None),
) -> StateModel:
    """The ``GET /api/state`` document for a controller snapshot and the loop's statistics."""
    return StateModel(
        mode="play" if snapshot.mode is PendantMode.PLAY else "teach",
        remote=snapshot.remote,
        servo=snapshot.servo,
        estop=snapshot.estop,
        hold=snapshot.hold,
        alarms=[AlarmModel(code=a.code, subcode=a.subcode, text=a.text) for a in snapshot.alarms],
        motion_ready=snapshot.motion_ready,
        groups=[
            GroupModel(
                name=g.name,
                joint_names=list(g.joint_names),
                command_rad=list(g.command_rad),
                feedback_rad=list(g.feedback_rad),
                command_pulse=list(g.command_pulse),
                queue=g.queue,
                tool=g.tool,
                tcp=_tcp_model(g.tcp),
            )
            for g in snapshot.groups
        ],
        fsu=FsuModel(
            joint_speed_pct=snapshot.fsu_joint_speed_pct,
            tcp_speed_mm_s=snapshot.fsu_tcp_speed_mm_s,
        ),
        pfl=snapshot.pfl,  # type: ignore[arg-type]
        motoros=snapshot.motoros,
        events=[
            {
                "t": e.t,
                "action": e.action,
                **dict(e.params),
                **({"error": e.error} if e.error else {}),
            }
            for e in snapshot.events
        ],
        ports=PortsModel(motion=ports[0], state=ports[1], io=ports[2]),
        tick=TickModel(
            period_ms=tick.period_ms,
            count=tick.count,
            overruns=tick.overruns,
            lateness_ms=LatenessModel(
                p50=tick.lateness_ms.p50, p99=tick.lateness_ms.p99, max=tick.lateness_ms.max
            ),
        ),
    )


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


async def _value_error(request: Request, exc: Exception) -> JSONResponse:
    message = f"{request.method} {request.url.path}: {exc}"
    if api_refusal_allowed(request.scope, logger, logging.INFO):  # a flood: counted
        logger.info("control API refused a request: %s", message)
    return JSONResponse({"error": message}, status_code=400)


# --------------------------------------------------------------------------- the app

_ERRORS: dict[int | str, dict[str, object]] = {
    400: {"model": ErrorModel, "description": "the controller refused the arguments"},
    422: {"model": ErrorModel, "description": "the body is malformed"},
}


def create_http_app(
    controller: SimulatedController,
    tick_stats: Callable[[], TickStats],
    reset_tick_stats: Callable[[], None] | None = None,
    *,
    ports: Callable[[], tuple[int | None, int | None, int | None]] | None = None,
    clients: Callable[[], dict[str, int]] | None = None,
    after_ticks: Callable[[int], Awaitable[None]] | None = None,
    observers: Observers | None = None,
) -> FastAPI:
    """The control API of one simulated controller."""
    app = FastAPI(
        title="pymotoros control API",
        version=__version__,
        docs_url=None,  # /docs is served offline by install_offline_docs below
        redoc_url=None,  # /redoc too (ReDoc from the installed files, not a CDN)
        description=(
            "The operator of the virtual controller: pendant keys, E-stop, mode switch, "
            'alarms and forced IO. Errors are 4xx with {"error": "..."}.'
        ),
    )
    app.router.route_class = StrictJsonRoute  # a JSON body naming a key twice: 422
    install_offline_docs(app)
    app.add_middleware(CsrfGuard)  # the pendant's buttons: refuse other sites' POSTs
    if observers is not None:  # idle batching: every request sees an up-to-date controller
        app.add_middleware(CatchUpMiddleware, observers=observers)
    app.add_middleware(BodyLimit)  # outermost: no body read beyond MAX_BODY_BYTES
    app.add_exception_handler(RequestValidationError, _validation_error)
    app.add_exception_handler(StarletteHTTPException, _http_error)
    app.add_exception_handler(ValueError, _value_error)

    def state() -> StateModel:
        listening = ports() if ports is not None else (None, None, None)
        return state_model(controller.snapshot(), tick_stats(), listening)

    install_pendant(app, controller, tick_stats, ports, clients, after_ticks)

    @app.get("/api/state", response_model=StateModel, tags=["state"])
    async def get_state() -> StateModel:
        """Operator state, alarms, groups (command/feedback positions, queue, tool), loop timing."""
        return state()

    @app.post("/api/estop", response_model=StateModel, responses=_ERRORS, tags=["operator"])
    async def estop(body: EstopBody) -> StateModel:
        """Press or release the pendant E-stop: cuts servo power, stops the job, no alarm."""
        logger.info("operator: E-stop %s", "pressed" if body.pressed else "released")
        controller.press_estop(body.pressed)
        return state()

    @app.post("/api/hold", response_model=StateModel, responses=_ERRORS, tags=["operator"])
    async def hold(body: OnOffBody) -> StateModel:
        """Switch HOLD on or off."""
        logger.info("operator: hold %s", "on" if body.on else "off")
        controller.set_hold(body.on)
        return state()

    @app.post("/api/mode", response_model=StateModel, responses=_ERRORS, tags=["operator"])
    async def mode(body: ModeBody) -> StateModel:
        """Turn the pendant's mode key to TEACH or PLAY."""
        logger.info("operator: mode %s", body.mode)
        controller.set_mode(PendantMode(body.mode))
        return state()

    @app.post("/api/remote", response_model=StateModel, responses=_ERRORS, tags=["operator"])
    async def remote(body: OnOffBody) -> StateModel:
        """Switch REMOTE on or off."""
        logger.info("operator: remote %s", "on" if body.on else "off")
        controller.set_remote(body.on)
        return state()

    @app.post("/api/servo", response_model=StateModel, responses=_ERRORS, tags=["operator"])
    async def servo(body: OnOffBody) -> StateModel:
        """Request servo power on or off (refused silently while E-stopped)."""
        logger.info("operator: servo %s", "on" if body.on else "off")
        controller.set_servo(body.on)
        return state()

    @app.post("/api/alarm", response_model=StateModel, responses=_ERRORS, tags=["operator"])
    async def alarm(body: AlarmBody) -> StateModel:
        """Raise an alarm."""
        logger.info("operator: raise alarm %d/%d %r", body.code, body.subcode, body.text)
        controller.raise_alarm(body.code, body.subcode, body.text)
        return state()

    @app.post("/api/reset", response_model=StateModel, responses=_ERRORS, tags=["operator"])
    async def reset() -> StateModel:
        """The pendant's RESET key: clears alarms and errors whose cause is gone."""
        logger.info("operator: reset")
        controller.reset()
        return state()

    @app.post("/api/io", response_model=StateModel, responses=_ERRORS, tags=["io"])
    async def force_io(body: IoBody) -> StateModel:
        """Force any bit (0/1) or M-register (address 1000000 + n, 0..65535)."""
        logger.info("operator: force IO %d = %d", body.address, body.value)
        controller.force_io(body.address, body.value)
        return state()

    @app.post("/api/error", response_model=StateModel, responses=_ERRORS, tags=["operator"])
    async def raise_error(body: AlarmBody) -> StateModel:
        """Raise an operator error (not an alarm): motion is refused with 5002 until reset."""
        logger.info("operator: raise error %d/%d %r", body.code, body.subcode, body.text)
        controller.raise_error(body.code, body.subcode, body.text)
        return state()

    @app.post("/api/io/failure", response_model=StateModel, responses=_ERRORS, tags=["io"])
    async def io_failure(body: IoFailureBody) -> StateModel:
        """Fault injection: make client IO reads (1004) and/or writes (1005) fail."""
        logger.info("operator: IO API failure reads=%s writes=%s", body.reads, body.writes)
        controller.set_io_api_failure(reads=body.reads, writes=body.writes)
        return state()

    @app.post("/api/pfl", response_model=StateModel, responses=_ERRORS, tags=["safety"])
    async def pfl(body: PflBody) -> StateModel:
        """A PFL contact (PFL stop) or clamping (stop, then retreat with PFL escape)."""
        logger.info("operator: PFL %s", body.event)
        kwargs: dict[str, int] = {}
        if body.retreat_ms is not None:
            if body.event != "clamping":
                raise ValueError("retreat_ms applies to a clamping only")
            kwargs["retreat_ms"] = body.retreat_ms
        if body.stop_ms is not None:
            kwargs["stop_ms"] = body.stop_ms
        controller.pfl_event(body.event, **kwargs)
        return state()

    @app.post("/api/fsu", response_model=StateModel, responses=_ERRORS, tags=["safety"])
    async def fsu(body: FsuBody) -> StateModel:
        """Switch the FSU speed limits at run time (the cell file's value is the boot value)."""
        logger.info("operator: FSU %s", body.model_dump(exclude_defaults=True))
        controller.set_fsu(
            joint_speed_pct=body.joint_speed_pct, tcp_speed_mm_s=body.tcp_speed_mm_s, off=body.off
        )
        return state()

    @app.post("/api/scenario", response_model=StateModel, responses=_ERRORS, tags=["safety"])
    async def scenario(body: ScenarioBody) -> StateModel:
        """Run timed events (same keys as a scenario file); replaces events not fired yet."""
        parsed = parse_scenario({"events": body.events}, source="POST /api/scenario")
        logger.info("operator: scenario with %d events", len(parsed.events))
        controller.load_scenario(parsed)
        return state()

    @app.post("/api/tick/reset", response_model=StateModel, tags=["state"])
    async def reset_tick() -> StateModel:
        """Forget the loop's lateness samples and overrun count (e.g. after a warm-up)."""
        if reset_tick_stats is not None:
            reset_tick_stats()
        return state()

    @app.get("/api/io/{address}", response_model=IoValueModel, responses=_ERRORS, tags=["io"])
    async def read_io(address: int) -> IoValueModel:
        """Read a bit, or an M-register (address 1000000 + n), as a client would."""
        if address >= 1_000_000:
            read = controller.read_mregister(address)
        else:
            read = controller.read_io_bit(address)
        if read.result_code != 0:
            raise ValueError(f"address {address}: {read.result_code.meaning}")
        return IoValueModel(address=address, value=read.value, result_code=int(read.result_code))

    return app
