"""The front door (``import pymotoros``) and the blocking facade's completeness."""

from __future__ import annotations

import ast
import importlib
import inspect
import subprocess
import sys
from pathlib import Path

import pytest

import pymotoros
from pymotoros import client as client_package
from pymotoros.client import RobotClient, SyncRobotClient
from pymotoros.errors import PymotorosError

USER_NAMES = (
    "RobotClient",
    "SyncRobotClient",
    "connect",
    "MoveResult",
    "JointTrajectory",
    "MotionReadiness",
    "VirtualController",
    "RobotModel",
    "GroupModel",
    "DhLink",
    "PymotorosError",
    "ClientError",
    "PlanningError",
    "NamedPoseError",
    "NotReadyError",
)


def test_front_door_exports_what_users_need() -> None:
    for name in USER_NAMES:
        assert name in pymotoros.__all__, name
        assert name in dir(pymotoros), name
        assert getattr(pymotoros, name) is not None
    for name in pymotoros.__all__:
        assert hasattr(pymotoros, name), name
    assert len(set(pymotoros.__all__)) == len(pymotoros.__all__)


def test_the_names_are_declared_once() -> None:
    """``_EXPORTS`` is the one declaration (issue 19): the run-time map from name to
    module and ``__all__`` derive from it, no name is lent by two modules, and the
    ``TYPE_CHECKING`` imports that type checkers read say exactly the same, every line an
    explicit re-export (``X as X``)."""
    lent = [name for names in pymotoros._EXPORTS.values() for name in names]
    assert len(lent) == len(set(lent)), "a name is lent to the front door twice"
    tree = ast.parse(Path(pymotoros.__file__).read_text(encoding="utf-8"))
    block = next(
        node
        for node in tree.body
        if isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING"
    )
    declared: dict[str, str] = {}
    for node in block.body:
        assert isinstance(node, ast.ImportFrom), ast.unparse(node)
        assert node.module is not None
        for alias in node.names:
            assert alias.asname == alias.name, f"{alias.name}: write it `X as X`"
            declared[alias.name] = node.module
    assert declared == pymotoros._WHERE
    assert pymotoros.__all__ == sorted([*declared, "__version__"])
    for name, module in declared.items():
        assert getattr(pymotoros, name) is getattr(importlib.import_module(module), name)


def test_one_name_per_concept() -> None:
    from pymotoros import models

    assert pymotoros.GroupModel is models.GroupModel
    assert pymotoros.DhLink is models.DhLink
    assert pymotoros.MotionReadiness is client_package.MotionReadiness
    assert not hasattr(client_package, "Readiness")


def test_every_exception_is_in_the_one_tree() -> None:
    exceptions = [
        getattr(pymotoros, n)
        for n in pymotoros.__all__
        if inspect.isclass(getattr(pymotoros, n))
        and issubclass(getattr(pymotoros, n), BaseException)
    ]
    assert pymotoros.PlanningError in exceptions
    assert pymotoros.NamedPoseError in exceptions
    for exc in exceptions:
        assert issubclass(exc, PymotorosError), exc
    for name in ("PlanningError", "NamedPoseError"):
        assert getattr(client_package, name) is getattr(pymotoros, name)
        assert issubclass(getattr(pymotoros, name), pymotoros.ClientError)


def test_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no attribute 'Readiness'"):
        _ = pymotoros.Readiness  # type: ignore[attr-defined]


def test_the_front_door_imports_nothing_until_asked() -> None:
    code = (
        "import sys, pymotoros\n"
        "print(','.join(m for m in ('asyncio', 'socket', 'pymotoros.client', "
        "'pymotoros.controller', 'numpy') if m in sys.modules))\n"
    )
    done = subprocess.run(  # noqa: S603 - fixed interpreter and code
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=60
    )
    assert done.stdout.strip() == ""


# ------------------------------------------------------------------ the blocking facade


def _public(cls: type) -> dict[str, object]:
    return {
        name: inspect.getattr_static(cls, name) for name in dir(cls) if not name.startswith("_")
    }


def _parameters(function: object) -> list[tuple[str, object, object]]:
    signature = inspect.signature(function)  # type: ignore[arg-type]
    return [(p.name, p.kind, p.default) for p in signature.parameters.values()]


def test_sync_client_has_every_public_member_of_the_async_client() -> None:
    """Names and parameters match; coroutines become blocking calls; properties stay so.
    The calls are compared as an instance shows them (both classes inherit one descriptor
    per call, which gives each its own kind of method)."""
    async_api = _public(RobotClient)
    sync_api = _public(SyncRobotClient)
    missing = sorted(set(async_api) - set(sync_api))
    assert not missing, f"SyncRobotClient lacks {missing}"
    client, facade = RobotClient(robot="hc10"), SyncRobotClient(robot="hc10")
    try:
        for name, member in async_api.items():
            if isinstance(member, property):
                assert isinstance(sync_api[name], property), name
                continue
            method, twin = getattr(client, name), getattr(facade, name)
            assert callable(method), name
            assert callable(twin), name
            assert not inspect.iscoroutinefunction(twin), f"{name} must block, not return one"
            assert not inspect.isasyncgenfunction(twin), name
            assert _parameters(twin) == _parameters(method), name
    finally:
        facade.close()


ASYNC_ONLY_ATTRIBUTES = {"tracker", "streamer", "clock", "connector"}
"""Instance attributes of RobotClient that belong to its event loop (the facade's users
reach them, if at all, through ``SyncRobotClient.client``)."""


def test_sync_client_offers_the_public_instance_attributes_too() -> None:
    """Plain attributes (set in ``__init__``) are not in ``dir(cls)``: compare instances."""
    robot = SyncRobotClient(robot="hc10")
    try:
        attributes = {n for n in vars(robot.client) if not n.startswith("_")}
        missing = sorted(attributes - ASYNC_ONLY_ATTRIBUTES - set(dir(SyncRobotClient)))
        assert not missing, f"SyncRobotClient lacks {missing}"
        for name in attributes - ASYNC_ONLY_ATTRIBUTES:
            assert getattr(robot, name) is getattr(robot.client, name), name
    finally:
        robot.close()


def test_sync_client_plain_methods_work_on_the_facade() -> None:
    """``plan``, ``limits`` and ``named_pose`` run on the client behind (no AttributeError)."""
    robot = SyncRobotClient(robot="hc10")
    try:
        limits = robot.limits()
        assert limits.dof == 6
        home = robot.named_pose("home")
        plan = robot.plan(home, (0.1, 0.0, 0.0, 0.0, 0.0, 0.0))
        assert plan.goal[0] == pytest.approx(0.1)
        assert robot.robot.name == "hc10"
        assert robot.timeout_s == robot.client.timeout_s
    finally:
        robot.close()
