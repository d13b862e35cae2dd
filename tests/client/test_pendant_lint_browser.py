"""The pendant's client lint panel in a real headless browser: it shows a client's
finding (code, connection, remedy) and its Clear button empties it (issue 31)."""

from __future__ import annotations

import socket

import pytest
from client_sim import running_sim
from headless import NEEDS_CHROMIUM, headless_chromium, wait_for

from pymotoros.protocol.constants import ByteOrder
from pymotoros.protocol.framing import encode
from pymotoros.protocol.messages import MotoMotionCtrl

pytest.importorskip("selenium.webdriver", reason="selenium is not installed")

from selenium.webdriver.common.by import By
from selenium.webdriver.remote.webdriver import WebDriver

pytestmark = [pytest.mark.timeout(120), NEEDS_CHROMIUM]


def _panel(driver: WebDriver) -> str:
    return str(driver.find_element(By.ID, "lint-box").text)


def test_the_panel_shows_a_finding_and_clears_it() -> None:
    with running_sim() as sim, headless_chromium(window="1400,1000") as driver:
        driver.get(f"http://{sim.host}:{sim.http}/")
        wait_for(driver, lambda d: "none:" in _panel(d), "the empty panel")
        with socket.create_connection((sim.host, sim.motion), timeout=10) as sock:
            sock.sendall(encode(MotoMotionCtrl(0, 0, 200199, (0.0,) * 10), ByteOrder.LITTLE))
            sock.recv(1024)
        wait_for(driver, lambda d: "unknown-command" in _panel(d), "the finding on the page")
        text = _panel(driver)
        assert "stale-reply" in text
        assert "127.0.0.1:" in text
        assert "fix: Send only the commands of §3.1" in text
        driver.find_element(By.ID, "btn-lint-clear").click()
        wait_for(driver, lambda d: "none:" in _panel(d), "the panel cleared")
        assert sim.api("/api/lint") == {"findings": []}
