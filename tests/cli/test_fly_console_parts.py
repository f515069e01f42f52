"""The parts of ``robosoc fly``'s console that need no flight: the status spinner and the video state.

The video state is driven with stand-ins for the renderer and the frame sink (MuJoCo's GL context
cannot be created in every test process), so what is checked is the decimation to VIDEO_FPS, that
the renderer is made once for the first quadrotor's body at the render size, and how a missing GL
backend is reported and leaves the flight going.
"""

from __future__ import annotations

import io
from pathlib import Path
from types import SimpleNamespace
from typing import ClassVar

import pytest
from rich.console import Console

from robosoc.cli.fly import VIDEO_FPS, FlightProgress, _VideoState
from robosoc.physics import render
from robosoc.physics.mjcf import RENDER_SIZE


def _console() -> Console:
    return Console(file=io.StringIO(), force_terminal=True, width=120, record=True, color_system=None)


def _rendered(progress) -> str:
    out = Console(file=io.StringIO(), width=120, record=True, color_system=None)
    out.print(progress.make_tasks_table(progress.tasks))
    return out.export_text()


def test_status_says_the_text_and_spins_its_short_form_with_the_elapsed_time() -> None:
    console = _console()
    progress = FlightProgress(console, 2.0, 100.0)
    progress.status("compiling the chip kernels (first run: about a minute) ...")
    spinner = progress.spinner
    assert spinner is not None and spinner.console is console and spinner.live.transient
    assert [t.description for t in spinner.tasks] == ["compiling the chip kernels"]
    shown = _rendered(spinner)
    assert shown.split()[1:] == ["compiling", "the", "chip", "kernels", "0:00:00"]
    assert shown.split()[0] in "⠋⠙⠹⠸⠼⠴⠦⠧⠇⠏"  # the spinner's first frame
    progress.status("building the firmware.")
    assert not spinner.live.is_started  # the first spinner stopped
    assert [t.description for t in progress.spinner.tasks] == ["building the firmware"]
    progress.stop()
    assert progress.spinner is None
    text = console.export_text()
    assert "compiling the chip kernels (first run: about a minute) ..." in text
    assert "building the firmware." in text


class _Sink:
    def __init__(self, path: Path, fps: float) -> None:
        self.path, self.fps, self.frames, self.closed = path, fps, [], False

    def add(self, frame) -> None:
        self.frames.append(frame)

    def close(self) -> None:
        self.closed = True


class _Renderer:
    made: ClassVar[list[tuple]] = []

    def __init__(self, model, body, width, height, backend) -> None:
        _Renderer.made.append((model, body, width, height, backend))
        self.closed = False

    def render(self, data):
        return ("frame", data)

    def close(self) -> None:
        self.closed = True


WORLD = SimpleNamespace(model="model", data="data", quadrotors=[SimpleNamespace(body_id=7), SimpleNamespace(body_id=9)])


@pytest.fixture
def fakes(monkeypatch: pytest.MonkeyPatch):
    _Renderer.made = []
    monkeypatch.setattr(render, "find_backend", lambda: "egl")
    monkeypatch.setattr(render, "FrameSink", _Sink)
    monkeypatch.setattr(render, "OffscreenRenderer", _Renderer)
    return monkeypatch


def test_frames_are_taken_at_the_video_rate_by_one_renderer(fakes, tmp_path: Path) -> None:
    video = tmp_path / "flight.mp4"
    state = _VideoState(_console(), video)
    assert (state.sink.path, state.sink.fps) == (video, VIDEO_FPS)
    every = round(100.0 / VIDEO_FPS)  # 100 Hz samples, 25 frames a second: every 4th sample
    for k in range(10):
        state.frame(WORLD, k, 100.0)
    assert state.sink.frames == [("frame", "data")] * len(range(0, 10, every))
    assert _Renderer.made == [("model", 7, *RENDER_SIZE, "egl")]
    sink, renderer = state.sink, state.renderer
    state.close()
    assert sink.closed and renderer.closed


def test_slow_samples_give_a_frame_each(fakes, tmp_path: Path) -> None:
    state = _VideoState(_console(), tmp_path / "v.mp4")
    for k in range(3):
        state.frame(WORLD, k, 10.0)  # fewer samples than frames a second
    assert len(state.sink.frames) == 3


def test_no_gl_backend_is_a_note_and_no_video(fakes, tmp_path: Path) -> None:
    def missing() -> str:
        raise render.RenderUnavailable("no OpenGL backend works here")

    fakes.setattr(render, "find_backend", missing)
    console = _console()
    state = _VideoState(console, tmp_path / "v.mp4")
    state.frame(WORLD, 0, 100.0)
    state.close()
    assert state.sink is None and _Renderer.made == []
    assert console.export_text() == "no video: no OpenGL backend works here\n"


