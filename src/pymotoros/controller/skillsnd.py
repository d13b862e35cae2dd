"""The DX100 SKILLSND listener tasks (reference §4.3): "ROS-START" / "ROS-STOP" per slave."""

from __future__ import annotations

import logging
from typing import Final

from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.readiness import Readiness

logger = logging.getLogger(__name__)

SKILL_START: Final = "ROS-START"
SKILL_STOP: Final = "ROS-STOP"


class SkillListeners:
    """Set and clear the skill flags that gate motion-ready on a DX100."""

    def __init__(self, ctx: MotoRosContext, readiness: Readiness) -> None:
        self._dx100 = ctx.cell.controller.skillsnd
        self._readiness = readiness
        self._num_groups = ctx.num_groups

    def on_skill(self, slave: int, text: str) -> None:
        """A SKILLSND reached slave ``slave`` (DX100 listener tasks, §4.3)."""
        if not self._dx100 or slave not in (1, 2) or (slave == 2 and self._num_groups < 2):
            logger.debug('SKILLSND SL%d "%s": no MotoROS listener for it', slave, text)
            return
        if text == SKILL_START:
            self._readiness.flags.set_skill_flag(slave, True)
        elif text == SKILL_STOP:
            self._readiness.flags.set_skill_flag(slave, False)
        else:
            logger.info('SKILLSND SL%d "%s" (ignored by MotoROS)', slave, text)

    def on_job_stopped(self) -> None:
        """The job ended or was stopped: the skill commands end with it."""
        if any(self._readiness.flags.latches.skill_flags):
            self._readiness.flags.clear_skill_flags()
