"""Each MotoROS rule exists once, and the client's pre-flight agrees with the controller.

Issue 8, item 1: the start tolerance, the speed limit, the pulse conversions, the IO
address rules, ROBOT_STATUS's mode and "FALSE with a 5xxx subcode means not ready"
each live in one numpy-free place (``models.rules``, ``models.io``,
``protocol.constants``) that both sides import. The tests below check that the two
sides hold the very same objects, that no copy is left in the source, and, on random
points, that the client's pre-flight predicts the virtual controller's answer
(accept, 3011 or 3013, the axis and the sentence) to the bit.

Both sides call the same rule objects, so those property tests check the *wiring* (the
same rule, fed the same inputs, reached from both sides): under a wrong rule they still
agree. What the rule itself must answer is pinned by ``test_*_by_hand`` below, with
expected answers worked out from the reference, not from the code.
"""

from __future__ import annotations

import ast
import dataclasses
import math
import re
import subprocess
import sys
from collections.abc import Iterator
from functools import cache
from pathlib import Path
from types import ModuleType

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

import pymotoros.client.errors as client_errors
import pymotoros.client.io_map as client_io_map
import pymotoros.client.joint_text as client_joint_text
import pymotoros.client.planning as client_planning
import pymotoros.client.preflight as client_preflight
import pymotoros.client.state as client_state
import pymotoros.controller.io_image as controller_io_image
import pymotoros.controller.state_view as controller_state_view
import pymotoros.controller.trajectory as controller_trajectory
import pymotoros.motion as motion
import pymotoros.motion.axes as motion_axes
import pymotoros.motion.constants as motion_constants
import pymotoros.motion.numerics as motion_numerics
import pymotoros.motion.offline as motion_offline
import pymotoros.motion.points as motion_points
import pymotoros.runtime.motion_server as runtime_motion_server
from pymotoros.client.planning import TrajectoryPoint
from pymotoros.controller import Outcome, Pending, PointData, VirtualController
from pymotoros.controller.cell import InitialState, default_cell
from pymotoros.models import io as io_rules
from pymotoros.models import rules
from pymotoros.protocol import constants as protocol
from pymotoros.protocol.constants import InvalidSubcode, MotionCommand, ResultCode

SRC = Path(__file__).resolve().parents[1] / "src" / "pymotoros"

# --------------------------------------------------------------------------- one object


@pytest.mark.parametrize(
    ("name", "homes"),
    [
        ("START_TOLERANCE_PULSES", (client_errors, client_joint_text, motion)),
        ("MAX_POINT_TIME_S", (motion_offline,)),
        ("SLOTS", (motion, motion_constants, motion_points)),
        ("check_start", (motion, controller_trajectory, client_preflight, motion_offline)),
        ("check_speed", (motion, controller_trajectory, client_preflight, motion_offline)),
        ("check_time", (motion, controller_trajectory, motion_offline)),
        ("Refusal", (motion, controller_trajectory, client_preflight)),
        ("TrajPoint", (motion, motion_points, client_preflight)),
        ("to_pulses", (motion, motion_axes, client_preflight)),
        ("from_pulses", (motion, motion_axes)),
        ("f32", (motion_numerics, motion_points, client_preflight)),
        ("pulse", (motion_numerics,)),
        ("c_int", (motion_numerics,)),
        ("from_pulse", (motion_numerics,)),
        ("axis_speed_limit", (client_planning,)),
    ],
)
def test_point_rules_are_one_object_on_both_sides(name: str, homes: tuple[ModuleType, ...]) -> None:
    shared = getattr(rules, name)
    for module in homes:
        assert getattr(module, name) is shared, f"{module.__name__}.{name}"


def test_group_axes_are_the_shared_rules_plus_arrays() -> None:
    assert issubclass(motion.GroupAxes, rules.GroupRules)
    cell = default_cell("yrc1000", "hc10")
    axes = motion.GroupAxes.from_model(cell.groups[0], cell.controller)
    shared = rules.group_rules(cell.groups[0], cell.controller)
    for f in dataclasses.fields(rules.GroupRules):
        assert getattr(axes, f.name) == getattr(shared, f.name), f.name


