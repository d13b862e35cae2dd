"""The (result, subcode) → exception table: every code MotoROS sends has a class and remedy."""

from __future__ import annotations

import pytest

from pymotoros.client.errors import (
    INVALID_REMEDIES,
    NOT_READY_REMEDIES,
    BusyTimeoutError,
    CommandFailedError,
    InvalidRequestError,
    NotReadyError,
    SpeedLimitError,
    StartPositionError,
    io_error,
    reply_error,
)
from pymotoros.errors import PymotorosError
from pymotoros.protocol.constants import (
    InvalidSubcode,
    IoResultCode,
    MotionCommand,
    NotReadySubcode,
    ResultCode,
)


@pytest.mark.parametrize("sub", list(NotReadySubcode))
def test_every_not_ready_subcode(sub: NotReadySubcode) -> None:
    err = reply_error(ResultCode.NOT_READY, sub, MotionCommand.START_TRAJ_MODE)
    assert isinstance(err, NotReadyError)
    assert isinstance(err, PymotorosError)
    assert err.reason is sub
    assert sub.meaning in str(err)
    assert err.remedy == NOT_READY_REMEDIES[sub]
    assert str(int(sub)) in str(err)


def test_false_with_not_ready_subcode_is_not_ready() -> None:
    err = reply_error(ResultCode.FALSE, NotReadySubcode.HOLD, MotionCommand.CHECK_MOTION_READY)
    assert isinstance(err, NotReadyError)
    assert err.meaning.startswith("HOLD (5007)")


@pytest.mark.parametrize("sub", list(InvalidSubcode))
def test_every_invalid_subcode(sub: InvalidSubcode) -> None:
    err = reply_error(ResultCode.INVALID, sub, 14, point=3)
    assert isinstance(err, InvalidRequestError)
    expected = {
        InvalidSubcode.DATA_START_POS: StartPositionError,
        InvalidSubcode.DATA_SPEED: SpeedLimitError,
    }.get(sub, InvalidRequestError)
    assert type(err) is expected
    assert err.point == 3
    assert "point 3" in str(err)
    assert err.remedy == INVALID_REMEDIES[sub]


def test_busy_and_failure() -> None:
    assert isinstance(reply_error(ResultCode.BUSY, 0, 14), BusyTimeoutError)
    err = reply_error(ResultCode.FAILURE, 0, MotionCommand.STOP_TRAJ_MODE)
    assert isinstance(err, CommandFailedError)
    assert "STOP_TRAJ_MODE" in str(err)
    assert "queued" in err.remedy


def test_unknown_codes_still_read_well() -> None:
    err = reply_error(ResultCode.NOT_READY, 5099, 200121)
    assert isinstance(err, NotReadyError)
    assert err.reason is None
    assert "5099" in str(err)


@pytest.mark.parametrize("code", [c for c in IoResultCode if c])
def test_io_codes(code: IoResultCode) -> None:
    err = io_error(code, 10010, "IO write")
    assert err.result_code == code
    assert str(int(code)) in str(err)
    assert err.remedy