def test_a_renderer_that_cannot_start_closes_the_sink_and_says_why(fakes, tmp_path: Path) -> None:
    class Broken(_Renderer):
        def __init__(self, *args) -> None:
            raise render.RenderUnavailable("the context could not be made")

    fakes.setattr(render, "OffscreenRenderer", Broken)
    console = _console()
    state = _VideoState(console, tmp_path / "v.mp4")
    sink = state.sink
    state.frame(WORLD, 0, 100.0)
    assert sink.closed and sink.frames == [] and state.sink is None
    state.frame(WORLD, 4, 100.0)  # later frames: nothing, no second note
    assert console.export_text() == "no video: the context could not be made\n"


def test_samples_drive_a_bar_of_simulated_seconds_that_replaces_the_spinner(monkeypatch: pytest.MonkeyPatch) -> None:
    from robosoc.cli import fly

    readings = [0.0, 0.0, 0.1, 0.2, 0.5]  # the bar's start, then the four samples below

    def clock() -> float:
        return readings.pop(0) if len(readings) > 1 else readings[0]

    monkeypatch.setattr(fly.time, "perf_counter", clock)
    console = _console()
    progress = FlightProgress(console, 2.0, 100.0)
    progress.status("compiling ...")
    spinner = progress.spinner
    progress.sample(0)
    assert progress.spinner is None and not spinner.live.is_started
    bar = progress.progress
    assert bar is not None and bar.console is console and bar.live.transient
    (task,) = bar.tasks
    assert (task.total, task.completed, task.fields) == (200, 1, {"sim": "0.01/2 s", "rtf": ""})
    progress.sample(9)  # 0.1 s simulated in 0.1 s: too early for a real-time factor
    assert (task.completed, task.fields["sim"], task.fields["rtf"]) == (10, "0.10/2 s", "")
    progress.sample(19)  # 0.2 s simulated in 0.2 s: still too early
    assert (task.completed, task.fields["rtf"]) == (20, "")
    progress.sample(99)  # 1 s simulated in 0.5 s
    assert (task.completed, task.fields["sim"], task.fields["rtf"]) == (100, "1.00/2 s", "2.00x real time")
    assert task.description == "fly"
    shown = _rendered(bar)
    assert shown.startswith("flight ") and "1.00/2 s" in shown and "2.00x real time" in shown
    assert shown.index("━") < shown.index("1.00/2 s") < shown.index("2.00x real time")  # the bar, then the figures
    progress.stop()
    assert progress.progress is None and not bar.live.is_started


def test_the_live_server_option(monkeypatch: pytest.MonkeyPatch) -> None:
    from robosoc.cli.errors import CliError
    from robosoc.cli.fly import _start_live
    from robosoc.outputs import foxglove_live

    console = _console()
    assert _start_live(console, None) is None

    class Busy:
        def __init__(self, port: int) -> None:
            raise foxglove_live.LiveFlightError(f"port {port} is in use")

    monkeypatch.setattr(foxglove_live, "LiveFlight", Busy)
    with pytest.raises(CliError) as caught:
        _start_live(console, 8765)
    assert caught.value.message == "--foxglove: port 8765 is in use"

    class Served:
        url = "ws://127.0.0.1:8765"

        def __init__(self, port: int) -> None:
            self.port = port

    monkeypatch.setattr(foxglove_live, "LiveFlight", Served)
    live = _start_live(console, 8765)
    assert isinstance(live, Served) and live.port == 8765
    assert console.export_text().endswith(
        "foxglove: ws://127.0.0.1:8765 (Foxglove: Open connection, Foxglove WebSocket)\n"
    )


def test_the_live_view_gets_the_first_vehicles_rows_and_telemetry_only() -> None:
    from robosoc.cli import fly as fly_cli

    class Live:
        def __init__(self) -> None:
            self.rows: list[tuple[str, dict]] = []

        def publish(self, row, telemetry) -> None:  # type: ignore[no-untyped-def]
            self.rows.append((row, telemetry))

    live = Live()
    on_row = fly_cli._live_rows(live)
    for vehicle, row in ((0, "a"), (1, "b"), (0, "c"), (2, "d")):
        on_row(vehicle, row, {"jobs": ord(row)})
    assert live.rows == [("a", {"jobs": 97}), ("c", {"jobs": 99})]  # with the row's telemetry
    assert fly_cli._live_rows(None) is None