@pytest.mark.parametrize(
    "name",
    [
        "bit_address_result",
        "group_address_result",
        "mregister_address_result",
        "bit_value_result",
        "group_value_result",
        "mregister_value_result",
        "m_register_index",
        "M_REGISTER_MAX",
    ],
)
def test_io_rules_are_one_object_on_both_sides(name: str) -> None:
    """Each side uses the shared object, by name or through the shared module, and
    defines no copy of its own."""
    shared = getattr(io_rules, name)
    for module in (controller_io_image, client_io_map):
        own = vars(module).get(name)
        through_module = any(v is io_rules for v in vars(module).values())
        assert own is shared or (own is None and through_module), f"{module.__name__}.{name}"


@pytest.mark.parametrize(
    ("name", "homes"),
    [
        ("StatusMode", (client_state, controller_state_view)),
        ("reply_result", (client_errors, runtime_motion_server)),
    ],
)
def test_status_rules_are_one_object_on_both_sides(
    name: str, homes: tuple[ModuleType, ...]
) -> None:
    shared = getattr(protocol, name)
    for module in homes:
        assert getattr(module, name) is shared, f"{module.__name__}.{name}"


def test_mode_and_not_ready_rules() -> None:
    mode = protocol.StatusMode
    assert mode.encode(True) == 2
    assert mode.encode(False) == 1
    assert mode.is_play(mode.encode(True))
    assert not mode.is_play(mode.encode(False))
    assert not mode.is_play(0)
    for sub in protocol.NotReadySubcode:
        assert protocol.reply_result(ResultCode.FALSE, sub) == ResultCode.NOT_READY
    assert protocol.reply_result(ResultCode.FALSE, 0) == ResultCode.FALSE
    assert protocol.reply_result(ResultCode.INVALID, 5001) == ResultCode.INVALID


