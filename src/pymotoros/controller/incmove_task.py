"""The IncMove and AddToIncQueue tasks, per tick (reference §5.6).

:meth:`IncMoveTask.inc_move_tick` is MotoROS's IncMove task calling the controller's
incremental-move function (mpExRcsIncrementMove) once per interpolation period, with
the v1.9.12 compensation for a controller whose FSU clips the increments, and its
failure paths: the eco-mode retry, and otherwise the inc-move error (and PFL) latch
that refuses motion until the next START_TRAJ_MODE.
:meth:`IncMoveTask.fill_tick` is every group's AddToIncQueue task.
"""

from __future__ import annotations

import enum
import logging

from pymotoros.controller import signals
from pymotoros.controller.context import MotoRosContext
from pymotoros.controller.machine import Event, OperatorState, ServoPower
from pymotoros.controller.polling import POLL_LIMIT_MS, POLL_MS
from pymotoros.controller.readiness import Readiness
from pymotoros.controller.stop_motion import stop_motion_now
from pymotoros.motion import inc_move
from pymotoros.motion.constants import SLOTS

logger = logging.getLogger(__name__)


class IncMoveReturn(enum.Enum):
    """What the controller's incremental-move call returns (names as in MotoPlus)."""

    OK = "ok"
    IMOV_UNREADY = "E_EXRCS_IMOV_UNREADY: the controller cannot take increments now"
    PFL_FUNC_BUSY = "PFL_FUNC_BUSY (-19): a PFL function is active"
    UNDER_ENERGY_SAVING = "UNDER_ENERGY_SAVING (-20): eco mode"


