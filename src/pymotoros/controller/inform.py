"""INFORM jobs: a parser for the JBI text format and a runner on the controller clock.

Only the instructions MotoROS's INIT_ROS jobs use are supported (reference §7):
``NOP``, ``DOUT OT#(n) ON|OFF``, ``TIMER T=s``, ``WAIT OT#(n)=ON|OFF``,
``SKILLSND [SLn] "text"``, ``PSTART JOB:NAME SUBn``, ``PWAIT SUBn``, ``TSYNC n``,
comments (``'...``) and ``END``. Anything else is refused when the job is loaded,
with a :class:`~pymotoros.errors.JobError` naming the file and the line.

Execution model (a modelling choice, see ``docs/fidelity.md``): instructions that do
not wait run back to back within one tick; ``TIMER`` resumes at the first tick at or
after its end; ``WAIT`` is tested every tick; ``TSYNC n`` releases when every running
task that is not parked at a ``PWAIT`` has reached ``TSYNC n``. The job is over when
every task has ended.
"""

from __future__ import annotations

import enum
import logging
import re
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Final

from pymotoros.controller.io_image import IoImage
from pymotoros.controller.signals import universal_output
from pymotoros.errors import JobError
from pymotoros.models import IoArea
from pymotoros.models.toml_file import read_text_file

logger = logging.getLogger(__name__)

IDLE_WAKE_MS: Final = 1 << 62
"""``JobRunner.wake_ms`` when no timer runs: only an IO change can wake a task."""
MAX_INSTRUCTIONS_PER_TICK: Final = 1000
"""Guard against a job that never blocks (none of the supported instructions loops)."""


class Op(enum.Enum):
    """The INFORM instructions this controller runs; each one's value is its keyword."""

    @staticmethod
    def _generate_next_value_(name: str, start: int, count: int, last_values: list[str]) -> str:
        return name

    NOP = enum.auto()
    DOUT = enum.auto()
    TIMER = enum.auto()
    WAIT = enum.auto()
    SKILLSND = enum.auto()
    PSTART = enum.auto()
    PWAIT = enum.auto()
    TSYNC = enum.auto()
    END = enum.auto()


@dataclass(frozen=True, slots=True)
class Instruction:
    """One executable line of a job."""

    op: Op
    line: int
    """Line number in the file (1-based), for error messages."""
    address: int = 0
    """DOUT/WAIT: the bit address of OT#n."""
    output: int = 0
    """DOUT/WAIT: n of OT#n."""
    value: bool = False
    """DOUT/WAIT: ON (True) or OFF."""
    duration_ms: int = 0
    """TIMER."""
    text: str = ""
    """SKILLSND payload; PSTART job name."""
    number: int = 0
    """SKILLSND slave (0 = the task's own); PSTART/PWAIT sub-task; TSYNC number."""


@dataclass(frozen=True, slots=True)
class Job:
    name: str
    source: str
    """File name (or a description) for error messages."""
    instructions: tuple[Instruction, ...]
    groups: tuple[str, ...] = ()
    """The ``///GROUPn`` attributes, e.g. ("RB1", "RB2")."""


_OT: Final = r"OT#\((?P<n>\d+)\)"
_PATTERNS: Final[tuple[tuple[Op, re.Pattern[str]], ...]] = (
    (Op.NOP, re.compile(r"NOP")),
    (Op.END, re.compile(r"END")),
    (Op.DOUT, re.compile(rf"DOUT {_OT} (?P<v>ON|OFF)")),
    (Op.WAIT, re.compile(rf"WAIT {_OT}=(?P<v>ON|OFF)")),
    (Op.TIMER, re.compile(r"TIMER T=(?P<t>\d+(?:\.\d+)?)")),
    (Op.SKILLSND, re.compile(r'SKILLSND (?:SL(?P<sl>\d+) )?"(?P<text>[^"]*)"')),
    (Op.PSTART, re.compile(r"PSTART JOB:(?P<job>[A-Z0-9_\-]+) SUB(?P<sub>\d+)")),
    (Op.PWAIT, re.compile(r"PWAIT SUB(?P<sub>\d+)")),
    (Op.TSYNC, re.compile(r"TSYNC (?P<n>\d+)")),
)
TIMER_MAX_S: Final = 655.35
"""The pendant accepts TIMER T=0.01..655.35."""


