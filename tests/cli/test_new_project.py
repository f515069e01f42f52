"""``robosoc new`` and ``robosoc fly --firmware`` (issue 32): every shipped template scaffolded, built
in the four builds and flown; the blank one takes off and hovers; the errors a firmware author
makes end the command with a message naming the cause, and nothing half-made."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from robosoc.cli import app, exit_codes
from robosoc.cli.new import TEMPLATES
from robosoc.cli.scenario_flags import ScenarioFlags, resolve
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.project import load_project
from robosoc.config.scenario import ScenarioConfig
from robosoc.control.flight import ROW_FIELDS

BUILDS = [("fixed", True), ("fixed", False), ("float", True), ("float", False)]


def invoke(*args: object):
    return CliRunner().invoke(app, [str(a) for a in args])


def test_the_templates_are_the_shipped_projects() -> None:
    assert set(TEMPLATES) == {"blank", "quadrotor", "position"}


@pytest.mark.parametrize("template", ["blank", "quadrotor"])
def test_new_makes_a_project_that_loads(tmp_path: Path, template: str) -> None:
    result = invoke("new", tmp_path / "mine", "--template", template)
    assert result.exit_code == 0, result.output
    project = load_project(tmp_path / "mine")
    assert project.project.name == template
    assert f"robosoc fly --firmware {tmp_path / 'mine'}" in result.output
    assert len(project.inputs()) == 1 and len(project.outputs()) == 1


def test_new_refuses_a_folder_that_holds_something(tmp_path: Path) -> None:
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("mine")
    result = invoke("new", tmp_path / "mine")
    assert result.exit_code == exit_codes.USAGE and "is not empty" in result.output
    assert sorted(p.name for p in (tmp_path / "mine").iterdir()) == ["notes.txt"]
    (tmp_path / "file").write_text("x")
    assert invoke("new", tmp_path / "file").exit_code == exit_codes.USAGE
    assert invoke("new", tmp_path / "x", "--template", "nope").exit_code == exit_codes.USAGE


@pytest.mark.parametrize("template", ["blank", "quadrotor"])
@pytest.mark.parametrize(("arith", "multiplier"), BUILDS)
def test_every_template_flies_in_every_build(tmp_path: Path, template: str, arith: str, multiplier: bool) -> None:
    from robosoc.outputs.flight_session import fly_scenario

    assert invoke("new", tmp_path / "p", "--template", template).exit_code == 0
    project = load_project(tmp_path / "p")
    fw = FirmwareConfig(arith=arith, multiplier=multiplier, project=str(tmp_path / "p"))
    flight = fly_scenario(ScenarioConfig(duration_s=0.2, firmware=fw), None, plot=False, logs=False)
    tasks = flight.summary["tasks"]
    assert list(tasks) == list(project.task_names)
    assert all(t["jobs"] == 20 and t["deadline_misses"] == 0 for t in tasks.values())
    assert flight.summary["firmware"]["project"] == str(tmp_path / "p")
    pwm = [ROW_FIELDS.index(f"pwm{i}") for i in range(4)]
    assert (flight.rows[0][:, pwm] == 0).all()  # disarmed on the ground: calibrating


def test_the_blank_project_takes_off_and_holds_its_height(tmp_path: Path) -> None:
    assert invoke("new", tmp_path / "mine").exit_code == 0
    out = tmp_path / "run"
    result = invoke("fly", "--firmware", tmp_path / "mine", "--duration", "5.5", "--out", out)
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["tasks"]["controller"]["jobs"] == 550 and summary["deadline_misses"] == 0
    rows = np.loadtxt(out / "flight.csv", delimiter=",", skiprows=1)
    z, sp = rows[:, ROW_FIELDS.index("z")], rows[:, ROW_FIELDS.index("sp_height")]
    last = slice(-50, None)  # the last half second: climbed to the 1 m setpoint, holding it
    assert np.abs(z[last] - sp[last]).max() < 0.1 and sp[-1] == pytest.approx(1.0)
    assert "from --firmware: firmware.project" in result.output


def test_a_scenario_names_its_project_relative_to_its_own_folder(tmp_path: Path) -> None:

    assert invoke("new", tmp_path / "sc" / "fw").exit_code == 0
    scenario = tmp_path / "sc" / "flight.toml"
    scenario.write_text('duration_s = 0.1\n[firmware]\nproject = "fw"\n')
    config = resolve(ScenarioFlags.of(None, scenario, {})).config
    assert config.firmware.project == str(tmp_path / "sc" / "fw")


def test_project_errors_end_the_flight_before_it_starts(tmp_path: Path) -> None:
    missing = invoke("fly", "--firmware", tmp_path / "none", "--no-out")
    assert missing.exit_code == exit_codes.USAGE and f"--firmware: no folder {tmp_path / 'none'}" in missing.output
    assert invoke("new", tmp_path / "p").exit_code == 0
    toml = tmp_path / "p" / "robosoc.toml"
    toml.write_text(toml.read_text().replace("tile = [0, 1]", "tile = [1, 1]"))  # the project's chip powers it
    dark = tmp_path / "dark.toml"
    dark.write_text("[chip]\npowered_off = [[1, 1]]\n")
    off = invoke("fly", dark, "--firmware", tmp_path / "p", "--no-out")
    assert off.exit_code == exit_codes.USAGE
    assert "tasks[0].tile: [1, 1] (controller) is powered off" in off.output
    mapped = resolve(ScenarioFlags.of(None, None, {"firmware": str(tmp_path / "p")})).config
    assert mapped.chip.powered_off == ((0, 1), (1, 0))  # the seed's rule: every tile no task uses is off
    toml.write_text(toml.read_text().replace("stack_bytes = 8192", "stack_bytes = 8192\ncolour = 3"))
    bad = invoke("fly", "--firmware", tmp_path / "p", "--no-out")
    assert bad.exit_code == exit_codes.USAGE and f"{toml}: tasks[0].colour: unknown field" in bad.output


def test_a_compile_error_names_file_and_line_and_leaves_no_run(tmp_path: Path) -> None:
    assert invoke("new", tmp_path / "p").exit_code == 0
    source = tmp_path / "p" / "controller.c"
    source.write_text(source.read_text().replace("pid_init(&pid);", "pid_init(&pid)"))  # a missing ;
    result = invoke("fly", "--firmware", tmp_path / "p", "--duration", "0.1", "--out", tmp_path / "run")
    assert result.exit_code == exit_codes.USAGE
    assert "the firmware does not build" in result.output and "controller.c:" in result.output
    assert "Traceback" not in result.output


def test_an_unsupported_build_is_refused_with_the_key(tmp_path: Path) -> None:
    assert invoke("new", tmp_path / "p").exit_code == 0
    toml = tmp_path / "p" / "robosoc.toml"
    toml.write_text(toml.read_text().replace('arith = ["float", "fixed"]', 'arith = ["fixed"]'))
    result = invoke("fly", "--firmware", tmp_path / "p", "--arith", "float", "--duration", "0.1", "--no-out")
    assert result.exit_code == exit_codes.USAGE and "supports fixed, not 'float'" in result.output


def test_table_measures_a_projects_tasks_in_the_builds_it_supports(tmp_path: Path) -> None:
    import csv

    assert invoke("new", tmp_path / "p", "--template", "quadrotor").exit_code == 0
    toml = tmp_path / "p" / "robosoc.toml"
    toml.write_text(toml.read_text().replace("multiplier = [true, false]", "multiplier = [true]"))
    result = invoke(
        "table", "--firmware", tmp_path / "p", "--iterations", "5", "--workers", "1", "--out", tmp_path / "t"
    )
    assert result.exit_code == 0, result.output
    rows = list(csv.DictReader((tmp_path / "t" / "table.csv").open()))
    assert [(r["build"], r["task"]) for r in rows] == [
        (b, t) for b in ("float+mul", "fixed+mul") for t in ("estimator", "pid")
    ]  # the builds it lists, a row per task of its robosoc.toml
    # the quadrotor project carries the seed's Table I ([[reference]]): its figures beside each row
    assert all(r["jobs"] == "5" for r in rows)
    assert [float(r["seed_response_ms"]) for r in rows] == [107.01, 25.5, 87.5, 20.0]
    data = json.loads((tmp_path / "t" / "table.json").read_text())
    assert data["spec"]["project"] == str(tmp_path / "p")
    # its orderings are checked where both builds ran (with the multiplier only: none compares two)
    assert data["orderings"] and all(
        o["holds"] is None for o in data["orderings"] if "no-mul" in o["lower"] + o["higher"]
    )
    assert "EKF response mean (us)" in result.output  # the project's labels
    assert "fixed-no-mul" in result.output  # its column, empty
    # the release is the scenario's for a project with its own main (this one), its robosoc.toml's otherwise
    assert invoke("new", tmp_path / "b").exit_code == 0
    refused = invoke("table", "--firmware", tmp_path / "b", "--release", "both")
    assert refused.exit_code == exit_codes.USAGE and "ROBOSOC_RELEASE_PERIODIC" in refused.output


def _broken(tmp_path: Path, before: str, insert: str) -> Path:
    assert invoke("new", tmp_path / "p").exit_code == 0
    source = tmp_path / "p" / "controller.c"
    text = source.read_text()
    assert before in text
    source.write_text(text.replace(before, insert + before, 1))
    return tmp_path / "p"


def test_a_task_that_faults_names_tile_task_pc_and_the_run_says_incomplete(tmp_path: Path) -> None:
    project = _broken(
        tmp_path, "    if (est_packet_step", '    if (in.seq == 3) { __asm__ volatile(".word 0x00000000"); }\n'
    )
    out = tmp_path / "run"
    result = invoke("fly", "--firmware", project, "--duration", "0.2", "--out", out)
    assert result.exit_code == exit_codes.SIMULATOR_STOP, result.output
    message = " ".join(result.output.split())
    assert "tile (0, 1): illegal instruction at pc 0x" in message and "(controller_on_message+0x" in message
    assert "(task 'controller')" in message and "Traceback" not in message
    summary = json.loads((out / "summary.json").read_text())
    assert summary["complete"] is False and "illegal instruction" in summary["stopped"]
    assert summary["tasks"]["controller"]["jobs"] == 3  # the jobs of samples 0, 1, 2 were done


def test_a_task_the_kernel_refuses_is_named(tmp_path: Path) -> None:
    """Two tasks of 1 MiB stack each on one tile of 2 MiB SRAM: no room for the second."""
    assert invoke("new", tmp_path / "p", "--template", "quadrotor").exit_code == 0
    toml = tmp_path / "p" / "robosoc.toml"
    text = toml.read_text().replace("tile = [1, 0]", "tile = [0, 1]")
    toml.write_text(
        text.replace("stack_bytes = 6144", "stack_bytes = 1048576").replace(
            "stack_bytes = 3072", "stack_bytes = 1048576"
        )
    )
    result = invoke("fly", "--firmware", tmp_path / "p", "--duration", "0.05", "--no-out")
    assert result.exit_code == exit_codes.SIMULATOR_STOP, result.output
    assert "tile (0, 1): the kernel refused task 'pid'" in " ".join(result.output.split())


def test_a_project_is_linked_for_its_tiles_sram_and_one_too_large_is_a_build_error(tmp_path: Path) -> None:
    assert invoke("new", tmp_path / "p").exit_code == 0
    scenario = tmp_path / "s.toml"  # 1 MiB tiles: the stack's top moves down, the program still fits
    scenario.write_text('duration_s = 0.05\n[firmware]\nproject = "p"\n[chip.tile]\nsram_bytes = 1048576\n')
    assert invoke("fly", scenario, "--no-out").exit_code == 0
    scenario.write_text(scenario.read_text().replace("1048576", "16384"))  # smaller than the program
    small = invoke("fly", scenario, "--no-out")
    assert small.exit_code == exit_codes.USAGE and "the firmware does not build" in small.output
    assert "does not fit in SRAM of 16384 bytes" in small.output and "Traceback" not in small.output


def test_the_firmware_commands_build_measure_and_replay_a_project(tmp_path: Path) -> None:
    assert invoke("new", tmp_path / "p").exit_code == 0
    built = invoke("firmware", "build", "--firmware", tmp_path / "p", "--arith", "float", "-o", tmp_path / "p.elf")
    assert built.exit_code == 0, built.output
    assert (tmp_path / "p.elf").read_bytes()[:4] == b"\x7fELF"
    size = invoke("firmware", "size", "--firmware", tmp_path / "p", "--top", "200")
    assert size.exit_code == 0 and "controller_on_message" in size.output and "est_packet_step" in size.output
    out = tmp_path / "replay"
    replayed = invoke("firmware", "replay", "--firmware", tmp_path / "p", "--seconds", "0.5", "--out", out)
    assert replayed.exit_code == 0, replayed.output
    assert json.loads((out / "summary.json").read_text())["tasks"]["controller"]["jobs"] == 50
    source = tmp_path / "p" / "controller.c"
    source.write_text(source.read_text().replace("pid_init(&pid);", "pid_init(&pid)"))
    broken = invoke("firmware", "build", "--firmware", tmp_path / "p")
    assert broken.exit_code == exit_codes.USAGE and "controller.c:" in broken.output


def test_profile_refuses_a_run_whose_scenario_names_a_project_that_is_gone(tmp_path: Path) -> None:
    assert invoke("new", tmp_path / "p").exit_code == 0
    run = tmp_path / "run"
    assert invoke("fly", "--firmware", tmp_path / "p", "--duration", "0.05", "--out", run).exit_code == 0
    scenario = run / "scenario.toml"
    scenario.write_text(scenario.read_text().replace(str(tmp_path / "p"), str(tmp_path / "gone")))  # edited by hand
    result = invoke("profile", run)
    assert result.exit_code == exit_codes.USAGE and "Traceback" not in result.output
    assert f"{scenario}: firmware.project: no folder {tmp_path / 'gone'}" in " ".join(result.output.split())


def test_a_firmware_that_stops_commanding_marks_the_run(tmp_path: Path) -> None:
    """The controller answers samples 0..29 only: from sample 30 no PWM command reaches the I/O tile,
    so 20 periods (0.2 s at 100 Hz) of silence, at least the timeout of 15."""
    assert invoke("new", tmp_path / "p").exit_code == 0
    source = tmp_path / "p" / "controller.c"
    quiet = "    if (in.seq >= 30u) {\n        return; /* gone quiet */\n    }\n    os_send(ROBOSOC_MSG_PWM_TILE"
    source.write_text(source.read_text().replace("    os_send(ROBOSOC_MSG_PWM_TILE", quiet))
    scenario = tmp_path / "s.toml"
    scenario.write_text('duration_s = 0.5\n[firmware]\nproject = "p"\ncommand_timeout_periods = 15\n')
    result = invoke("fly", scenario, "--out", tmp_path / "out")
    assert result.exit_code == 0, result.output
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    silence = summary["no_actuator_command"]
    assert silence["periods"] == 20 and silence["from_s"] == pytest.approx(0.30)
    assert silence["seconds"] == pytest.approx(0.20, abs=1e-9)  # to the end of the run, 0.5 s
    assert "no actuator command for 0.20 s from t = 0.30 s" in " ".join(result.output.split())
    # the motors held the last command: every PWM column from 0.3 s on equals that of 0.29 s
    rows = np.genfromtxt(tmp_path / "out" / "flight.csv", delimiter=",", names=True)
    held = rows[(rows["t"] >= 0.3)]
    last = rows[np.searchsorted(rows["t"], 0.295)]
    assert all((held[f"pwm{i}"] == last[f"pwm{i}"]).all() for i in range(4))
    scenario.write_text(scenario.read_text().replace("= 15", "= 21"))  # longer than the silence: not marked
    assert invoke("fly", scenario, "--out", tmp_path / "out2").exit_code == 0
    assert "no_actuator_command" not in json.loads((tmp_path / "out2" / "summary.json").read_text())


def test_a_pwm_message_of_the_wrong_size_stops_the_flight_naming_it(tmp_path: Path) -> None:
    """The I/O tile knows the size of the message it takes (robosoc_msg_pwm_t, 16 bytes): a
    controller that sends 4 bytes short ends the flight with exit code 3, the message named."""
    project = _broken(tmp_path, "    os_send(ROBOSOC_MSG_PWM_TILE", "")
    source = project / "controller.c"
    sent = "&out, ROBOSOC_MSG_PWM_BYTES);"
    assert sent in source.read_text()
    source.write_text(source.read_text().replace(sent, "&out, ROBOSOC_MSG_PWM_BYTES - 4u);"))
    out = tmp_path / "run"
    result = invoke("fly", "--firmware", project, "--duration", "0.05", "--out", out)
    assert result.exit_code == exit_codes.SIMULATOR_STOP, result.output
    text = " ".join(result.output.split())
    assert "malformed message 'pwm' on its port 3: pwm: 12 bytes, expected 16" in text and "Traceback" not in text
    assert json.loads((out / "summary.json").read_text())["complete"] is False
