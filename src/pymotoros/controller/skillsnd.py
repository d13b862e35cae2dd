"""The DX100 SKILLSND listener tasks (reference §4.3): "ROS-START" / "ROS-STOP" per slave."""

from __future__ import annotations

import logging
from typing import Final

from pymotoros.controller.cell import CellConfig
from pymotoros.controller.readiness import Readiness

logger = logging.getLogger(__name__)

SKILL_START: Final = "ROS-START"
SKILL_STOP: Final = "ROS-STOP"


class SkillListeners:
    """Set and clear the skill flags that gate motion-ready on a DX100."""

    def __init__(self, cell: CellConfig, readiness: Readiness, num_groups: int) -> None:
        self._dx100 = cell.controller.skillsnd
        self._readiness = readiness
        self._num_groups = num_groups

    def on_skill(self, slave: int, text: str) -> None:
        """A SKILLSND reached slave ``slave`` (DX100 listener tasks, §4.3)."""
        if not self._dx100 or slave not in (1, 2) or (slave == 2 and self._num_groups < 2):
            logger.debug('SKILLSND SL%d "%s": no MotoROS listener for it', slave, text)
            return
        readiness = self._readiness
        if text == SKILL_START:
            readiness.skill_flags[slave - 1] = True
        elif text == SKILL_STOP:
            readiness.skill_flags[slave - 1] = False
        else:
            logger.info('SKILLSND SL%d "%s" (ignored by MotoROS)', slave, text)
        readiness.refresh_ready()

    def on_job_stopped(self) -> None:
        """The job ended or was stopped: the skill commands end with it."""
        readiness = self._readiness
        if any(readiness.skill_flags):
            readiness.skill_flags = [False, False]
            readiness.refresh_ready()
