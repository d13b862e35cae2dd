"""The INFORM job parser and runner (reference §7)."""

from __future__ import annotations

from pathlib import Path

import pytest

from pymotoros.controller import VirtualController, cell_from_dict, default_cell
from pymotoros.controller.inform import (
    BUILTIN_VARIANTS,
    JobRunner,
    Op,
    builtin_jobs,
    load_job,
    parse_job,
)
from pymotoros.controller.io_image import IoImage
from pymotoros.controller.signals import OPERATING, ROS_DONE, ROS_READY
from pymotoros.errors import JobError
from pymotoros.models import controller_model
from pymotoros.protocol.constants import NotReadySubcode as Nr

from .helpers import CMD, command, tick_until
from .states import settle_monitor

JOBS_DIR = Path(__file__).resolve().parents[2] / "src" / "pymotoros" / "controller" / "jobs"


def jbi(*body: str, name: str = "TEST") -> str:
    return "\r\n".join(["/JOB", f"//NAME {name}", "//POS", "//INST", "///ATTR SC,RW", *body])


def runner(text: str) -> tuple[JobRunner, IoImage]:
    io = IoImage(controller_model("yrc1000"))
    job = parse_job(text, "TEST.JBI")
    return JobRunner({job.name: job}, io, main=job.name), io


# ------------------------------------------------------------------ parsing


def test_builtin_jobs_are_crlf_and_load() -> None:
    files = sorted(JOBS_DIR.rglob("*.JBI"))
    assert {f.parent.name for f in files} == set(BUILTIN_VARIANTS)
    for f in files:
        data = f.read_bytes()
        assert data.count(b"\r\n") == data.count(b"\n") > 5, f
        load_job(f)
    for variant in BUILTIN_VARIANTS:
        assert "INIT_ROS" in builtin_jobs(variant)


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("MOVJ VJ=10.00", "line 7: unsupported instruction 'MOVJ'"),
        ("DOUT OT#(x) ON", "line 7: cannot read DOUT"),
        ("TIMER T=0", "line 7: TIMER T=0"),
        ("WAIT OT#(890)=MAYBE", "line 7: cannot read WAIT"),
        ('SKILLSND ROS-START"', "line 7: cannot read SKILLSND"),
        ("DOUT OT#(0) ON", "line 7: OT#(0) does not exist"),
    ],
)
def test_parse_errors_name_file_and_line(line: str, message: str) -> None:
    with pytest.raises(JobError, match=r"TEST\.JBI") as info:
        parse_job(jbi("NOP", line, "END"), "TEST.JBI")
    assert message in str(info.value)


def test_structure_errors() -> None:
    with pytest.raises(JobError, match="starts with /JOB"):
        parse_job("NOP\r\nEND\r\n", "X.JBI")
    with pytest.raises(JobError, match="no END"):
        parse_job(jbi("NOP"), "X.JBI")
    with pytest.raises(JobError, match="line 8: text after END"):
        parse_job(jbi("NOP", "END", "NOP"), "X.JBI")
    with pytest.raises(JobError, match="PSTART of unknown job NOPE"):
        runner(jbi("PSTART JOB:NOPE SUB1", "END"))
    with pytest.raises(JobError, match="does not exist on this controller"):
        runner(jbi("DOUT OT#(9999) ON", "END"))


def test_comments_and_attributes_are_skipped() -> None:
    job = parse_job(jbi("'a comment", "///GROUP1 RB1", "NOP", "END"), "X.JBI")
    assert [i.op.value for i in job.instructions] == ["NOP", "END"]
    assert [i.line for i in job.instructions] == [8, 9]


# ------------------------------------------------------------------ timing


def test_dout_timer_wait_on_the_controller_clock() -> None:
    run, io = runner(
        jbi("NOP", "DOUT OT#(1) ON", "TIMER T=0.05", "DOUT OT#(2) ON", "WAIT OT#(3)=ON", "END")
    )
    run.start()
    now = 0
    assert not run.step(now)
    assert (io.get(10010), io.get(10011)) == (1, 0)
    while now < 48:
        now += 4
        run.step(now)
        assert io.get(10011) == 0, now
    now += 4  # 52 ms ≥ 50 ms: the first tick at or after the end of the TIMER
    run.step(now)
    assert io.get(10011) == 1
    for _ in range(10):
        now += 4
        assert not run.step(now)
    assert run.at_wait
    io.set(10012, 1)
    assert run.step(now + 4)
    assert not run.running


