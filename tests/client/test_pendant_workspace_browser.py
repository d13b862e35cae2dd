"""Issue 21 item 7: the web pendant draws the workspace, in a real headless browser.

Obstacles put through the control API appear in the 3D view beside the robot's
collision capsules; an obstacle the robot touches turns red (read from the page's
``window.pendant.scene`` and from the canvas's pixels). Screenshots go to a temporary
directory, or to ``$PYMOTOROS_SCREENSHOT_DIR`` when it is set.
"""

from __future__ import annotations

import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from client_sim import Sim, running_sim, sim_fixture
from headless import BROWSER_TEST, count_in_png, wait_for
from test_pendant_browser import _canvas_png, browser

from pymotoros.models import ROBOTS

webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed")

from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.remote.webdriver import WebDriver  # noqa: E402

__all__ = ["browser"]  # the module-scoped Chromium of test_pendant_browser

TABLE = {"name": "table", "box": [1.2, 0.8, 0.05], "xyz": [0.6, 0.0, -0.03]}
POST = {"name": "post", "cylinder": [0.05, 1.5], "xyz": [0.5, -0.5, 0.75]}
CRATE = {"name": "crate", "sphere": 0.12, "xyz": [0.0, 0.0, 0.975]}
"""Around the HC10's elbow at its zero pose (where the simulator boots): a contact."""
SCENE_JS = "return window.pendant.scene || null"
RED_PIXELS_JS = """
let red = 0;
for (let i = 0; i < d.length; i += 4) if (d[i] > 150 && d[i + 1] < 90 && d[i + 2] < 90) red++;
return red;
"""
MIN_RED_PIXELS = 200
"""A touched obstacle filled red covers far more than this; the robot and the grid have
no red at all."""

pytestmark = BROWSER_TEST
sim = sim_fixture("--robot", "hc10")


def _red_pixels(driver: WebDriver, png: bytes) -> int:
    return count_in_png(driver, png, RED_PIXELS_JS)


def _scene(driver: WebDriver) -> dict[str, Any] | None:
    scene: dict[str, Any] | None = driver.execute_script(SCENE_JS)
    return scene


def _obstacle(driver: WebDriver, name: str) -> dict[str, Any] | None:
    scene = _scene(driver)
    found = [o for o in (scene or {}).get("obstacles", []) if o["name"] == name]
    return found[0] if found else None


def test_the_pendant_draws_obstacles_capsules_and_a_contact_in_red(
    sim: Sim, browser: WebDriver, screenshot_dir: Path
) -> None:
    sim.api("/api/workspace", TABLE)
    sim.api("/api/workspace", POST)
    browser.get(f"http://127.0.0.1:{sim.http}/")
    wait_for(browser, lambda d: d.find_element(By.ID, "link").text == "live", "the live feed")
    wait_for(browser, lambda d: len((_scene(d) or {}).get("obstacles", [])) == 2, "two obstacles")
    scene = _scene(browser)
    assert scene is not None
    assert [(o["name"], o["shape"], o["contact"]) for o in scene["obstacles"]] == [
        ("table", "box", False),
        ("post", "cylinder", False),
    ]
    assert scene["capsules"] == len(ROBOTS["hc10"].groups[0].link_radii)  # base link and six links
    calm = _canvas_png(browser)
    assert _red_pixels(browser, calm) == 0
    assert browser.save_screenshot(str(screenshot_dir / "pendant-workspace.png"))

    # the crate appears on the elbow: the twin reports a contact, the page draws it red
    state = sim.api("/api/workspace", CRATE)
    assert [o["name"] for o in state["workspace"]["obstacles"]] == ["table", "post", "crate"]
    crate = wait_for(
        browser,
        lambda d: (o := _obstacle(d, "crate")) is not None and o["contact"] and o,
        "the crate drawn as touched",
    )
    assert crate["color"].startswith("rgba(235,50,50")
    table = _obstacle(browser, "table")
    assert table is not None
    assert not table["contact"]  # only what is touched turns red
    assert {c["obstacle"] for c in sim.api("/api/state")["workspace"]["contacts"]} == {"crate"}
    wait_for(
        browser,
        lambda d: _red_pixels(d, _canvas_png(d)) > MIN_RED_PIXELS,
        "red in the 3D view",
    )
    assert browser.save_screenshot(str(screenshot_dir / "pendant-workspace-contact.png"))

    # removed: gone from the scene
    request = urllib.request.Request(
        f"http://127.0.0.1:{sim.http}/api/workspace/crate", method="DELETE"
    )
    with urllib.request.urlopen(request, timeout=10) as response:  # noqa: S310
        assert response.status == 200
    wait_for(browser, lambda d: _obstacle(d, "crate") is None, "the crate gone from the view")


