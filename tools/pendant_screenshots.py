"""Regenerate the web pendant's screenshots in docs/ (docs/pendant.png, docs/pendant-estop.png).

Usage, from the repository root (needs Chromium, chromedriver and selenium, as the
browser test does)::

    python tools/pendant_screenshots.py

It runs the browser test tests/client/test_pendant_browser.py (a simulator, a client
streaming a trajectory, the page's E-STOP), which saves its two screenshots into
``$PYMOTOROS_SCREENSHOT_DIR``; the directory is a temporary one, and only when the test
passes are the pictures copied into docs/. An ordinary test run writes them into its
own temporary directory and never touches docs/.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TEST = "tests/client/test_pendant_browser.py::test_pendant_in_a_real_browser_offline"
SCREENSHOTS = ("pendant.png", "pendant-estop.png")


def main() -> int:
    with tempfile.TemporaryDirectory(prefix="pendant-shots-") as out:
        env = dict(os.environ, PYMOTOROS_SCREENSHOT_DIR=out)
        env.pop("CI", None)  # a tool run, not CI: a missing browser skips, saying why
        done = subprocess.run(  # noqa: S603 - this interpreter, fixed arguments
            [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", TEST],
            cwd=ROOT,
            env=env,
            check=False,
        )
        made = [Path(out) / name for name in SCREENSHOTS]
        missing = [p.name for p in made if not p.is_file()]
        if done.returncode != 0 or missing:
            sys.stderr.write(
                f"pendant_screenshots: the browser test did not pass (exit {done.returncode}); "
                f"missing: {missing or 'none'}; docs/ left as it was\n"
            )
            return 1
        for path in made:
            shutil.copyfile(path, ROOT / "docs" / path.name)
            sys.stdout.write(f"wrote docs/{path.name}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
