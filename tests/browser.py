"""Headless Chromium for the tests of the interactive view (tests/plot/test_interactive.py),
and the screenshot of the view in docs/figures/view.png.

The browser is Debian's Chromium and its ChromeDriver (``apt-get install -y chromium
chromium-driver``; .ci/run installs them), driven by selenium with the driver's path given,
so selenium never looks for or downloads a browser or a driver of its own. Chromium starts
with a fresh profile and its background network traffic off: the tests need no network.

Make the screenshot (from the checkout's root; it runs a scene for a few seconds)::

    python -m tests.browser docs/figures/view.png
"""

from __future__ import annotations

import shutil
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

#: The switches Chromium starts with: headless, no sandbox (CI runs as root), and nothing
#: that reaches for the network on its own.
CHROMIUM_SWITCHES = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-dev-shm-usage",
    "--hide-scrollbars",
)
#: How to install the browser (README.md, "Interactive view"; .ci/run).
INSTALL = "apt-get install -y chromium chromium-driver"


def missing() -> str | None:
    """Why the browser cannot be started here (None when it can)."""
    try:
        import selenium  # noqa: F401
    except ImportError:
        return "the Python package selenium is not installed (pip install -e '.[test]')"
    absent = [name for name in ("chromium", "chromedriver") if executable(name) is None]
    if absent:
        return f"{' and '.join(absent)} not found on PATH (install them: {INSTALL})"
    return None


def executable(name: str) -> str | None:
    return shutil.which(name)


@contextmanager
def chromium(width: int = 1280, height: int = 1000) -> Iterator[Any]:
    """A selenium driver of headless Chromium with a fresh profile, quit on exit. Its
    console messages are kept (``driver.get_log("browser")``)."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    with tempfile.TemporaryDirectory(prefix="billiard-chromium-") as profile:
        options = webdriver.ChromeOptions()
        options.binary_location = executable("chromium") or "chromium"
        for switch in (*CHROMIUM_SWITCHES, f"--user-data-dir={profile}"):
            options.add_argument(switch)
        options.add_argument(f"--window-size={width},{height}")
        options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
        service = Service(executable("chromedriver") or "chromedriver")
        driver = webdriver.Chrome(service=service, options=options)
        try:
            yield driver
        finally:
            driver.quit()


def console_errors(driver: Any) -> list[str]:
    """The console's messages of level SEVERE since the last call (errors and uncaught
    exceptions)."""
    return [e["message"] for e in driver.get_log("browser") if e["level"] == "SEVERE"]


def screenshot(
    page: Path,
    out: Path,
    *,
    time: float | None = None,
    follow: float | None = None,
    width: int = 1280,
) -> None:
    """Open ``page`` (an HTML file), move its selection to ``time`` (s), let its first
    panel follow the ball in a square of ``follow`` mm, and save a screenshot of the whole
    page to ``out`` (PNG)."""
    with chromium(width, 1000) as driver:
        driver.get(page.resolve().as_uri())
        if follow is not None:
            driver.execute_script("billiardView.follow(arguments[0])", follow)
        if time is not None:
            driver.execute_script("billiardView.setTime(arguments[0])", time)
        height = driver.execute_script("return document.documentElement.scrollHeight")
        driver.set_window_size(width, int(height) + 140)  # the window's frame is counted
        driver.get_screenshot_as_file(str(out))
        errors = console_errors(driver)
    if errors:
        raise RuntimeError(f"{page}: console errors: {errors}")


def main(argv: list[str]) -> int:
    """Run the wedge with contact phases, write its view and a screenshot to argv[0]."""
    import numpy as np

    from billiard.cli import main as billiard
    from billiard.runfile.sidecsv import read_side_csv

    if len(argv) != 1:
        print("usage: python -m tests.browser OUT.png", file=sys.stderr)
        return 2
    reason = missing()
    if reason:
        print(f"cannot take the screenshot: {reason}", file=sys.stderr)
        return 1
    with tempfile.TemporaryDirectory() as folder:
        run = Path(folder) / "wedge"
        args = ["run", "wedge-6.6hz", "--set", "contact.model=phases", "--collisions", "400"]
        assert billiard([*args, "--sample", "0.002", "--out", str(run), "--no-plot"]) == 0
        assert billiard(["view", str(run)]) == 0
        # the selection in the middle of the run's longest rolling phase
        phases = read_side_csv(run / "contacts.csv")
        rolls = np.flatnonzero(phases["mode"] == "roll")
        k = rolls[np.argmax(phases["t_end"][rolls] - phases["t_start"][rolls])]
        middle = 0.5 * float(phases["t_start"][k] + phases["t_end"][k])
        screenshot(run / "view.html", Path(argv[0]), time=middle, follow=60.0)
    print(f"wrote {argv[0]}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
