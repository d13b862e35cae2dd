"""What ``pymotoros status`` says beyond the raw fields, and its live (redrawn) display.

* Why motion is not possible, from ROBOT_STATUS alone (the state port, so ``status``
  stays safe next to a moving client): told with the meaning of the NOT_READY subcode
  MotoROS would answer (``protocol.constants.NotReadySubcode``), the cause first as
  MotoROS checks it (E-stop, alarm, mode, servo …), and what to do.
* Alarm texts: ROBOT_STATUS carries only the alarm number. For the twin, whose control
  API the ports file tells, the texts are the ones the pendant shows (``GET /api/state``).
* ``--watch`` redraws in place with rich on a terminal; elsewhere it prints a frame only
  when it differs from the last one.
"""

from __future__ import annotations

import json
import sys
import urllib.error
import urllib.request
from collections.abc import Callable
from typing import IO, Final

from pymotoros.client.state import Mode, Status
from pymotoros.protocol.constants import NotReadySubcode

API_TIMEOUT_S: Final = 1.0
"""The twin's control API answers at once; a slow one is skipped, not waited for."""


def not_ready_reason(st: Status) -> str:
    """``SUBCODE_NAME (code): meaning; what to do`` for a status without motion possible:
    the reason MotoROS would answer, with the remedy the reason declares."""
    if st.e_stopped:
        code = NotReadySubcode.ESTOP
    elif st.in_error:
        code = NotReadySubcode.ALARM
    elif st.mode is Mode.TEACH:
        code = NotReadySubcode.NOT_PLAY
    elif not st.drives_powered:
        code = NotReadySubcode.SERVO_OFF
    else:
        code = NotReadySubcode.NOT_STARTED
    alarm = f" ({st.error_code})" if code is NotReadySubcode.ALARM and st.error_code else ""
    return f"{code.name} ({int(code)}): {code.meaning}{alarm}; {code.remedy}"


def twin_alarm_texts(
    host: str,
    http_port: int | None,
    token: str | None = None,
    warn: Callable[[str], None] | None = None,
) -> dict[int, str]:
    """Alarm number -> pendant text from the twin's control API ({} when unknown), with
    its ``token`` when given. A refusal (401: the token; 403: the Host name) is told to
    ``warn`` (stderr by default): the alarm line alone would not say why its text is
    missing. An unreachable API is not (a real controller has none)."""
    if http_port is None:
        return {}
    from pymotoros.cli.sim_view import api_request, refusal_text

    url = f"http://{host}:{http_port}/api/state"
    try:
        with urllib.request.urlopen(api_request(url, token), timeout=API_TIMEOUT_S) as response:  # noqa: S310 - http
            data = json.loads(response.read())
    except urllib.error.HTTPError as exc:
        text = f"alarm texts not read: {refusal_text(url, exc, token)}"
        (warn or _to_stderr)(text)
        return {}
    except (OSError, urllib.error.URLError, ValueError):
        return {}
    alarms = data.get("alarms", []) if isinstance(data, dict) else []
    return {
        int(a["code"]): str(a.get("text", ""))
        for a in alarms
        if isinstance(a, dict) and isinstance(a.get("code"), int)
    }


def _to_stderr(text: str) -> None:
    print(text, file=sys.stderr)


class OnceWriter:
    """Writes each distinct text once to stderr (a ``--watch`` asks for the texts again
    at every frame with an alarm; its refusal need not scroll the screen)."""

    def __init__(self) -> None:
        self.told: set[str] = set()

    def tell_once(self, text: str) -> None:
        if text not in self.told:
            self.told.add(text)
            _to_stderr(text)


def alarm_line(st: Status, texts: dict[int, str]) -> str:
    """The alarm number with its text when known, else where to read it."""
    if not st.in_error:
        return "none"
    text = texts.get(st.error_code)
    return f"{st.error_code} {text}" if text else f"{st.error_code} (text on the pendant)"


class FrameWriter:
    """Show successive frames: redrawn in place with rich's Live on a terminal, else
    printed only when a frame differs from the previous one."""

    def __init__(self, stream: IO[str], *, live: bool) -> None:
        self._stream = stream
        self._last: str | None = None
        self._live: object | None = None
        self._update: Callable[[str], None] | None = None
        self.shown = 0
        if live:
            from rich.console import Console
            from rich.live import Live
            from rich.text import Text

            console = Console(file=stream, force_terminal=True)
            display = Live(Text(""), console=console, auto_refresh=False, transient=False)
            display.start()
            self._live = display

            def update(frame: str) -> None:
                display.update(Text(frame), refresh=True)

            self._update = update

    def show(self, frame: str) -> bool:
        """Show ``frame`` if it differs from the last; True when it was shown."""
        if frame == self._last:
            return False
        self._last = frame
        if self._update is not None:
            self._update(frame)
        else:
            self._stream.write(frame + "\n")
            self._stream.flush()
        self.shown += 1
        return True

    def close(self) -> None:
        if self._live is not None:
            from rich.live import Live

            if isinstance(self._live, Live):
                self._live.stop()
            self._live = None


__all__ = ["FrameWriter", "OnceWriter", "alarm_line", "not_ready_reason", "twin_alarm_texts"]
