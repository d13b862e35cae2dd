"""The shared option declarations (issue 19) and what they promise (issue 20): an unknown
option is told as unknown, negative joint values need no ``--``, one help text per
option everywhere, ``move``'s progress line, and ``plot``'s limit lines."""

from __future__ import annotations

import io
from pathlib import Path

import click
import numpy as np
import pytest
from click.testing import CliRunner

from pymotoros.cli.main import _COMMANDS, cli
from pymotoros.cli.move_report import progress_bar, progress_line
from pymotoros.client.streaming import FollowingSample
from pymotoros.models import controller_model, robot_model
from pymotoros.trajectory import Trajectory, check_trajectory
from pymotoros.trajectory.plot import plot_trajectory

NOWHERE = ["--motion-port", "1", "--state-port", "1", "--io-port", "1", "--timeout", "0.2"]


def test_an_unknown_option_is_reported_as_unknown_with_the_nearest() -> None:
    result = CliRunner().invoke(cli, ["move", "--speed", "0.5", "0", "0", "0", "0", "0", "0"])
    assert result.exit_code == 2
    assert "No such option" in result.stderr
    assert "--speed" in result.stderr
    assert "--speed-scale" in result.stderr  # the nearest real option
    assert "valid float" not in result.stderr


def test_an_unknown_option_after_the_values_too() -> None:
    result = CliRunner().invoke(cli, ["move", "0", "0", "0", "0", "0", "0", "--spede-scale=1"])
    assert result.exit_code == 2
    assert "No such option" in result.stderr
    assert "--speed-scale" in result.stderr


@pytest.mark.parametrize(
    "values", [["-0.5", "0", "0", "0", "0", "0"], ["0", "-.5", "-1e-3", "0", "-0", "0"]]
)
def test_negative_values_need_no_double_dash(values: list[str]) -> None:
    # nothing listens on port 1: a parsed command gets as far as connecting (exit 3)
    result = CliRunner().invoke(cli, ["move", *values, "--speed-scale", "0.5", *NOWHERE])
    assert result.exit_code == 3, result.output
    assert "cannot connect" in result.stderr


def test_an_option_value_that_looks_like_an_option_is_a_value() -> None:
    result = CliRunner().invoke(cli, ["move", "--named", "-weird", *NOWHERE])
    assert "No such option" not in result.stderr
    assert "no named pose '-weird'" in result.stderr


def _options() -> dict[str, dict[str, str]]:
    """Option flag -> command -> help, over every command but the simulator's."""
    out: dict[str, dict[str, str]] = {}
    group = cli
    assert isinstance(group, click.Group)
    ctx = click.Context(group)
    for name in _COMMANDS:
        command = group.get_command(ctx, name)
        assert command is not None
        subs = command.commands if isinstance(command, click.Group) else {"": command}
        for sub_name, sub in subs.items():
            for param in sub.params:
                if isinstance(param, click.Option) and param.help:
                    flag = max(param.opts, key=len)
                    out.setdefault(flag, {})[f"{name} {sub_name}".strip()] = param.help
    return out


@pytest.mark.parametrize(
    ("flag", "commands"),
    [
        ("--speed-scale", {"move", "plan"}),
        ("--accel-scale", {"move", "plan"}),
        ("--controller", {"status", "move", "run", "check", "plan", "plot", "interpolate"}),
        ("--robot", {"status", "move", "run", "check", "plan", "plot", "interpolate", "urdf"}),
        ("--config", {"status", "move", "run", "check", "plan", "plot", "replay"}),
        ("--motion-port", {"status", "move", "run", "replay"}),
        ("--output", {"plan", "plot", "interpolate", "urdf"}),
    ],
)
def test_a_shared_option_has_one_help_text(flag: str, commands: set[str]) -> None:
    helps = _options()[flag]
    assert commands <= set(helps)

    def core(text: str) -> str:  # what a command adds: its default, a note, what it writes
        return text.split(" [default:")[0].split(". ")[0].rstrip(".")

    if flag == "--output":
        assert all(h.endswith("(its directory must exist).") for h in helps.values())
        return
    assert len({core(helps[c]) for c in commands}) == 1, {c: helps[c] for c in commands}


def _sample(progress: float, elapsed: float, lag: float = 0.0) -> FollowingSample:
    return FollowingSample(elapsed_s=elapsed, progress=progress, lag_s=lag, error=0.0)


def test_progress_line_shows_time_left_and_the_joints() -> None:
    line = progress_line("moving", _sample(0.25, 1.0, 0.2), [0.1, -0.5], duration_s=3.0, deg=False)
    assert " 25%" in line
    assert "2.2 s left" in line  # 3.0 planned - (1.0 elapsed - 0.2 behind)
    assert "[0.100, -0.500] rad" in line
    guessed = progress_line("moving", _sample(0.5, 2.0), [0.1], duration_s=None, deg=True)
    assert "2.0 s left" in guessed  # extrapolated from the progress
    assert "[5.730] deg" in guessed


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_bar_on_a_terminal_redraws_the_line() -> None:
    out = _Terminal()
    with progress_bar("moving", duration_s=2.0, stream=out) as progress:
        progress(_sample(0.5, 1.0))
        progress(_sample(1.0, 2.0))
    text = out.getvalue()
    assert "\r" in text
    assert "1.0 s left" in text
    assert "0.0 s left" in text
    plain = io.StringIO()
    with progress_bar("moving", duration_s=2.0, stream=plain) as progress:
        progress(_sample(0.5, 1.0))
    assert plain.getvalue() == ""  # not a terminal: nothing


def test_plot_limit_lines_lie_within_the_drawn_range(tmp_path: Path) -> None:
    hc10, yrc = robot_model("hc10"), controller_model("yrc1000")
    t = np.linspace(0.0, 4.0, 41)
    pos = np.zeros((41, 6))
    pos[:, 0] = 3.0 * np.sin(np.pi * t / 8.0) ** 2  # joint_1_s up to 3.0 rad: near its limit
    pos[:, 1] = 0.1 * np.sin(np.pi * t / 8.0) ** 2  # joint_2_l 0.1 rad: limits far away
    vel = np.gradient(pos, t, axis=0)
    vel[0] = vel[-1] = 0.0
    traj = Trajectory(hc10.groups[0].joint_names, t, pos, vel)
    report = check_trajectory(traj, hc10, yrc)
    fig = plot_trajectory(traj, hc10, yrc, report, tmp_path / "p.png")
    limit_labels = {"joint limits", "velocity limit"}
    for ax in fig.get_axes():
        lo, hi = ax.get_ylim()
        for line in ax.get_lines():
            if line.get_linestyle() == "--":
                y = float(line.get_ydata()[0])
                assert lo <= y <= hi, (ax.get_ylabel(), y, lo, hi)
        legend = ax.get_legend()
        listed = {t.get_text() for t in legend.get_texts()} if legend else set()
        drawn = {str(line.get_label()) for line in ax.get_lines()}
        assert (listed & limit_labels) <= drawn
    first = fig.get_axes()[0]
    assert "joint limits" in {line.get_label() for line in first.get_lines()}  # 3.0 of 3.14
    second = fig.get_axes()[2]  # joint_2_l position: its limits off the scale, said so
    assert any("off the scale" in text.get_text() for text in second.texts)
