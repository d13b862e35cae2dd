"""S1CxG register outputs computed when read give what computing them every tick gives.

The same seeded conversation (streamed motion, M-register reads at random ticks, client
writes, E-stop and servo off mid-motion, tool changes, a scenario that E-stops inside a
tick and one that reads an M-register) runs on a controller computing the words every
tick (the oracle ``tests/oracles/registers.py``) and on one as the library builds it,
computing them only when an M-register is read or written; every read and the final
image must be identical, word for word.
"""

from __future__ import annotations

import random
import tomllib
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import pytest

from oracles.registers import every_tick
from pymotoros.controller import Outcome, Pending, PointData, VirtualController, cell_from_dict
from pymotoros.controller.cell import CellConfig
from pymotoros.controller.registers import RegisterOutputs
from pymotoros.controller.scenario import parse_scenario
from pymotoros.controller.servo import ServoGroup
from pymotoros.models.controllers import M_REGISTER_BASE, M_REGISTER_COUNT
from pymotoros.protocol.constants import ResultCode

from .helpers import CMD, point

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "cells"
REGISTER_CELL = EXAMPLES / "hc10_register_outputs.toml"
SCENARIO_REGISTER = 500
"""A register no table writes: the client's write there fires the scenario's E-stop."""


def _table(rng: random.Random, axes: int) -> dict[str, int]:
    """Every kind of output, command and feedback, 2 and 4 bytes, random registers."""
    mask = (1 << axes) - 1

    def reg() -> int:
        return rng.randrange(1, 480)

    table = {
        "208": 1,
        "209": 1,
        "217": 1,
        "218": 0,
        "330": 1,
        "331": reg(),
        "332": 2,
        "333": reg(),
        "334": 2,
        "335": 1,
        "336": 1,
        "337": 2,
        "202": rng.randrange(mask + 1),
        "203": rng.randrange(mask + 1),
        "204": rng.randrange(mask + 1),
        "205": rng.randrange(mask + 1),
        "207": mask,
    }
    for k in range(7):
        table[str(210 + k)] = reg()
        table[str(219 + k)] = reg()
    for k in range(axes):
        for base in (1090, 1120, 1270, 1280, 1290, 1300):
            table[str(base + k)] = reg()
        table[str(1100 + k)] = rng.randrange(0, 9)
        table[str(1110 + k)] = rng.randrange(-500, 500)
        table[str(1130 + k)] = rng.randrange(0, 5)
    return table


def _example(**controller: int) -> CellConfig:
    data = tomllib.loads(REGISTER_CELL.read_text())
    data["controller"] |= controller
    return cell_from_dict(data, source=str(REGISTER_CELL))


def _sia20d(**controller: int) -> CellConfig:
    return cell_from_dict(
        {
            "controller": {"model": "yrc1000", **controller},
            "groups": [{"robot": "sia20d", "s1cxg": _table(random.Random(20), 7)}],
            "tools": [{"number": 2, "tcp_m": [0.0, 0.05, 0.2], "rpy_rad": [0.1, 0.0, 0.3]}],
            "initial": {"servo": True, "joints": {"R1": [0.1, 0.4, 0.2, -0.6, 0.3, 0.5, 0.2]}},
        }
    )


def _two_groups(**controller: int) -> CellConfig:
    rng = random.Random(21)
    first, second = _table(rng, 7), _table(rng, 6)
    second["336"], second["1290"] = 2, first["1300"]  # both groups write that register
    return cell_from_dict(
        {
            "controller": {"model": "yrc1000", **controller},
            "groups": [
                {"robot": "sia20d", "s1cxg": first},
                {"robot": "hc10", "s1cxg": second},
            ],
            "initial": {
                "servo": True,
                "joints": {
                    "R1": [0.1, 0.4, 0.2, -0.6, 0.3, 0.5, 0.2],
                    "R2": [0.0, 0.5, 1.9, 0.0, 0.9, 0.0],
                },
            },
        }
    )


