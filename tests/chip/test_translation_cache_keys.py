"""The translator's cached objects and region records are keyed by its sources, not by a number.

A checkout must never load an object or a record written by other translator sources (an
abandoned branch's objects, written for other chip-loop conventions, crashed the chip loop of a
later checkout that reused its hand-bumped version number).
"""

from __future__ import annotations

import shutil
from pathlib import Path

from robosoc.jit import compiler, manifest
from robosoc.kernels import kernel_digest

JIT_DIR = Path(compiler.__file__).parent


def _copies(tmp_path: Path) -> list[Path]:
    folder = tmp_path / "jit"
    folder.mkdir()
    for path in sorted(JIT_DIR.glob("*.py")):
        shutil.copy(path, folder / path.name)
    return sorted(folder.glob("*.py"))


def test_the_digest_follows_every_byte_of_the_translators_sources_and_the_kernels(tmp_path: Path) -> None:
    sources = _copies(tmp_path)
    assert {p.name for p in sources} >= {"emit_ir.py", "regions.py", "tables.py", "manifest.py", "compiler.py"}
    same = compiler.pipeline_digest(sources, kernels="k")
    assert compiler.pipeline_digest(sources, kernels="k") == same  # a function of its inputs
    emit = next(p for p in sources if p.name == "emit_ir.py")
    emit.write_bytes(emit.read_bytes() + b"\n# one comment more\n")
    assert compiler.pipeline_digest(sources, kernels="k") != same
    emit.write_bytes(emit.read_bytes()[: -len(b"\n# one comment more\n")])
    assert compiler.pipeline_digest(sources, kernels="k") == same
    assert compiler.pipeline_digest(sources, kernels="other kernels") != same


def test_objects_and_manifests_are_keyed_by_this_checkouts_digest() -> None:
    assert compiler.pipeline_digest(sorted(JIT_DIR.glob("*.py")), kernel_digest()) == compiler.PIPELINE
    assert compiler.Compiler(cache=False).env.endswith(f"pipeline {compiler.PIPELINE}")
    assert manifest._manifest_host().endswith(compiler.PIPELINE)
    code, options = b"\x13\x00\x00\x00", "options"
    key = manifest.manifest_key(code, options)
    manifest._manifest_host.cache_clear()
    real = compiler.PIPELINE
    try:
        manifest.PIPELINE = "another"  # what another checkout's sources would give
        assert manifest.manifest_key(code, options) != key
    finally:
        manifest.PIPELINE = real
        manifest._manifest_host.cache_clear()
    assert manifest.manifest_key(code, options) == key
