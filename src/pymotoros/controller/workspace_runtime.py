"""The cell's obstacles at run time: added, moved and removed by name while the twin runs.

"A person walks into the cell at t = 3 s" is an obstacle that appears: the control
surfaces (HTTP, scenario actions, the pendant) call :meth:`WorkspaceRuntime.put` with
the cell file's keys as a mapping (``{"name": "person", "cylinder": [0.3, 1.8],
"xyz": [0.8, 0.0, 0.9]}``) and :meth:`WorkspaceRuntime.remove` with a name; a bad
obstacle is a :class:`~pymotoros.errors.ConfigError` naming its key. The contact
function of the tick (:mod:`pymotoros.controller.safety.contact`) follows: built when
the first obstacle appears, dropped with the last one (so a cell without obstacles
still costs nothing per tick), told to check again after every change. This part owns
that function (:attr:`WorkspaceRuntime.contact`); the tick cycle, built with this part,
runs it. A contact acts through the ports the part is built with: the PFL function, and
the operator state (:class:`~pymotoros.controller.ports.OperatorPort`: alarm 4315, servo
off).
"""

from __future__ import annotations

from collections.abc import Mapping

from pymotoros.controller.api import ContactInfo, WorkspaceSnapshot
from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.ports import OperatorPort
from pymotoros.controller.safety.contact import ContactFunction, workspace_contact
from pymotoros.controller.safety.pfl import PflFunction
from pymotoros.models.workspace import Obstacle, Workspace, parse_obstacle


class WorkspaceRuntime:
    """The obstacles of one controller now, and the contact check that follows them."""

    def __init__(self, ctx: MotoRosContext, pfl: PflFunction, operator: OperatorPort) -> None:
        self._ctx = ctx
        self._pfl = pfl
        self._operator = operator
        self.workspace: Workspace = ctx.cell.workspace
        self.contact: ContactFunction | None = workspace_contact(ctx, pfl, operator, self.workspace)
        """The contact check the tick runs after the increments (None: nothing to touch,
        nothing to do)."""

    @property
    def obstacles(self) -> tuple[Obstacle, ...]:
        return self.workspace.obstacles

    def put(self, entry: Mapping[str, object]) -> Obstacle:
        """Add an obstacle, or move/reshape the one of the same name (the cell file's keys)."""
        groups = [g.name for g in self._ctx.cell.groups]
        obstacle = parse_obstacle(entry, "obstacle", groups)
        self._set(self.workspace.with_obstacle(obstacle))
        return obstacle

    def remove(self, name: str) -> None:
        """Remove the obstacle ``name`` (ConfigError naming the known ones if there is none)."""
        self._set(self.workspace.without(name))

    def state(self) -> dict[str, object]:
        """``{"obstacles": [...], "contacts": [...]}`` for the state document."""
        contact = self.contact
        contacts = contact.contacts if contact is not None else ()
        return {
            "obstacles": [o.as_dict() for o in self.workspace.obstacles],
            "contacts": [c.as_dict() for c in contacts],
        }

    def snapshot(self) -> WorkspaceSnapshot:
        """The snapshot's part: the obstacles now and the latest check's contacts."""
        contact = self.contact
        contacts = contact.contacts if contact is not None else ()
        return WorkspaceSnapshot(
            self.workspace.obstacles,
            tuple(
                ContactInfo(
                    c.obstacle,
                    c.link,
                    c.group,
                    round(-c.distance_m * 1000.0, 3),
                    c.self_collision,
                )
                for c in contacts
            ),
        )

    def _set(self, workspace: Workspace) -> None:
        self.workspace = workspace
        contact = self.contact
        if contact is None or not workspace.obstacles:
            self.contact = workspace_contact(self._ctx, self._pfl, self._operator, workspace)
            return
        contact.world.set_obstacles(workspace)
        contact.workspace_changed()


__all__ = ["WorkspaceRuntime"]
