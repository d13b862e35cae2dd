"""Tags on the client's log records, for a front end that words them its own way.

A library user sees the client's notes and stop reports as ordinary log records (a
warning for a note). A front end that talks to a person (the CLI) prints a record tagged
:data:`NOTE` as a plain ``note: …`` line instead of a timestamped log line, and drops a
record tagged :data:`STOP_REPORT`, because it says where the robot stopped in its own
message (otherwise the position would be printed twice).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

NOTE: Final = "pymotoros_note"
"""Record attribute: a note for the person at the robot (a move allowed with a remark)."""

STOP_REPORT: Final = "pymotoros_stop_report"
"""Record attribute: where a stopped move left the robot, also said by the error (or by
the front end that cancelled the move)."""

AS_NOTE: Final[Mapping[str, object]] = {NOTE: True}
"""``extra=`` of a note's log call."""

AS_STOP_REPORT: Final[Mapping[str, object]] = {STOP_REPORT: True}
"""``extra=`` of a successful early stop's log call."""
