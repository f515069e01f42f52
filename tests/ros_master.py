"""A real ROS 1 master for the tests (``roscore`` on a free port), and the nodes run against it.

The tests skip when ROS 1 is not installed (``roscore`` and rospy, e.g. Debian's ``ros-core`` and
``python3-rospy``; ``.ci/run`` installs them).  Every node runs as a process of its own with
``ROS_MASTER_URI`` pointing at the test's master: the robosoc nodes as ``python -m robosoc``, the
nodes no part of robosoc wrote under the system's Python (``/usr/bin/python3``, which has Debian's
rospy), and ROS's own tools (``rosbag``, ``rostopic``).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
SYSTEM_PYTHON = "/usr/bin/python3"


def ros_missing() -> str | None:
    """Why the ROS tests cannot run here, or None."""
    if shutil.which("roscore") is None or shutil.which("rosbag") is None:
        return "ROS 1 is not installed (roscore, rosbag)"
    probe = subprocess.run([SYSTEM_PYTHON, "-c", "import rospy, rosbag"], capture_output=True, check=False)
    if probe.returncode != 0:
        return "ROS 1's Python packages (rospy, rosbag) are not installed"
    return None


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@dataclass
class Master:
    uri: str
    env: dict[str, str]
    home: Path

    def start(self, args: Sequence[str], log: Path, *, python: str | None = None) -> subprocess.Popen:
        """A process (in its own process group) with this master's environment, output to ``log``."""
        command = [python, *args] if python else list(args)
        out = log.open("w")
        return subprocess.Popen(command, env=self.env, stdout=out, stderr=subprocess.STDOUT, start_new_session=True)

    def robosoc(self, args: Sequence[str], log: Path) -> subprocess.Popen:
        return self.start(["-m", "robosoc", *args], log, python=sys.executable)

    def run(self, args: Sequence[str], timeout: float = 120) -> subprocess.CompletedProcess[str]:
        return subprocess.run(list(args), env=self.env, capture_output=True, text=True, timeout=timeout, check=False)


def stop(process: subprocess.Popen, sig: int = signal.SIGINT, timeout: float = 20) -> int:
    """End ``process`` and its group (``sig`` first, then SIGKILL); its exit code."""
    if process.poll() is None:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, sig)
        try:
            process.wait(timeout)
        except subprocess.TimeoutExpired:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(process.pid, signal.SIGKILL)
            process.wait(10)
    return int(process.returncode)


def stop_recorder(process: subprocess.Popen, bag: Path, timeout: float = 30) -> int:
    """End a ``rosbag record -O bag`` and wait until its bag is closed: the ``rosbag`` script exits
    on SIGINT while its ``record`` child is still writing ``bag.active``, and renames it to ``bag``
    only when done (a reader started at once found no bag now and then)."""
    code = stop(process)
    active = bag.with_name(bag.name + ".active")
    deadline = time.monotonic() + timeout
    while (active.exists() or not bag.exists()) and time.monotonic() < deadline:
        time.sleep(0.1)
    return code


def wait_all(processes: Sequence[subprocess.Popen], timeout: float) -> list[int | None]:
    deadline = time.monotonic() + timeout
    for p in processes:
        with contextlib.suppress(subprocess.TimeoutExpired):
            p.wait(max(0.1, deadline - time.monotonic()))
    return [p.poll() for p in processes]


@contextlib.contextmanager
def running_master(home: Path) -> Iterator[Master]:
    """``roscore`` on a free port; its environment for the nodes; stopped at the end."""
    reason = ros_missing()
    if reason:
        pytest.skip(reason)
    port = free_port()
    uri = f"http://127.0.0.1:{port}"
    env = dict(os.environ)
    env.update(
        ROS_MASTER_URI=uri,
        ROS_HOME=str(home),
        ROS_LOG_DIR=str(home / "log"),
        ROS_HOSTNAME="127.0.0.1",
        PYTHONPATH=os.pathsep.join([str(SRC), env.get("PYTHONPATH", "")]).rstrip(os.pathsep),
    )
    master = Master(uri, env, home)
    core = master.start(["roscore", "-p", str(port)], home / "roscore.log")
    try:
        deadline = time.monotonic() + 30
        while master.run(["rosparam", "get", "/rosdistro"], timeout=10).returncode != 0:
            if core.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"roscore did not start: {(home / 'roscore.log').read_text()}")
            time.sleep(0.3)
        yield master
    finally:
        stop(core)