def test_shared_homes_stay_numpy_free() -> None:
    code = (
        "import sys\n"
        "import pymotoros.models.rules, pymotoros.models.io, pymotoros.client.preflight\n"
        "import pymotoros.client.io_map, pymotoros.client.state, pymotoros.client.errors\n"
        "assert 'numpy' not in sys.modules, 'numpy imported'\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)  # noqa: S603 - fixed code


# --------------------------------------------------------------------------- no copy left


def _modules() -> Iterator[tuple[Path, ast.Module]]:
    for path in sorted(SRC.rglob("*.py")):
        yield path, ast.parse(path.read_text(encoding="utf-8"))


def _definitions(tree: ast.Module) -> set[str]:
    names: set[str] = set()
    for node in tree.body:
        if isinstance(node, ast.FunctionDef | ast.ClassDef):
            names.add(node.name)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
    return names


SHARED_NAMES = {
    # name: the one module that may define it
    "START_TOLERANCE_PULSES": "models/rules.py",
    "MAX_POINT_TIME_S": "models/rules.py",
    "INVALID_AXIS_FACTOR": "models/rules.py",
    "Refusal": "models/rules.py",
    "TrajPoint": "models/rules.py",
    "check_start": "models/rules.py",
    "check_speed": "models/rules.py",
    "check_time": "models/rules.py",
    "to_pulses": "models/rules.py",
    "from_pulses": "models/rules.py",
    "from_pulse": "models/rules.py",
    "pulse": "models/rules.py",
    "c_int": "models/rules.py",
    "f32": "models/rules.py",
    "BIT_VALUES": "models/io.py",
    "GROUP_MAX": "models/io.py",
    "M_REGISTER_MAX": "models/io.py",
    "m_register_index": "models/io.py",
    "StatusMode": "protocol/constants.py",
    "reply_result": "protocol/constants.py",
}

GONE_NAMES = {
    "MREGISTER_MAX",  # client/io_map.py's copy of M_REGISTER_MAX
    "MODE_PLAY",  # controller.py's ROBOT_STATUS encoding
    "MODE_TEACH",
    "passes_motoros_speed_check",  # client/planning.py's float64 speed test
}


def test_no_second_definition_of_a_shared_rule() -> None:
    assert not (SRC / "motion" / "checks.py").exists()
    for path, tree in _modules():
        rel = path.relative_to(SRC).as_posix()
        defined = _definitions(tree)
        for name, home in SHARED_NAMES.items():
            if name in defined:
                assert rel == home, f"{rel} defines {name}; its home is {home}"
        assert not defined & GONE_NAMES, f"{rel} defines {defined & GONE_NAMES}"


def _client_constants(value: int) -> list[str]:
    found = []
    for path in sorted((SRC / "client").glob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.Compare):
                for part in (node.left, *node.comparators):
                    if isinstance(part, ast.Constant) and part.value == value:
                        found.append(f"{path.name}:{node.lineno}")
    return found


@pytest.mark.parametrize("value", [30, 2, 5000, 5999, 6000])
def test_client_compares_with_no_rule_literal(value: int) -> None:
    # 30: the start tolerance; 2: ROBOT_STATUS's PLAY; 5000..5999: the NOT_READY family
    assert _client_constants(value) == []


# --------------------------------------------------------------------------- agreement

CELLS = [
    ("yrc1000", "hc10"),  # x87, 6 axes
    ("fs100", "mh5"),  # FS100 strict single, 6 axes
    ("fs100", "sia20d"),  # FS100, 7 axes: ROS S,L,E,U,R,B,T → slots S,L,U,R,B,T,E
    ("yrc1000", "sia20d"),  # x87, 7 axes
]
POSE = (0.31, -0.52, 0.73, -1.14, 0.45, 0.96, -0.27)
"""A start pose away from zero, so that pulse truncation and rounding matter."""

MAX_TICKS = 5000


def _complete(vc: VirtualController, result: Outcome | Pending) -> Outcome:
    for _ in range(MAX_TICKS):
        if isinstance(result, Outcome):
            return result
        if result.done:
            return result.outcome
        vc.tick()
    raise AssertionError("request still pending")


@cache
def _controller(controller: str, robot: str, use: str) -> VirtualController:
    """A controller in trajectory mode, at rest at :data:`POSE` (one per test ``use``)."""
    base = default_cell(controller, robot)
    pose = POSE[: base.groups[0].num_axes]
    vc = VirtualController(dataclasses.replace(base, initial=InitialState(joints=(pose,))))
    outcome = _complete(vc, vc.motion_ctrl(0, MotionCommand.START_TRAJ_MODE))
    assert outcome.ok, outcome
    for _ in range(50):  # a few state cycles: feedback settled on the command
        vc.tick()
    return vc


def _pad(values: tuple[float, ...]) -> tuple[float, ...]:
    return values + (0.0,) * (10 - len(values))


def _send(
    vc: VirtualController,
    sequence: int,
    time_s: float,
    pos: tuple[float, ...],
    vel: tuple[float, ...] = (),
) -> Outcome:
    """The controller's answer to point ``sequence`` of group 0 (all three fields valid)."""
    return _complete(
        vc, vc.trajectory_point(sequence, PointData(0, 7, time_s, _pad(pos), _pad(vel), _pad(())))
    )


def _agree(
    predicted: client_preflight.PreflightRefusal | None,
    outcome: Outcome,
    subcode: int | None,
    axis: int | None,
) -> None:
    """The client's prediction and the controller's answer both say ``subcode`` on
    ``axis``, or both accept the point (``subcode`` None)."""
    if subcode is None:
        assert predicted is None
        assert outcome.ok, outcome.detail
        return
    assert predicted is not None
    assert (predicted.refusal.subcode, predicted.refusal.axis) == (subcode, axis)
    assert (outcome.result, outcome.subcode) == (ResultCode.INVALID, subcode)


@st.composite
def _velocity(draw: st.DrawFn, limit: float) -> float:
    """Around the limit, including the truncation band [limit, floor(limit) + 1)."""
    kind = draw(st.sampled_from(["zero", "below", "band", "edge", "above"]))
    sign = draw(st.sampled_from([1.0, -1.0]))
    band_top = math.floor(limit) + 1.0
    if kind == "zero":
        return 0.0
    if kind == "below":
        return sign * draw(st.floats(0.0, limit))
    if kind == "band":
        return sign * draw(st.floats(limit, band_top, exclude_max=True))
    if kind == "edge":
        return sign * draw(st.sampled_from([band_top, math.nextafter(band_top, 0.0), limit]))
    return sign * draw(st.floats(band_top, band_top + 2.0))


Case = tuple[str, str, tuple[float, ...], tuple[float, ...]]
"""(controller, robot, joint positions, joint speeds) of a drawn point."""


@st.composite
def _case(draw: st.DrawFn, use: str) -> Case:
    controller, robot = draw(st.sampled_from(CELLS))
    vc = _controller(controller, robot, use)
    axes = rules.group_rules(vc.cell.groups[0], vc.cell.controller)
    n = axes.num_axes
    current = vc.snapshot().groups[0].command_rad
    commanded = rules.feedback_pulses(current, axes)
    pos = []
    vel = []
    for i in range(n):
        slot = axes.ros_to_slot[i]
        factor = axes.pulses_per_unit[slot]
        offset = draw(st.integers(-60, 60))
        if draw(st.booleans()):  # mostly within the tolerance, so that 3013 can show
            offset //= 3
        frac = draw(st.floats(0.0, 1.0, exclude_max=True))
        pos.append((commanded[slot] + offset + frac) / factor)
        moving = draw(st.integers(0, 3)) == 0
        vel.append(draw(_velocity(axes.max_speed[i])) if moving else 0.0)
    return controller, robot, tuple(pos), tuple(vel)


@settings(
    max_examples=300,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(case=_case("start"))
def test_preflight_is_wired_to_the_controllers_start_rules(case: Case) -> None:
    controller, robot, pos, vel = case
    vc = _controller(controller, robot, "start")
    feedback = vc.snapshot().groups[0].feedback_rad  # what JOINT_FEEDBACK tells a client
    predicted = client_preflight.first_refusal(
        TrajectoryPoint(0.0, pos, vel), 0, [vc.cell.groups[0]], vc.cell.controller, feedback
    )
    outcome = _send(vc, 0, 0.0, pos, vel)
    event(f"{controller}/{robot}: {outcome.subcode or 'accepted'}")
    if predicted is None:
        assert outcome.ok, outcome.detail
        return
    refusal = predicted.refusal
    assert refusal.subcode in (InvalidSubcode.DATA_START_POS, InvalidSubcode.DATA_SPEED)
    assert outcome.result == ResultCode.INVALID
    assert outcome.subcode == refusal.subcode
    assert outcome.detail == f"point 0 of group 0: {refusal.message}"
    where = "controller slot" if refusal.subcode == InvalidSubcode.DATA_START_POS else "ROS index"
    assert re.search(rf"\({where} {refusal.axis}\)", outcome.detail)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(case=_case("after"))
def test_preflight_is_wired_to_the_controllers_speed_rule_after_the_start(case: Case) -> None:
    controller, robot, _, vel = case
    vc = _controller(controller, robot, "after")
    group = vc.cell.groups[0]
    here = vc.snapshot().groups[0].command_rad
    assert _send(vc, 0, 0.0, here).ok
    point = TrajectoryPoint(0.5, here, vel)
    predicted = client_preflight.first_refusal(point, 1, [group], vc.cell.controller)
    outcome = _send(vc, 1, 0.5, here, vel)
    event(f"{controller}/{robot}: {outcome.subcode or 'accepted'}")
    try:
        if predicted is None:
            assert outcome.ok, outcome.detail
            assert client_preflight.speed_deviations(point, [group], vc.cell.controller) == []
        else:
            assert outcome.subcode == predicted.refusal.subcode == InvalidSubcode.DATA_SPEED
            assert outcome.detail == f"point 1 of group 0: {predicted.refusal.message}"
            devs = client_preflight.speed_deviations(point, [group], vc.cell.controller)
            assert devs[0].axis == predicted.refusal.axis
    finally:
        # Clear the pending point and queue, so the next example starts at rest here.
        assert _complete(vc, vc.motion_ctrl(0, MotionCommand.STOP_MOTION)).ok


MULTI_POSES = ((0.2, -0.3, 0.4, -0.5, 0.6, -0.7, 0.8), (-0.2, 0.3, -0.4, 0.5, -0.6, 0.7, -0.8))
"""Start poses of the SDA10F's two arms (its base and station axes start at 0)."""


@cache
def _dual_arm() -> VirtualController:
    """An SDA10F (arms R1, R2, base B1, station S1) on its FS100, in trajectory mode."""
    base = default_cell("fs100", "sda10f")
    joints = tuple(
        MULTI_POSES[g] if g < len(MULTI_POSES) else (0.1,) * group.num_axes
        for g, group in enumerate(base.groups)
    )
    vc = VirtualController(dataclasses.replace(base, initial=InitialState(joints=joints)))
    assert _complete(vc, vc.motion_ctrl(0, MotionCommand.START_TRAJ_MODE)).ok
    for _ in range(50):
        vc.tick()
    return vc


@st.composite
def _multi_case(
    draw: st.DrawFn,
) -> tuple[tuple[int, ...], list[tuple[float, ...]], list[tuple[float, ...]]]:
    vc = _dual_arm()
    groups = vc.cell.groups
    order = tuple(draw(st.permutations(range(len(groups))))[: draw(st.integers(2, len(groups)))])
    positions, velocities = [], []
    for g in order:
        rules_g = rules.group_rules(groups[g], vc.cell.controller)
        commanded = rules.feedback_pulses(vc.snapshot().groups[g].command_rad, rules_g)
        pos, vel = [], []
        for i in range(rules_g.num_axes):
            slot = rules_g.ros_to_slot[i]
            offset = draw(st.integers(-40, 40)) if draw(st.integers(0, 5)) == 0 else 0
            frac = draw(st.floats(0.0, 1.0, exclude_max=True))
            pos.append((commanded[slot] + offset + frac) / rules_g.pulses_per_unit[slot])
            moving = draw(st.integers(0, 5)) == 0
            vel.append(draw(_velocity(rules_g.max_speed[i])) if moving else 0.0)
        positions.append(tuple(pos))
        velocities.append(tuple(vel))
    return order, positions, velocities


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(case=_multi_case())
def test_preflight_is_wired_to_the_controllers_multi_group_start_rules(
    case: tuple[tuple[int, ...], list[tuple[float, ...]], list[tuple[float, ...]]],
) -> None:
    order, positions, velocities = case
    vc = _dual_arm()
    models = [vc.cell.groups[g] for g in order]
    feedback = tuple(v for g in order for v in vc.snapshot().groups[g].feedback_rad)
    point = TrajectoryPoint(
        0.0,
        tuple(v for p in positions for v in p),
        tuple(v for p in velocities for v in p),
    )
    predicted = client_preflight.first_refusal(point, 0, models, vc.cell.controller, feedback)
    data = [
        PointData(g, 7, 0.0, _pad(p), _pad(v), _pad(()))
        for g, p, v in zip(order, positions, velocities, strict=True)
    ]
    outcome = _complete(vc, vc.trajectory_point_ex(0, data))
    event(f"FULL_EX: {outcome.subcode or 'accepted'}")
    if predicted is None:
        assert outcome.ok, outcome.detail
        return
    g = order[predicted.group]
    assert outcome.subcode == predicted.refusal.subcode
    assert outcome.detail == f"point 0 of group {g}: {predicted.refusal.message}"


# --------------------------------------------------------------------------- by hand
#
# HC10 on a YRC1000, at rest at the zero pose (commanded position 0 pulses). Pulses per
# radian: S, L 81646.4858; U 71619.7244; R 52998.596; B 52139.159; T 37242.257. The
# speed limit maxSpeed (reference §5.5) is 100 % of the axis maximum: S, L 2.2689 rad/s
# (130°/s), U, R 3.1416, B, T 4.3633. Reference §3.4 step 5.3, per index in turn:
# |trunc(pos × ppr) − 0| > 30 → 3011; trunc(|vel|) > maxSpeed → 3013.

S_30_PULSES = 0.000373  # 0.000373 × 81646.4858 = 30.45 → 30: within the tolerance
S_31_PULSES = 0.000381  # 31.11 → 31: one pulse over

BY_HAND_START = [
    # (positions, velocities, expected subcode or None, axis (slot / ROS index))
    ((S_30_PULSES, 0, 0, 0, 0, 0), (0,) * 6, None, None),
    ((S_31_PULSES, 0, 0, 0, 0, 0), (0,) * 6, InvalidSubcode.DATA_START_POS, 0),
    ((-S_31_PULSES, 0, 0, 0, 0, 0), (0,) * 6, InvalidSubcode.DATA_START_POS, 0),
    ((0, S_31_PULSES, 0, 0, 0, 0), (0,) * 6, InvalidSubcode.DATA_START_POS, 1),
    # U: 0.000433 × 71619.7244 = 31.01 → 31; 0.000419 → 30.01 → 30
    ((0, 0, 0.000433, 0, 0, 0), (0,) * 6, InvalidSubcode.DATA_START_POS, 2),
    ((0, 0, 0.000419, 0, 0, 0), (0,) * 6, None, None),
    # the speed quirk: trunc(2.99) = 2 ≤ 2.2689 passes, trunc(3.0) = 3 does not
    ((0,) * 6, (2.99, 0, 0, 0, 0, 0), None, None),
    ((0,) * 6, (3.0, 0, 0, 0, 0, 0), InvalidSubcode.DATA_SPEED, 0),
    ((0,) * 6, (-3.0, 0, 0, 0, 0, 0), InvalidSubcode.DATA_SPEED, 0),
    ((0,) * 6, (0, 0, 0, 0, 4.99, 0), None, None),  # B: trunc 4 ≤ 4.3633
    ((0,) * 6, (0, 0, 0, 0, 5.0, 0), InvalidSubcode.DATA_SPEED, 4),
    # interleaved per index: index 0's speed before index 1's position, and back
    ((0, S_31_PULSES, 0, 0, 0, 0), (3.0, 0, 0, 0, 0, 0), InvalidSubcode.DATA_SPEED, 0),
    ((S_31_PULSES, 0, 0, 0, 0, 0), (0, 3.0, 0, 0, 0, 0), InvalidSubcode.DATA_START_POS, 0),
]


@pytest.mark.parametrize(("pos", "vel", "subcode", "axis"), BY_HAND_START)
def test_start_rules_by_hand(
    pos: tuple[float, ...], vel: tuple[float, ...], subcode: int | None, axis: int | None
) -> None:
    vc = VirtualController()
    assert vc.snapshot().groups[0].command_pulse == (0,) * 6
    assert _complete(vc, vc.motion_ctrl(0, MotionCommand.START_TRAJ_MODE)).ok
    group = vc.cell.groups[0]
    pos_f = tuple(float(x) for x in pos)
    vel_f = tuple(float(x) for x in vel)
    predicted = client_preflight.first_refusal(
        TrajectoryPoint(0.0, pos_f, vel_f), 0, [group], vc.cell.controller, (0.0,) * 6
    )
    outcome = _send(vc, 0, 0.0, pos_f, vel_f)
    _agree(predicted, outcome, subcode, axis)


# After the start (sequence > 0) only the speed check runs, for i < numAxes.
BY_HAND_AFTER = [
    ((2.99, 0, 0, 0, 0, 0), None, None),
    ((3.0, 0, 0, 0, 0, 0), InvalidSubcode.DATA_SPEED, 0),
    ((0, 0, 3.99, 0, 0, 0), None, None),  # U: trunc 3 ≤ 3.1416
    ((0, 0, 4.0, 0, 0, 0), InvalidSubcode.DATA_SPEED, 2),
    ((0, 0, 0, 0, 0, -5.5), InvalidSubcode.DATA_SPEED, 5),
]


@pytest.mark.parametrize(("vel", "subcode", "axis"), BY_HAND_AFTER)
def test_speed_rule_after_the_start_by_hand(
    vel: tuple[float, ...], subcode: int | None, axis: int | None
) -> None:
    vc = VirtualController()
    assert _complete(vc, vc.motion_ctrl(0, MotionCommand.START_TRAJ_MODE)).ok
    zero = (0.0,) * 6
    assert _send(vc, 0, 0.0, zero).ok
    vel_f = tuple(float(x) for x in vel)
    point = TrajectoryPoint(0.5, zero, vel_f)
    predicted = client_preflight.first_refusal(point, 1, [vc.cell.groups[0]], vc.cell.controller)
    outcome = _send(vc, 1, 0.5, zero, vel_f)
    _agree(predicted, outcome, subcode, axis)


def test_multi_group_start_by_hand() -> None:
    """Two HC10s (2016, sequence 0): groups are checked in message order and the first
    failing one answers; the speed quirk and the 30-pulse tolerance as above."""
    from pymotoros.controller import cell_from_dict

    vc = VirtualController(cell_from_dict({"groups": [{"robot": "hc10"}, {"robot": "hc10"}]}))
    assert _complete(vc, vc.motion_ctrl(0, MotionCommand.START_TRAJ_MODE)).ok
    zero = (0.0,) * 6
    over = (S_31_PULSES, 0.0, 0.0, 0.0, 0.0, 0.0)
    fast = (0.0, 0.0, 0.0, 0.0, 5.0, 0.0)  # B: trunc 5 > 4.3633
    cases = [
        # (group order, positions, velocities, expected subcode, the group that answers)
        ((0, 1), (zero, zero), (zero, zero), None, 1),
        ((0, 1), (zero, over), (zero, zero), InvalidSubcode.DATA_START_POS, 1),
        ((1, 0), (over, zero), (zero, fast), InvalidSubcode.DATA_START_POS, 1),
        ((1, 0), (zero, zero), (zero, fast), InvalidSubcode.DATA_SPEED, 0),
    ]
    for order, positions, velocities, subcode, group_no in cases:
        data = [
            PointData(g, 7, 0.0, _pad(p), _pad(v), _pad(()))
            for g, p, v in zip(order, positions, velocities, strict=True)
        ]
        outcome = _complete(vc, vc.trajectory_point_ex(0, data))
        assert (outcome.subcode or None, outcome.group_no) == (subcode, group_no), outcome