SAG_NOISE = {"brake_sag_pulses": 40, "feedback_noise_pulses": 3}
CELLS: Mapping[str, Callable[[], CellConfig]] = {
    "example": _example,
    "example with brake sag": lambda: _example(brake_sag_pulses=40),
    "example with sag and noise": lambda: _example(**SAG_NOISE),
    "example, lag 0": lambda: _example(feedback_lag_ticks=0),
    "sia20d 7 axes": _sia20d,
    "sia20d with sag and noise": lambda: _sia20d(**SAG_NOISE),
    "sia20d and hc10, two tables": _two_groups,
    "two tables with sag": lambda: _two_groups(brake_sag_pulses=25),
}


def _registers(cell: CellConfig) -> list[int]:
    """Every register a table writes, and a few others."""
    out = {0, 1, SCENARIO_REGISTER, M_REGISTER_COUNT - 1}
    for table in cell.s1cxg:
        if table is not None:
            for o in table.outputs:
                out.update((o.register, o.register + 1) if o.four_bytes else (o.register,))
    return sorted(r for r in out if r < M_REGISTER_COUNT)


class _Conversation:
    """One seeded script of operator and client actions; ``log`` records every answer."""

    def __init__(self, cell: CellConfig, *, lazy: bool, seed: int) -> None:
        self.vc = VirtualController(cell, seed=seed)
        if not lazy:
            every_tick(self.vc)
        self.rng = random.Random(seed)
        self.registers = _registers(cell)
        self.log: list[tuple[Any, ...]] = []
        self.sequence = 0

    # ------------------------------------------------------------------ primitives

    def tick(self, count: int = 1) -> None:
        """Ticks; after each, now and then, a client reads a few M-registers."""
        for _ in range(count):
            self.vc.tick()
            if self.rng.random() < 0.15:
                self.read()

    def read(self) -> None:
        picks = self.rng.sample(self.registers, k=min(6, len(self.registers)))
        values = [self.vc.read_mregister(n).value for n in picks]
        self.log.append(("read", self.vc.tick_count, picks, values))

    def write(self) -> None:
        number = self.rng.choice([r for r in self.registers if 0 < r < 560])
        value = self.rng.randrange(0x10000)
        self.log.append(
            ("write", self.vc.tick_count, number, self.vc.write_mregister(number, value))
        )
        if self.rng.random() < 0.5:
            self.read()  # the write is visible until the next tick

    def outcome(self, result: Outcome | Pending) -> Outcome:
        for _ in range(3000):
            if isinstance(result, Outcome):
                return result
            if result.done:
                return result.outcome
            self.tick()
        raise AssertionError(f"{result.description}: not done in 3000 ticks")

    # ------------------------------------------------------------------ actions

    def move(self) -> None:
        """Streams a short trajectory of every group from where it stands."""
        vc = self.vc
        for _ in range(3000):
            if not vc.has_queued_motion():
                break
            self.tick()
        o = self.outcome(vc.motion_ctrl(0, CMD.START_TRAJ_MODE))
        self.log.append(("start", vc.tick_count, o.result, o.subcode))
        if not o.ok:
            return
        groups = range(vc.num_groups)
        here = [list(vc.snapshot().groups[g].command_rad) for g in groups]
        steps = [[point(g, 0.0, here[g]) for g in groups]]
        t = 0.0
        for _ in range(3):
            t += self.rng.uniform(0.15, 0.5)
            here = [[q + self.rng.uniform(-0.15, 0.15) for q in h] for h in here]
            steps.append([point(g, t, here[g]) for g in groups])
        for seq, pts in enumerate(steps):
            self.send(seq, pts)

    def send(self, seq: int, pts: list[PointData]) -> None:
        vc = self.vc
        for _ in range(2000):
            if len(pts) == 1:
                o = self.outcome(vc.trajectory_point(seq, pts[0]))
            else:
                o = self.outcome(vc.trajectory_point_ex(seq, pts))
            if o.result != ResultCode.BUSY:
                self.log.append(("point", vc.tick_count, seq, o.result, o.subcode))
                return
            self.tick()
        raise AssertionError(f"point {seq} still BUSY")

    def recover(self) -> None:
        vc = self.vc
        vc.press_estop(False)
        vc.reset()
        vc.set_servo(True)
        for _ in range(1000):
            if vc.snapshot().servo:
                break
            self.tick()
        self.log.append(("servo", vc.tick_count, vc.snapshot().servo))

    def step(self, action: str) -> None:
        vc = self.vc
        if action == "move":
            self.move()
            self.tick(self.rng.randrange(20, 200))
        elif action == "write":
            self.write()
        elif action == "tool":
            group = self.rng.randrange(vc.num_groups)
            tool = self.rng.choice([0, 1, 2])
            self.log.append(("tool", vc.tick_count, group, vc.select_tool(group, tool)))
        elif action == "stop":
            self.move()
            self.tick(self.rng.randrange(5, 60))
            if self.rng.random() < 0.5:
                vc.press_estop(True)
            else:
                vc.set_servo(False)
            self.log.append(("stop", vc.tick_count))
            if self.rng.random() < 0.5:
                self.read()  # before the next tick: the words of the last tick
            self.tick(self.rng.randrange(1, 30))
            self.recover()
        elif action == "scenario":
            self.scenario()
        else:
            self.tick(self.rng.randrange(1, 100))

    def scenario(self) -> None:
        """An E-stop fired inside a tick (after the outputs' step), at a time or when the
        client writes a value into an M-register."""
        vc = self.vc
        if self.rng.random() < 0.5:
            at = (vc.time_ms + 4 * self.rng.randrange(40, 120)) / 1000
            trigger: dict[str, object] = {"at": at}
        else:
            trigger = {"when_io": {"address": M_REGISTER_BASE + SCENARIO_REGISTER, "value": 7}}
        vc.write_mregister(SCENARIO_REGISTER, 0)
        vc.load_scenario(
            parse_scenario({"events": [trigger | {"action": "estop", "pressed": True}]})
        )
        self.move()
        self.tick(self.rng.randrange(10, 40))
        if "when_io" in trigger:
            vc.write_mregister(SCENARIO_REGISTER, 7)
        for _ in range(200):
            self.vc.tick()
            if vc.fired_events and vc.fired_events[-1].action == "estop":
                break
        self.log.append(("fired", vc.tick_count, len(vc.fired_events)))
        if self.rng.random() < 0.7:
            self.read()
        self.recover()


