"""What ``robosoc fly --decoupled`` prints and where it writes, around a stand-in for the two-process
flight (``cosim.decoupled.fly_decoupled``; the real one is flown in tests/cosim/test_decoupled_flight.py).

Every expected line is written by hand from the canned summary below.
"""

from __future__ import annotations

import dataclasses
import io
from pathlib import Path
from typing import Any

import pytest
from rich.console import Console

from robosoc.cli import exit_codes
from robosoc.cli.errors import CliError
from robosoc.cli.fly_decoupled import fly_decoupled_run
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.link import LinkConfig, LinkFaults
from robosoc.config.scenario import ScenarioConfig
from robosoc.outputs import decoupled_flight as decoupled
from robosoc.outputs.decoupled_flight import DecoupledFlight, SideFailed

SUMMARY: dict[str, Any] = {
    "flight": {
        "hover_rms_m": 0.0234,
        "hover_max_m": 0.061,
        "tracking_rms_deg": {"roll": 1.5, "pitch": float("nan"), "yaw": 0.25},
    },
    "tasks": {"ekf": {"jobs": 99, "response_us_mean": 41.26, "response_us_max": 80.04, "deadline_misses": 0}},
    "link": {
        "readings": {"injected": 98, "late": 1, "stale": 2},
        "commands": {"received": 97, "late": 3, "missed": 1},
        "to_chip": {"sent": 100, "received": 99},
        "to_physics": {"sent": 99, "received": 97},
    },
    "real_time_factor": 1.234,
    "simulated_s": 1.0,
}


class _Fake:
    """Records the call and returns a canned flight (or raises)."""

    def __init__(self, flight: DecoupledFlight | None = None, error: SideFailed | None = None) -> None:
        self.flight, self.error, self.calls = flight, error, []

    def __call__(self, scenario, vehicle, link, folder, *, bind=None, on_status=None, on_progress=None):
        self.calls.append((scenario, scenario.seed, link, Path(folder), bind, Path(folder).is_dir()))
        on_status("both sides are up")
        on_progress(50, 100)
        if self.error is not None:
            raise self.error
        return self.flight


def _console() -> Console:
    return Console(file=io.StringIO(), width=200, record=True, color_system=None, force_terminal=False)


def _run(monkeypatch, fake: _Fake, out: Path | None, faults: LinkFaults | None = None) -> list[str]:
    monkeypatch.setattr(decoupled, "fly_decoupled", fake)
    console = _console()
    scenario = ScenarioConfig(name="hop", duration_s=1.0, seed=7)
    link = LinkConfig(pace="fast", resend=1, faults=faults or LinkFaults())
    fly_decoupled_run(console, scenario, out, link, None)
    return [" ".join(line.split()) for line in console.export_text().splitlines()]


