"""Shell completion as docs/client.md documents it: ``_PYMOTOROS_COMPLETE=bash_source
pymotoros`` prints a script that bash loads, and that script completes commands and
options by asking the installed ``pymotoros``."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

BASH = shutil.which("bash")
SRC = Path(__file__).resolve().parents[2] / "src"


def _env(**extra: str) -> dict[str, str]:
    path = os.pathsep.join(p for p in (str(SRC), os.environ.get("PYTHONPATH")) if p)
    return {**os.environ, "PYTHONPATH": path, **extra}


def _console_script(folder: Path) -> Path:
    """A ``pymotoros`` command as pip installs it (click names the completion variable
    after the program's name, so ``python -m pymotoros`` would not do)."""
    script = folder / "pymotoros"
    script.write_text(
        f"#!{sys.executable}\nimport sys\nfrom pymotoros.cli.main import main\nsys.exit(main())\n"
    )
    script.chmod(0o755)
    return script


def _succeeds(args: list[str], timeout_s: float, **env: str) -> subprocess.CompletedProcess[str]:
    """``args`` run with :func:`_env` plus ``env``; it must exit 0."""
    done = subprocess.run(  # noqa: S603 - our CLI, or bash running the documented line
        args, env=_env(**env), capture_output=True, text=True, check=False, timeout=timeout_s
    )
    assert done.returncode == 0, done.stderr
    return done


@pytest.mark.parametrize(
    ("shell", "marker"),
    [
        ("bash", "complete -o nosort -F _pymotoros_completion pymotoros"),
        ("zsh", "#compdef pymotoros"),
        ("fish", "complete --no-files --command pymotoros"),
    ],
)
def test_the_completion_script_is_printed(shell: str, marker: str, tmp_path: Path) -> None:
    done = _succeeds([str(_console_script(tmp_path))], 60, _PYMOTOROS_COMPLETE=f"{shell}_source")
    assert marker in done.stdout


@pytest.mark.skipif(BASH is None, reason="bash is not installed")
def test_bash_completes_commands_and_options(tmp_path: Path) -> None:
    """The documented ``eval`` line, then bash's completion function as Tab calls it.
    ``pymotoros`` runs this interpreter on this source tree."""
    _console_script(tmp_path)
    script = """
    eval "$(_PYMOTOROS_COMPLETE=bash_source pymotoros)"
    complete_words() {
        COMP_WORDS=("$@"); COMP_CWORD=$(($# - 1)); COMPREPLY=()
        _pymotoros_completion pymotoros
        printf '%s\\n' "${COMPREPLY[@]}"
    }
    echo "== commands"; complete_words pymotoros sta
    echo "== options"; complete_words pymotoros move --speed
    echo "== choices"; complete_words pymotoros status --controller fs
    """
    path = f"{tmp_path}{os.pathsep}{os.environ['PATH']}"
    done = _succeeds([str(BASH), "-c", script], 120, PATH=path)
    sections = dict(part.split("\n", 1) for part in done.stdout.split("== ")[1:] if "\n" in part)
    assert "status" in sections["commands"].split()
    assert "--speed-scale" in sections["options"].split()
    assert "fs100" in sections["choices"].split()
