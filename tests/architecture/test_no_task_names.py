"""No module of robosoc names a task of a shipped firmware example: tasks are data (issue 32).

Every string literal of ``src/robosoc`` (docstrings aside) that equals the name of a task of a
shipped project (``firmware/templates/*/robosoc.toml``), or names one in a dotted summary field
(``tasks.<name>.``), must be one of the uses listed here, each a different thing that happens to
share the word (a scenario field, a packet format, a C library, a trace-format key).  The project
loader (``config/project.py``) is exempt: it is where task names are read.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

from robosoc.config.project import load_project
from robosoc.firmware import TEMPLATES_DIR

SRC = Path(__file__).resolve().parents[2] / "src" / "robosoc"
LOADER = "config/project.py"

NOT_A_TASK: dict[tuple[str, str], str] = {
    ("benchmarks/fly.py", "controller"): "the scenario's controller (chip or host), a table column",
    ("benchmarks/sweep.py", "controller"): "the scenario field controller",
    ("cli/link_options.py", "controller"): "the --controller option's value",
    ("cli/scenario_flags.py", "controller"): "the --controller option and its field",
    ("config/scenario.py", "controller"): "the scenario field controller",
    ("outputs/decoupled_summary.py", "controller"): "the summary key controller",
    ("outputs/report.py", "controller"): "the summary key controller",
    ("outputs/run_summary.py", "controller"): "the summary key controller",
    ("cli/project_check.py", "position"): "the position packet format (host/packets.py)",
    ("config/project.py", "position"): "the position packet format",
    ("cosim/lockstep.py", "position"): "the position packet format",
    ("cosim/replay.py", "position"): "the position packet's field",
    ("host/packets.py", "position"): "the position packet format and its field",
    ("outputs/ros2_flight.py", "position"): "a ROS message field (geometry_msgs/Pose.position)",
    ("firmware/__init__.py", "estimator"): "the C library of that name (firmware/app/estimator.c)",
    ("firmware/__init__.py", "pid"): "the C library of that name (firmware/app/pid.c)",
    ("outputs/chip_trace.py", "pid"): "the Chrome trace format's process id key",
    ("outputs/report.py", "attitude"): "the id of the report's attitude figure",
}


def _task_names() -> set[str]:
    templates = [d for d in TEMPLATES_DIR.iterdir() if (d / "robosoc.toml").is_file()]
    assert len(templates) >= 3  # blank, quadrotor, position at least
    return {task.name for d in templates for task in load_project(d).tasks}


def _literals(path: Path) -> list[str]:
    tree = ast.parse(path.read_text())
    docstrings = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                docstrings.add(id(first.value))
    return [
        node.value
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings
    ]


def test_no_module_names_a_task_of_a_shipped_example() -> None:
    names = _task_names()
    assert {"estimator", "pid", "controller"} <= names
    dotted = re.compile(r"\btasks\.(" + "|".join(map(re.escape, sorted(names))) + r")\b")
    found: dict[tuple[str, str], int] = {}
    for path in sorted(SRC.rglob("*.py")):
        where = path.relative_to(SRC).as_posix()
        for text in _literals(path):
            if text in names:
                found[(where, text)] = found.get((where, text), 0) + 1
            for match in dotted.finditer(text):
                found[(where, f"tasks.{match.group(1)}")] = 1
    named = {key for key in found if key[0] != LOADER or key in NOT_A_TASK}
    assert named - set(NOT_A_TASK) == set(), "a module names a task of a shipped example: read it from the project"
    assert set(NOT_A_TASK) - named == set(), "listed uses that are gone: remove them from NOT_A_TASK"


def test_the_scan_finds_a_task_name_where_one_is_written(tmp_path: Path) -> None:
    """The scanner itself: a literal task name in code is found, in a docstring it is not."""
    sample = tmp_path / "m.py"
    sample.write_text('"""estimator in a docstring."""\nTASK = "estimator"\nMETRIC = "tasks.pid.energy"\n')
    assert _literals(sample) == ["estimator", "tasks.pid.energy"]