def test_init_ros_handshake_timing() -> None:
    vc = VirtualController()
    vc.set_servo(True)
    tick_until(vc, lambda: vc.snapshot().servo, "servo on")
    vc.io.set(ROS_READY, 1)  # left on by a previous run (single-arm variant)
    vc.io.set(ROS_DONE, 1)
    vc.force_io(OPERATING, 1)  # start INIT_ROS
    vc.tick()
    assert (vc.io.get(ROS_READY), vc.io.get(ROS_DONE)) == (0, 0)
    low_since = vc.time_ms
    tick_until(vc, lambda: vc.io.get(ROS_READY) == 1, "OT#889 on")
    assert vc.time_ms - low_since >= 50  # TIMER T=0.05
    settle_monitor(vc)
    assert vc.motoros.job_ready
    assert vc.motoros.motion_ready
    wait_line = next(
        i.line for i in builtin_jobs("single_arm")["INIT_ROS"].instructions if i.op is Op.WAIT
    )
    assert vc.job_position == (("INIT_ROS", wait_line),)
    # STOP_TRAJ_MODE: OT#890 on → the job clears 890 and ends; 889 stays on
    assert command(vc, CMD.STOP_TRAJ_MODE).ok
    tick_until(vc, lambda: vc.job_position == (), "job ended")
    assert (vc.io.get(ROS_READY), vc.io.get(ROS_DONE)) == (1, 0)


def test_hold_stops_the_job() -> None:
    vc = VirtualController()
    assert command(vc, CMD.START_TRAJ_MODE).ok
    vc.set_hold(True)
    assert vc.job_position == ()
    assert vc.io.get(OPERATING) == 0
    vc.set_hold(False)
    assert vc.job_position == ()
    assert command(vc, CMD.START_TRAJ_MODE).ok  # restarts INIT_ROS from its first line


# ------------------------------------------------------------------ multi-group and DX100


def two_arms(controller: str) -> VirtualController:
    return VirtualController(
        cell_from_dict(
            {"controller": {"model": controller}, "groups": [{"robot": "hc10"}, {"robot": "hc10"}]}
        )
    )


def test_multi_group_job_drops_889_at_the_end() -> None:
    vc = two_arms("yrc1000")
    assert vc.cell.job_variant == "multi_group"
    assert command(vc, CMD.START_TRAJ_MODE).ok
    assert command(vc, CMD.STOP_TRAJ_MODE).ok
    tick_until(vc, lambda: vc.job_position == (), "job ended")
    assert (vc.io.get(ROS_READY), vc.io.get(ROS_DONE)) == (0, 0)


def test_dx100_multi_group_pstart_tsync_pwait() -> None:
    vc = two_arms("dx100")
    assert vc.cell.job_variant == "dx100_multi_group"
    outcome = command(vc, CMD.START_TRAJ_MODE)
    assert outcome.ok, outcome.detail
    names = sorted(name for name, _ in vc.job_position)
    assert names == ["INIT_ROS", "ROS_R1", "ROS_R2"]  # parent at PWAIT, both subs at WAIT
    assert vc.motoros.skill_flags == (True, True)
    assert command(vc, CMD.STOP_TRAJ_MODE).ok
    tick_until(vc, lambda: vc.job_position == (), "all tasks ended")
    assert vc.motoros.skill_flags == (False, False)
    settle_monitor(vc)
    assert command(vc, CMD.CHECK_MOTION_READY).subcode == Nr.NOT_STARTED


def test_tsync_waits_for_the_slower_task() -> None:
    parent = jbi("PSTART JOB:A SUB1", "PSTART JOB:B SUB2", "PWAIT SUB1", "PWAIT SUB2", "END")
    a = jbi("TSYNC 1", "DOUT OT#(1) ON", "END", name="A")
    b = jbi("TIMER T=0.1", "TSYNC 1", "DOUT OT#(2) ON", "END", name="B")
    io = IoImage(controller_model("dx100"))
    jobs = {j.name: j for j in (parse_job(parent, "P"), parse_job(a, "A"), parse_job(b, "B"))}
    run = JobRunner(jobs, io, main="TEST")
    run.start()
    now = 0
    run.step(now)
    while now < 96:
        now += 4
        run.step(now)
        assert io.get(10010) == 0, now  # A waits at TSYNC for B's TIMER
    now += 4
    assert run.step(now)  # both pass TSYNC together, both end, the parent ends
    assert (io.get(10010), io.get(10011)) == (1, 1)


def test_dx100_without_skillsnd_reports_5010(tmp_path: Path) -> None:
    job = jbi(
        "NOP",
        "DOUT OT#(890) OFF",
        "DOUT OT#(889) OFF",
        "TIMER T=0.05",
        "DOUT OT#(889) ON",
        "WAIT OT#(890)=ON",
        "END",
        name="INIT_ROS",
    )
    (tmp_path / "INIT_ROS.JBI").write_text(job, newline="")
    cell = cell_from_dict(
        {"controller": {"model": "dx100", "jobs": str(tmp_path)}}, base_dir=tmp_path
    )
    vc = VirtualController(cell)
    outcome = command(vc, CMD.START_TRAJ_MODE)
    assert (outcome.result, outcome.subcode) == (5, Nr.SKILLSEND)
    assert "SKILLSND" in outcome.detail
    assert vc.time_ms >= 5000  # it waited its 5 s for motion-ready


def test_dx100_single_arm_needs_and_gets_the_skill_flag() -> None:
    vc = VirtualController(default_cell("dx100"))
    assert command(vc, CMD.START_TRAJ_MODE).ok
    assert vc.motoros.skill_flags[0]
    vc.press_estop(True)  # the job is aborted: the skill command ends with it
    assert vc.motoros.skill_flags == (False, False)
