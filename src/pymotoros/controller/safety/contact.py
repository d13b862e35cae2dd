"""Contact with the workspace: the twin's robot touching an obstacle of the cell.

The real robot meets a table with its body, and the controller notices through its
motor currents: an HC robot's PFL function stops it (a contact; a clamping when a link
is pinned between two things, and the robot backs off), any other arm's collision
detection raises alarm 4315 COLLISION DETECT and cuts servo power. The twin has no
currents, so it checks the commanded position against the cell's obstacles
(:class:`~pymotoros.kinematics.collision.CollisionWorld`) after each tick's increments
and answers the way the controller would, through the existing paths: the PFL function
(:mod:`pymotoros.controller.safety.pfl`) or the operator machine (alarm, servo off).
So the robot never passes into an obstacle by more than one tick's travel.

Cost: nothing at all for a cell without obstacles (no function is built). Otherwise the
check is not run every tick: after a check that found ``clearance`` metres between the
robot and the nearest obstacle, no point of the robot can touch anything before it has
moved that far, and each tick's travel is bounded by Σ |Δq| × lever (per joint, the
farthest point it moves at the last check, grown by that clearance, and never more than
its reach in any pose, :meth:`CollisionWorld.joint_reach`): a few multiplications per
tick, a full check only when that bound has used up the clearance.
"""

from __future__ import annotations

import logging
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from operator import add, mul
from typing import Final

import numpy as np
import numpy.typing as npt

from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.ports import OperatorPort
from pymotoros.controller.safety.pfl import DEFAULT_RETREAT_MS, PflFunction
from pymotoros.controller.servo import SLOTS, ServoGroup
from pymotoros.kinematics.collision import CollisionWorld, Contact
from pymotoros.models.cell_tools import CellTool
from pymotoros.models.workspace import Workspace
from pymotoros.motion import GroupAxes

logger = logging.getLogger(__name__)

COLLISION_ALARM: Final = 4315
"""The alarm a collision raises: 4315 COLLISION DETECT, as we remember the DX200 /
YRC1000 alarm lists. A modelling choice: no source the project holds gives the number
(MotoROS raises no such alarm, reference §8); see docs/fidelity.md §3."""
COLLISION_ALARM_TEXT: Final = "COLLISION DETECT"
DEEPER_M: Final = 1e-6
"""A link already touching an obstacle counts as a new contact only when it goes at
least this much deeper: moving out of a contact after the stop is allowed."""

ContactKey = tuple[str, str, str]


@dataclass(slots=True)
class _Watched:
    """One group the contact function follows."""

    group: int
    servo: ServoGroup
    slots: tuple[int, ...]
    """The controller slot of each joint (ROS order)."""
    ppu: tuple[float, ...]
    """Pulses per radian of each joint."""
    reach: tuple[float, ...]
    """Per joint, the farthest any point it moves can be from it (any pose)."""
    weights: tuple[float, ...] = (0.0,) * SLOTS
    """Per controller slot: metres of travel per pulse, at most, until the next check."""
    moved: list[int] = field(default_factory=lambda: [0] * SLOTS)
    """Per controller slot: pulses travelled (summed absolute increments) since the check."""
    clearances: npt.NDArray[np.float64] | None = None
    """Each moving part's clearance at the last check (m)."""
    levers: npt.NDArray[np.float64] | None = None
    """Each moving part's metres per radian of each joint (ROS order) since the last check."""


