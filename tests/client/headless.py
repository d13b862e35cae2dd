"""One way to start the headless Chromium the browser tests drive (Debian's chromium and
chromium-driver; `.ci/run` installs both).

Every non-loopback request goes to a closed proxy port, so a page that tries to reach
the internet fails visibly instead of working by luck; loopback bypasses the proxy.
"""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from selenium.webdriver.remote.webdriver import WebDriver

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
CHROMEDRIVER = shutil.which("chromedriver")
DEAD_PROXY = "127.0.0.1:9"
"""Every non-loopback request goes to this closed port (the discard port): blocked."""


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
