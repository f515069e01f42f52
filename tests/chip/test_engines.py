"""The engines as objects (robosoc.chip.engines): one resolver, one check of a name, the same
methods on each; the interpreter imports nothing of the translator."""

from __future__ import annotations

import subprocess
import sys

import pytest

from robosoc.chip.core_state import CoreState
from robosoc.chip.engines import AUTO, ENGINES, INTERP, JIT, resolve_engine
from robosoc.config.chip import ENGINE_CHOICES, ChipConfig, engine_name


def test_every_name_resolves_to_its_engine_and_an_engine_to_itself() -> None:
    assert tuple(ENGINES) == ENGINE_CHOICES
    assert [resolve_engine(name) for name in ENGINE_CHOICES] == [INTERP, JIT, AUTO]
    for engine in (INTERP, JIT, AUTO):
        assert resolve_engine(engine) is engine
        assert str(engine) == engine.name


@pytest.mark.parametrize("bad", ["fast", "", "JIT", "interp "])
def test_an_unknown_name_is_refused_with_the_choices(bad: str) -> None:
    message = f"engine: must be one of 'interp', 'jit', 'auto', got {bad!r}"
    with pytest.raises(ValueError) as resolved:
        resolve_engine(bad)
    with pytest.raises(ValueError) as configured:
        ChipConfig(engine=bad)
    assert str(resolved.value) == str(configured.value) == message
    with pytest.raises(ValueError, match=r"^--engine: must be one of interp, jit, auto, got "):
        engine_name(bad, "--engine", quote=False)  # the command line's words


def test_the_engines_answer_the_same_questions() -> None:
    state = CoreState.new(mul=True, sram_size=4096, base=0x40000000, errata=0)
    assert INTERP.translator(state) is None and not INTERP.translates and not INTERP.waits_for_busy_tiles
    for engine, waits in ((JIT, False), (AUTO, True)):
        translator = engine.translator(state)
        assert translator is not None and translator.mode == engine.name
        assert engine.translates and engine.waits_for_busy_tiles == waits


def test_the_interpreter_imports_nothing_of_the_translator() -> None:
    script = (
        "import sys\n"
        "from robosoc.chip.mpsoc import MPSoC\n"
        "from robosoc.chip.single import SingleCoreSoC\n"
        "from robosoc.config.chip import ChipConfig\n"
        "SingleCoreSoC(engine='interp')\n"
        "MPSoC(ChipConfig(), engine='interp')\n"
        "print(sorted(m for m in sys.modules if m.startswith('robosoc.jit')))\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300, check=True)
    assert done.stdout.strip() == "[]", done.stderr


def test_the_core_benchmark_reports_the_engine_it_was_given(capsys: pytest.CaptureFixture[str]) -> None:
    """Named or given as an object, the engine's median is the one returned and printed last."""
    from rich.console import Console

    from robosoc.benchmarks.core import run_core_benchmark

    for engine in ("jit", JIT):
        console = Console(record=True, width=200)
        median = run_core_benchmark(runs=1, iterations=2, engine=engine, console=console)
        text = console.export_text()
        assert "jit / interp: " in text
        assert f"jit: MIPS median {median:.1f}," in text
        assert capsys.readouterr().out.strip().splitlines()[-1] == f"core: {median:.0f} MIPS"
