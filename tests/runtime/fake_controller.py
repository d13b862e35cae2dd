"""A tiny stand-in controller for the servers' edge-case tests (protocol, policies, timing).

It implements the ``MotoRosController`` / ``OperatorPanel`` protocols just enough to
answer on the wire: the MotoROS semantics are tested against ``VirtualController``
elsewhere (and end to end in tests/cli/test_sim.py).
"""

from __future__ import annotations

import asyncio
from collections.abc import Sequence

from pymotoros.controller.api import (
    AlarmInfo,
    ControllerSnapshot,
    FeedbackData,
    GroupSnapshot,
    IoRead,
    OperatorSnapshot,
    Outcome,
    Pending,
    PointData,
    StatusData,
)
from pymotoros.controller.lint import ClientLint, ResumedMotion
from pymotoros.models.fidelity import Fidelity
from pymotoros.protocol.constants import IoResultCode, MotionCommand, PendantMode, ResultCode


class FakeController:
    def __init__(self, num_groups: int = 1, period_ms: int = 4) -> None:
        self._groups = num_groups
        self._period = period_ms
        self.ticks = 0
        self.queued = False
        self.events: list[str] = []
        self._event_added = asyncio.Event()
        self.pending: list[tuple[int, Pending]] = []
        self.bits: dict[int, int] = {}
        self.mregs: dict[int, int] = {}
        self.estop = False
        self.hold = False
        self.mode = PendantMode.PLAY
        self.remote = True
        self.servo = False
        self.alarms: list[AlarmInfo] = []
        self.dh_ok = True
        self.state_clients = 0
        self.lint = ClientLint()

    def _record(self, event: str) -> None:
        self.events.append(event)
        self._event_added.set()

    async def wait_event(self, event: str) -> None:
        """Until ``event`` has been recorded (callers bound it with asyncio.timeout)."""
        while event not in self.events:
            self._event_added.clear()
            await self._event_added.wait()

    # --- MotoRosController
    @property
    def period_ms(self) -> int:
        return self._period

    @property
    def num_groups(self) -> int:
        return self._groups

    @property
    def time_ms(self) -> int:
        return self.ticks * self._period

    def tick(self) -> None:
        self.ticks += 1
        due = [p for t, p in self.pending if t <= self.ticks]
        self.pending = [(t, p) for t, p in self.pending if t > self.ticks]
        for p in due:
            p.complete(Outcome(ResultCode.SUCCESS))

    def motion_ctrl(self, group_no: int, command: int) -> Outcome | Pending:
        self._record(f"ctrl {command}")
        if command == MotionCommand.START_TRAJ_MODE:
            pending = Pending("START_TRAJ_MODE")
            self.pending.append((self.ticks + 10, pending))
            return pending
        if command == MotionCommand.DISCONNECT:
            return Outcome(ResultCode.SUCCESS, close_connection=True)
        if command == MotionCommand.CHECK_QUEUE_CNT:
            return Outcome(ResultCode.SUCCESS, subcode=7)
        if command == MotionCommand.CHECK_MOTION_READY:
            return Outcome(ResultCode.FALSE, subcode=5006, detail="servo power is off")
        if command not in MotionCommand.__members__.values():
            return Outcome(ResultCode.INVALID, subcode=3006, detail=f"unknown command {command}")
        return Outcome(ResultCode.SUCCESS)

    def trajectory_point(self, sequence: int, point: PointData) -> Outcome | Pending:
        self._record(f"point {sequence}")
        return Outcome(ResultCode.SUCCESS)

    def trajectory_point_ex(self, sequence: int, points: Sequence[PointData]) -> Outcome | Pending:
        self._record(f"point_ex {sequence} {len(points)}")
        return Outcome(ResultCode.SUCCESS)

    def select_tool(self, group_no: int, tool: int) -> Outcome:
        if not 0 <= tool <= 63:
            return Outcome(ResultCode.INVALID, 3017, detail=f"tool {tool} outside 0..63")
        return Outcome(ResultCode.SUCCESS)

    def dh_parameters(self) -> tuple[tuple[tuple[float, float, float, float], ...], ...] | None:
        if not self.dh_ok:
            return None
        return (((0.0, 0.275, 0.0, -1.5), (0.0, 0.0, 0.7, 0.0)),)

    def read_io_bit(self, address: int) -> IoRead:
        if address % 10 > 7 or address > 99999:
            return IoRead(0, IoResultCode.READ_ADDRESS_INVALID)
        return IoRead(self.bits.get(address, 0), IoResultCode.OK)

    def write_io_bit(self, address: int, value: int) -> IoResultCode:
        if not 10010 <= address <= 15127:
            return IoResultCode.WRITE_ADDRESS_INVALID
        if value not in (0, 1):
            return IoResultCode.WRITE_VALUE_INVALID
        self.bits[address] = value
        return IoResultCode.OK

    def read_io_group(self, address: int) -> IoRead:
        return IoRead(
            sum(self.bits.get(address * 10 + k, 0) << k for k in range(8)), IoResultCode.OK
        )

    def write_io_group(self, address: int, value: int) -> IoResultCode:
        if value > 0xFF:
            return IoResultCode.WRITE_VALUE_INVALID
        for k in range(8):
            self.bits[address * 10 + k] = (value >> k) & 1
        return IoResultCode.OK

    def read_mregister(self, number: int) -> IoRead:
        return IoRead(self.mregs.get(number % 1_000_000, 0), IoResultCode.OK)

    def write_mregister(self, number: int, value: int) -> IoResultCode:
        if value > 0xFFFF:
            return IoResultCode.WRITE_VALUE_INVALID
        self.mregs[number % 1_000_000] = value
        return IoResultCode.OK

    fidelity = Fidelity.EXACT
    """The servers' setting (docs/fidelity.md); the fake keeps no queues to resume."""

    def motion_connected(self) -> ResumedMotion | None:
        self._record("motion_connected")
        return None

    def motion_disconnected(self) -> None:
        self._record("motion_disconnected")

    def state_clients_changed(self, count: int) -> None:
        self.state_clients = count

    def io_connected(self) -> None:
        self._record("io_connected")

    def has_queued_motion(self) -> bool:
        return self.queued

    def joint_feedback(self, group_no: int) -> FeedbackData:
        pos = (float(self.ticks) * 1e-3,) + (0.0,) * 9
        return FeedbackData(group_no, 6, pos, (0.0,) * 10)

    def robot_status(self) -> StatusData:
        return StatusData(int(self.servo), int(self.estop), 0, 0, int(self.queued), 2, 0)

    def snapshot(self) -> ControllerSnapshot:
        return ControllerSnapshot(
            time_ms=self.ticks * self._period,
            tick_count=self.ticks,
            operator=OperatorSnapshot(
                mode=self.mode,
                remote=self.remote,
                servo=self.servo,
                estop=self.estop,
                hold=self.hold,
                alarms=tuple(self.alarms),
            ),
            motion_ready=False,
            groups=tuple(
                GroupSnapshot(f"R{g + 1}", ("s", "l"), (0.0, 0.0), (0.0, 0.0), (0, 0), 0, 0)
                for g in range(self._groups)
            ),
        )

    # --- OperatorPanel
    def press_estop(self, pressed: bool) -> None:
        self.estop = pressed
        if pressed:
            self.servo = False

    def set_hold(self, on: bool) -> None:
        self.hold = on

    def set_mode(self, mode: PendantMode) -> None:
        self.mode = mode

    def set_remote(self, on: bool) -> None:
        self.remote = on

    def set_servo(self, on: bool) -> None:
        if not self.estop:
            self.servo = on

    def raise_alarm(self, code: int, subcode: int, text: str) -> None:
        self.alarms.append(AlarmInfo(code, subcode, text))

    def reset(self) -> None:
        self.alarms.clear()

    # --- FaultInjection
    def raise_error(self, code: int, subcode: int = 0, text: str = "") -> None:
        self._record(f"error {code}")

    def set_io_api_failure(self, *, reads: bool = False, writes: bool = False) -> None:
        self._record(f"io failure reads={reads} writes={writes}")

    def force_io(self, address: int, value: int) -> None:
        if address >= 1_000_000:
            if not 0 <= value <= 0xFFFF:
                raise ValueError(f"M-register value {value} outside 0..65535")
            self.mregs[address - 1_000_000] = value
            return
        if value not in (0, 1):
            raise ValueError(f"bit value {value} must be 0 or 1")
        if address % 10 > 7:
            raise ValueError(f"address {address}: the last digit must be 0..7")
        self.bits[address] = value


class BrokenAtTick3(FakeController):
    """A controller with a bug: its third tick raises."""

    def tick(self) -> None:
        super().tick()
        if self.ticks == 3:
            raise RuntimeError("controller bug")
