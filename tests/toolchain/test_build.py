"""Building for the core: compile errors, the cache, the two -mcpu variants, the x27 check, the CLI."""

import warnings
from pathlib import Path

import pytest
from typer.testing import CliRunner

import robosoc.toolchain.build as build_module
from robosoc.cli import app
from robosoc.program.elf import load_elf
from robosoc.toolchain import CompileError, FixedRegisterWarning, ToolchainError, build_elf
from robosoc.toolchain.linker_script import render_linker_script
from robosoc.toolchain.x27_check import find_x27_writes, writes_register

MULTIPLY = """
#include <stdint.h>
volatile uint32_t a = 12345, b = 678;
int main(void) { return (int)((a * b) & 0x7f); }
"""


def text_words(elf: Path) -> list[int]:
    """Every 32-bit word of the executable segments."""
    program = load_elf(elf)
    words = []
    for seg in program.segment_info:
        if seg.executable:
            words += [int.from_bytes(seg.data[i : i + 4], "little") for i in range(0, len(seg.data), 4)]
    return words


def is_m_extension(word: int) -> bool:
    """MUL/MULH/MULHSU/MULHU/DIV/...: opcode 0x33 with funct7 = 1."""
    return word & 0x7F == 0x33 and word >> 25 == 1


@pytest.fixture
def cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A private build cache, sharing zig's own cache with the session to stay fast."""
    from robosoc.toolchain.cache import zig_cache_dir

    zig = zig_cache_dir()
    monkeypatch.setenv("ROBOSOC_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(build_module, "zig_cache_dir", lambda: zig)
    return tmp_path / "cache"


def test_compile_error_names_file_and_message(tmp_path: Path, cache: Path) -> None:
    src = tmp_path / "broken.c"
    src.write_text("int main(void) { return undefined_name; }\n")
    with pytest.raises(CompileError) as info:
        build_elf([src], mul=False)
    text = str(info.value)
    assert "broken.c" in text
    assert "undefined_name" in text
    assert info.value.files == [src.resolve()]


def test_link_error_is_a_compile_error(tmp_path: Path, cache: Path) -> None:
    src = tmp_path / "nomain.c"
    src.write_text("int helper(void) { return 1; }\n")
    with pytest.raises(CompileError, match="main"):
        build_elf([src], mul=False)


def test_missing_source_and_bad_option(tmp_path: Path, cache: Path) -> None:
    with pytest.raises(ToolchainError, match=r"nothere\.c"):
        build_elf([tmp_path / "nothere.c"], mul=False)
    src = tmp_path / "ok.c"
    src.write_text(MULTIPLY)
    with pytest.raises(ToolchainError, match="-O7"):
        build_elf([src], mul=False, opt="-O7")


def test_second_identical_build_is_a_cache_hit(tmp_path: Path, cache: Path, monkeypatch) -> None:
    src = tmp_path / "prog.c"
    src.write_text(MULTIPLY)
    first = build_elf([src], mul=True)
    assert first.is_relative_to(cache)

    def no_compiler(*args, **kwargs):
        raise AssertionError("the compiler ran on a cache hit")

    monkeypatch.setattr(build_module, "run_zig_cc", no_compiler)
    assert build_elf([src], mul=True) == first
    out = build_elf([src], tmp_path / "copy.elf", mul=True)
    assert out.read_bytes() == first.read_bytes()
    # Changing the source, the options or a header next to the source must rebuild.
    for change in (
        lambda: build_elf([src], mul=False),
        lambda: build_elf([src], mul=True, opt="-Os"),
        lambda: build_elf([src], mul=True, defines={"X": 1}),
    ):
        with pytest.raises(AssertionError, match="cache hit"):
            change()
    (tmp_path / "local.h").write_text("#define Y 2\n")
    with pytest.raises(AssertionError, match="cache hit"):
        build_elf([src], mul=True)


def test_no_mul_build_has_no_multiply_and_mul_build_has(tmp_path: Path, cache: Path) -> None:
    src = tmp_path / "mul.c"
    src.write_text(MULTIPLY)
    no_mul = text_words(build_elf([src], mul=False))
    with_mul = text_words(build_elf([src], mul=True))
    assert not any(is_m_extension(w) for w in no_mul)
    assert any(is_m_extension(w) for w in with_mul)
    # Zmmul only: never a divide (funct3 4..7 of the M group).
    assert not any(is_m_extension(w) and (w >> 12) & 7 >= 4 for w in with_mul)


def test_only_the_interrupt_entry_writes_x27(tmp_path: Path, cache: Path) -> None:
    src = tmp_path / "float.c"
    src.write_text(
        "volatile double x = 3.0; volatile float y = 2.0f;\n"
        "int main(void) { return (int)(x / 7.0 * 1e6) + (int)(y / 3.0f * 1e3f); }\n"
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error", FixedRegisterWarning)
        elf = build_elf([src], mul=False)
    program = load_elf(elf)
    assert find_x27_writes(program) == []
    # The entry itself does write s11 (the return sequence).
    assert find_x27_writes(program, allowed_function="nothing") != []


def test_hand_written_x27_write_is_reported(tmp_path: Path, cache: Path) -> None:
    src = tmp_path / "bad.S"
    src.write_text(
        ".text\n.globl main\n.type main, @function\nmain:\n  li s11, 5\n  li a0, 0\n  ret\n.size main, .-main\n"
    )
    with pytest.warns(FixedRegisterWarning, match=r"main writes x27"):
        build_elf([src], mul=False)


def test_writes_register_decoding() -> None:
    assert writes_register(0x00500D93, 27)  # addi s11, zero, 5
    assert writes_register(0x040D2D83, 27)  # lw s11, 64(s10)
    assert not writes_register(0x01B12023, 27)  # sw s11, 0(sp): rd field is imm
    assert not writes_register(0x01BD8463, 27)  # beq s11, s11: rd field is imm
    assert not writes_register(0x00500D93, 26)


def test_linker_script_geometry() -> None:
    text = render_linker_script(0x40000000, 0x10000)
    assert "ORIGIN = 0x40000000, LENGTH = 0x10000" in text
    with pytest.raises(ToolchainError):
        render_linker_script(0x40000000, 100)


def test_program_too_big_for_sram_fails_to_link(tmp_path: Path, cache: Path) -> None:
    src = tmp_path / "big.c"
    src.write_text("static volatile unsigned char big[60000];\nint main(void) { return big[7]; }\n")
    with pytest.raises(CompileError, match="fit"):
        build_elf([src], mul=False, sram_size=64 * 1024)


def test_cli_cc(tmp_path: Path, cache: Path) -> None:
    src = tmp_path / "prog.c"
    src.write_text(MULTIPLY)
    out = tmp_path / "prog.elf"
    result = CliRunner().invoke(app, ["cc", str(src), "-o", str(out), "--no-mul", "-Os"])
    assert result.exit_code == 0, result.output
    assert out.is_file() and load_elf(out).address_of("main") > 0
    bad = tmp_path / "bad.c"
    bad.write_text("int main(void) { return nope; }\n")
    result = CliRunner().invoke(app, ["cc", str(bad), "-o", str(tmp_path / "bad.elf")])
    assert result.exit_code == 2  # an input error (1 is kept for robosoc's own bugs)
    assert "bad.c" in result.output and "nope" in result.output


def test_hand_written_tp_write_is_reported(tmp_path: Path, cache: Path) -> None:
    # tp is the interrupt return sequence's register (crt/irq_entry.S): nobody else may write it
    src = tmp_path / "tp.S"
    src.write_text(".globl main\n.type main, @function\nmain:\n  li tp, 7\n  li a0, 0\n  ret\n.size main, .-main\n")
    with pytest.warns(FixedRegisterWarning, match=r"main writes x4 \(tp\)"):
        build_elf([src], mul=False)
