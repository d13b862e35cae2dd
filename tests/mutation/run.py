"""Deliberate bugs in the MotoROS rules, one at a time: does the suite notice each?

Usage, from the repository root::

    python tests/mutation/run.py                            # run all, print the report
    python tests/mutation/run.py --report docs/mutation.md  # ... and write it there
    python tests/mutation/run.py --only busy-multi-precheck --only fsu-joint-pct-plus-5

Each mutant (:data:`MUTANTS`) replaces one exact piece of source text with a plausible
wrong version, then runs only the tests that guard that rule. A run that fails kills the
mutant; one that passes lets it survive. The source tree is copied once into a temporary
directory and mutated *there* (``PYTHONPATH`` points the tests at the copy), so the
checkout is never edited: an interrupted run (Ctrl-C, or SIGTERM from a CI timeout)
leaves it as it was, ends the test runs still going and removes the copies.

A mutant whose text is no longer in its file is reported as *stale* (the code moved or
changed): update its ``old`` text, do not delete it. The run fails (exit 1) when a mutant
survives without a written reason (``accepted``), is stale, or its tests cannot run; a
baseline run of every selected test on the unmutated copy comes first and must pass.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import os
import queue
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = "pymotoros"
RUN_TIMEOUT_S = 300.0
"""Bound on one mutant's test run (a mutant that makes a loop endless is a kill)."""
COMMAND = "python tests/mutation/run.py --report docs/mutation.md"


@dataclass(frozen=True)
class Mutant:
    """One deliberate bug: in ``path`` (under src/pymotoros), ``old`` becomes ``new``."""

    name: str
    rule: str
    path: str
    old: str
    new: str
    tests: tuple[str, ...]
    accepted: str = ""
    """Why a survivor is acceptable (an equivalent mutant); empty: it must be killed."""


SHARED_RULES = ("tests/test_shared_rules.py", "-k", "by_hand")
POINTS = ("tests/controller/test_points.py",)
BUSY = ("tests/controller/test_points.py", "tests/controller/test_busy_all_or_nothing.py")
PFL = (
    "tests/controller/test_pfl_latch.py",
    "tests/controller/test_safety.py",
    "tests/controller/test_readiness.py",
    "tests/controller/test_not_ready_order.py",
)
FSU = (
    "tests/models/test_fsu_formula.py",
    "tests/controller/test_fsu_by_hand.py",
    "tests/controller/test_safety.py",
)
S1CXG = ("tests/controller/test_s1cxg_registers.py",)

