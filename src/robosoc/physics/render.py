"""Offscreen rendering of a world through MuJoCo's OpenGL renderer, with a headless backend probe.

MuJoCo picks its OpenGL backend when it is first imported (``MUJOCO_GL``), which is too early
for a command that decides late whether it renders at all.  So :func:`find_backend` tries the
backends in a child process first (EGL, then OSMesa, or only the one named by ``MUJOCO_GL``),
and :class:`OffscreenRenderer` then creates that backend's context itself and renders through
the low-level ``mjr_*`` API.  Any failure becomes :class:`RenderUnavailable` with a readable
reason; callers report it and go on without frames.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np

from robosoc import output_files

_PROBE = """
import mujoco
m = mujoco.MjModel.from_xml_string('<mujoco><worldbody><geom type="sphere" size="1"/></worldbody></mujoco>')
r = mujoco.Renderer(m, 32, 32)
d = mujoco.MjData(m)
mujoco.mj_forward(m, d)
r.update_scene(d)
assert r.render().shape == (32, 32, 3)
"""


class RenderUnavailable(RuntimeError):
    """No OpenGL backend can render here (the message says why)."""


def find_backend(timeout_s: float = 60.0) -> str:
    """The first OpenGL backend that renders in a child process.

    Raises:
        RenderUnavailable: none works; the message lists what was tried.
    """
    requested = os.environ.get("MUJOCO_GL", "").strip().lower()
    candidates = [requested] if requested else ["egl", "osmesa"]
    failures = []
    for backend in candidates:
        env = dict(os.environ, MUJOCO_GL=backend)
        if backend in ("egl", "osmesa"):
            env["PYOPENGL_PLATFORM"] = backend
        try:
            result = subprocess.run(
                [sys.executable, "-c", _PROBE], env=env, capture_output=True, text=True, timeout=timeout_s, check=False
            )
        except (OSError, subprocess.TimeoutExpired) as exc:
            failures.append(f"{backend}: {exc}")
            continue
        if result.returncode == 0:
            return backend
        last = (result.stderr.strip().splitlines() or ["failed"])[-1]
        failures.append(f"{backend}: {last}")
    raise RenderUnavailable("no OpenGL backend for offscreen rendering (" + "; ".join(failures) + ")")


def _context_class(backend: str) -> type:
    if backend == "egl":
        from mujoco.egl import GLContext
    elif backend == "osmesa":
        from mujoco.osmesa import GLContext
    else:
        from mujoco.glfw import GLContext
    return GLContext


class OffscreenRenderer:
    """Renders RGB frames of a world, the camera tracking one body.

    Args:
        model: the MuJoCo model (its offscreen buffer must be at least ``width``×``height``).
        body_id: the body the camera follows.
        width, height: frame size in pixels.
        backend: from :func:`find_backend`.

    Raises:
        RenderUnavailable: the backend cannot be started in this process.
    """

    def __init__(self, model: mujoco.MjModel, body_id: int, width: int, height: int, backend: str) -> None:
        self.model = model
        self.width = width
        self.height = height
        try:
            self._gl = _context_class(backend)(width, height)
            self._gl.make_current()
            self._context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150)
            mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._context)
        except Exception as exc:  # any backend failure (import, driver, context) means "no video"
            raise RenderUnavailable(f"cannot start the {backend} renderer: {exc}") from exc
        self._scene = mujoco.MjvScene(model, maxgeom=1000)
        self._option = mujoco.MjvOption()
        self._camera = mujoco.MjvCamera()
        self._camera.type = mujoco.mjtCamera.mjCAMERA_TRACKING
        self._camera.trackbodyid = body_id
        self._camera.distance = 3.0
        self._camera.elevation = -20.0
        self._camera.azimuth = 135.0
        self._rect = mujoco.MjrRect(0, 0, width, height)
        self._pixels = np.empty((height, width, 3), dtype=np.uint8)

    def render(self, data: mujoco.MjData) -> np.ndarray:
        """One RGB frame (height × width × 3, uint8) of the current state."""
        self._gl.make_current()
        mujoco.mjv_updateScene(
            self.model, data, self._option, None, self._camera, mujoco.mjtCatBit.mjCAT_ALL, self._scene
        )
        mujoco.mjr_render(self._rect, self._scene, self._context)
        mujoco.mjr_readPixels(self._pixels, None, self._rect, self._context)
        return np.flipud(self._pixels).copy()

    def close(self) -> None:
        """Free the GL resources."""
        self._context.free()
        self._gl.free()


class FrameSink:
    """Writes frames to an MP4 (through imageio-ffmpeg) or as numbered PNG files in a folder.

    A path ending in ``.mp4`` makes a video; anything else is a folder of ``frame_00000.png``.

    Raises:
        RenderUnavailable: an MP4 is asked for but imageio/imageio-ffmpeg are not installed.
    """

    def __init__(self, path: Path, fps: float) -> None:
        self.path = path
        self.frames = 0
        self._writer = None
        if path.suffix.lower() == ".mp4":
            try:
                import imageio.v2 as imageio
            except ImportError as exc:
                raise RenderUnavailable(
                    "writing MP4 needs the optional 'video' extra (pip install 'robosoc[video]'); "
                    "give a folder instead to get PNG frames"
                ) from exc
            path.parent.mkdir(parents=True, exist_ok=True)
            output_files.check_regular(path)  # ffmpeg writes in place: no device, FIFO or socket
            self._writer = imageio.get_writer(str(path), fps=fps, codec="libx264", macro_block_size=8)
        else:
            path.mkdir(parents=True, exist_ok=True)

    def add(self, frame: np.ndarray) -> None:
        """Append one RGB frame."""
        if self._writer is not None:
            self._writer.append_data(frame)
        else:
            import matplotlib.image

            frame_path = self.path / f"frame_{self.frames:05d}.png"
            output_files.check_regular(frame_path)
            matplotlib.image.imsave(frame_path, frame)
        self.frames += 1

    def close(self) -> None:
        """Finish the file."""
        if self._writer is not None:
            self._writer.close()
            self._writer = None
