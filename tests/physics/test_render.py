"""The OpenGL backend probe, the offscreen renderer and the frame sink.

The probe runs in a child process with the caller's environment plus ``MUJOCO_GL`` (and
``PYOPENGL_PLATFORM`` for EGL/OSMesa, as PyOpenGL needs).  A stand-in ``mujoco`` module put first
on the child's ``PYTHONPATH`` reports the environment it was imported under, which shows what the
child saw without any OpenGL.
"""

import os
import subprocess
import sys
from pathlib import Path

import imageio.v3 as iio
import mujoco
import numpy as np
import pytest

from robosoc.config.vehicle import default_vehicle
from robosoc.physics import World
from robosoc.physics.mjcf import RENDER_SIZE
from robosoc.physics.render import FrameSink, OffscreenRenderer, RenderUnavailable, find_backend

_SPHERE = '<mujoco><worldbody><geom type="sphere" size="1"/></worldbody></mujoco>'


def _renders_in_a_child(backend: str) -> bool:
    """Whether MuJoCo's own high-level renderer works under ``MUJOCO_GL=backend`` (this test's probe)."""
    code = f"import mujoco; m = mujoco.MjModel.from_xml_string({_SPHERE!r}); mujoco.Renderer(m, 16, 16).render()"
    env = dict(os.environ, MUJOCO_GL=backend)
    env.pop("PYOPENGL_PLATFORM", None)
    return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, check=False).returncode == 0


EGL = _renders_in_a_child("egl")
needs_egl = pytest.mark.skipif(not EGL, reason="no EGL rendering here")


