"""IO rules of reference §6.1–§6.3, for every controller's address map."""

from __future__ import annotations

from pathlib import Path

import pytest

from pymotoros.controller import VirtualController, default_cell
from pymotoros.controller.signals import (
    CONNECT_SERVER_RUNNING,
    FAILURE,
    INIT_DONE,
    IO_SERVER_CONNECTED,
    MOTION_SERVER_CONNECTED,
    ROS_DONE,
    ROS_READY,
    STATE_SERVER_CONNECTED,
    universal_output,
)
from pymotoros.models import CONTROLLERS, ControllerType
from pymotoros.protocol.constants import IoResultCode as Io

AREAS = Path(__file__).with_name("io_areas.txt")
"""The IO areas of reference §6.2, a row per area: first-last address per controller."""


def _ranges(table: str) -> dict[str, list[tuple[int, int, bool]]]:
    """(first, last, writable) per controller, from a table such as AREAS."""
    lines = [line for line in table.splitlines() if line.strip() and not line.startswith("#")]
    header, *rows = lines
    controllers = header.split()[1:]
    ranges: dict[str, list[tuple[int, int, bool]]] = {c: [] for c in controllers}
    for row in rows:
        writable, *spans = row.split()
        for controller, span in zip(controllers, spans, strict=True):
            first, last = span.split("-")
            ranges[controller].append((int(first), int(last), writable == "yes"))
    return ranges


RANGES = _ranges(AREAS.read_text(encoding="utf-8"))


def vc_for(controller: str) -> VirtualController:
    return VirtualController(default_cell(controller))


def test_every_controller_is_covered() -> None:
    assert set(RANGES) == {t.value for t in ControllerType} == {t.value for t in CONTROLLERS}


@pytest.mark.parametrize("controller", list(RANGES))
def test_bit_ranges(controller: str) -> None:
    vc = vc_for(controller)
    ranges = RANGES[controller]
    for first, last, writable in ranges:
        for address in (first, last, first + 7):
            assert vc.read_io_bit(address).result_code == Io.OK, address
            code = vc.write_io_bit(address, 1)
            assert code == (Io.OK if writable else Io.WRITE_ADDRESS_INVALID), address
            if writable:
                assert vc.read_io_bit(address).value == 1
        # bit digits 8 and 9 never exist; the byte after the range does not either
        # (unless the next range starts right there)
        candidates = [first - 1, last + 1, first + 8, first + 9]
        after = last + 3
        if not any(f <= after <= la for f, la, _ in ranges):
            candidates.append(after)
        for outside in candidates:
            assert vc.read_io_bit(outside).result_code == Io.READ_ADDRESS_INVALID, outside
            assert vc.write_io_bit(outside, 1) == Io.WRITE_ADDRESS_INVALID, outside


def test_write_bit_checks_address_before_value() -> None:
    vc = vc_for("yrc1000")
    assert vc.write_io_bit(10010, 2) == Io.WRITE_VALUE_INVALID
    assert vc.write_io_bit(10, 2) == Io.WRITE_ADDRESS_INVALID
    assert vc.write_io_bit(10018, 1) == Io.WRITE_ADDRESS_INVALID
    assert vc.read_io_bit(10018).value == 0


def test_groups_lsb_first() -> None:
    vc = vc_for("yrc1000")
    assert vc.write_io_group(1001, 0b1010_0101) == Io.OK
    assert [vc.read_io_bit(10010 + k).value for k in range(8)] == [1, 0, 1, 0, 0, 1, 0, 1]
    assert vc.read_io_group(1001).value == 0b1010_0101
    assert vc.write_io_group(1001, 256) == Io.WRITE_VALUE_INVALID
    assert vc.write_io_group(1, 1) == Io.WRITE_ADDRESS_INVALID  # general input
    assert vc.read_io_group(1).result_code == Io.OK
    assert vc.read_io_group(9000).result_code == Io.READ_ADDRESS_INVALID
    assert vc.read_io_group(-1).result_code == Io.READ_ADDRESS_INVALID
    assert vc.write_io_group(6001, 255) == Io.OK  # interface panel
    assert vc.write_io_group(2701, 7) == Io.OK  # network input