def _parse_instruction(text: str, line: int, source: str) -> Instruction:
    keyword = text.split(" ", 1)[0]
    for op, pattern in _PATTERNS:
        if op.value != keyword:
            continue
        m = pattern.fullmatch(text)
        if m is None:
            raise JobError(f"{source}, line {line}: cannot read {op.value} instruction {text!r}")
        groups = m.groupdict()
        if op in (Op.DOUT, Op.WAIT):
            n = int(groups["n"])
            if n < 1:
                raise JobError(f"{source}, line {line}: OT#({n}) does not exist")
            return Instruction(op, line, universal_output(n), n, groups["v"] == "ON")
        if op is Op.TIMER:
            seconds = float(groups["t"])
            if not 0 < seconds <= TIMER_MAX_S:
                raise JobError(
                    f"{source}, line {line}: TIMER T={groups['t']} outside 0.01..{TIMER_MAX_S}"
                )
            return Instruction(op, line, duration_ms=round(seconds * 1000))
        if op is Op.SKILLSND:
            slave = int(groups["sl"]) if groups["sl"] else 0
            return Instruction(op, line, text=groups["text"], number=slave)
        if op is Op.PSTART:
            return Instruction(op, line, text=groups["job"], number=int(groups["sub"]))
        if op is Op.PWAIT:
            return Instruction(op, line, number=int(groups["sub"]))
        if op is Op.TSYNC:
            return Instruction(op, line, number=int(groups["n"]))
        return Instruction(op, line)
    supported = ", ".join(op.value for op in Op)
    raise JobError(
        f"{source}, line {line}: unsupported instruction {keyword!r} "
        f"(this controller model runs only {supported} and comments)"
    )


def parse_job(text: str, source: str = "<job>") -> Job:
    """Parse the text of one ``.JBI`` file (CRLF or LF line endings)."""
    lines = text.splitlines()
    if not lines or lines[0].strip() != "/JOB":
        raise JobError(f"{source}, line 1: a JBI file starts with /JOB")
    name = ""
    groups: list[str] = []
    instructions: list[Instruction] = []
    in_body = False
    ended = False
    for number, raw in enumerate(lines[1:], start=2):
        line = raw.strip()
        if not line:
            continue
        if ended:
            raise JobError(f"{source}, line {number}: text after END")
        if not in_body:
            if line.startswith("//NAME "):
                name = line.removeprefix("//NAME ").strip()
            elif line == "//INST":
                in_body = True
            continue
        if line.startswith("///"):
            attr = line[3:]
            if attr.startswith("GROUP"):
                groups.extend(g.strip() for g in attr.split(" ", 1)[-1].split(","))
            continue
        if line.startswith("'"):
            continue
        instruction = _parse_instruction(line, number, source)
        instructions.append(instruction)
        ended = instruction.op is Op.END
    if not name:
        raise JobError(f"{source}: no //NAME line")
    if not in_body:
        raise JobError(f"{source}: no //INST section")
    if not ended:
        raise JobError(f"{source}, line {len(lines)}: the job has no END")
    return Job(name, source, tuple(instructions), tuple(groups))


def load_job(path: Path | str) -> Job:
    """Read and parse a ``.JBI`` file."""
    p = Path(path)
    text = read_text_file(
        p, "job file", encoding="ascii", not_text="not an ASCII JBI file", error=JobError
    )
    return parse_job(text, str(p))


def check_job_set(jobs: Mapping[str, Job], main: str) -> None:
    """Every PSTART names a loaded job, and the main job exists."""
    if main not in jobs:
        raise JobError(f"job {main} is not loaded (loaded: {', '.join(sorted(jobs)) or 'none'})")
    for job in jobs.values():
        for ins in job.instructions:
            if ins.op is Op.PSTART and ins.text not in jobs:
                raise JobError(f"{job.source}, line {ins.line}: PSTART of unknown job {ins.text}")


BUILTIN_VARIANTS: Final = ("single_arm", "multi_group", "dx100_single_arm", "dx100_multi_group")
"""The INIT_ROS job sets shipped in ``controller/jobs/`` (one directory each)."""


