"""``robosoc run``: output, exit code, summary line and the stats file, on a real compiled program."""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from typer.testing import CliRunner

from robosoc.chip.energy import EnergyModel
from robosoc.cli import app
from robosoc.toolchain import build_elf

PROGRAM = """
#include "hf_print.h"
int main(void) {
    volatile unsigned a = 1234, b = 5678;
    hf_printf("product %u\\n", a * b);
    return 42;
}
"""


@pytest.fixture(scope="module")
def elf(tmp_path_factory: pytest.TempPathFactory) -> Path:
    src = tmp_path_factory.mktemp("prog") / "prog.c"
    src.write_text(PROGRAM)
    return build_elf([src], mul=True)


def test_run_prints_output_and_returns_the_exit_code(elf: Path, tmp_path: Path):
    stats = tmp_path / "stats.json"
    result = CliRunner().invoke(app, ["run", str(elf), "--stats", str(stats), "--exit-code", "program"])
    assert result.exit_code == 42
    assert "product 7006652" in result.stdout
    record = json.loads(stats.read_text())
    c = record["counters"]
    assert record["exit_code"] == 42 and record["error"] is None
    assert c["instructions"] == sum(
        c[k] for k in ("jump", "branch", "memory", "add", "logic", "other", "mul", "system")
    )
    model = EnergyModel.load()
    assert record["energy_nj"] == pytest.approx(model.total_nj(c))
    assert record["energy_nj"] > 0


