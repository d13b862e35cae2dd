"""The servo model: commanded pulses, and a feedback that follows them.

Commanded position = initial position + the sum of every increment sent (the
controller's command register, which MotoROS reads for the start-position check).
Feedback is what the encoders report: the mean of the commanded position over the
last ``2·lag + 1`` ticks, i.e. the command delayed by ``lag`` ticks on average and
smoothed, so it differs from the command while moving and settles ``2·lag`` ticks
after the last increment. Optional noise of ±``noise_pulses`` is added while the
drives are powered; it is a pure function of (seed, group, tick, axis), so the
values do not depend on how often anybody reads them.

Everything is computed only when asked (state server every ~25 ms, the start check
of a trajectory): a tick only appends the increment to two lists.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from operator import add
from typing import Final

from pymotoros.protocol.constants import MAX_PULSE_AXES

SLOTS: Final = MAX_PULSE_AXES
ZERO_INCREMENT: Final = (0,) * SLOTS
IN_MOTION_PULSES: Final = 30
"""|feedback − command| above which ROBOT_STATUS reports in_motion (§2.6)."""

FOLD_EVERY: Final = 64
"""Increments kept unsummed at most (bounds memory when nobody reads the command).
Small on purpose: each fold's ``zip`` makes one iterator per kept increment, and the
kept tuples count as young objects, so 1,024 (before issue 13's second round) started
a garbage collection inside the folding tick about every 1,000 streaming ticks with no
state client reading (bench/bench_tick_spikes.py: 12 collections in 10,000 ticks,
2 with 64); summing 64 rows is a few µs."""

_MASK64: Final = (1 << 64) - 1

ServoState = tuple[tuple[int, ...], tuple[Sequence[int], ...], tuple[Sequence[int], ...], int]
"""What :meth:`ServoGroup.state` captures: command, unfolded increments, feedback window,
quiet ticks (immutable: later ticks do not change it)."""

# Salts of the deterministic noise and brake sag. Their values carry no meaning beyond
# keeping the hashed streams apart: changing one changes every simulated encoder
# jitter and sag, so recorded runs and tests that pin them would no longer match.
SEED_STRIDE: Final = 1_000_003
"""Seed × this + group index: a prime larger than any group count, so two (seed, group)
pairs never give the same stream."""
SAG_SALT: Final = 0x5A6
"""Multiplies the power-loss count: brake-sag offsets never share a stream with noise."""
TICK_SALT: Final = 0x100000001B3
"""Multiplies the tick count (the 64-bit FNV prime): neighbouring ticks hash far apart."""


def _mix(x: int) -> int:
    """splitmix64 finaliser: a cheap, well-spread deterministic hash."""
    x = (x + 0x9E3779B97F4A7C15) & _MASK64
    x = ((x ^ (x >> 30)) * 0xBF58476D1CE4E5B9) & _MASK64
    x = ((x ^ (x >> 27)) * 0x94D049BB133111EB) & _MASK64
    return x ^ (x >> 31)


class ServoGroup:
    """One control group's command register and encoder feedback, controller order, 8 slots."""

    __slots__ = (
        "_command",
        "_history",
        "_noise_pulses",
        "_quiet",
        "_seed",
        "_unfolded",
        "_weights",
        "_window",
        "period_ms",
        "recorder",
    )

    def __init__(
        self,
        initial: Sequence[int],
        *,
        period_ms: int,
        lag_ticks: int,
        noise_pulses: int = 0,
        seed: int = 0,
        group_index: int = 0,
        record_ticks: int = 0,
    ) -> None:
        """``record_ticks``: keep that many ticks of increments in :attr:`recorder` (a
        PFL cell's servos, for a clamping's retreat); 0: none."""
        if lag_ticks < 0:
            raise ValueError(f"lag_ticks must be ≥ 0, not {lag_ticks}")
        if noise_pulses < 0:
            raise ValueError(f"noise_pulses must be ≥ 0, not {noise_pulses}")
        self._command: list[int] = [int(p) for p in initial] + [0] * (SLOTS - len(initial))
        self._unfolded: list[Sequence[int]] = []
        self._quiet = 0
        self.period_ms = period_ms
        self._window = 2 * lag_ticks + 1
        self._history: deque[Sequence[int]] = deque(
            [ZERO_INCREMENT] * self._window, maxlen=self._window
        )
        w = self._window
        # feedback = command − Σ_m weight[m]·inc[t−m], weight[m] = (w−1−m)/w
        self._weights = tuple((w - 1 - m) / w for m in range(w))
        self._noise_pulses = noise_pulses
        self._seed = _mix(seed * SEED_STRIDE + group_index)
        self.recorder: deque[Sequence[int]] | None = (
            deque(maxlen=record_ticks) if record_ticks > 0 else None
        )
        """With ``record_ticks``: every tick's increment is appended, zeros included (the
        PFL function reads it for a clamping's retreat)."""

    @property
    def lag_ticks(self) -> int:
        return (self._window - 1) // 2

    @property
    def command(self) -> list[int]:
        """Commanded pulses (controller order): the initial position plus every increment."""
        unfolded = self._unfolded
        if unfolded:
            totals = map(sum, zip(*unfolded, strict=True))
            self._command = list(map(add, self._command, totals))
            unfolded.clear()
        return self._command

    def apply_limited(self, increment: Sequence[int], limit: Sequence[int]) -> tuple[int, ...]:
        """One tick under an FSU speed limit: each axis moves at most ``limit`` pulses.

        Returns what was executed; the rest is dropped, as the FSU does.
        """
        executed = tuple(
            max(-lim, min(lim, inc)) for inc, lim in zip(increment, limit, strict=True)
        )
        self.apply(executed)
        return executed

    def apply(self, increment: Sequence[int]) -> None:
        """One tick with these pulse increments (8 slots)."""
        self._history.append(increment)
        recorder = self.recorder
        if recorder is not None:
            recorder.append(increment)
        unfolded = self._unfolded
        unfolded.append(increment)
        self._quiet = 0
        if len(unfolded) > FOLD_EVERY:
            self.command  # noqa: B018 - folds the increments into the command

    def idle(self) -> None:
        """One tick without increments."""
        recorder = self.recorder
        if recorder is not None:
            recorder.append(ZERO_INCREMENT)
        if self._quiet < self._window:
            self._history.append(ZERO_INCREMENT)
            self._quiet += 1

    def reset_to(self, pulses: Sequence[int]) -> None:
        """Put the axis at ``pulses``, command and feedback alike (no motion)."""
        self._unfolded.clear()
        self._command = [int(p) for p in pulses] + [0] * (SLOTS - len(pulses))
        for _ in range(self._window):
            self._history.append(ZERO_INCREMENT)
        self._quiet = self._window

    def shift(self, offsets: Sequence[int]) -> None:
        """Move command and feedback together by ``offsets`` (brakes catching the axes)."""
        self.reset_to([c + o for c, o in zip(self.command, offsets, strict=True)])

    def sag_offsets(self, amplitude: int, event: int, valid: Sequence[bool]) -> list[int]:
        """Deterministic offsets within ±amplitude for the ``event``-th power loss."""
        span = 2 * amplitude + 1
        base = _mix(self._seed ^ (SAG_SALT * (event + 1)))
        return [(_mix(base + k) % span - amplitude) if valid[k] else 0 for k in range(SLOTS)]

    def settled(self) -> bool:
        """No increment in the whole feedback window: feedback equals the command."""
        return self._quiet >= self._window or all(not any(inc) for inc in self._history)

    def at_rest(self, powered: bool) -> bool:
        """Feedback equals the command and the speed is zero: settled, and no noise is
        added (none configured, or the drives off). Then :meth:`feedback` is the command
        and :meth:`speed` all zeros, whatever the tick."""
        return (not powered or not self._noise_pulses) and self.settled()

    def feedback(self, tick: int, powered: bool) -> list[int]:
        """Encoder pulses now (controller order)."""
        hist = self._history
        weights = self._weights
        out: list[int] = []
        command = self.command
        n = len(hist)
        for k in range(SLOTS):
            lag = 0.0
            for m in range(1, n):
                inc = hist[n - m][k]
                if inc:
                    lag += weights[m - 1] * inc
            out.append(command[k] - int(lag))
        if powered and self._noise_pulses:
            span = 2 * self._noise_pulses + 1
            base = _mix(self._seed ^ (tick * TICK_SALT))
            for k in range(SLOTS):
                out[k] += _mix(base + k) % span - self._noise_pulses
        return out

    def state(self) -> ServoState:
        """Everything :meth:`feedback`, :meth:`speed`, :meth:`settled` and
        :meth:`last_increment` read, as it is now: a few short tuples (well under a
        microsecond), so a tick can keep it and a reader compute from it later, exactly as
        it would have then (the S1CxG register outputs, computed only when read)."""
        return (tuple(self._command), tuple(self._unfolded), tuple(self._history), self._quiet)

    def as_of(self, state: ServoState) -> ServoGroup:
        """A copy of this servo (same lag, noise and seed) put back in ``state``: its
        methods give what this servo's gave when ``state`` was taken."""
        command, unfolded, history, quiet = state
        past = ServoGroup.__new__(ServoGroup)
        past._command = list(command)
        past._unfolded = list(unfolded)
        past._history = deque(history, maxlen=self._window)
        past._quiet = quiet
        past._window = self._window
        past._weights = self._weights
        past._noise_pulses = self._noise_pulses
        past._seed = self._seed
        past.period_ms = self.period_ms
        past.recorder = None
        return past

    @property
    def last_increment(self) -> Sequence[int]:
        """The increments of the latest tick (zeros when idle): the command speed."""
        return self._history[-1] if self._history else ZERO_INCREMENT

    def speed(self) -> list[int]:
        """Feedback speed in whole pulses/s (controller order), truncated as MotoROS does."""
        hist = self._history
        w = self._window
        per_s = 1000.0 / self.period_ms
        out = []
        for k in range(SLOTS):
            total = 0
            for inc in hist:
                total += inc[k]
            out.append(int(total / w * per_s))
        return out
