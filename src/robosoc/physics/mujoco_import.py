"""MuJoCo imported without loading its windowed OpenGL library (GLFW), which robosoc never uses in-process.

``import mujoco`` also imports ``mujoco.GLContext``'s backend, GLFW by default on Linux (about
0.07 s of every warm ``robosoc fly``), unless ``MUJOCO_GL`` says ``disable``.  robosoc's own
renderer (``physics/render.py``) creates the context of the backend it found by itself
(``mujoco.egl``, ``mujoco.osmesa`` or ``mujoco.glfw``, each imported when a video is made) and
probes backends in child processes whose environment it sets, so nothing in this process reads
``mujoco.GLContext``.  This module, imported first by ``robosoc.physics``, makes the first import
with ``MUJOCO_GL=disable`` and puts the variable back as it was, so child processes and
``render.find_backend`` see the user's own.
"""

from __future__ import annotations

import importlib
import os
import sys


def import_mujoco() -> None:
    """Import ``mujoco`` once without its default OpenGL context; the environment is left as it was."""
    if "mujoco" in sys.modules:
        return
    saved = os.environ.get("MUJOCO_GL")
    os.environ["MUJOCO_GL"] = "disable"
    try:
        importlib.import_module("mujoco")
    finally:
        if saved is None:
            del os.environ["MUJOCO_GL"]
        else:
            os.environ["MUJOCO_GL"] = saved


import_mujoco()