def test_summary_line_goes_to_stderr(elf: Path):
    proc = subprocess.run(
        [sys.executable, "-m", "robosoc", "run", str(elf)], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 4  # --exit-code status: the program exited with a non-zero code
    assert "exit code 42" in proc.stderr
    assert proc.stdout == "product 7006652\n"
    assert "cycles" in proc.stderr and "CPI" in proc.stderr and "nJ" in proc.stderr and "MIPS" in proc.stderr


def test_running_a_mul_program_on_a_core_without_multiplier_fails_clearly(elf: Path, tmp_path: Path):
    stats = tmp_path / "stats.json"
    result = CliRunner().invoke(app, ["run", str(elf), "--no-mul", "--stats", str(stats)])
    assert result.exit_code == 3
    assert "without the multiplier" in result.stderr and "main+0x" in result.stderr
    assert "without the multiplier" in json.loads(stats.read_text())["error"]


def test_cycle_budget(elf: Path):
    result = CliRunner().invoke(app, ["run", str(elf), "--max-cycles", "50"])
    assert result.exit_code == 3 and "cycle budget of 50 cycles" in result.stderr


def test_bad_files_are_named(tmp_path: Path):
    missing = tmp_path / "missing.elf"
    result = CliRunner().invoke(app, ["run", str(missing)])
    assert result.exit_code == 2 and "missing.elf" in result.stderr
    text = tmp_path / "text.elf"
    text.write_text("not an elf")
    result = CliRunner().invoke(app, ["run", str(text)])
    assert result.exit_code == 2 and "text.elf" in result.stderr


def test_custom_energy_file_is_used_and_validated(elf: Path, tmp_path: Path):
    default = Path(EnergyModel.load().path)
    source = (Path(__file__).parents[2] / "src" / default).read_text() if not default.exists() else default.read_text()
    doubled = tmp_path / "doubled.toml"
    doubled.write_text(source.replace("pj = 43.15", "pj = 86.30"))
    out_a, out_b = tmp_path / "a.json", tmp_path / "b.json"
    CliRunner().invoke(app, ["run", str(elf), "--stats", str(out_a)])
    CliRunner().invoke(app, ["run", str(elf), "--stats", str(out_b), "--energy", str(doubled)])
    a, b = json.loads(out_a.read_text()), json.loads(out_b.read_text())
    assert b["energy_pj"]["memory"] == pytest.approx(2 * a["energy_pj"]["memory"])
    broken = tmp_path / "broken.toml"
    broken.write_text(textwrap.dedent(source.replace('source = "ORCA HF-RISCV characterisation: loads', 'x = "')))
    result = CliRunner().invoke(app, ["run", str(elf), "--energy", str(broken)])
    assert result.exit_code == 2 and "broken.toml" in result.stderr and "instruction.memory.source" in result.stderr


MULHSU_PROGRAM = """
#include "hf_print.h"
int main(void) {
    volatile int a = -3;
    volatile unsigned b = 5;
    int hi;
    __asm__ volatile("mulhsu %0, %1, %2" : "=r"(hi) : "r"(a), "r"(b));
    hf_printf("high %d\\n", hi);
    return 0;
}
"""


@pytest.fixture(scope="module")
def mulhsu_elf(tmp_path_factory: pytest.TempPathFactory) -> Path:
    src = tmp_path_factory.mktemp("mulhsu") / "mulhsu.c"
    src.write_text(MULHSU_PROGRAM)
    return build_elf([src], mul=True)


def test_errata_modes_of_run(mulhsu_elf: Path, tmp_path: Path):
    # -3 * 5 = -15: the signed x unsigned high word is -1 (all ones); the RTL computes MULHU
    # (0xfffffffd * 5) >> 32 = 4
    stats = tmp_path / "spec.json"
    spec = CliRunner().invoke(app, ["run", str(mulhsu_elf), "--stats", str(stats)])
    assert spec.exit_code == 0 and "high -1" in spec.stdout
    assert "RTL errata: mulhsu 1" in spec.stderr and "robosoc computed the RISC-V result" in spec.stderr
    assert json.loads(stats.read_text())["errata"] == {"mulhsu": 1, "irq_during_mul": 0}
    rtl = CliRunner().invoke(app, ["run", str(mulhsu_elf), "--errata", "rtl"])
    assert rtl.exit_code == 0 and "high 4" in rtl.stdout
    assert "RTL errata: mulhsu 1" in rtl.stderr


def test_errata_mode_must_be_known(mulhsu_elf: Path):
    result = CliRunner().invoke(app, ["run", str(mulhsu_elf), "--errata", "hardware"])
    assert result.exit_code == 2
    assert "--errata: must be one of spec, rtl, got 'hardware'" in result.stderr


@pytest.mark.parametrize("engine", ["jit", "auto"])
def test_every_engine_gives_the_same_run(elf: Path, tmp_path: Path, engine: str):
    records = {}
    for name in ("interp", engine):
        stats = tmp_path / f"{name}.json"
        result = CliRunner().invoke(app, ["run", str(elf), "--stats", str(stats), "--engine", name])
        assert result.exit_code == 4 and "product 7006652" in result.stdout
        records[name] = json.loads(stats.read_text())
    assert records[engine]["counters"] == records["interp"]["counters"]
    assert records[engine]["energy_nj"] == records["interp"]["energy_nj"]


def test_every_engine_gives_the_same_mesh_run(elf: Path, tmp_path: Path):
    records, outputs = {}, {}
    for name in ("interp", "jit"):
        stats = tmp_path / f"{name}.json"
        result = CliRunner().invoke(app, ["run", str(elf), "--mesh", "2x2", "--stats", str(stats), "--engine", name])
        outputs[name] = (result.exit_code, result.stdout)
        records[name] = json.loads(stats.read_text())
    assert outputs["jit"] == outputs["interp"] and "product 7006652" in outputs["interp"][1]
    assert records["jit"] == records["interp"]


def test_engine_is_refused_where_it_does_not_run(elf: Path):
    result = CliRunner().invoke(app, ["run", str(elf), "--engine", "jit", "--gdb", "0"])
    assert result.exit_code == 2
    assert "--engine: jit runs without --gdb (the debugger uses the interpreter)" in result.stderr


def test_one_core_refuses_a_program_too_big_for_its_sram_size(tmp_path: Path):
    src = tmp_path / "big.c"
    src.write_text("volatile char big[8192] = {1};\nint main(void) { return big[0]; }\n")
    big = build_elf([src], mul=True)
    result = CliRunner().invoke(app, ["run", str(big), "--sram-size", "4096"])
    assert result.exit_code == 2 and f"robosoc run: {big}: segment " in result.stderr
    assert CliRunner().invoke(app, ["run", str(big), "--sram-size", "65536"]).exit_code == 4  # returns 1


def test_the_summary_line_reads_like_the_stats(elf: Path, tmp_path: Path):
    import re

    stats = tmp_path / "s.json"
    result = CliRunner().invoke(app, ["run", str(elf), "--stats", str(stats)])
    record = json.loads(stats.read_text())
    c = record["counters"]
    line = result.stderr.splitlines()[0]
    expected = (
        rf"robosoc: {c['cycles']} cycles, {c['instructions']} instructions, CPI {c['cycles'] / c['instructions']:.3f}, "
        rf"energy {record['energy_nj']:.3f} nJ, host (\d+) MIPS; exit code 42"
    )
    match = re.fullmatch(expected, line)
    assert match is not None, line
    assert int(match.group(1)) < 100_000  # instructions per host microsecond, not per second
    assert record["energy_model"] == EnergyModel.load().path


def test_an_exit_code_that_reads_as_zero_is_noted_on_stderr(tmp_path: Path):
    src = tmp_path / "wide.c"
    src.write_text("int main(void) { return 512; }\n")
    wide = build_elf([src], mul=True)
    result = CliRunner().invoke(app, ["run", str(wide), "--exit-code", "program"])
    assert result.exit_code == 0  # 512 modulo 256
    note = "robosoc run: the program's exit code 512 (0x00000200) reads as 0 modulo 256; use --exit-code status\n"
    assert result.stderr.endswith(note) and "modulo" not in result.stdout
