"""The packages of robosoc import only downward: a declared layer order, checked on the import graph.

Every ``import robosoc.X...`` and ``from robosoc.X... import`` in ``src/robosoc`` counts, at module
level, inside functions (lazy imports) and under ``TYPE_CHECKING`` alike.  A package may import
packages of lower layers only; packages of one layer do not import each other.  The order is the
picture of docs/architecture.md, and that document lists the same layers (checked here too).
"""

from __future__ import annotations

import ast
import re
from collections import defaultdict
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "src" / "robosoc"

#: Bottom to top.  A package (or top-level module) may import those of the layers below its own.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("cache", "isa", "records", "output_files", "program", "firmware"),
    ("config",),
    ("kernels", "physics"),
    ("toolchain",),
    ("jit",),
    ("chip",),
    ("debug", "control"),
    ("host",),
    ("cosim",),
    ("analysis", "outputs"),
    ("sweep",),
    ("benchmarks",),
    ("cli",),
    ("__main__",),
)

#: Imports that still run upward, each with the reason and the work that removes it.  The test
#: fails when one of them is gone (so this list only shrinks) or when a new one appears.
KNOWN_UPWARD: dict[tuple[str, str], str] = {}


def _layer_of() -> dict[str, int]:
    return {name: k for k, layer in enumerate(LAYERS) for name in layer}


def _unit(path: Path, package: Path = PACKAGE) -> str:
    rel = path.relative_to(package)
    return rel.parts[0] if len(rel.parts) > 1 else rel.stem


def import_graph(package: Path = PACKAGE) -> dict[tuple[str, str], set[str]]:
    """(importing package, imported package) -> the files (relative to ``package``) that do it."""
    edges: dict[tuple[str, str], set[str]] = defaultdict(set)
    for path in sorted(package.rglob("*.py")):
        here = _unit(path, package)
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
                if node.module == "robosoc":  # from robosoc import X
                    names = [f"robosoc.{alias.name}" for alias in node.names]
            else:
                continue
            for name in names:
                parts = name.split(".")
                if parts[0] == "robosoc" and len(parts) > 1 and parts[1] != here:
                    edges[(here, parts[1])].add(str(path.relative_to(package)))
    return edges


def test_every_package_has_a_declared_layer() -> None:
    units = {_unit(p) for p in PACKAGE.rglob("*.py")} - {"__init__"}
    undeclared = sorted(units - set(_layer_of()))
    assert not undeclared, f"packages without a layer (declare them here and in docs/architecture.md): {undeclared}"
    gone = sorted(set(_layer_of()) - units)
    assert not gone, f"LAYERS names packages that no longer exist: {gone}"


def test_packages_import_only_downward() -> None:
    layer = _layer_of()
    upward = {}
    for (src, dst), files in import_graph().items():
        if dst not in layer:
            continue  # a module that is not a package of its own (robosoc.__init__): nothing to order
        if layer[dst] >= layer[src]:
            upward[(src, dst)] = sorted(files)
    new = {edge: files for edge, files in upward.items() if edge not in KNOWN_UPWARD}
    assert not new, "imports that run upward or sideways (move the code, or the layer order):\n" + "\n".join(
        f"  {a} -> {b}: {', '.join(files)}" for (a, b), files in sorted(new.items())
    )
    fixed = sorted(set(KNOWN_UPWARD) - set(upward))
    assert not fixed, f"these known upward imports are gone: take them out of KNOWN_UPWARD: {fixed}"


def test_no_cycle_between_packages_but_the_known_ones() -> None:
    edges = {edge for edge in import_graph() if edge not in KNOWN_UPWARD}
    graph: dict[str, set[str]] = defaultdict(set)
    for a, b in edges:
        graph[a].add(b)
    state: dict[str, int] = {}

    def visit(node: str, path: list[str]) -> None:
        state[node] = 1
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                pytest.fail("cycle of imports between packages: " + " -> ".join([*path[path.index(nxt) :], nxt]))
            if nxt not in state:
                visit(nxt, [*path, nxt])
        state[node] = 2

    for start in sorted(graph):
        if start not in state:
            visit(start, [start])


def test_the_graph_holds_imports_at_module_level_in_functions_and_for_type_checking(tmp_path: Path) -> None:
    package = tmp_path / "robosoc"
    (package / "chip").mkdir(parents=True)
    (package / "chip" / "mpsoc.py").write_text(
        "from typing import TYPE_CHECKING\n"
        "import robosoc.cli.typer_apps\n"
        "from robosoc.chip import elf\n"  # its own package: no edge
        "if TYPE_CHECKING:\n    from robosoc.sweep import plan\n"
        "def f():\n    from robosoc import outputs, records\n"
    )
    (package / "records.py").write_text("import json\nfrom robosoc.config.chip import ChipConfig\n")
    assert import_graph(package) == {
        ("chip", "cli"): {"chip/mpsoc.py"},
        ("chip", "sweep"): {"chip/mpsoc.py"},
        ("chip", "outputs"): {"chip/mpsoc.py"},
        ("chip", "records"): {"chip/mpsoc.py"},
        ("records", "config"): {"records.py"},
    }


def test_docs_architecture_lists_the_layers_in_this_order() -> None:
    """docs/architecture.md's layer list (lines ``N. name, name``) is LAYERS from the top down."""
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    block = text.split("<!-- layers -->")[1].split("<!-- /layers -->")[0]
    documented = [
        tuple(name.strip(" `") for name in m.group(1).split(","))
        for m in re.finditer(r"^\s*\d+\.\s+(.+?)\s*(?:—|$)", block, flags=re.MULTILINE)
    ]
    assert documented == [tuple(f"{n}" for n in layer) for layer in reversed(LAYERS)]
