"""MotoROS's start-up checks: alarms at boot and the library's set-up validation (§2.1, §4.4, §8).

:func:`setup_validation` is pure: from a cell's controller, robots and
:class:`StartupConfig` it gives the 8003 subcode the closed parameter library raises (or
None). :class:`MotoRosStartup` is the init task's path through them, ticking with the
controller: wait until no alarm is on (checked every 2.5 s), run the validation, raise
its alarm and wait until it is reset; after a fatal one the init task sleeps forever
(INIT_DONE never on, no servers); otherwise MotoROS boots and its servers start.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Final

from pymotoros.controller.values import StartupConfig
from pymotoros.models import ControllerModel, ControllerType

logger = logging.getLogger(__name__)

SETUP_ALARM: Final = 8003
"""The alarm every set-up validation failure raises (§8)."""
ALARM_POLL_MS: Final = 2500
"""Ros_Controller_Init checks every 2.5 s that no alarm is on before it goes on (§2.1)."""

PASSING_PARAMETERS: Final[Mapping[str, int]] = {
    "RS000": 2,
    "S2C541": 0,
    "S2C542": 0,
    "S2C1100": 1,
    "S2C1103": 2,
    "S2C1117": 1,
    "S2C1119": 0,
}
"""The set-up parameters the validation reads, at values that pass (alarm texts of §8)."""

MIN_HC_SOFTWARE: Final[Mapping[ControllerType, tuple[str, tuple[int, int]]]] = {
    ControllerType.YRC1000: ("YAS", (2, 80)),
    ControllerType.YRC1000MICRO: ("YBS", (2, 30)),
}
"""Oldest system software that supports an HC robot with MotoROS (§4.4)."""

DEFAULT_SOFTWARE: Final[Mapping[ControllerType, str]] = {
    ControllerType.YRC1000: "YAS2.80.00-00",
    ControllerType.YRC1000MICRO: "YBS2.30.00-00",
}
"""The software version of a cell file that names none: the oldest that passes."""

CONFIG_INVALID_TEXT: Final = "Controller config invalid"
HC_INCOMPATIBLE_CODE: Final = 9
HC_INCOMPATIBLE_TEXT: Final = "MotoROS not compatible with HC"
"""Subcode 9 is in the library's table, but no check of 1.9.12 that the reference names
raises it (HC on YRC1000/micro is supported; HC elsewhere is not a sold combination):
reachable only through ``validation_code = 9``."""

_SOFTWARE = re.compile(r"^([A-Z]+)(\d+)\.(\d+)")


@dataclass(frozen=True, slots=True)
class SetupFinding:
    """What the set-up validation found: the 8003 subcode, its text, fatal or warning."""

    subcode: int
    text: str
    fatal: bool
    why: str


_PARAMETER_CHECKS: Final = (
    ("RS000", (2,), 1, False, "Config Err: Set RS000=2"),
    ("S2C541", (0,), 2, False, "Config Err: Set S2C541=0"),
    ("S2C542", (0,), 3, False, "Config Err: Set S2C542=0"),
    ("S2C1100", (1,), 4, True, "Config Err: Set S2C1100=1"),
    ("S2C1103", (2,), 5, True, "Config Err: Set S2C1103=2"),
    ("S2C1117", (1,), 6, True, "Config Err: Set S2C1117=1"),
    ("S2C1119", (0, 2), 7, False, "Config Err: Set S2C1119=0 or 2"),
)
"""(parameter, passing values, subcode, fatal, alarm text), in validation-code order (§8)."""


def setup_validation(
    controller: ControllerModel, hc_robot: bool, cfg: StartupConfig
) -> SetupFinding | None:
    """The library's one-time set-up validation: the first failing check, or None."""
    params = {**PASSING_PARAMETERS, **cfg.parameters}
    for name, good, subcode, fatal, text in _PARAMETER_CHECKS:
        if name == "S2C1117" and controller.type is ControllerType.YRC1000:
            continue  # §8: no check for it was found in the YRC1000 object
        if params[name] not in good:
            return SetupFinding(subcode, text, fatal, f"{name} = {params[name]}")
    minimum = MIN_HC_SOFTWARE.get(controller.type) if hc_robot else None
    if minimum is not None:
        software = cfg.software or DEFAULT_SOFTWARE[controller.type]
        prefix, (major, minor) = minimum
        m = _SOFTWARE.match(software)
        old = (
            m is None or m.group(1) != prefix or (int(m.group(2)), int(m.group(3))) < (major, minor)
        )
        if old:
            return SetupFinding(
                8,
                "PFL invalid controller version",
                True,
                f"software {software}: an HC robot needs {prefix}{major}.{minor:02d} or later",
            )
        if cfg.conveyor_tracking:
            return SetupFinding(
                11,
                "HC/Convey trking not compatible",
                True,
                "conveyor tracking is set up on a controller with an HC robot",
            )
    if cfg.validation_code is not None:
        code = cfg.validation_code
        text = HC_INCOMPATIBLE_TEXT if code == HC_INCOMPATIBLE_CODE else CONFIG_INVALID_TEXT
        return SetupFinding(
            code, text, True, f"validation code {code} (controller.validation_code)"
        )
    return None


