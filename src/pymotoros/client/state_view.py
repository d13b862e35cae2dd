"""The state part of :class:`~pymotoros.client.RobotClient`: the latest state, waiting for
it, and checking that the controller is the robot model the client plans with.

The state port streams ROBOT_STATUS and each group's joint feedback; a
:class:`~pymotoros.client.state.StateTracker` keeps the latest of each. What the
controller streams (groups, axes) and its DH parameters are compared with the robot
model, since a plan made for another robot is a crash waiting to happen.
"""

from __future__ import annotations

from collections.abc import AsyncIterator, Awaitable, Callable, Sequence
from dataclasses import dataclass
from typing import Final

from pymotoros.client.errors import GroupError, ModelMismatchError
from pymotoros.client.link import Link
from pymotoros.client.state import (
    DEFAULT_STATE_TIMEOUT_S,
    JointState,
    Listener,
    RobotState,
    StateTracker,
)
from pymotoros.models import ROBOTS, RobotModel
from pymotoros.protocol.constants import Port
from pymotoros.protocol.messages import DhLink

DH_TOLERANCE: Final = 1e-4
"""DH parameters travel as float32 (reference §1.5): ~1e-7 relative; 0.1 mm / 0.1 mrad is
far below any real difference between two robot models."""

_DH_FIELDS: Final = ("theta", "d", "a", "alpha")
_DH_UNIT: Final = {"theta": "rad", "d": "m", "a": "m", "alpha": "rad"}
"""The unit of each DH parameter: angles in rad, lengths in m (``GroupModel.dh``)."""