ACTIONS = ("move", "move", "write", "write", "tool", "stop", "scenario", "idle")
"""Each conversation runs every action (in a seeded order), moves and writes twice."""


def _run(cell: CellConfig, *, lazy: bool, seed: int) -> _Conversation:
    conv = _Conversation(cell, lazy=lazy, seed=seed)
    conv.tick(5)
    actions = list(ACTIONS)
    conv.rng.shuffle(actions)
    for action in actions:
        conv.step(action)
    return conv


def _image(vc: VirtualController) -> list[int]:
    return [vc.read_mregister(n).value for n in range(M_REGISTER_COUNT)]


@pytest.mark.parametrize(("seed", "name"), list(enumerate(sorted(CELLS), start=1)))
def test_lazy_outputs_give_every_reader_the_eager_words(seed: int, name: str) -> None:
    cell = CELLS[name]()
    eager = _run(cell, lazy=False, seed=seed)
    lazy = _run(cell, lazy=True, seed=seed)
    reads = [e for e in eager.log if e[0] == "read"]
    assert len(reads) > 20, "the conversation reads too little to compare"
    assert any(v != 0 for e in reads for v in e[3]), "the outputs were never non-zero"
    kinds = {e[0] for e in eager.log}
    assert {"read", "write", "point", "tool", "stop", "fired"} <= kinds
    assert any(e[0] == "point" and e[3] == ResultCode.SUCCESS and e[2] > 0 for e in eager.log)
    for k, (a, b) in enumerate(zip(eager.log, lazy.log, strict=True)):
        assert a == b, (name, seed, k, a, b)
    assert _image(eager.vc) == _image(lazy.vc)
    assert eager.vc.tick_count == lazy.vc.tick_count


