"""The replies MotoROS commands share: an :class:`~pymotoros.controller.api.Outcome` builder."""

from __future__ import annotations

from typing import Final

from pymotoros.controller.api import Outcome
from pymotoros.protocol.constants import ResultCode


def reply(
    result: ResultCode,
    subcode: int = 0,
    detail: str = "",
    *,
    group_no: int | None = None,
    close_connection: bool = False,
) -> Outcome:
    return Outcome(
        result, subcode, group_no=group_no, close_connection=close_connection, detail=detail
    )


SUCCESS: Final = Outcome(ResultCode.SUCCESS)
FAILURE: Final = Outcome(ResultCode.FAILURE)


def invalid(subcode: int, detail: str, group_no: int | None = None) -> Outcome:
    """3000 INVALID with ``subcode``: the request itself is wrong (§3.1 subcodes)."""
    return Outcome(ResultCode.INVALID, subcode, group_no=group_no, detail=detail)
