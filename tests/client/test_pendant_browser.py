"""The web pendant end to end in a real headless browser (Debian's Chromium + chromedriver,
driven by Selenium), with every non-local request blocked and recorded.

While the client streams a trajectory, the page's joint values change and match
``GET /api/state``; the 3D canvas is not blank and changes between two screenshots; the
page's E-STOP button stops the robot (light on, the client's move fails with a typed
:class:`~pymotoros.client.NotReadyError`); release and RESET recover. The two screenshots
go to a temporary directory, or to ``$PYMOTOROS_SCREENSHOT_DIR`` when it is set:
``python tools/pendant_screenshots.py`` sets it and copies them into ``docs/`` (the README
and docs/sim.md show them). A test run never writes into the checkout.
"""

from __future__ import annotations

import concurrent.futures
import json
import math
import re
from pathlib import Path
from urllib.parse import urlsplit

import pytest
from client_sim import Sim, running_sim, sim_fixture
from headless import BROWSER_TEST, WAIT_S, browser_fixture, count_in_png, wait_for

from pymotoros.client import NotReadyError, SyncRobotClient

webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed")

from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.remote.webdriver import WebDriver  # noqa: E402

SCREENSHOTS = ("pendant.png", "pendant-estop.png")
MOVING_TOLERANCE_DEG = 15.0
"""Page vs ``GET /api/state`` while moving: the two readings are up to ~0.3 s apart, at
most ~40 °/s at the test's speed scale."""
RESTING_TOLERANCE_DEG = 0.01
"""Page vs ``GET /api/state`` at rest: the same value shown with two decimals."""
GOAL = (1.2, 0.5, 0.6, 0.8, -1.2, 1.0)
LIGHT_ON_JS = 'return document.getElementById("estop-light").classList.contains("on")'
ANSWERED_JS = "return window.pendant.answeredAt"
STALE_FEED_JS = """
const p = window.pendant, stale = JSON.parse(JSON.stringify(p.last));
stale.estop = false;
stale.tick.count = p.answeredAt;
return p.fromFeed(stale);
"""
DISTINCT_COLOURS_JS = """
const seen = new Set();
for (let i = 0; i < d.length; i += 4) seen.add((d[i] << 16) | (d[i+1] << 8) | d[i+2]);
return seen.size;
"""
MIN_COLOURS = 20
"""A blank canvas has one colour; grid, links, joints and ghost give far more."""
PLOT_SAMPLES = 60
"""About 2.4 s of updates at 25 Hz before the screenshot, so the plots show a trend."""
SPEED_SCALE = 0.05
"""Slow enough that the move lasts about 12 s (S: 1.2 rad at 5 % of 130 °/s), so it is
still running when the page's E-STOP is clicked: the checks before it take 3-5 s on an
idle machine and were measured at over 4 s (the move's length at 15 %) with 8 processes
on 2 cores, which made the client's move end before the E-STOP."""
PLOT_MIN_SAMPLES = 10
"""Updates before the per-group plots are looked at: enough for a line to be drawn."""
MIN_PLOT_COLOURS = 4
"""A blank plot is one colour; a label and dashed and solid lines in joint colours give more."""
SDA10F_ECO_CELL = """
name = "SDA10F in eco mode: two arms and the two torso axes"

[controller]
model = "fs100"

[[groups]]
robot = "sda10f"

[initial]
servo = true
eco = true
"""

pytestmark = BROWSER_TEST
sim = sim_fixture()
browser = browser_fixture(window="1500,1150", logs={"performance": "ALL"})


def _requested_urls(driver: WebDriver) -> list[str]:
    urls = []
    for entry in driver.get_log("performance"):
        message = json.loads(entry["message"])["message"]
        if message.get("method") in ("Network.requestWillBeSent", "Network.webSocketCreated"):
            params = message["params"]
            urls.append(params.get("request", {}).get("url") or params.get("url", ""))
    return urls


def _non_local(urls: list[str]) -> list[str]:
    return [
        u
        for u in urls
        if not u.startswith(("data:", "blob:", "about:"))
        and urlsplit(u).hostname not in ("127.0.0.1", "localhost")
    ]


def _page_feedback_deg(driver: WebDriver) -> list[float]:
    """The first group's feedback as the page shows it (read in one script: the table is
    redrawn at every update, so element handles go stale)."""
    texts = driver.execute_script(
        'return Array.from(document.querySelectorAll("#groups table.joints td.fb"))'
        ".slice(0, 6).map((c) => c.textContent);"
    )
    return [float(t) for t in texts]


