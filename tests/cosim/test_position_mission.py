"""The position example (issue 32, item 5): three tasks on the three core tiles of the seed's 2×2
(estimator → position → attitude), the position fix and the mission's setpoint from the I/O tile,
its shipped mission (take-off, a 2 m square, landing) flown in all four builds within the stated
bound; the report shows the waypoints; Table I has a row group per task; and the runs that cannot
give it its position packets refuse it by name."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from robosoc.cli import app, exit_codes
from robosoc.config.project import load_project
from robosoc.config.project_scenario import project_scenario
from robosoc.config.scenario import ScenarioConfig
from robosoc.control import mission

BOUND_M = 0.20
"""The stated bound (docs/firmware-projects.md): the horizontal distance from each waypoint
throughout its 2 s hold, in every build (measured: 7.6 to 7.7 cm at seed 1; up to 12.7 cm over
seeds 1, 2, 3 and 7 in fixed+mul)."""
BUILDS = [("fixed", True), ("fixed", False), ("float", True), ("float", False)]
TASKS = {"estimator": (0, 1), "position": (1, 1), "attitude": (1, 0)}


def invoke(*args: object):
    return CliRunner().invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def project(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("position") / "m"
    result = invoke("new", folder, "--template", "position")
    assert result.exit_code == 0, result.output
    assert f"fly it: robosoc fly --firmware {folder}" in result.output
    return folder


def _mission(project: Path, **firmware: object) -> ScenarioConfig:
    """The project's own mission (its robosoc.toml's [chip] and [scenario]), ``firmware`` changed."""
    scenario = project_scenario(str(project))
    return dataclasses.replace(scenario, firmware=dataclasses.replace(scenario.firmware, **firmware))


def test_the_project_maps_three_tasks_on_the_three_core_tiles(project: Path) -> None:
    loaded = load_project(project)
    assert {t.name: tuple(t.tile) for t in loaded.tasks} == TASKS
    assert [(m.name, m.io_packet) for m in loaded.inputs()] == [("sensor", "sensor"), ("position", "position")]
    scenario = _mission(project)
    assert scenario.chip.powered_off == () and scenario.sensors.position.enabled
    assert scenario.flight.mission is not None and len(scenario.flight.mission.waypoints) == 4


@pytest.mark.parametrize(("arith", "multiplier"), BUILDS, ids=[f"{a}-{'mul' if m else 'no-mul'}" for a, m in BUILDS])
def test_the_mission_is_flown_in_every_build(project: Path, arith: str, multiplier: bool) -> None:
    from robosoc.outputs.flight_session import fly_scenario

    scenario = _mission(project, arith=arith, multiplier=multiplier)
    flight = fly_scenario(scenario, None, plot=False, logs=False)
    summary = flight.summary
    samples = scenario.samples
    assert list(summary["tasks"]) == list(TASKS)
    assert all(t["jobs"] == samples for t in summary["tasks"].values())  # one job of each task per sample
    assert summary["deadline_misses"] == 0
    figures = summary["mission"]
    assert figures["reached"] == 4
    for waypoint in figures["waypoints"]:
        assert waypoint["horizontal_error_max_m"] <= BOUND_M, waypoint
        assert waypoint["height_error_max_m"] <= BOUND_M, waypoint
    line = mission.timeline(scenario.flight, 0.18)
    assert line.landing is not None and line.disarm_s is not None
    assert figures["landed"] is True and line.landing.start_s < figures["landed_s"] < line.disarm_s
    assert figures["landing_error_m"] <= BOUND_M


def test_fly_firmware_flies_the_projects_mission_and_the_report_shows_the_waypoints(
    project: Path, tmp_path: Path
) -> None:
    out = tmp_path / "run"
    result = invoke("fly", "--firmware", project, "--out", out)
    assert result.exit_code == 0, result.output
    assert "waypoints reached" in result.output and "4 of 4" in result.output
    assert "landed" in result.output and "position jobs" in result.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["firmware"]["project"] == str(project)
    page = (out / "report.html").read_text()
    assert 'data-plot="mission"' in page and "waypoint x (hold)" in page
    assert page.count("waypoint (reached: green)") == 1


def test_table_closed_loop_has_a_row_group_per_task(project: Path) -> None:
    from robosoc.sweep import table_one

    spec = table_one.TableSpec(iterations=5, closed_loop=True, workers=1, project=str(project))
    result = table_one.measure_table(spec)
    assert len(result.runs) == 4 and all(run.source == "closed-loop" for run in result.runs)
    for run in result.runs:
        assert list(run.tasks) == list(TASKS)
        assert all(r.jobs == 5 and r.deadline_misses == 0 for r in run.tasks.values())
    text = "\n".join(table_one.format_table(result))
    assert "position response mean (us)" in text and "attitude energy per job (nJ)" in text


def test_runs_that_cannot_give_it_position_packets_refuse_it(project: Path, tmp_path: Path) -> None:
    off = tmp_path / "off.toml"
    off.write_text(f'duration_s = 1.0\n[firmware]\nproject = "{project}"\n[sensors.position]\nenabled = false\n')
    result = invoke("fly", off, "--no-out")
    assert result.exit_code == exit_codes.USAGE
    assert "sensors.position.enabled: the project 'position' takes position packets" in result.output
    dark = tmp_path / "dark.toml"
    dark.write_text("duration_s = 1.0\n[chip]\npowered_off = [[1, 1]]\n")
    result = invoke("fly", dark, "--firmware", project, "--no-out")
    assert result.exit_code == exit_codes.USAGE and "tasks[1].tile: [1, 1] (position) is powered off" in result.output
    result = invoke("firmware", "replay", "--firmware", project, "--seconds", "0.1")
    assert result.exit_code == exit_codes.USAGE
    assert "messages[2]: the project takes position packets from the I/O tile" in result.output
    result = invoke("fly", "--firmware", project, "--decoupled", "--no-out")
    assert result.exit_code == exit_codes.USAGE and "which the decoupled mode cannot send" in result.output
    result = invoke("table", "--firmware", project, "--iterations", "5")
    assert result.exit_code == exit_codes.USAGE and "--closed-loop flies each build instead" in result.output
    assert invoke("firmware", "build", "--firmware", project).exit_code == 0  # building needs no sensor
    assert dataclasses.replace(_mission(project), duration_s=1.0).firmware.project == str(project)


def test_each_vehicle_of_a_fleet_flies_the_mission_from_its_own_take_off_point(project: Path) -> None:
    from robosoc.outputs.flight_session import fly_scenario

    scenario = dataclasses.replace(_mission(project), vehicles=2, duration_s=9.0)  # to the first hold's end
    flight = fly_scenario(scenario, None, plot=False, logs=False)
    firsts = [v["mission"]["waypoints"][0] for v in flight.summary["vehicles"]]
    assert firsts[1]["x"] - firsts[0]["x"] == pytest.approx(3.0)  # the fleet's grid: 3 m apart
    assert all(w["reached"] and w["horizontal_error_max_m"] <= BOUND_M for w in firsts)
    assert flight.summary["min_separation_m"] > 2.5