def test_the_figures_of_a_flown_flight(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    flight = DecoupledFlight(
        SUMMARY, physics={"ended": "done", "cpu_s": 0.8}, chip={"ended": "done", "cpu_s": 0.6, "side": "chip"}
    )
    fake = _Fake(flight)
    lines = _run(monkeypatch, fake, tmp_path, LinkFaults(loss=0.1, reorder=0.05))
    label = FirmwareConfig().label
    assert lines[0] == (
        f"flying scenario hop for 1 s, vehicle default, controller chip ({label}, decoupled: two processes over "
        "UDP, pace fast, hold zoh, resend 1), seed 7"
    )
    assert lines[1] == "injected faults per datagram, each direction: loss 0.1, reorder 0.05"
    assert "both sides are up" in lines
    assert "hover height error (RMS, after the climb): 2.34 cm (max 6.10 cm)" in lines
    assert "attitude tracking error (RMS, 0.5 s after steps excluded): roll 1.50 deg, pitch n/a, yaw 0.25 deg" in lines
    assert "ekf 99 jobs: response mean 41.3 us, max 80.0 us; deadline misses 0" in lines
    assert (
        "readings injected 98 (late 1, stale 2); commands applied 97 (late 3, missed 1); real-time factor 1.23" in lines
    )
    assert (
        "CPU time while flying: physics 0.8 s, chip 0.6 s (real time needs each below the flight's 1 s, "
        "on a core of its own)" in lines
    )
    assert any(line.startswith("to chip 100 99") for line in lines)
    assert lines[-1] == f"run folder: {tmp_path} (flight.csv, flight.mcap, jobs.csv, summary.json, link-*.log)"
    (_, seed, link, folder, bind, existed) = fake.calls[0]
    assert (seed, link.pace, folder, bind, existed) == (7, "fast", tmp_path, None, True)


def test_without_out_the_flight_goes_to_a_temporary_folder_that_is_removed(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    flight = DecoupledFlight({**SUMMARY, "flight": {}, "tasks": {}}, physics={"ended": "done"}, chip={"ended": "done"})
    fake = _Fake(flight)
    lines = _run(monkeypatch, fake, None)
    folder, existed = fake.calls[0][3], fake.calls[0][5]
    assert existed and folder.name.startswith("robosoc-decoupled-") and not folder.exists()
    assert not any(
        line.startswith(("hover", "attitude", "injected faults", "CPU time", "run folder")) for line in lines
    )


def test_a_side_that_ended_early_is_noted_and_ends_the_command(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    flight = DecoupledFlight(
        SUMMARY, physics={"ended": "peer_lost", "side": "physics", "message": "no datagram for 5 s"}, chip={}
    )
    monkeypatch.setattr(decoupled, "fly_decoupled", _Fake(flight))
    console = _console()
    with pytest.raises(CliError) as caught:
        fly_decoupled_run(console, ScenarioConfig(name="hop", duration_s=1.0, seed=7), tmp_path, LinkConfig(), None)
    assert console.export_text().splitlines()[-1] == "physics side: no datagram for 5 s"
    assert caught.value.message == f"physics side: no datagram for 5 s; what was done is in {tmp_path}"
    assert caught.value.code == exit_codes.PEER_LOST


@pytest.mark.parametrize(
    ("error", "message", "code"),
    [
        (SideFailed("physics", "link", "address in use"), "--bind: address in use", exit_codes.USAGE),
        (SideFailed("chip", "link", "cannot reach the physics side"), "chip side: cannot reach the physics side",
         exit_codes.USAGE),
        (SideFailed("chip", "internal", "Traceback ..."), "the chip side failed:\nTraceback ...",
         exit_codes.INTERNAL_ERROR),
    ],
)  # fmt: skip
def test_a_side_that_fails_is_an_error_naming_it(
    monkeypatch: pytest.MonkeyPatch, error: SideFailed, message: str, code: int
) -> None:
    fake = _Fake(error=error)
    with pytest.raises(CliError) as caught:
        _run(monkeypatch, fake, None)
    assert (caught.value.message, caught.value.code) == (message, code)
    assert not fake.calls[0][3].exists()  # the temporary folder is removed


def test_without_both_sides_counts_there_is_no_link_line(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    for readings, commands in (({}, SUMMARY["link"]["commands"]), (SUMMARY["link"]["readings"], {})):
        summary = {**SUMMARY, "link": {**SUMMARY["link"], "readings": readings, "commands": commands}}
        flight = DecoupledFlight(summary, physics={"ended": "done"}, chip={"ended": "done", "side": "chip"})
        lines = _run(monkeypatch, _Fake(flight), tmp_path)
        assert not any(line.startswith(("readings injected", "CPU time")) for line in lines)
        assert "ekf 99 jobs: response mean 41.3 us, max 80.0 us; deadline misses 0" in lines


def test_the_progress_bar_counts_samples_and_status_lines_are_dim(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    import rich.progress

    made: list[rich.progress.Progress] = []

    class Recording(rich.progress.Progress):
        def __init__(self, *columns, **kwargs) -> None:  # type: ignore[no-untyped-def]
            super().__init__(*columns, **kwargs)
            made.append(self)

    monkeypatch.setattr(rich.progress, "Progress", Recording)
    flight = DecoupledFlight(SUMMARY, physics={"ended": "done"}, chip={"ended": "done", "side": "chip"})
    monkeypatch.setattr(decoupled, "fly_decoupled", _Fake(flight))
    console = Console(file=io.StringIO(), width=200, record=True, color_system="standard", force_terminal=True)
    scenario = ScenarioConfig(name="hop", duration_s=1.0)
    fly_decoupled_run(console, dataclasses.replace(scenario, seed=7), tmp_path, LinkConfig(), None)
    (bar,) = made
    (task,) = bar.tasks
    assert (task.description, task.total, task.completed) == ("fly", 100, 50)  # 1 s at 100 Hz; the fake's 50
    assert bar.live.transient and bar.console is console
    kinds = [type(c).__name__ for c in bar.columns]
    assert kinds == ["TextColumn", "BarColumn", "TextColumn", "TimeRemainingColumn"]
    assert [c.text_format for c in bar.columns if isinstance(c, rich.progress.TextColumn)] == [
        "flight", "{task.percentage:>3.0f}%"
    ]  # fmt: skip
    (status,) = [line for line in console.export_text(styles=True).splitlines() if "both sides are up" in line]
    assert "\x1b[2m" in status  # dim