MUTANTS: tuple[Mutant, ...] = (
    # --- 3011: the start tolerance (reference §3.4 step 5.3)
    Mutant(
        "start-tolerance-inclusive",
        "3011: |Δpulse| > 30 refuses (not ≥ 30)",
        "models/rules.py",
        "return diff if diff > START_TOLERANCE_PULSES else None",
        "return diff if diff >= START_TOLERANCE_PULSES else None",
        (*POINTS, *SHARED_RULES),
    ),
    Mutant(
        "start-tolerance-31",
        "3011: the tolerance is 30 pulses",
        "models/rules.py",
        "START_TOLERANCE_PULSES: Final = 30",
        "START_TOLERANCE_PULSES: Final = 31",
        (*POINTS, *SHARED_RULES),
    ),
    # --- 3013: the speed check and its truncation quirk (§5.5)
    Mutant(
        "speed-no-truncation",
        "3013 quirk: trunc(|v|) is compared, not |v|",
        "models/rules.py",
        "whole = int(speed)  # C: abs((int)v)",
        "whole = speed  # C: abs((int)v)",
        (*POINTS, *SHARED_RULES),
    ),
    Mutant(
        "speed-inclusive",
        "3013: trunc(|v|) > maxSpeed refuses (not ≥)",
        "models/rules.py",
        "    if whole > limit:\n",
        "    if whole >= limit:\n",
        (*POINTS, *SHARED_RULES),
    ),
    Mutant(
        "speed-round-up",
        "3013 quirk: truncation toward zero, not rounding",
        "models/rules.py",
        "whole = int(speed)  # C: abs((int)v)",
        "whole = round(speed)  # C: abs((int)v)",
        (*POINTS, *SHARED_RULES),
    ),
    # --- BUSY (§3.4 step 6.1, §3.5 step 2)
    Mutant(
        "busy-single-full-path",
        "BUSY: a pending group answers BUSY (type 14, and the 2016 apply step: one route)",
        "controller/trajectory.py",
        "        if interp.pending:  # type 14's BUSY (no group number) is made once: no call\n"
        "            return self._busy_replies[g] if group_no is None "
        "else self._busy(g, sequence, group_no)\n",
        "",
        BUSY,
    ),
    Mutant(
        "busy-multi-precheck",
        "BUSY all or nothing: 2016 pre-checks every group before accepting any",
        "controller/trajectory.py",
        "            if self._interpolators[g].pending:\n"
        "                return self._busy(g, sequence, group_no=g)\n",
        "",
        BUSY,
    ),
    # --- PFL: the "PFL during ROS move" latch and its clearing (§2.6, §3.2)
    Mutant(
        "pfl-latch-not-set",
        "PFL: a PFL event latches 5011",
        "controller/ready_flags.py",
        "            self._change(job_ready=job_ready, pfl_during_move=True)\n",
        "            self._change(job_ready=job_ready)\n",
        PFL,
    ),
    Mutant(
        "pfl-latch-not-cleared",
        "PFL: START_TRAJ_MODE clears the latch",
        "controller/ready_flags.py",
        "        self._change(pfl_during_move=False, inc_move_error=False)\n",
        "        self._change(inc_move_error=False)\n",
        PFL,
    ),
    Mutant(
        "pfl-latch-ignored",
        "PFL: the latch keeps motion NOT_READY",
        "controller/ready_flags.py",
        "and not (self.pfl_option and (pfl_latched or pfl_signals_active(pfl)))",
        "and not (self.pfl_option and pfl_signals_active(pfl))",
        PFL,
    ),
    # --- FSU: the joint and TCP clips (controller's FSU; MotoROS's compensation §5.6)
    Mutant(
        "fsu-joint-pct-plus-5",
        "FSU joint clip: pct % of maxInc (5 % is not 10 %)",
        "models/fsu.py",
        "max(1, m * pct // 100)",
        "max(1, m * (pct + 5) // 100)",
        FSU,
    ),
    Mutant(
        "fsu-joint-no-floor",
        "FSU joint clip: at least one pulse",
        "models/fsu.py",
        "max(1, m * pct // 100)",
        "max(0, m * pct // 100)",
        FSU,
    ),
    Mutant(
        "fsu-joint-rounds",
        "FSU joint clip: rounded down",
        "models/fsu.py",
        "max(1, m * pct // 100)",
        "max(1, round(m * pct / 100))",
        FSU,
    ),
    Mutant(
        "fsu-tcp-rounds",
        "FSU TCP clip: each axis rounded down (never above the limit)",
        "controller/tool_point.py",
        "return tuple(int(abs(p) * scale) for p in increment)",
        "return tuple(round(abs(p) * scale) for p in increment)",
        FSU,
    ),
    Mutant(
        "fsu-tcp-off",
        "FSU TCP clip: scaled to the limit",
        "controller/tool_point.py",
        "scale = 1.0 if speed <= limit_mm_s else limit_mm_s / speed",
        "scale = 1.0",
        FSU,
    ),
    # --- S1CxG register outputs (seed 003 Appendix A)
    Mutant(
        "s1cxg-deg-scale",
        "S1CxG: 4-byte angles in 0.0001°",
        "models/s1cxg.py",
        "        return deg * (1e4 if four_bytes else 1.0)\n    return 1.0  # pulses",
        "        return deg * (1e3 if four_bytes else 1.0)\n    return 1.0  # pulses",
        S1CXG,
    ),
    Mutant(
        "s1cxg-mm-scale",
        "S1CxG: 2-byte Cartesian positions in mm",
        "models/s1cxg.py",
        "        if index < 3:\n            return 1e6 if four_bytes else 1e3\n",
        "        if index < 3:\n            return 1e6 if four_bytes else 1e2\n",
        S1CXG,
    ),
    Mutant(
        "s1cxg-truncates-values",
        "S1CxG: values rounded half away from zero, not truncated",
        "controller/registers.py",
        "np.trunc(x + np.copysign(0.5, x))",
        "np.trunc(x)",
        S1CXG,
    ),
    Mutant(
        "s1cxg-pulse-rounds",
        "S1CxG: pulse outputs truncate their division (C ints)",
        "controller/registers.py",
        "np.where(self.is_pulse, np.trunc(x),",
        "np.where(self.is_pulse, np.round(x),",
        S1CXG,
    ),
    Mutant(
        "s1cxg-word-15-bits",
        "S1CxG: each register holds 16 bits",
        "controller/registers.py",
        "per_word >> 16, per_word) & 0xFFFF",
        "per_word >> 16, per_word) & 0x7FFF",
        S1CXG,
    ),
)