def _api_feedback_deg(sim: Sim) -> list[float]:
    return [math.degrees(v) for v in sim.api("/api/state")["groups"][0]["feedback_rad"]]


def _canvas_png(driver: WebDriver) -> bytes:
    return driver.find_element(By.ID, "view3d").screenshot_as_png


def _colours(driver: WebDriver, png: bytes) -> int:
    """Distinct colours in a PNG."""
    return count_in_png(driver, png, DISTINCT_COLOURS_JS)


def test_pendant_in_a_real_browser_offline(
    sim: Sim, browser: WebDriver, screenshot_dir: Path
) -> None:
    url = f"http://127.0.0.1:{sim.http}/"
    robot = SyncRobotClient(**sim.client_options())
    pool = concurrent.futures.ThreadPoolExecutor(1)
    try:
        robot.connect()
        robot.enable()
        move = pool.submit(robot.move_joints, GOAL, speed_scale=SPEED_SCALE)

        browser.get(url)
        wait_for(browser, lambda d: d.find_element(By.ID, "link").text == "live", "the live feed")
        wait_for(browser, lambda d: any(abs(v) > 1.0 for v in _page_feedback_deg(d)), "motion")

        # the page's joint values change and match GET /api/state
        first = _page_feedback_deg(browser)
        api = _api_feedback_deg(sim)
        assert max(abs(a - b) for a, b in zip(first, api, strict=True)) < MOVING_TOLERANCE_DEG
        wait_for(browser, lambda d: _page_feedback_deg(d) != first, "joint values to change")

        # the 3D view renders and moves
        shot_a = _canvas_png(browser)
        wait_for(browser, lambda d: _canvas_png(d) != shot_a, "the 3D view to change")
        assert (
            _colours(browser, _canvas_png(browser)) > MIN_COLOURS
        )  # not blank: floor grid, links, ghost
        wait_for(  # a few seconds of plot history for the screenshot
            browser,
            lambda d: d.execute_script("return window.pendant.history.length") >= PLOT_SAMPLES,
            "plot history",
        )
        assert browser.save_screenshot(str(screenshot_dir / SCREENSHOTS[0]))

        # E-STOP from the page: the light, the state, the client's typed error
        browser.find_element(By.ID, "btn-estop").click()
        wait_for(
            browser,
            lambda d: d.execute_script(LIGHT_ON_JS),
            "the E-stop light",
        )
        assert browser.find_element(By.ID, "st-estop").text == "PRESSED"
        # a feed document captured before the press but sent after the button's answer
        # must not switch the light off again
        wait_for(browser, lambda d: d.execute_script(ANSWERED_JS) >= 0, "the button's answer")
        assert browser.execute_script(STALE_FEED_JS) is False
        assert browser.find_element(By.ID, "st-estop").text == "PRESSED"
        assert browser.execute_script(LIGHT_ON_JS)
        assert sim.api("/api/state")["estop"] is True
        with pytest.raises(NotReadyError) as info:
            move.result(WAIT_S)
        assert "E-stop" in str(info.value) or "estop" in str(info.value).lower()
        # at rest the page and the API agree to the displayed two decimals
        wait_for(
            browser,
            lambda d: (
                max(
                    abs(a - b)
                    for a, b in zip(_page_feedback_deg(d), _api_feedback_deg(sim), strict=True)
                )
                <= RESTING_TOLERANCE_DEG
            ),
            "page and API to agree at rest",
        )
        assert browser.save_screenshot(str(screenshot_dir / SCREENSHOTS[1]))

        # release, RESET, and the client moves again
        browser.find_element(By.ID, "btn-estop").click()
        wait_for(browser, lambda d: d.find_element(By.ID, "st-estop").text == "released", "release")
        browser.find_element(By.ID, "btn-reset").click()
        wait_for(browser, lambda d: sim.api("/api/state")["alarms"] == [], "alarms cleared")
        robot.enable()
        result = robot.move_joints((0.0,) * 6, speed_scale=0.5)
        assert result is not None
        assert max(abs(v) for v in _api_feedback_deg(sim)) < 0.1

        assert _non_local(_requested_urls(browser)) == []
        logs = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
        assert logs == [], logs
        for name in SCREENSHOTS:
            assert (screenshot_dir / name).read_bytes().startswith(b"\x89PNG"), name
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        robot.close()


