"""One way to start the headless Chromium the browser tests drive (Debian's chromium and
chromium-driver; `.ci/run` installs both).

Every non-loopback request goes to a closed proxy port, so a page that tries to reach
the internet fails visibly instead of working by luck; loopback bypasses the proxy.
"""

from __future__ import annotations

import shutil
from base64 import b64encode
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

import pytest

if TYPE_CHECKING:
    from selenium.webdriver.remote.webdriver import WebDriver

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
CHROMEDRIVER = shutil.which("chromedriver")
DEAD_PROXY = "127.0.0.1:9"
"""Every non-loopback request goes to this closed port (the discard port): blocked."""
WAIT_S = 20.0
"""Bound on every wait for the page (a cold Chromium start on a busy 2-core machine)."""
NEEDS_CHROMIUM = pytest.mark.skipif(
    CHROMIUM is None or CHROMEDRIVER is None,
    reason="chromium and chromium-driver are not installed (.ci/run installs them)",
)
BROWSER_TEST = [pytest.mark.timeout(180), NEEDS_CHROMIUM]
"""The ``pytestmark`` of a browser test module: a Chromium start and a simulator take
a while on a busy machine; without Chromium the module is skipped, saying why."""


def browser_fixture(*, window: str | None = None, logs: dict[str, str] | None = None) -> Any:
    """A module-scoped ``browser`` fixture: one :func:`headless_chromium` per module."""

    @pytest.fixture(scope="module")
    def browser() -> Iterator[WebDriver]:
        with headless_chromium(window=window, logs=logs) as driver:
            yield driver

    return browser


def wait_for(
    driver: WebDriver,
    condition: Callable[[WebDriver], Any],
    what: str,
    *,
    timeout_s: float = WAIT_S,
    poll_s: float = 0.05,
) -> Any:
    """``condition``'s first truthy value, polled in the page; fails naming ``what``."""
    from selenium.webdriver.support.ui import WebDriverWait

    return WebDriverWait(driver, timeout_s, poll_frequency=poll_s).until(condition, what)


@contextmanager
def headless_chromium(
    *, window: str | None = None, logs: dict[str, str] | None = None
) -> Iterator[WebDriver]:
    """A Chromium WebDriver (``window``: "W,H"; ``logs``: goog:loggingPrefs), quit on exit."""
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    options = Options()
    options.binary_location = str(CHROMIUM)
    args = [
        "--headless=new",
        "--no-sandbox",
        "--disable-dev-shm-usage",
        "--disable-gpu",
        f"--proxy-server={DEAD_PROXY}",  # loopback bypasses the proxy; nothing else gets out
        "--disable-background-networking",
        "--disable-component-update",
        "--no-first-run",
    ]
    if window is not None:
        args.append(f"--window-size={window}")
    for arg in args:
        options.add_argument(arg)
    if logs is not None:
        options.set_capability("goog:loggingPrefs", logs)
    driver = webdriver.Chrome(options=options, service=Service(str(CHROMEDRIVER)))
    try:
        yield driver
    finally:
        driver.quit()


PNG_PIXELS_JS = """
const done = arguments[arguments.length - 1];
const img = new Image();
img.onload = () => {
  const c = document.createElement("canvas");
  c.width = img.width; c.height = img.height;
  const ctx = c.getContext("2d"); ctx.drawImage(img, 0, 0);
  const d = ctx.getImageData(0, 0, c.width, c.height).data;
  done((() => { COUNT })());
};
img.src = "data:image/png;base64," + arguments[0];
"""


def count_in_png(driver: WebDriver, png: bytes, count_js: str) -> int:
    """A number counted by ``count_js`` (a function body over ``d``, the RGBA bytes) in a
    PNG decoded by the browser itself: no imaging library."""
    script = PNG_PIXELS_JS.replace("COUNT", count_js)
    return int(driver.execute_async_script(script, b64encode(png).decode()))
