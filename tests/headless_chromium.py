"""Loading a page in headless Chromium (Debian's ``chromium``, installed by ``.ci/run``).

:func:`load` runs the browser twice on a local file, with every host name unresolvable (the page
must need no network): once to dump the DOM after its scripts ran, once for a screenshot.  The
browser's stderr log carries every console message of the page (``INFO:CONSOLE``).

``ROBOSOC_TEST_BROWSER=off`` leaves the browser out (the tests skip their rendering part): mutation
runs set it, where each surviving mutant would otherwise start the browser for every render test.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import matplotlib.image

BROWSER = (
    None
    if os.environ.get("ROBOSOC_TEST_BROWSER") == "off"
    else shutil.which("chromium") or shutil.which("chromium-browser")
)
FLAGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--host-resolver-rules=MAP * ~NOTFOUND",
    "--enable-logging=stderr", "--v=0",
]  # fmt: skip
TIMEOUT_S = 120
_CONSOLE = re.compile(r":CONSOLE[:(]\d*\)?\]\s*(.*)")


@dataclass(frozen=True)
class Page:
    dom: str
    console: list[str]
    screenshot: object  # an (h, w, channels) array

    def body_attribute(self, name: str) -> str | None:
        match = re.search(r"<body[^>]*\s" + re.escape(name) + r'="([^"]*)"', self.dom)
        return match.group(1) if match else None


def _run(args: list[str], profile: Path) -> subprocess.CompletedProcess[str]:
    assert BROWSER is not None
    return subprocess.run(
        [BROWSER, *FLAGS, f"--user-data-dir={profile}", *args],
        capture_output=True, text=True, timeout=TIMEOUT_S, check=False,
    )  # fmt: skip


def load(page: Path, work: Path, width: int = 1200, height: int = 3000) -> Page:
    """The page's DOM after its scripts, its console messages and a screenshot."""
    url = page.resolve().as_uri()
    dumped = _run(["--dump-dom", url], work / "profile-dom")
    shot = work / "shot.png"
    shown = _run([f"--window-size={width},{height}", f"--screenshot={shot}", url], work / "profile-shot")
    console = [m.group(1) for line in (dumped.stderr + shown.stderr).splitlines() if (m := _CONSOLE.search(line))]
    return Page(dumped.stdout, console, matplotlib.image.imread(shot))
