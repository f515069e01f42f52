"""What a warm ``robosoc fly --no-out`` loads: only what the flight needs (docs/translation.md, Start-up).

The command runs in a child process (a fresh interpreter, as a user's shell starts it) that then
lists the modules it loaded.  Plotting (matplotlib), sweeps (dask), flight logs (mcap), video
(imageio, PIL) and MuJoCo's windowed OpenGL context (glfw, PyOpenGL) are all installed here, so
each assertion fails as soon as something on the flight's path imports one of them at start-up.
"""

import json
import os
import subprocess
import sys

_CHILD = """
import json, os, runpy, sys
sys.argv = ["robosoc", "fly", "--duration", "0.01", "--no-out"]
try:
    runpy.run_module("robosoc", run_name="__main__")
except SystemExit as stop:
    code = stop.code
else:
    code = 0
loaded = sorted({name.split(".")[0] for name in sys.modules})
print(json.dumps({"code": code, "loaded": loaded, "MUJOCO_GL": os.environ.get("MUJOCO_GL")}), file=sys.stderr)
"""

NOT_FOR_A_FLIGHT = {"matplotlib", "dask", "mcap", "imageio", "PIL", "glfw", "OpenGL"}


def _fly_in_a_child(env: dict[str, str]) -> dict:
    proc = subprocess.run([sys.executable, "-c", _CHILD], env=env, capture_output=True, text=True, timeout=600)
    return json.loads(proc.stderr.strip().splitlines()[-1])


def test_a_flight_without_outputs_loads_no_plotting_sweep_log_video_or_window_library() -> None:
    env = {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"}
    report = _fly_in_a_child(env)
    assert report["code"] == 0
    assert "mujoco" in report["loaded"] and "numba" in report["loaded"]  # the flight did fly
    assert NOT_FOR_A_FLIGHT.isdisjoint(report["loaded"]), NOT_FOR_A_FLIGHT & set(report["loaded"])
    assert report["MUJOCO_GL"] is None  # MuJoCo's import left no MUJOCO_GL behind


def test_the_users_mujoco_gl_is_left_as_it_was_for_the_video_backend_probe() -> None:
    report = _fly_in_a_child(dict(os.environ, MUJOCO_GL="osmesa"))
    assert report["code"] == 0
    assert report["MUJOCO_GL"] == "osmesa"
    assert "glfw" not in report["loaded"]