FIXTURE_CELL = (
    Path(__file__).resolve().parents[2] / "examples" / "cells" / "hc10_table_fixture.toml"
)
HC10_BASE_M = 0.275
"""The HC10's S-axis height: its base frame above base_link (robot model)."""


@pytest.fixture(scope="module")
def cell_sim() -> Iterator[Sim]:
    """The HC10 on a table with its gripper (tool 0: a 150 mm capsule of radius 40 mm)."""
    with running_sim("--config", str(FIXTURE_CELL)) as sim:
        yield sim


def test_the_pendant_draws_the_tool_in_force_and_the_frames(
    cell_sim: Sim, browser: WebDriver, screenshot_dir: Path
) -> None:
    """Issue 29 item 5: the 3D view draws the gripper (its shape as the contact check
    mounts it, and its TCP), so an obstacle touched by the tool is seen touching it; the
    obstacles' frame and the poses' frame are drawn and the pose readout names its frame."""
    browser.get(f"http://127.0.0.1:{cell_sim.http}/")
    wait_for(browser, lambda d: d.find_element(By.ID, "link").text == "live", "the live feed")
    scene = wait_for(
        browser, lambda d: (s := _scene(d)) is not None and s.get("tools") and s, "a tool"
    )
    [tool] = scene["tools"]
    assert (tool["group"], tool["number"], tool["name"], tool["shape"]) == (
        "R1", 0, "gripper", "capsule",
    )  # fmt: skip
    assert tool["size"] == pytest.approx([0.04, 0.15])  # workspace.tool_radius_m, tcp_m
    state = cell_sim.api("/api/state")
    x, y, z = state["groups"][0]["tcp"]["feedback"][:3]  # base coordinates
    assert tool["tcp"] == pytest.approx([x, y, z + HC10_BASE_M], abs=1e-3)  # drawn in base_link
    assert scene["frames"] == ["base_link R1 (obstacles)", "base R1 (poses, +0.275 m)"]
    pose = browser.execute_script('return document.querySelector("#groups .tcp-pose").textContent')
    assert pose.endswith("in base (0.275 m above base_link, the S-axis height)")

    # a probe at the gripper's TCP: the twin reports the tool touching it, the page
    # draws it red where the drawn tool ends
    probe = {"name": "probe", "sphere": 0.05, "xyz": tool["tcp"]}
    touched = cell_sim.api("/api/workspace", probe)["workspace"]["contacts"]
    assert {(c["obstacle"], c["link"]) for c in touched} == {("probe", "tool")}
    wait_for(
        browser,
        lambda d: (o := _obstacle(d, "probe")) is not None and o["contact"],
        "the probe drawn as touched",
    )

    def red_canvas(d: WebDriver) -> bytes | None:
        png = _canvas_png(d)
        return png if _red_pixels(d, png) > 0 else None

    png = wait_for(browser, red_canvas, "the touched probe drawn red")
    assert browser.save_screenshot(str(screenshot_dir / "pendant-tool.png"))
    (screenshot_dir / "pendant-tool-view.png").write_bytes(png)