@pytest.mark.parametrize("controller", list(RANGES))
def test_m_registers(controller: str) -> None:
    vc = vc_for(controller)
    assert vc.write_mregister(0, 0xFFFF) == Io.OK
    assert vc.read_mregister(1_000_000).value == 0xFFFF  # n and 1000000 + n are the same
    assert vc.write_mregister(1_000_559, 7) == Io.OK
    assert vc.read_mregister(559).value == 7
    assert vc.write_mregister(560, 1) == Io.WRITE_ADDRESS_INVALID
    assert vc.write_mregister(0, 0x10000) == Io.WRITE_VALUE_INVALID
    assert vc.write_mregister(560, 0x10000) == Io.WRITE_ADDRESS_INVALID
    assert vc.read_mregister(999).result_code == Io.OK
    assert vc.read_mregister(1000).result_code == Io.READ_ADDRESS_INVALID
    assert vc.read_mregister(1_001_000).result_code == Io.READ_ADDRESS_INVALID


def test_api_failures() -> None:
    vc = vc_for("yrc1000")
    vc.set_io_api_failure(reads=True, writes=True)
    assert vc.read_io_bit(10010).result_code == Io.READ_API_ERROR
    assert vc.read_io_bit(10018).result_code == Io.READ_ADDRESS_INVALID  # address first
    assert vc.write_io_bit(10010, 1) == Io.WRITE_API_ERROR
    assert vc.read_io_group(1001).result_code == Io.READ_API_ERROR
    assert vc.write_io_group(1001, 1) == Io.WRITE_API_ERROR
    assert vc.read_mregister(5).result_code == Io.READ_API_ERROR
    assert vc.write_mregister(5, 1) == Io.WRITE_API_ERROR
    vc.set_io_api_failure()
    assert vc.write_io_bit(10010, 1) == Io.OK


def test_feedback_outputs() -> None:
    assert universal_output(889) == ROS_READY == 11120
    assert universal_output(896) == FAILURE == 11127
    vc = vc_for("yrc1000")
    get = vc.io.get
    assert (get(INIT_DONE), get(CONNECT_SERVER_RUNNING), get(FAILURE)) == (1, 1, 0)
    assert (get(ROS_READY), get(ROS_DONE), get(MOTION_SERVER_CONNECTED)) == (0, 0, 0)
    vc.motion_connected()
    assert get(MOTION_SERVER_CONNECTED) == 1
    vc.motion_disconnected()
    assert get(MOTION_SERVER_CONNECTED) == 0
    vc.state_clients_changed(2)
    assert get(STATE_SERVER_CONNECTED) == 1
    vc.state_clients_changed(0)
    assert get(STATE_SERVER_CONNECTED) == 0
    vc.io_connected()
    assert get(IO_SERVER_CONNECTED) == 1  # never cleared again
    assert vc.read_io_bit(IO_SERVER_CONNECTED).value == 1


def test_force_io_rules() -> None:
    vc = vc_for("yrc1000")
    vc.force_io(10, 1)  # an input: only the operator can set it
    assert vc.read_io_bit(10).value == 1
    vc.force_io(1_000_999, 65535)
    assert vc.read_mregister(999).value == 65535
    for address, value in ((18, 1), (10, 2), (1_001_000, 1), (1_000_000, 70000), (95000, 1)):
        with pytest.raises(ValueError, match=r"\d"):
            vc.force_io(address, value)


def test_forcing_an_estop_input_presses_the_estop() -> None:
    vc = vc_for("yrc1000")
    vc.force_io(80025, 0)
    assert vc.snapshot().estop
    assert vc.read_io_bit(80025).value == 0
    vc.force_io(80025, 1)
    assert not vc.snapshot().estop
