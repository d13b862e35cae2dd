"""The pendant's actions come from the declarations (issue 19 item 1), in a real browser:
the page reads ``GET /api/pendant/actions``, its number inputs take their limits from
it, and its "Action" picker runs any declared action, a refusal shown in the control
API's words (Debian's Chromium + chromedriver, driven by Selenium)."""

from __future__ import annotations

import pytest
from client_sim import Sim, sim_fixture
from headless import BROWSER_TEST, browser_fixture, wait_for

webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed")

from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.remote.webdriver import WebDriver  # noqa: E402
from selenium.webdriver.support.ui import Select  # noqa: E402

pytestmark = BROWSER_TEST
sim = sim_fixture()
browser = browser_fixture()


def _run(browser: WebDriver, action: str, params: str) -> None:
    Select(browser.find_element(By.ID, "action-name")).select_by_value(action)
    box = browser.find_element(By.ID, "action-params")
    box.clear()
    box.send_keys(params)
    browser.find_element(By.ID, "btn-action").click()


def test_the_pendants_actions_are_the_declared_ones(sim: Sim, browser: WebDriver) -> None:
    browser.get(f"http://127.0.0.1:{sim.http}/")
    wait_for(browser, lambda d: d.find_elements(By.ID, "action-name"), "the action picker")
    listed = browser.execute_script("return Object.keys(window.pendant.actions)")
    assert listed == [a["name"] for a in sim.api("/api/pendant/actions")]
    assert {"estop", "eco", "io_failure", "drop_motion"} <= set(listed)
    # the inputs' limits are the declarations'
    assert browser.find_element(By.ID, "alarm-code").get_attribute("max") == "9999"
    assert browser.find_element(By.ID, "fsu-pct").get_attribute("min") == "1"
    # any declared action runs from the picker
    _run(browser, "hold", '{"on": true}')
    wait_for(browser, lambda d: sim.api("/api/state")["hold"] is True, "HOLD from the picker")
    # a refused value is shown in the words every surface uses
    _run(browser, "fsu", '{"tcp_speed_mm_s": 0}')
    words = "POST /api/fsu: tcp_speed_mm_s: must be > 0 mm/s, not 0"
    wait_for(browser, lambda d: d.find_element(By.ID, "message").text == words, "the refusal")
    _run(browser, "hold", '{"on": false}')
    wait_for(browser, lambda d: sim.api("/api/state")["hold"] is False, "HOLD off")
