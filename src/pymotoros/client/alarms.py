"""Texts for alarm numbers the client can see (ROBOT_STATUS carries only the number).

The wire gives an alarm's number, never its text or subcode (reference §2.6). The
alarms MotoROS itself raises (§8) are known here; for any other number the pendant, or
the simulator's control API (``GET /api/state``), has the text.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

MOTOROS_ALARMS: Final[Mapping[int, str]] = {
    8000: "MotoROS assertion (the controller stopped MotoROS; see the pendant)",
    8001: "MotoROS: speed feedback just enabled, reboot the controller",
    8003: "MotoROS set-up validation failed (the subcode on the pendant says which check)",
    8004: "MOTOROS FAILED TO CREATE TASK",
}
"""The alarms MotoROS 1.9.12 and its parameter library raise (reference §8)."""


CONTROLLER_ALARMS: Final[Mapping[int, str]] = {
    4315: "COLLISION DETECT",
}
"""Controller alarms (not MotoROS's) a client names in its errors: 4315, the collision
detection (shock sensor) that stopped a robot which touched something (Yaskawa's alarm
list; the twin raises it for a contact with a cell obstacle, docs/workspace.md)."""


def alarm_text(code: int) -> str:
    """What an alarm number means, as far as the client can know it ("" if unknown)."""
    return MOTOROS_ALARMS.get(code) or CONTROLLER_ALARMS.get(code, "")