def builtin_jobs(variant: str) -> dict[str, Job]:
    """Load one of our own INIT_ROS job sets (package data)."""
    if variant not in BUILTIN_VARIANTS:
        raise JobError(f"no built-in job set {variant!r}; known: {', '.join(BUILTIN_VARIANTS)}")
    folder = resources.files("pymotoros.controller").joinpath("jobs", variant)
    jobs: dict[str, Job] = {}
    for entry in sorted(folder.iterdir(), key=lambda e: e.name):
        if entry.name.upper().endswith(".JBI"):
            job = parse_job(entry.read_text(encoding="ascii"), f"jobs/{variant}/{entry.name}")
            jobs[job.name] = job
    return jobs


def load_jobs(paths: Iterable[Path | str]) -> dict[str, Job]:
    """Load job files (a directory contributes every ``*.JBI`` in it)."""
    jobs: dict[str, Job] = {}
    for path in paths:
        p = Path(path)
        files = sorted(p.glob("*.JBI")) + sorted(p.glob("*.jbi")) if p.is_dir() else [p]
        for f in files:
            job = load_job(f)
            jobs[job.name] = job
    return jobs


# ------------------------------------------------------------------------------ runner


class _Block(enum.Enum):
    NONE = 0
    TIMER = 1
    WAIT = 2
    TSYNC = 3
    PWAIT = 4


class _Task:
    __slots__ = ("block", "ended", "job", "number", "pc", "until_ms", "wait_address", "wait_value")

    def __init__(self, number: int, job: Job) -> None:
        self.number = number
        self.job = job
        self.pc = 0
        self.block = _Block.NONE
        self.until_ms = 0
        self.wait_address = 0
        self.wait_value = 0
        self.ended = False


SkillHandler = Callable[[int, str], None]


