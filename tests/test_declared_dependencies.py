"""Every third-party package robosoc imports is declared in pyproject.toml with a lower bound (issue 34,
item 8: llvmlite was imported directly but arrived only through numba)."""

from __future__ import annotations

import ast
import re
import sys
import tomllib
from importlib import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _requirements() -> dict[str, str]:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    lines = list(project["dependencies"])
    for extra in project.get("optional-dependencies", {}).values():
        lines.extend(extra)
    out = {}
    for line in lines:
        name = re.match(r"[A-Za-z0-9_.-]+", line).group(0)  # type: ignore[union-attr]
        out[re.sub(r"[-_.]+", "-", name).lower()] = line
    return out


def _type_checking_only(tree: ast.AST) -> set[int]:
    """ids of the import nodes under ``if TYPE_CHECKING:`` (never imported at run time)."""
    skipped = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skipped.update(id(n) for child in node.body for n in ast.walk(child))
    return skipped


def _imported_top_level_modules() -> set[str]:
    names = set()
    for path in (ROOT / "src" / "robosoc").rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        skipped = _type_checking_only(tree)
        for node in ast.walk(tree):
            if id(node) in skipped:
                continue
            if isinstance(node, ast.Import):
                names.update(alias.name.split(".")[0] for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names.add(node.module.split(".")[0])
    return {n for n in names if n != "robosoc" and n not in sys.stdlib_module_names}


def test_every_imported_package_is_declared_with_a_lower_bound() -> None:
    declared = _requirements()
    distributions = metadata.packages_distributions()
    missing = []
    for module in sorted(_imported_top_level_modules()):
        providers = [re.sub(r"[-_.]+", "-", d).lower() for d in distributions.get(module, [])]
        named = [p for p in providers if p in declared]
        if providers and not named:
            missing.append(f"{module} (from {', '.join(providers)})")
        for key in named:
            assert ">=" in declared[key], f"{declared[key]}: give a lower bound"
    assert not missing, f"imported but not declared in pyproject.toml: {missing}"
    assert declared["llvmlite"].startswith("llvmlite>=")