@pytest.fixture
def stand_in_mujoco(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Children started now import a ``mujoco`` that fails, naming the GL settings it was given."""
    (tmp_path / "mujoco.py").write_text(
        "import os\n"
        "raise RuntimeError('stand-in under MUJOCO_GL=' + os.environ.get('MUJOCO_GL', 'unset')"
        " + ' PYOPENGL_PLATFORM=' + os.environ.get('PYOPENGL_PLATFORM', 'unset'))\n"
    )
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    monkeypatch.delenv("PYOPENGL_PLATFORM", raising=False)


def test_probe_tries_egl_then_osmesa_in_the_callers_environment(
    stand_in_mujoco: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    with pytest.raises(RenderUnavailable) as error:
        find_backend()
    assert str(error.value) == (
        "no OpenGL backend for offscreen rendering ("
        "egl: RuntimeError: stand-in under MUJOCO_GL=egl PYOPENGL_PLATFORM=egl; "
        "osmesa: RuntimeError: stand-in under MUJOCO_GL=osmesa PYOPENGL_PLATFORM=osmesa)"
    )


def test_probe_tries_only_the_backend_the_user_named(stand_in_mujoco: None, monkeypatch: pytest.MonkeyPatch) -> None:
    # GLFW is not a PyOpenGL platform name: PYOPENGL_PLATFORM stays unset.
    monkeypatch.setenv("MUJOCO_GL", " GLFW ")
    with pytest.raises(RenderUnavailable) as error:
        find_backend()
    assert str(error.value) == (
        "no OpenGL backend for offscreen rendering (glfw: RuntimeError: stand-in under MUJOCO_GL=glfw "
        "PYOPENGL_PLATFORM=unset)"
    )
    monkeypatch.setenv("MUJOCO_GL", "OSMesa")
    with pytest.raises(RenderUnavailable, match=r"\(osmesa: RuntimeError: stand-in under MUJOCO_GL=osmesa "):
        find_backend()


def test_unknown_backend_name_is_reported_with_mujocos_reason(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MUJOCO_GL", "nonsense")
    env = dict(os.environ, MUJOCO_GL="nonsense")
    own = subprocess.run([sys.executable, "-c", "import mujoco"], env=env, capture_output=True, text=True, check=False)
    reason = own.stderr.strip().splitlines()[-1]  # MuJoCo's own complaint about the variable
    assert "MUJOCO_GL" in reason
    with pytest.raises(RenderUnavailable) as error:
        find_backend()
    assert str(error.value) == f"no OpenGL backend for offscreen rendering (nonsense: {reason})"


@needs_egl
def test_probe_finds_egl_first_and_honours_a_user_choice(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    assert find_backend() == "egl"
    monkeypatch.setenv("MUJOCO_GL", " EGL\n")
    assert find_backend() == "egl"


@needs_egl
def test_probe_that_outlives_its_timeout_counts_as_a_failure(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MUJOCO_GL", "egl")
    with pytest.raises(RenderUnavailable, match=r"\(egl: Command .* timed out after 0\.001 seconds\)"):
        find_backend(timeout_s=0.001)
    monkeypatch.delenv("MUJOCO_GL")  # a timed-out EGL probe does not stop the OSMesa one
    with pytest.raises(RenderUnavailable, match=r"\(egl: Command .* timed out after .*; osmesa: Command .* timed out"):
        find_backend(timeout_s=0.001)


def test_probe_failing_silently_is_reported_as_failed(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / "mujoco.py").write_text("raise SystemExit(3)\n")
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    monkeypatch.setenv("MUJOCO_GL", "egl")
    with pytest.raises(RenderUnavailable) as error:
        find_backend()
    assert str(error.value) == "no OpenGL backend for offscreen rendering (egl: failed)"


@needs_egl
def test_offscreen_frame_is_the_tracked_body_seen_from_above_the_ground(tmp_path: Path) -> None:
    world = World([default_vehicle(spawn_position=(0.0, 0.0, 1.0))])
    world.reset(0)
    width, height = RENDER_SIZE
    renderer = OffscreenRenderer(world.model, world.quadrotors[0].body_id, width, height, "egl")
    try:
        frame = renderer.render(world.data)
        # The camera looks down 20° at the vehicle, 3 m away: the vehicle is dark (hull .15 .15 .18)
        # in the middle, the checker floor (grey-blue, never that dark) fills the lower half.
        assert frame.shape == (height, width, 3) and frame.dtype == np.uint8
        centre = frame[height // 2 - 4 : height // 2 + 4, width // 2 - 4 : width // 2 + 4].astype(float)
        assert centre.mean() < 90
        bottom = frame[-40:].astype(float)
        assert bottom.mean() > centre.mean() + 20
        # Top and bottom are not swapped: OpenGL reads rows bottom-up; the frame comes top-down, so the
        # floor (lit plane) is at the bottom and the darker sky-less background at the top.
        assert frame[:40].astype(float).mean() < bottom.mean()
        # The camera tracks the body: moved 1 m up, the vehicle stays in the frame centre.
        world.data.qpos[2] += 1.0
        mujoco.mj_forward(world.model, world.data)
        moved = renderer.render(world.data)
        assert moved[height // 2 - 4 : height // 2 + 4, width // 2 - 4 : width // 2 + 4].astype(float).mean() < 90
        assert not np.array_equal(moved, frame)  # the floor lies further below: the frame changed
    finally:
        renderer.close()


def test_renderer_on_a_backend_that_cannot_start_says_which() -> None:
    model = mujoco.MjModel.from_xml_string(_SPHERE)
    with pytest.raises(RenderUnavailable, match="cannot start the osmesa renderer: "):
        # OSMesa is not usable once EGL or another platform was chosen in this process (or not
        # installed at all): either way the renderer must say so, not crash.
        OffscreenRenderer(model, 0, 32, 32, "osmesa")


def test_frame_sink_writes_numbered_pngs_that_read_back(tmp_path: Path) -> None:
    folder = tmp_path / "frames" / "run"
    sink = FrameSink(folder, 25.0)
    assert FrameSink(folder, 25.0).frames == 0  # the folder exists now: opening it again is fine
    frames = [np.full((6, 8, 3), value, dtype=np.uint8) for value in (0, 100, 255)]
    frames[1][2, 3] = (10, 20, 30)
    for frame in frames:
        sink.add(frame)
    sink.close()
    assert sink.frames == 3
    assert sorted(p.name for p in folder.iterdir()) == ["frame_00000.png", "frame_00001.png", "frame_00002.png"]
    for i, frame in enumerate(frames):
        np.testing.assert_array_equal(iio.imread(folder / f"frame_{i:05d}.png")[..., :3], frame)


def test_frame_sink_writes_an_mp4_with_every_frame(tmp_path: Path) -> None:
    pytest.importorskip("imageio_ffmpeg")
    path = tmp_path / "out" / "nested" / "flight.MP4"
    sink = FrameSink(path, 25.0)
    FrameSink(tmp_path / "out" / "nested" / "again.mp4", 25.0).close()  # an existing folder is fine
    for k in range(5):
        # 40 × 56: multiples of 8 (the macro block asked for) but not of 16 (imageio's default), so a
        # frame that comes back resized would show
        sink.add(np.full((40, 56, 3), 40 * k, dtype=np.uint8))
    sink.close()
    sink.close()  # closing twice is harmless
    assert sink.frames == 5
    import imageio.v2 as imageio

    reader = imageio.get_reader(str(path))
    assert reader.get_meta_data()["fps"] == pytest.approx(25.0)
    video = np.array([reader.get_data(i) for i in range(reader.count_frames())])
    reader.close()
    assert video.shape[:3] == (5, 40, 56)
    np.testing.assert_allclose(video[:, 20, 28].mean(axis=1), [40.0 * k for k in range(5)], atol=6)


def test_mp4_without_imageio_says_how_to_get_it(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "imageio.v2", None)  # import fails as if not installed
    with pytest.raises(RenderUnavailable) as error:
        FrameSink(tmp_path / "v.mp4", 25.0)
    assert str(error.value) == (
        "writing MP4 needs the optional 'video' extra (pip install 'robosoc[video]'); "
        "give a folder instead to get PNG frames"
    )
    assert not (tmp_path / "v.mp4").exists()