def test_every_group_has_its_live_plot_and_eco_mode_shows(
    browser: WebDriver, tmp_path: Path
) -> None:
    """A multi-group cell (SDA10F) gets one command-vs-feedback plot per group, each
    drawn; the controller state shows eco mode, and its end when servo power goes off."""
    cell = tmp_path / "sda10f_eco.toml"
    cell.write_text(SDA10F_ECO_CELL)
    with running_sim("--config", str(cell)) as sim:
        groups = [g["name"] for g in sim.api("/api/state")["groups"]]
        assert len(groups) > 1
        browser.get(f"http://127.0.0.1:{sim.http}/")
        wait_for(browser, lambda d: d.find_element(By.ID, "link").text == "live", "the live feed")
        wait_for(
            browser,
            lambda d: d.execute_script("return window.pendant.history.length") >= PLOT_MIN_SAMPLES,
            "plot history",
        )
        plots = browser.execute_script(
            'return Array.from(document.querySelectorAll("#plot-groups canvas.plot-joints"))'
            ".map((c) => c.id);"
        )
        assert plots == [f"plot-joints-{i}" for i in range(len(groups))]
        for plot in plots:
            png = browser.find_element(By.ID, plot).screenshot_as_png
            assert _colours(browser, png) >= MIN_PLOT_COLOURS, plot
        assert "ECO" in browser.find_element(By.ID, "st-eco").text
        sim.api("/api/servo", {"on": False})
        wait_for(browser, lambda d: d.find_element(By.ID, "st-eco").text == "off", "eco mode off")
        assert _non_local(_requested_urls(browser)) == []


def test_non_local_requests_are_blocked(sim: Sim, browser: WebDriver) -> None:
    """The blocking the offline test relies on is real: a fetch to the internet fails."""
    browser.get(f"http://127.0.0.1:{sim.http}/")
    outcome = browser.execute_async_script(
        """
        const done = arguments[arguments.length - 1];
        fetch("http://example.com/").then(() => done("reached"), (e) => done("blocked: " + e));
        """
    )
    assert str(outcome).startswith("blocked")
    assert _non_local(_requested_urls(browser)) == ["http://example.com/"]


RECORD_PLOT_TEXT_JS = """
window.plotTexts = {};
const original = CanvasRenderingContext2D.prototype.fillText;
CanvasRenderingContext2D.prototype.fillText = function (text, x, y, ...rest) {
  const id = this.canvas.id;
  if (id.startsWith("plot-")) {
    (window.plotTexts[id] = window.plotTexts[id] || new Set()).add(String(text));
  }
  return original.call(this, text, x, y, ...rest);
};
"""
PLOT_TEXTS_JS = """
const out = {};
for (const [id, texts] of Object.entries(window.plotTexts || {})) out[id] = Array.from(texts);
return out;
"""


def test_plots_have_ticks_units_and_a_joint_legend(sim: Sim, browser: WebDriver) -> None:
    """Each plot draws value ticks, time ticks in seconds, its unit and a legend naming
    every joint (the texts the page draws on the canvases, recorded as it draws them)."""
    browser.get(f"http://127.0.0.1:{sim.http}/")
    wait_for(browser, lambda d: d.find_element(By.ID, "link").text == "live", "the live feed")
    browser.execute_script(RECORD_PLOT_TEXT_JS)
    wait_for(
        browser,
        lambda d: {"plot-joints-0", "plot-lateness"} <= set(d.execute_script(PLOT_TEXTS_JS)),
        "the plots to be redrawn",
    )
    texts = browser.execute_script(PLOT_TEXTS_JS)
    joints = texts["plot-joints-0"]
    names = sim.api("/api/state")["groups"][0]["joint_names"]
    assert set(names) <= set(joints), joints  # the legend
    assert any("(rad)" in t for t in joints), joints  # the unit
    value_ticks = [t for t in joints if re.fullmatch(r"−?-?\d+(\.\d+)?", t)]
    assert len(value_ticks) >= 3, joints
    assert {"now", "−2 s", "−10 s"} <= set(joints), joints  # time ticks
    lateness = texts["plot-lateness"]
    assert any("(ms)" in t for t in lateness), lateness
    assert len([t for t in lateness if re.fullmatch(r"-?\d+(\.\d+)?", t)]) >= 2, lateness
    assert "−4 s" in lateness, lateness
