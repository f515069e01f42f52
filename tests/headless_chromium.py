"""Loading a page in headless Chromium (Debian's ``chromium``, installed by ``.ci/run``).

:func:`load` runs the browser twice on a local file, with every host name unresolvable (the page
must need no network): once to dump the DOM after its scripts ran, once for a screenshot.  The
browser's stderr log carries every console message of the page (``INFO:CONSOLE``).
:func:`devtools_flows` runs DevTools' own trace model in the browser on a trace's events.

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


# --- DevTools' own trace model, run in the browser ---

_DEVTOOLS_FLOWS = """(async () => {
  const {TraceModel} = await import('/devtools/models/trace/trace.js');
  const model = TraceModel.Model.createWithAllHandlers();
  await model.parse(%s);
  const parsed = model.parsedTrace(0);
  const flows = (parsed.data ?? parsed).Flows.flows;
  return JSON.stringify(flows.map(flow => flow.map(e => ({name: e.name, cat: e.cat, ph: e.ph, ts: e.ts,
                                                           pid: e.pid, tid: e.tid}))));
})()"""


def devtools_flows(trace_events: list[dict], work: Path) -> list[list[dict]]:
    """The flows Chromium's DevTools performance panel draws for ``trace_events``: each a list of
    the slices it joins (name, cat, ph, ts, pid, tid), as DevTools' trace model
    (``models/trace/trace.js`` of the frontend bundled in the browser, served on its remote
    debugging port) reports them after parsing the events."""
    import json
    import time
    import urllib.request

    from websockets.sync.client import connect

    assert BROWSER is not None
    profile = work / "profile-devtools"
    # every host unresolvable but the loopback address the debugging port listens on
    flags = [f"{f}, EXCLUDE 127.0.0.1" if f.startswith("--host-resolver-rules=") else f for f in FLAGS]
    args = [BROWSER, *flags, f"--user-data-dir={profile}", "--remote-debugging-port=0", "about:blank"]
    browser = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        port_file = profile / "DevToolsActivePort"
        deadline = time.monotonic() + TIMEOUT_S
        while not (port_file.is_file() and port_file.read_text().strip()):
            assert browser.poll() is None, f"chromium exited with {browser.returncode}"
            assert time.monotonic() < deadline, "chromium opened no remote debugging port"
            time.sleep(0.1)
        base = f"http://127.0.0.1:{int(port_file.read_text().split()[0])}"
        with urllib.request.urlopen(urllib.request.Request(f"{base}/json/new?about:blank", method="PUT")) as answer:
            target = json.load(answer)
        with connect(target["webSocketDebuggerUrl"], max_size=None, open_timeout=TIMEOUT_S) as ws:
            calls = iter(range(1, 1_000_000))

            def call(method: str, **params: object) -> dict:
                number = next(calls)
                ws.send(json.dumps({"id": number, "method": method, "params": params}))
                while True:
                    reply = json.loads(ws.recv(timeout=TIMEOUT_S))
                    if reply.get("id") == number:
                        assert "error" not in reply, reply
                        return reply["result"]

            # a page of the frontend's origin, from which its modules import
            call("Page.navigate", url=f"{base}/devtools/models/trace/trace.js")
            while call("Runtime.evaluate", expression="document.readyState")["result"].get("value") != "complete":
                time.sleep(0.1)
            result = call(
                "Runtime.evaluate", expression=_DEVTOOLS_FLOWS % json.dumps(trace_events), awaitPromise=True,
                returnByValue=True,
            )  # fmt: skip
            assert "exceptionDetails" not in result, result["exceptionDetails"]
            return json.loads(result["result"]["value"])
    finally:
        browser.terminate()
        try:
            browser.wait(timeout=30)
        except subprocess.TimeoutExpired:
            browser.kill()
            browser.wait()