HISTORY: tuple[tuple[str, str], ...] = (
    (
        "busy-multi-precheck",
        "issue 24: passed all ~300 tests of the twelve relevant files; killed by "
        "tests/controller/test_busy_all_or_nothing.py (every pending combination of 2-4 "
        "groups, and the resend counted)",
    ),
    (
        "fsu-joint-pct-plus-5",
        "issue 24: caught only by two copies of the formula agreeing; the formula is now "
        "models/fsu.py, pinned by tests/models/test_fsu_formula.py and "
        "tests/controller/test_fsu_by_hand.py",
    ),
    (
        "pfl-latch-ignored",
        "the first run of this list (2026-11-26): a PFL contact while moving also latches "
        "5012, which hid the PFL latch; tests/controller/test_pfl_latch.py sets the latch "
        "alone (the PFL signal at rest)",
    ),
)
"""Mutants that once survived, and what kills them now (kept in the report)."""


@dataclass
class Result:
    mutant: Mutant
    outcome: str  # killed, survived, stale, error
    seconds: float = 0.0
    detail: str = ""
    failing: list[str] = field(default_factory=list)


def _copy_source(into: Path) -> Path:
    src = into / "src"
    shutil.copytree(
        ROOT / "src" / PACKAGE,
        src / PACKAGE,
        ignore=shutil.ignore_patterns("__pycache__", "*.pyc"),
    )
    return src


def _env(src: Path) -> dict[str, str]:
    env = dict(os.environ)
    env.pop("CI", None)  # a skip must not count as a kill
    env["PYTHONPATH"] = str(src)
    env["PYTHONDONTWRITEBYTECODE"] = "1"  # no .pyc: a restored file is never read stale
    return env


_CHILDREN: set[subprocess.Popen[str]] = set()
_CHILDREN_LOCK = threading.Lock()
_STOPPING = threading.Event()