class JobRunner:
    """Plays back one job set on task 0 (master) and sub-tasks SUB1, SUB2 …"""

    __slots__ = (
        "_io",
        "_jobs",
        "_on_skill",
        "_tasks",
        "generation",
        "main",
        "seen_changes",
        "wake_ms",
    )

    def __init__(
        self,
        jobs: Mapping[str, Job],
        io: IoImage,
        *,
        main: str = "INIT_ROS",
        on_skill: SkillHandler | None = None,
    ) -> None:
        check_job_set(jobs, main)
        for job in jobs.values():
            for ins in job.instructions:
                if ins.op not in (Op.DOUT, Op.WAIT):
                    continue
                rng = io.readable_range(ins.address)
                if rng is None or rng.area is not IoArea.GENERAL_OUTPUT:
                    raise JobError(
                        f"{job.source}, line {ins.line}: OT#({ins.output}) (address "
                        f"{ins.address}) does not exist on this controller"
                    )
        self._jobs = dict(jobs)
        self._io = io
        self._on_skill = on_skill
        self._tasks: list[_Task] = []
        self.main = main
        self.generation = 0
        """Incremented whenever a task moves, starts or stops (a cheap cache key)."""
        self.wake_ms = 0
        """:meth:`step` has nothing to do before this time unless an IO bit changes."""
        self.seen_changes = -1
        """``IoImage.changes`` when the runner last found every task parked."""

    @property
    def running(self) -> bool:
        return bool(self._tasks)

    @property
    def jobs(self) -> Mapping[str, Job]:
        return self._jobs

    def position(self) -> tuple[tuple[str, int], ...]:
        """(job name, line) of every running task: where the cursor of each task is."""
        return tuple(
            (t.job.name, t.job.instructions[t.pc].line) for t in self._tasks if not t.ended
        )

    @property
    def at_wait(self) -> bool:
        """Some task's cursor is on a WAIT: the incremental-move function works only then."""
        return any(t.block is _Block.WAIT for t in self._tasks)

    def start(self) -> None:
        """Start the main job from its first line on the master task."""
        self._tasks = [_Task(0, self._jobs[self.main])]
        self.generation += 1
        self.wake_ms = 0
        logger.debug("job %s started", self.main)

    def stop(self) -> None:
        """Stop every task (E-stop, hold, TEACH …); the skill commands are aborted."""
        if self._tasks:
            logger.debug("job %s stopped at %s", self.main, self.position())
            self._tasks = []
        self.generation += 1
        self.wake_ms = IDLE_WAKE_MS

    def _park(self) -> None:
        """Remember when the tasks can next move: a TIMER's end, or any IO change."""
        wake = IDLE_WAKE_MS
        for task in self._tasks:
            if task.ended:
                continue
            if task.block is _Block.TIMER:
                wake = min(wake, task.until_ms)
            elif task.block is _Block.NONE:
                wake = 0
        self.wake_ms = wake
        self.seen_changes = self._io.changes

    def step(self, now_ms: int) -> bool:
        """Run every task as far as it goes at ``now_ms``; True when the job just ended."""
        tasks = self._tasks
        if not tasks:
            self.wake_ms = IDLE_WAKE_MS
            self.seen_changes = self._io.changes
            return False
        # Fast path, every tick while the job is parked: is any task able to move?
        get = self._io.get
        for task in tasks:
            if task.ended:
                continue
            block = task.block
            if block is _Block.WAIT:
                if get(task.wait_address) != task.wait_value:
                    continue
            elif block is _Block.TIMER and now_ms < task.until_ms:
                continue
            break
        else:
            self._park()
            return False
        self.generation += 1
        # Every task sees the signals as they were at the start of the tick: release all
        # satisfied WAITs before any task runs (two tasks waiting for OT#890 both pass,
        # even if the first one clears it right after).
        for task in tasks:
            if task.block is _Block.WAIT and get(task.wait_address) == task.wait_value:
                task.block = _Block.NONE
                task.pc += 1
        budget = MAX_INSTRUCTIONS_PER_TICK
        progressed = True
        while progressed:
            progressed = False
            for task in tasks:
                if not task.ended:
                    ran = self._run_task(task, now_ms, budget)
                    budget -= ran
                    progressed = progressed or ran > 0
            if budget <= 0:
                raise RuntimeError(
                    f"job {self.main} ran {MAX_INSTRUCTIONS_PER_TICK} lines in one tick"
                )
        if all(t.ended for t in tasks):
            self._tasks = []
            self.wake_ms = IDLE_WAKE_MS
            logger.debug("job %s ended", self.main)
            return True
        self._park()
        return False

    def _run_task(self, task: _Task, now_ms: int, budget: int) -> int:
        ran = 0
        io = self._io
        while ran < budget:
            ins = task.job.instructions[task.pc]
            op = ins.op
            if task.block is not _Block.NONE:
                if not self._released(task, ins, now_ms):
                    return ran
                task.block = _Block.NONE
                task.pc += 1
                ran += 1
                continue
            if op is Op.DOUT:
                io.set(ins.address, ins.value)
            elif op is Op.TIMER:
                task.block = _Block.TIMER
                task.until_ms = now_ms + ins.duration_ms
                continue
            elif op is Op.WAIT:
                task.block = _Block.WAIT
                task.wait_address = ins.address
                task.wait_value = int(ins.value)
                continue
            elif op is Op.TSYNC:
                task.block = _Block.TSYNC
                continue
            elif op is Op.PWAIT:
                task.block = _Block.PWAIT
                continue
            elif op is Op.SKILLSND:
                slave = ins.number or max(task.number, 1)
                if self._on_skill is not None:
                    self._on_skill(slave, ins.text)
            elif op is Op.PSTART:
                self._pstart(ins)
            elif op is Op.END:
                task.ended = True
                return ran + 1
            task.pc += 1
            ran += 1
        return ran

    def _released(self, task: _Task, ins: Instruction, now_ms: int) -> bool:
        block = task.block
        if block is _Block.WAIT:
            return self._io.get(ins.address) == ins.value
        if block is _Block.TIMER:
            return now_ms >= task.until_ms
        if block is _Block.PWAIT:
            return not any(t.number == ins.number and not t.ended for t in self._tasks)
        # TSYNC: every live task not parked at a PWAIT is at TSYNC with this number;
        # then all of them pass it together.
        partners = []
        for other in self._tasks:
            if other is task or other.ended or other.block is _Block.PWAIT:
                continue
            other_ins = other.job.instructions[other.pc]
            if other.block is not _Block.TSYNC or other_ins.number != ins.number:
                return False
            partners.append(other)
        for other in partners:
            other.block = _Block.NONE
            other.pc += 1
        return True

    def _pstart(self, ins: Instruction) -> None:
        if any(t.number == ins.number and not t.ended for t in self._tasks):
            logger.warning("PSTART SUB%d: the sub-task is already running", ins.number)
            return
        task = _Task(ins.number, self._jobs[ins.text])
        for index, old in enumerate(self._tasks):
            if old.number == ins.number:
                self._tasks[index] = task  # an ended run of the same sub-task
                return
        self._tasks.append(task)