class ContactFunction:
    """Checks the commanded position against the workspace; reacts to a new contact."""

    def __init__(
        self,
        world: CollisionWorld,
        servos: Sequence[ServoGroup],
        axes: Sequence[GroupAxes],
        *,
        tool: Callable[[int], CellTool],
        react: Callable[[Sequence[Contact], int], None],
    ) -> None:
        self.world = world
        self._servos = tuple(servos)
        self._axes = tuple(axes)
        self._tool = tool
        self._react = react
        self._watch: list[_Watched] = []
        self._refresh_weights()
        self._clearance = -1.0
        self._touching: dict[ContactKey, float] = {}
        self.contacts: tuple[Contact, ...] = ()
        """The contacts found by the latest check (empty: the robot touches nothing)."""
        self.checks = 0
        """Full checks so far (the benchmark counts them)."""
        self.check(0, react=False)  # what the robot already touches at rest is no contact

    def _refresh_weights(self) -> None:
        """Per group: its servo, the slot and pulses per radian of each joint, and the
        joint's global reach (the bound that holds in any pose)."""
        watch = []
        for g, (servo, axes) in enumerate(zip(self._servos, self._axes, strict=True)):
            reach = self.world.joint_reach(g)
            if not reach:
                continue
            slots = tuple(axes.ros_to_slot[k] for k in range(axes.num_axes))
            ppu = tuple(float(axes.pulses_per_unit[s]) for s in slots)
            watch.append(_Watched(g, servo, slots, ppu, tuple(reach)))
        self._watch = watch

    def workspace_changed(self) -> None:
        """The obstacles changed (added, moved, removed). Checked at once without a
        reaction: an obstacle put against a robot at rest is a contact only when the
        robot moves into it (PFL and collision detection feel a moving arm)."""
        self._refresh_weights()
        self.check(0, react=False)

    def tick(self, now_ms: int) -> None:
        """After this tick's increments reached the servos."""
        travel = 0.0
        for w in self._watch:
            w.moved = moved = list(map(add, w.moved, map(abs, w.servo.last_increment)))
            travel += sum(map(mul, moved, w.weights))
        if travel < self._clearance or self._parts_clear():
            return
        self.check(now_ms)

    def _parts_clear(self) -> bool:
        """The finer test, part by part (:meth:`CollisionWorld.part_budgets`): no part
        has moved as far as its own clearance."""
        for w in self._watch:
            if w.levers is None or w.clearances is None:
                return False
            joints = np.array(w.moved, dtype=float)[list(w.slots)] / np.array(w.ppu)
            if np.any(w.levers @ joints >= w.clearances):
                return False
        return True

    def check(self, now_ms: int, *, react: bool = True) -> None:
        """A full check at the commanded position; reacts to a new or deeper contact."""
        self.checks += 1
        world = self.world
        qs: list[list[float]] = [[] for _ in self._servos]
        for w in self._watch:
            world.set_tool(w.group, self._tool(w.group))  # cached: the same tool is no work
            command = w.servo.command
            qs[w.group] = [command[s] / p for s, p in zip(w.slots, w.ppu, strict=True)]
        clearance, contacts = world.probe(qs)
        self._clearance = clearance
        margin = max(clearance, 0.0)
        budgets = {g: (clear, levers) for g, clear, levers in world.part_budgets()}
        for w in self._watch:
            w.moved = [0] * SLOTS
            if w.group not in budgets:
                w.clearances = w.levers = None
                continue
            clear, levers = budgets[w.group]
            # the lever arms now, grown by the most the arm can move before the next check
            w.clearances = clear
            w.levers = np.where(levers > 0.0, levers + np.maximum(clear, 0.0)[:, None], 0.0)
            widest = levers.max(axis=0)
            weights = [0.0] * SLOTS
            for k, slot in enumerate(w.slots):
                weights[slot] = min(w.reach[k], float(widest[k]) + margin) / w.ppu[k]
            w.weights = tuple(weights)
        touching = self._touching
        new = [
            c
            for c in contacts
            if c.distance_m < touching.get((c.group, c.link, c.obstacle), 1.0) - DEEPER_M
        ]
        self._touching = {(c.group, c.link, c.obstacle): c.distance_m for c in contacts}
        self.contacts = tuple(contacts)
        if new and react:
            for c in new:
                logger.warning(
                    "workspace contact: %s %s touches %s (%.1f mm deep)",
                    c.group,
                    c.link,
                    c.obstacle,
                    -c.distance_m * 1000.0,
                )
            self._react(contacts, now_ms)


def is_clamping(contacts: Sequence[Contact]) -> bool:
    """A link pinned between two obstacles (touching two or more at once)."""
    per_link = Counter((c.group, c.link) for c in contacts if not c.self_collision)
    return any(n >= 2 for n in per_link.values())


class ContactResponse:
    """What the controller does about a contact: PFL on an HC robot, else alarm 4315."""

    def __init__(
        self, pfl: PflFunction, *, group_names: Sequence[str], operator: OperatorPort
    ) -> None:
        self._pfl = pfl
        self._groups = tuple(group_names)
        self._operator = operator

    def __call__(self, contacts: Sequence[Contact], now_ms: int) -> None:
        pfl = self._pfl
        if pfl.enabled:
            if pfl.busy:  # already stopping or backing off
                return
            clamping = is_clamping(contacts)
            pfl.event(
                "clamping" if clamping else "contact",
                now_ms,
                moving=True,
                retreat_ms=DEFAULT_RETREAT_MS if clamping else 0,
            )
            return
        operator = self._operator
        if any(a.code == COLLISION_ALARM for a in operator.state.alarms):
            return
        first = contacts[0]
        subcode = self._groups.index(first.group) + 1 if first.group in self._groups else 0
        # the alarm stops the job (IncMove is refused from the next tick on), then the
        # collision detection function cuts servo power
        operator.raise_alarm(COLLISION_ALARM, subcode, COLLISION_ALARM_TEXT)
        operator.servo_off()


def workspace_contact(
    ctx: MotoRosContext,
    pfl: PflFunction,
    operator: OperatorPort,
    workspace: Workspace | None = None,
) -> ContactFunction | None:
    """The contact function of a cell with ``workspace`` (default: the cell file's), or
    None when there is nothing to touch (no obstacles, or no group with collision
    shapes): then the tick does nothing extra."""
    cell = ctx.cell
    workspace = workspace if workspace is not None else cell.workspace
    if not workspace.obstacles:
        return None
    world = CollisionWorld(cell.groups, workspace)
    if not any(world.joint_reach(g) for g in range(ctx.num_groups)):
        return None
    interps = ctx.interpolators

    frames: dict[tuple[int, int], CellTool] = {}

    def tool(g: int) -> CellTool:
        """The selected tool's file (TCP and shape), mounted by the collision model."""
        key = (g, interps[g].tool)
        if key not in frames:
            frames[key] = cell.tool(g, key[1]).cell_tool
        return frames[key]

    response = ContactResponse(pfl, group_names=[g.name for g in cell.groups], operator=operator)
    return ContactFunction(world, ctx.servos, ctx.axes, tool=tool, react=response)


__all__ = [
    "COLLISION_ALARM",
    "COLLISION_ALARM_TEXT",
    "ContactFunction",
    "ContactResponse",
    "is_clamping",
    "workspace_contact",
]