def test_a_lazy_tick_computes_nothing_until_a_register_is_read(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    calls: list[int] = []
    values = RegisterOutputs.values

    def counted(self: RegisterOutputs, *args: Any, **kwargs: Any) -> Any:
        calls.append(1)
        return values(self, *args, **kwargs)

    monkeypatch.setattr(RegisterOutputs, "values", counted)
    conv = _Conversation(_example(feedback_noise_pulses=2), lazy=True, seed=3)
    conv.move()
    vc = conv.vc
    assert vc.has_queued_motion()
    calls.clear()
    vc.run_ticks(100)  # moving, nobody reads
    assert calls == []
    first = [vc.read_mregister(n).value for n in (60, 61, 30)]
    assert len(calls) == 1  # one table, computed once, for the latest tick
    assert [vc.read_mregister(n).value for n in (60, 61, 30)] == first
    assert len(calls) == 1  # more reads before the next tick: nothing recomputed
    vc.tick()
    assert vc.write_mregister(60, 1234) == 0
    assert len(calls) == 2  # the write lands on the tick's words ...
    assert vc.read_mregister(60).value == 1234  # ... and is read back until the next tick
    vc.tick()
    assert vc.read_mregister(60).value != 1234
    assert len(calls) == 3


def test_a_read_between_ticks_sees_the_last_tick_not_the_sag_after_it() -> None:
    """E-stop between ticks moves the servos (brake sag); the registers still show the
    last tick's values until the next tick, as a controller writing them every tick. The
    lazy controller reads nothing before the E-stop, so its words come from what the
    tick kept."""
    cell = _example(brake_sag_pulses=200)
    eager = every_tick(VirtualController(cell))
    lazy = VirtualController(cell)
    for vc in (eager, lazy):
        vc.run_ticks(300)
        assert vc.snapshot().servo
    before = _image(eager)
    for vc in (eager, lazy):
        vc.press_estop(True)
    assert _image(eager) == before
    assert _image(lazy) == before
    for vc in (eager, lazy):
        vc.tick()
    assert _image(lazy) == _image(eager) != before  # the sag shows from the next tick on


def test_a_servo_state_reads_later_as_the_servo_read_then() -> None:
    """ServoGroup.state / as_of: what the lazy outputs compute from, with noise, folds,
    idle ticks and a brake shift after the state was taken."""
    rng = random.Random(5)
    servo = ServoGroup([100, -200, 300], period_ms=4, lag_ticks=3, noise_pulses=4, seed=9)
    settled = 0
    for tick in range(400):
        if rng.random() < 0.4:
            servo.apply(tuple(rng.randrange(-50, 50) for _ in range(8)))
        else:
            servo.idle()
        if rng.random() < 0.02:
            servo.shift([rng.randrange(-5, 5) for _ in range(8)])
        if rng.random() < 0.1:
            servo.command  # noqa: B018 - folds, as a state read does
        powered = rng.random() < 0.8
        seen = (
            list(servo.command),
            servo.feedback(tick, powered),
            servo.speed(),
            tuple(servo.last_increment),
            servo.settled(),
        )
        settled += seen[4]
        state = servo.state()
        for _ in range(rng.randrange(0, 3)):  # the servo goes on after the state was taken
            servo.apply(tuple(rng.randrange(-50, 50) for _ in range(8)))
        past = servo.as_of(state)
        assert (
            list(past.command),
            past.feedback(tick, powered),
            past.speed(),
            tuple(past.last_increment),
            past.settled(),
        ) == seen
    assert settled > 3  # at rest too