def check_parameters(parameters: Mapping[str, object]) -> list[str]:
    """Problems with a ``[controller.parameters]`` table (unknown names, non-integers)."""
    problems = []
    for name, value in parameters.items():
        if name not in PASSING_PARAMETERS:
            problems.append(
                f"{name}: unknown set-up parameter (known: {', '.join(PASSING_PARAMETERS)})"
            )
        elif not isinstance(value, int) or isinstance(value, bool):
            problems.append(f"{name}: must be an integer, not {value!r}")
    return problems


class MotoRosStartup:
    """The MotoROS init task's start-up path, one controller tick at a time."""

    def __init__(
        self,
        finding: SetupFinding | None,
        *,
        alarms_on: Callable[[], bool],
        raise_alarm: Callable[[int, int, str], None],
        boot: Callable[[], None],
    ) -> None:
        self._finding = finding
        self._alarms_on = alarms_on
        self._raise_alarm = raise_alarm
        self._boot = boot
        self.phase = "waiting for alarms to clear"
        self._next_check_ms = 0
        self.tick(0)

    @property
    def started(self) -> bool:
        """MotoROS booted: INIT_DONE is on and its servers may listen."""
        return self.phase == "running"

    @property
    def halted(self) -> bool:
        return self.phase.startswith("halted")

    @property
    def settled(self) -> bool:
        """Nothing more will happen (running or halted for good)."""
        return self.started or self.halted

    def tick(self, now_ms: int) -> None:
        phase = self.phase
        if phase == "waiting for alarms to clear":
            if now_ms < self._next_check_ms:
                return
            if self._alarms_on():
                self._next_check_ms = now_ms + ALARM_POLL_MS
                return
            finding = self._finding
            if finding is None:
                self._start()
                return
            kind = "fatal" if finding.fatal else "warning"
            logger.error(
                "MotoROS set-up validation: alarm %d/%d %s (%s; %s)",
                SETUP_ALARM,
                finding.subcode,
                finding.text,
                finding.why,
                kind,
            )
            self._raise_alarm(SETUP_ALARM, finding.subcode, finding.text)
            self.phase = f"waiting for RESET of alarm {SETUP_ALARM}/{finding.subcode}"
        elif phase.startswith("waiting for RESET"):
            if self._alarms_on():
                return
            finding = self._finding
            if finding is not None and finding.fatal:
                self.phase = (
                    f"halted: alarm {SETUP_ALARM}/{finding.subcode} {finding.text} "
                    f"({finding.why}) is fatal; MotoROS never starts its servers"
                )
                logger.error("MotoROS %s", self.phase)
            else:
                self._start()

    def _start(self) -> None:
        self.phase = "running"
        self._boot()