@dataclass(eq=False, repr=False)
class StateView:
    """The state stream as the client's users see it, checked against the robot model."""

    _link: Link
    _tracker: StateTracker
    _robot: RobotModel
    _dh_parameters: Callable[[], Awaitable[tuple[tuple[DhLink, ...], ...]]]

    @property
    def state(self) -> RobotState:
        """The latest state snapshot (empty until the first state message)."""
        return self._tracker.state

    def feedback(self, group: int = 0) -> JointState | None:
        """The latest joint feedback of ``group`` (None before the first)."""
        return self._tracker.state.joints.get(group)

    def add_listener(self, listener: Listener) -> Callable[[], None]:
        """Call ``listener(state)`` on every state message; returns the function that removes it."""
        return self._tracker.add_listener(listener)

    def states(
        self, message_timeout_s: float = DEFAULT_STATE_TIMEOUT_S
    ) -> AsyncIterator[RobotState]:
        """``async for state in robot.states():`` every state message, latest wins."""
        return self._tracker.states(message_timeout_s)

    async def wait_for_state(self, timeout_s: float = DEFAULT_STATE_TIMEOUT_S) -> RobotState:
        """Wait for a full state cycle: ROBOT_STATUS and every group's feedback.

        The groups the controller streams are checked against the robot model: other
        groups, or more axes than the model has, raise :class:`ModelMismatchError`.
        """
        self._link.need(Port.STATE)
        tracker = self._tracker
        await tracker.wait_for(
            lambda s: tracker.groups_seen is not None,
            timeout_s,
            what="a full state cycle (feedback of every group, then ROBOT_STATUS)",
        )
        self.check_groups()
        groups = range(len(self._robot.groups))
        return await tracker.wait_for(
            lambda s: s.status is not None and all(g in s.joints for g in groups),
            timeout_s,
            what="the first status and feedback from the state port",
        )

    async def wait_until(
        self, predicate: Callable[[RobotState], bool], timeout_s: float, what: str = "the condition"
    ) -> RobotState:
        """Wait until ``predicate(state)`` holds (checked on every state message)."""
        return await self._tracker.wait_for(predicate, timeout_s, what=what)

    def check_groups(self) -> None:
        """Compare the groups seen on the state stream with the robot model (no-op before)."""
        seen = self._tracker.groups_seen
        if seen is None:
            return
        model = self._robot
        expected = {i: g.num_axes for i, g in enumerate(model.groups)}
        problems = [
            f"group {i} ({model.groups[i].name}, {n} axes) sends no feedback"
            for i, n in expected.items()
            if i not in seen
        ]
        problems += [
            f"group {i} streams at least {seen[i]} axes, the model has {n}"
            for i, n in expected.items()
            if i in seen and seen[i] > n
        ]
        extra = sorted(set(seen) - set(expected))
        if extra:
            problems.append(f"the controller also streams group(s) {', '.join(map(str, extra))}")
        if problems:
            described = ", ".join(f"{g.name} {g.num_axes} axes" for g in model.groups)
            streamed = ", ".join(f"group {i}" for i in sorted(seen)) or "no group"
            raise ModelMismatchError(
                f"model mismatch: {model.name} expects {len(expected)} group(s) ({described}) "
                f"but the controller streams {len(seen)} ({streamed}): "
                + "; ".join(problems)
                + ". Give the controller's robot with --robot, or its cell file with --config"
            )

    async def check_dh_parameters(self) -> None:
        """Compare the controller's DH parameters (MOTO_GET_DH_PARAMETERS) with the model's.

        Two models with the same groups and axes (HC10 and GP12) look the same on the
        state stream; their DH parameters differ. Raises :class:`ModelMismatchError`
        naming the first difference, and the known robot whose parameters match. Opt-in:
        on a MotoROS whose library fails the request the connection is closed (§5.9).
        """
        streamed = await self._dh_parameters()
        for index, group in enumerate(self._robot.groups):
            if not group.dh or index >= len(streamed):
                continue
            links = streamed[index]
            for n, (model, seen) in enumerate(zip(group.dh, links, strict=False)):
                for field in _DH_FIELDS:
                    want, got = getattr(model, field), getattr(seen, field)
                    if abs(want - got) > DH_TOLERANCE:
                        raise ModelMismatchError(
                            f"model mismatch: the controller's DH parameters are not "
                            f"{self._robot.name}'s (group {index} {group.name}, link {n + 1}: "
                            f"{field} {got:.4f} {_DH_UNIT[field]} on the controller, "
                            f"{want:.4f} {_DH_UNIT[field]} in the model); " + _dh_hint(links)
                        )

    def group_index(self, group: int | str) -> int:
        """The number of a group given by number (0, 1 …) or name (R1, r2, B1 …)."""
        groups = self._robot.groups
        if isinstance(group, str):
            text = group.strip()
            if text.isdigit():
                group = int(text)
            else:
                for i, g in enumerate(groups):
                    if g.name.lower() == text.lower():
                        return i
                raise GroupError(f"no group {text!r}: {self._describe_groups()}")
        if not 0 <= group < len(groups):
            raise GroupError(f"no group {group}: {self._describe_groups()}")
        return group

    def _describe_groups(self) -> str:
        listed = ", ".join(
            f"{g.name} (group {i}, {g.num_axes} axes)" for i, g in enumerate(self._robot.groups)
        )
        return (
            f"{self._robot.name} has {listed}; a multi-arm cell is described with "
            "--config CELL.toml (RobotClient(cell=...))"
        )


def _dh_hint(links: Sequence[DhLink]) -> str:
    """What to give instead: the known robot whose first group has these DH parameters."""
    matches = [
        name
        for name, robot in ROBOTS.items()
        if robot.groups and robot.groups[0].dh and _dh_matches(robot.groups[0].dh, links)
    ]
    if matches:
        return f"they match {', '.join(matches)}: give --robot {matches[0]}"
    return "give the controller's robot with --robot or --config"


def _dh_matches(model: Sequence[object], seen: Sequence[object]) -> bool:
    return all(
        abs(getattr(m, f) - getattr(s, f)) <= DH_TOLERANCE
        for m, s in zip(model, seen, strict=False)
        for f in _DH_FIELDS
    )
