"""The web pendant of a twin started with ``--token``, in a real headless browser: the
page asks for the token once (a prompt), keeps it in ``sessionStorage``, and then the
live feed and the buttons work; a reload asks nothing (issue 23, item 5)."""

from __future__ import annotations

import json
import urllib.request
from typing import Any

import pytest
from client_sim import Sim, sim_fixture
from headless import BROWSER_TEST, browser_fixture, wait_for

webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed")
from selenium.common.exceptions import NoAlertPresentException  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.remote.webdriver import WebDriver  # noqa: E402
from selenium.webdriver.support import expected_conditions  # noqa: E402

TOKEN = "browser-test-token"  # noqa: S105 - a test token

pytestmark = BROWSER_TEST
sim = sim_fixture("--token", TOKEN)
browser = browser_fixture()


def api_state(sim: Sim) -> dict[str, Any]:
    request = urllib.request.Request(
        f"http://127.0.0.1:{sim.http}/api/state", headers={"Authorization": f"Bearer {TOKEN}"}
    )
    with urllib.request.urlopen(request, timeout=10) as response:  # noqa: S310
        result: dict[str, Any] = json.loads(response.read())
        return result


def test_the_pendant_asks_once_and_keeps_the_token(sim: Sim, browser: WebDriver) -> None:
    browser.get(f"http://127.0.0.1:{sim.http}/")
    alert = wait_for(browser, expected_conditions.alert_is_present(), "the token prompt")
    assert "token" in alert.text
    alert.send_keys(TOKEN)
    alert.accept()
    wait_for(browser, lambda d: d.find_element(By.ID, "link").text == "live", "the live feed")
    stored = browser.execute_script('return sessionStorage.getItem("pymotoros-token")')
    assert stored == TOKEN
    assert api_state(sim)["hold"] is False
    browser.find_element(By.ID, "btn-hold").click()  # a POST through the token
    wait_for(browser, lambda _: api_state(sim)["hold"] is True, "HOLD pressed from the page")
    # a reload in the same tab asks nothing: the session keeps the token
    browser.refresh()
    wait_for(browser, lambda d: d.find_element(By.ID, "link").text == "live", "the feed again")
    with pytest.raises(NoAlertPresentException):
        browser.switch_to.alert.text  # noqa: B018 - raises when no prompt is open


def test_the_docs_page_offers_to_send_the_token(sim: Sim, browser: WebDriver) -> None:
    """The OpenAPI document declares the bearer scheme (issue 28): swagger-ui shows its
    Authorize button, whose dialog takes the token for "Try it out"."""
    browser.get(f"http://localhost:{sim.http}/docs")  # another of the twin's own names
    button = wait_for(
        browser,
        expected_conditions.element_to_be_clickable((By.CSS_SELECTOR, "button.authorize")),
        "the Authorize button",
    )
    button.click()
    dialog = wait_for(
        browser,
        expected_conditions.visibility_of_element_located((By.CSS_SELECTOR, ".auth-container")),
        "the authorization dialog",
    )
    assert "bearerAuth" in dialog.text
    assert "bearer" in dialog.text.lower()
