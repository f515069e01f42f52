"""The console script imports only the module of the command it runs (robosoc.cli, docs/cli.md).

That is right only if every command and group ``robosoc X`` is registered by ``robosoc.cli.X`` and
needs no other command module's registration; these tests check both, and what a light command
then loads.
"""

import json
import subprocess
import sys

import pytest

from robosoc.cli import COMMANDS, app, commands_for


def test_every_command_and_group_is_registered_by_the_module_of_its_name() -> None:
    registered: dict[str, set[str]] = {}
    for command in app.registered_commands:
        assert command.callback is not None
        registered.setdefault(str(command.name), set()).add(command.callback.__module__)
    for group in app.registered_groups:
        modules = {c.callback.__module__ for c in group.typer_instance.registered_commands if c.callback}
        registered.setdefault(str(group.name), set()).update(modules)
    assert set(registered) == set(COMMANDS)
    for name, modules in registered.items():
        assert modules == {f"robosoc.cli.{name}"}, name


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["fly", "--duration", "1"], ("fly",)),
        (["bench", "fly"], ("bench",)),
        (["scenario", "show", "fly"], ("scenario",)),
        (["--help"], COMMANDS),
        (["flyy"], COMMANDS),  # misspelt: all of them, so that typer can suggest the right one
        (["--duration", "1", "fly"], COMMANDS),
        ([], COMMANDS),
    ],
)
def test_the_command_line_names_the_modules_it_needs(args: list[str], expected: tuple[str, ...]) -> None:
    assert commands_for(args) == expected


_CHILD = """
import json, runpy, sys
sys.argv = ["robosoc"] + json.loads(sys.argv[1])
try:
    runpy.run_module("robosoc", run_name="__main__")
except SystemExit as stop:
    code = stop.code
loaded = sorted(name for name in sys.modules if name.startswith(("robosoc.cli.", "numba", "mujoco")))
print(json.dumps({"code": code, "loaded": loaded}), file=sys.stderr)
"""


def _commands_loaded(report: dict) -> set[str]:
    return {m.split(".")[2] for m in report["loaded"] if m.startswith("robosoc.cli.")} & set(COMMANDS)


def _run_in_a_child(args: list[str]) -> tuple[dict, str]:
    proc = subprocess.run([sys.executable, "-c", _CHILD, json.dumps(args)], capture_output=True, text=True, timeout=600)
    return json.loads(proc.stderr.strip().splitlines()[-1]), proc.stdout


def test_a_light_command_loads_no_other_command_and_no_simulator() -> None:
    report, out = _run_in_a_child(["scenario", "show"])
    assert report["code"] == 0
    assert "[sensors]" in out and "[flight]" in out  # the resolved scenario was printed
    assert not any(m.startswith(("numba", "mujoco")) for m in report["loaded"]), report["loaded"]
    assert _commands_loaded(report) == {"scenario"}


@pytest.mark.parametrize("command", ["fly", "bench", "serve"])
def test_a_command_alone_has_the_help_it_has_among_all(command: str) -> None:
    from typer.testing import CliRunner

    among_all = CliRunner().invoke(app, [command, "--help"], terminal_width=100)
    report, alone = _run_in_a_child([command, "--help"])
    assert report["code"] == 0 and among_all.exit_code == 0
    assert _commands_loaded(report) == {command}
    # the same options and texts (the child's terminal width may differ: compare the words)
    assert alone.split() == among_all.output.split()