def _pytest(src: Path, args: tuple[str, ...]) -> subprocess.CompletedProcess[str]:
    """One pytest run on the copy at ``src``; the child is tracked so that an interrupted
    run can end it (:func:`_stop_children`)."""
    command = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", *args]
    with _CHILDREN_LOCK:
        if _STOPPING.is_set():
            raise KeyboardInterrupt
        child = subprocess.Popen(  # noqa: S603 - this interpreter, fixed arguments
            command,
            cwd=ROOT,
            env=_env(src),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        _CHILDREN.add(child)
    try:
        out, err = child.communicate(timeout=RUN_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        child.kill()
        child.communicate()
        raise
    finally:
        with _CHILDREN_LOCK:
            _CHILDREN.discard(child)
    return subprocess.CompletedProcess(command, child.returncode, out, err)


def _stop_children() -> None:
    """End every pytest run still going (an interrupt): no orphan outlives the runner."""
    with _CHILDREN_LOCK:
        _STOPPING.set()
        children = list(_CHILDREN)
    for child in children:
        child.kill()


def _interrupt(signum: int, frame: object) -> None:
    """SIGTERM (a CI timeout) as Ctrl-C: the temporary copies are removed on the way out."""
    raise KeyboardInterrupt


def _failing(output: str) -> list[str]:
    return [
        line.split(" ", 2)[1]
        for line in output.splitlines()
        if line.startswith(("FAILED ", "ERROR ")) and " " in line
    ][:3]


def _check_copy_is_used(src: Path) -> None:
    done = subprocess.run(  # noqa: S603 - this interpreter, fixed arguments
        [sys.executable, "-c", f"import {PACKAGE}; print({PACKAGE}.__file__)"],
        cwd=ROOT,
        env=_env(src),
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT_S,
        check=True,
    )
    if not Path(done.stdout.strip()).is_relative_to(src):
        raise SystemExit(
            f"mutation: the tests would import {done.stdout.strip()}, not the copy in {src}; "
            "an installed pymotoros shadows PYTHONPATH (install it editable from this tree)"
        )


def run_one(src: Path, mutant: Mutant) -> Result:
    path = src / PACKAGE / mutant.path
    original = path.read_text(encoding="utf-8")
    count = original.count(mutant.old)
    if count != 1:
        where = "not found" if count == 0 else f"found {count} times"
        return Result(mutant, "stale", detail=f"text {where} in {mutant.path}")
    path.write_text(original.replace(mutant.old, mutant.new), encoding="utf-8")
    started = time.monotonic()
    try:
        done = _pytest(src, mutant.tests)
    except subprocess.TimeoutExpired:
        return Result(mutant, "killed", RUN_TIMEOUT_S, detail="timed out")
    finally:
        path.write_text(original, encoding="utf-8")  # the copy, for the next mutant
    seconds = time.monotonic() - started
    if done.returncode in (1, 2):  # tests failed, or collection failed on the mutant
        return Result(mutant, "killed", seconds, failing=_failing(done.stdout))
    if done.returncode == 0:
        return Result(mutant, "survived", seconds)
    tail = (done.stdout + done.stderr).strip().splitlines()[-3:]
    return Result(mutant, "error", seconds, detail=" / ".join(tail))


def report(results: list[Result], baseline_s: float, total_s: float, jobs: int) -> str:
    lines = [
        "# Mutation run: deliberate bugs in the MotoROS rules",
        "",
        "Written by `tests/mutation/run.py` (run from `.ci/run`, which fails if a mutant",
        "survives without a written reason). Regenerate this page with:",
        "",
        "```console",
        f"$ {COMMAND}",
        "```",
        "",
        "Each mutant is one plausible bug, applied alone to a temporary copy of `src/`",
        "(the checkout is never edited); only the tests that guard its rule run. *Killed*:",
        "those tests failed. *Survived*: they passed, so the bug would reach users.",
        "",
        "| mutant | rule | file | result | tests that failed | s |",
        "|---|---|---|---|---|---|",
    ]
    for r in results:
        m = r.mutant
        failing = ", ".join(f"`{f}`" for f in r.failing) or r.detail
        outcome = r.outcome if not (r.outcome == "survived" and m.accepted) else "survived (ok)"
        lines.append(
            f"| `{m.name}` | {m.rule.replace('|', '&#124;')} | `{m.path}` | **{outcome}** | "
            f"{failing} | {r.seconds:.0f} |"
        )
    killed = sum(r.outcome == "killed" for r in results)
    lines += [
        "",
        f"{killed} of {len(results)} killed. Whole run {total_s:.0f} s with {jobs} at once "
        + (
            f"(the unmutated baseline {baseline_s:.0f} s of it)"
            if baseline_s
            else "(no baseline run: --no-baseline)"
        )
        + f"; load average {os.getloadavg()[0]:.1f} at the end. The seconds per mutant are "
        "wall time on the machine the report was made on.",
    ]
    lines += ["", "## Survivors found before, and the tests that now kill them", ""]
    lines += [f"- `{name}`: {what}" for name, what in HISTORY]
    reasons = [r for r in results if r.outcome == "survived" and r.mutant.accepted]
    if reasons:
        lines += ["", "## Survivors and why they are acceptable", ""]
        lines += [f"- `{r.mutant.name}`: {r.mutant.accepted}" for r in reasons]
    lines.append("")
    return "\n".join(lines)


def _baseline(src: Path, chosen: list[Mutant]) -> float | None:
    """Seconds the selected tests take unmutated; None (after saying why) if they fail."""
    started = time.monotonic()
    for tests in dict.fromkeys(m.tests for m in chosen):
        base = _pytest(src, tests)
        if base.returncode != 0:
            sys.stderr.write(base.stdout[-3000:] + base.stderr[-2000:])
            sys.stderr.write(
                f"mutation: the baseline (no mutant) of {' '.join(tests)} fails: "
                "fix the tests first\n"
            )
            return None
    return time.monotonic() - started


def _run_all(tmp: Path, chosen: list[Mutant], jobs: int) -> list[Result]:
    """Each mutant on one of ``jobs`` copies of the source tree, in parallel."""
    copies: queue.Queue[Path] = queue.Queue()
    for k in range(jobs):
        copies.put(_copy_source(tmp / f"copy{k}"))

    def one(m: Mutant) -> Result:
        src = copies.get()
        try:
            r = run_one(src, m)
        finally:
            copies.put(src)
        sys.stdout.write(f"{m.name}: {r.outcome} ({r.seconds:.0f} s) {r.detail}\n")
        sys.stdout.flush()
        return r

    with concurrent.futures.ThreadPoolExecutor(jobs) as pool:
        try:
            return list(pool.map(one, chosen))
        except BaseException:
            _stop_children()
            pool.shutdown(wait=True, cancel_futures=True)
            raise


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--report", type=Path, help="also write the Markdown report here")
    parser.add_argument("--only", action="append", default=[], help="run this mutant (repeat)")
    parser.add_argument("--list", action="store_true", help="list the mutants and exit")
    parser.add_argument(
        "--jobs", type=int, default=2, help="mutants run at once, each on its own copy (2)"
    )
    parser.add_argument(
        "--no-baseline",
        action="store_true",
        help="skip the unmutated run (when the whole suite has just passed, as in .ci/run)",
    )
    args = parser.parse_args(argv)
    if args.list:
        for m in MUTANTS:
            sys.stdout.write(f"{m.name}: {m.rule} ({m.path})\n")
        return 0
    unknown = set(args.only) - {m.name for m in MUTANTS}
    if unknown:
        parser.error(f"no mutant named {sorted(unknown)}; --list shows them")
    chosen = [m for m in MUTANTS if not args.only or m.name in args.only]
    signal.signal(signal.SIGTERM, _interrupt)
    started = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="pymotoros-mutation-") as tmp:
        src = _copy_source(Path(tmp) / "base")
        _check_copy_is_used(src)
        baseline_s: float | None = 0.0
        if not args.no_baseline:
            baseline_s = _baseline(src, chosen)
            if baseline_s is None:
                return 1
        results = _run_all(Path(tmp), chosen, max(1, args.jobs))
    text = report(results, baseline_s, time.monotonic() - started, args.jobs)
    sys.stdout.write("\n" + text)
    if args.report is not None:
        args.report.write_text(text, encoding="utf-8")
    bad = [
        r
        for r in results
        if r.outcome in ("stale", "error") or (r.outcome == "survived" and not r.mutant.accepted)
    ]
    for r in bad:
        sys.stderr.write(f"mutation: {r.mutant.name} {r.outcome}: {r.mutant.rule} {r.detail}\n")
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
