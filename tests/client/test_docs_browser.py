"""The control API's ``/docs`` (swagger-ui) and ``/redoc`` (ReDoc) pages render in a real
headless browser, offline: Debian's Chromium through chromedriver, every non-loopback
request sent to a closed port and recorded.

"Render" means the operations are listed in the page's DOM (``POST`` next to
``/api/estop``, ``GET`` next to ``/api/state``), which swagger-ui 4 never reached with
FastAPI's OpenAPI 3.1 document ("Unable to render this definition"); the assets merely
being served proves nothing.
"""

from __future__ import annotations

import json
from urllib.parse import urlsplit

import pytest
from client_sim import Sim, sim_fixture
from headless import BROWSER_TEST, browser_fixture, wait_for

webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed")

from selenium.webdriver.remote.webdriver import WebDriver  # noqa: E402

WAIT_S = 30.0
"""Bound on the wait for a page to render (a cold Chromium on a busy 2-core machine)."""

pytestmark = BROWSER_TEST
sim = sim_fixture()
browser = browser_fixture(window="1300,1000", logs={"performance": "ALL", "browser": "ALL"})


def _requests_that_left(driver: WebDriver) -> list[str]:
    """Non-loopback URLs the page asked for, less those the browser refused to request
    because the page's Content-Security-Policy forbids them (ReDoc's sidebar names a
    logo on its maker's CDN: refused, not fetched)."""
    asked: dict[str, str] = {}
    refused: set[str] = set()
    for entry in driver.get_log("performance"):
        message = json.loads(entry["message"])["message"]
        params = message.get("params", {})
        if message.get("method") == "Network.requestWillBeSent":
            asked[params["requestId"]] = params["request"]["url"]
        elif (
            message.get("method") == "Network.loadingFailed"
            and params.get("blockedReason") == "csp"
        ):
            refused.add(params["requestId"])
    return [
        u
        for rid, u in asked.items()
        if rid not in refused
        and not u.startswith(("data:", "blob:", "about:"))
        and urlsplit(u).hostname not in ("127.0.0.1", "localhost")
    ]


def _operations(driver: WebDriver, selector: str, method: str, path: str) -> list[str]:
    """The texts of the rendered operation blocks (``selector``) that show both the HTTP
    method and the path (read in one script: the page re-renders as it loads)."""
    texts: list[str] = driver.execute_script(
        "return Array.from(document.querySelectorAll(arguments[0]))"
        ".map((e) => e.innerText || e.textContent || '');",
        selector,
    )
    return [t for t in texts if method in t.upper() and path in t]


def _render(driver: WebDriver, url: str, selector: str) -> None:
    driver.get(url)
    wait_for(
        driver,
        lambda d: _operations(d, selector, "POST", "/api/estop"),
        f"{url}: the operation POST /api/estop to be listed",
        timeout_s=WAIT_S,
        poll_s=0.1,
    )


def test_swagger_ui_lists_the_operations_offline(sim: Sim, browser: WebDriver) -> None:
    _render(browser, f"http://127.0.0.1:{sim.http}/docs", ".opblock-summary")
    assert _operations(browser, ".opblock-summary", "GET", "/api/state")
    body = browser.execute_script("return document.body.innerText")
    assert "Unable to render" not in body
    assert "valid version field" not in body
    assert "pymotoros control API" in body
    assert _requests_that_left(browser) == []


def test_redoc_lists_the_operations_offline(sim: Sim, browser: WebDriver) -> None:
    # ReDoc renders each operation as a section with the method badge and the path
    _render(browser, f"http://127.0.0.1:{sim.http}/redoc", "[data-section-id]")
    assert _operations(browser, "[data-section-id]", "GET", "/api/state")
    body = browser.execute_script("return document.body.innerText")
    assert "pymotoros control API" in body
    assert "Something went wrong" not in body
    assert _requests_that_left(browser) == []