class IncMoveTask:
    """The IncMove task (increments to the servos) and the AddToIncQueue tasks."""

    def __init__(self, ctx: MotoRosContext, readiness: Readiness) -> None:
        self._clock = ctx.clock
        self._io = ctx.io
        self._machine = ctx.machine
        self._runner = ctx.runner
        self._readiness = readiness
        self._flags = readiness.flags  # motion_ready, read every tick / every point
        self._queues = ctx.queues
        self.axes = ctx.axes
        self.interpolators = ctx.interpolators
        self._servos = ctx.servos
        self._num_groups = len(self.axes)
        self.running = True
        """The IncMove and AddToIncQueue tasks exist: False from a motion connection's
        close (fidelity exact) until the next one opens. True before any connection, so
        the controller works without servers (tests, offline use)."""
        self.last_motion_ms = 0
        """Controller time of the last increment the servos took (for the eco idle timer)."""

        self._takes_state: OperatorState | None = None
        self._takes_gen = -1
        self._takes_changes = -1
        self._takes: IncMoveReturn = IncMoveReturn.IMOV_UNREADY
        # The controller's FSU clip (safety unit) and MotoROS's compensation for it (§5.6 step 3)
        self._clip = ctx.increment_clip
        self._tcp_clip = ctx.increment_tcp_clip
        self._fsu_missing = False
        """Pulses sent that the controller has not executed yet (resend before reading queues)."""
        self._to_process: list[list[int]] = [[0] * SLOTS for _ in self.axes]
        self._processed: list[list[int]] = [[0] * SLOTS for _ in self.axes]
        # IncMove retry while the controller leaves eco mode (§5.6 step 6.2)
        self._eco_retry: tuple[tuple[tuple[int, ...], ...], int, int] | None = None

    def end_tasks(self) -> None:
        """The motion connection closed (§2.2): MotoROS deletes the IncMove task and
        every AddToIncQueue task. A segment being generated ends where it stands and
        the pending point is dropped (its flag is cleared); the queued increments stay
        and nothing executes them until :meth:`start_tasks`. The IncMove task's own
        state (the eco-mode retry, the FSU compensation) goes with it."""
        self.running = False
        self._eco_retry = None
        self._fsu_reset()
        for interp in self.interpolators:
            interp.end_task()

    def start_tasks(self) -> bool:
        """A motion connection opened: the tasks exist again (§2.2). True when they
        find increments a closed connection left queued, which run from the next tick:
        the robot resumes the old motion."""
        resumed = not self.running and self._queues.has_queued_motion()
        self.running = True
        return resumed

    def fill_tick(self) -> None:
        """Every AddToIncQueue task's turn."""
        if not self.running:
            return
        ready = self._flags.motion_ready
        for interp in self.interpolators:
            interp.fill(ready)

    def inc_move_tick(self) -> bool:
        """The IncMove task's turn; True if increments reached the servos this tick."""
        if not self.running:  # no motion connection since one closed (exact fidelity)
            return False
        if self._eco_retry is not None:
            return self._retry_eco()
        # motion-ready is false while the stop flag is up (Readiness computes it so)
        if not self._flags.motion_ready:
            if self._fsu_missing:
                self._fsu_reset()
            return False
        clip = self._clip
        limits = clip() if clip is not None else None
        if limits is not None or self._fsu_missing:
            return self._inc_move_fsu(limits)
        incs = inc_move(self.interpolators)
        if incs is None:
            return False
        result = self._controller_takes_increments()
        if result is IncMoveReturn.OK:
            self.last_motion_ms = self._clock.time_ms
            servos = self._servos
            if len(servos) == 1:
                servos[0].apply(incs[0].pulses)
            else:
                for servo, inc in zip(servos, incs, strict=True):
                    servo.apply(inc.pulses)
            return True
        return self._inc_move_failed(result, tuple(i.pulses for i in incs))

    @property
    def unprocessed_pulses(self) -> tuple[tuple[int, ...], ...]:
        """Per group, pulses sent (or due) that the controller has not executed (FSU)."""
        return tuple(
            tuple(a - b for a, b in zip(t, p, strict=True))
            for t, p in zip(self._to_process, self._processed, strict=True)
        )

    @property
    def waiting(self) -> bool:
        """IncMove is retrying while the controller leaves eco mode."""
        return self._eco_retry is not None

    def _fsu_reset(self) -> None:
        self._fsu_missing = False
        for g in range(self._num_groups):
            self._to_process[g] = [0] * SLOTS
            self._processed[g] = [0] * SLOTS

    def _inc_move_fsu(self, clip: tuple[tuple[int, ...], ...] | None) -> bool:
        """IncMove with the v1.9.12 FSU compensation, on a controller whose FSU clips.

        The controller executes at most ``limits`` pulses per axis and tick and drops
        the rest. MotoROS measures what was executed (the change of the commanded
        position), keeps the unexecuted pulses, resends them clamped to what the
        controller took last time (or the axis maximum if it took nothing), and does
        not read its queue while such pulses remain.
        """
        missing = False
        remaining: list[list[int]] = []
        for g in range(self._num_groups):
            rest = [a - b for a, b in zip(self._to_process[g], self._processed[g], strict=True)]
            remaining.append(rest)
            missing = missing or any(rest)
        if missing:
            sends = []
            for g, rest in enumerate(remaining):
                taken = self._processed[g]
                max_inc = self.axes[g].max_increment
                clamp = [abs(t) or m for t, m in zip(taken, max_inc, strict=True)]
                sends.append(tuple(max(-c, min(c, r)) for r, c in zip(rest, clamp, strict=True)))
            to_process = remaining
        else:
            incs = inc_move(self.interpolators)
            if incs is None:
                self._fsu_reset()
                return False
            sends = [i.pulses for i in incs]
            to_process = [list(p) for p in sends]
        result = self._controller_takes_increments()
        if result is not IncMoveReturn.OK:
            self._fsu_reset()
            return self._inc_move_failed(result, tuple(tuple(s) for s in sends))
        self.last_motion_ms = self._clock.time_ms
        missing = False
        tcp_clip = self._tcp_clip
        for g, servo in enumerate(self._servos):
            limit = clip[g] if clip is not None else self.axes[g].max_increment
            if tcp_clip is not None:
                tcp_limit = tcp_clip(g, servo.command, sends[g])
                if tcp_limit is not None:
                    limit = tuple(min(a, b) for a, b in zip(limit, tcp_limit, strict=True))
            executed = servo.apply_limited(sends[g], limit)
            self._processed[g] = list(executed)
            self._to_process[g] = to_process[g]
            missing = missing or executed != tuple(to_process[g])
        self._fsu_missing = missing
        return True

    def _controller_takes_increments(self) -> IncMoveReturn:
        """The controller's answer to mpExRcsIncrementMove (cached while nothing changes)."""
        s = self._machine.state
        gen = self._runner.generation
        changes = self._io.monitored_changes
        if s is self._takes_state and gen == self._takes_gen and changes == self._takes_changes:
            return self._takes
        self._takes_state, self._takes_gen, self._takes_changes = s, gen, changes
        self._takes = self._controller_answer(s)
        return self._takes

    def _controller_answer(self, s: OperatorState) -> IncMoveReturn:
        if s.eco and s.servo_on:
            return IncMoveReturn.UNDER_ENERGY_SAVING
        if self._readiness.pfl_option and (
            self._io.get(signals.PFL_STOP) or self._io.get(signals.PFL_ESCAPE)
        ):
            return IncMoveReturn.PFL_FUNC_BUSY
        if (
            s.servo is not ServoPower.ON
            or not s.job_running
            or s.hold
            or s.estop
            or s.alarms
            or not self._runner.at_wait
        ):
            return IncMoveReturn.IMOV_UNREADY
        return IncMoveReturn.OK

    def _inc_move_failed(self, result: IncMoveReturn, pulses: tuple[tuple[int, ...], ...]) -> bool:
        """§5.6 step 6."""
        readiness = self._readiness
        readiness.status_update()
        s = self._machine.state
        if result is IncMoveReturn.PFL_FUNC_BUSY or (
            result is IncMoveReturn.IMOV_UNREADY
            and self._readiness.pfl_option
            and not (s.estop or s.hold or s.alarms or s.errors)
        ):
            readiness.flags.latch_pfl_event()
        if result is IncMoveReturn.UNDER_ENERGY_SAVING:
            now = self._clock.time_ms
            self._machine.fire(Event.WAKE_FROM_ECO, now)
            self._eco_retry = (pulses, now + POLL_LIMIT_MS, now + POLL_MS)
            return False
        logger.warning(
            "incremental move refused (%s); motion is refused with 5012 INC_MOVE_ERROR "
            "until the next START_TRAJ_MODE",
            result.value,
        )
        readiness.flags.latch_inc_move_error(f"an incremental move was refused: {result.value}")
        stop_motion_now(readiness, self._queues)
        return False

    def _retry_eco(self) -> bool:
        if self._eco_retry is None:
            return False
        pulses, deadline, next_try = self._eco_retry
        now = self._clock.time_ms
        if now < next_try:
            return False
        result = self._controller_takes_increments()
        if result is IncMoveReturn.OK:
            self._eco_retry = None
            self.last_motion_ms = now
            for servo, p in zip(self._servos, pulses, strict=True):
                servo.apply(p)
            return True
        if result is IncMoveReturn.UNDER_ENERGY_SAVING and now < deadline:
            self._eco_retry = (pulses, deadline, next_try + POLL_MS)
            return False
        self._eco_retry = None
        return self._inc_move_failed(
            IncMoveReturn.IMOV_UNREADY if result is IncMoveReturn.UNDER_ENERGY_SAVING else result,
            pulses,
        )
