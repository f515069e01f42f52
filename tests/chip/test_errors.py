"""Every error path stops the run with a message naming what happened, the pc, the symbol and
the instruction (platform.md §1 errata are reported, not imitated)."""

import textwrap

import pytest

import rv32_asm as A
from core_harness import exit_with, make_soc
from robosoc.chip.single import CoreError, CycleBudgetExceeded, MulhsuErratum, SingleCoreSoC, run_elf

SRAM = 0x40000000


def error_of(words: list[int], mul: bool = True) -> CoreError:
    soc = make_soc(words, mul=mul)
    with pytest.raises(CoreError) as info:
        soc.run(max_cycles=100_000)
    return info.value


def test_illegal_instruction():
    e = error_of([A.NOP, 0xFFFFFFFF])
    assert e.pc == SRAM + 4 and e.word == 0xFFFFFFFF
    assert "illegal instruction" in str(e) and "0x40000004" in str(e) and ".word 0xffffffff" in str(e)


@pytest.mark.parametrize("name", ["div", "divu", "rem", "remu"])
def test_division_is_not_implemented(name):
    e = error_of([A.r(name, 10, 11, 12)])
    assert "not implemented by the hardware" in str(e) and f"`{name} a0, a1, a2`" in str(e)


def test_multiply_on_a_core_without_multiplier():
    e = error_of([A.r("mul", 10, 11, 12)], mul=False)
    assert "without the multiplier" in str(e) and "`mul a0, a1, a2`" in str(e)


@pytest.mark.parametrize(
    "word,text,addr",
    [
        (A.load("lw", 10, 6, 2), "misaligned load", SRAM + 0x102),
        (A.load("lh", 10, 6, 1), "misaligned load", SRAM + 0x101),
        (A.store("sw", 10, 6, 1), "misaligned store", SRAM + 0x101),
        (A.store("sh", 10, 6, 3), "misaligned store", SRAM + 0x103),
    ],
)
def test_misaligned_accesses(word, text, addr):
    e = error_of([*A.li(6, SRAM + 0x100), word])
    assert text in str(e) and f"0x{addr:08x}" in str(e) and e.addr == addr


def test_unmapped_load_and_store():
    e = error_of([*A.li(6, 0x20000000), A.load("lw", 10, 6, 0)])
    assert "load from unmapped address 0x20000000" in str(e)
    e = error_of([*A.li(6, 0xE2000000), A.store("sb", 10, 6, 0)])
    assert "store to unmapped address 0xe2000000" in str(e)


def test_store_to_a_read_only_register():
    e = error_of([*A.li(6, 0xE1024000), A.store("sw", 10, 6, 0)])  # TIMER0
    assert "read-only" in str(e) and "0xe1024000" in str(e)


def test_fetch_outside_memory_by_jump_and_by_falling_off_the_end():
    e = error_of([*A.li(6, 0x10000000), A.jalr(0, 6, 0)])
    assert "fetch outside memory" in str(e) and "0x10000000" in str(e) and "jalr" in str(e)
    soc = make_soc([A.NOP] * 4, sram_size=16)
    with pytest.raises(CoreError, match="pc 0x40000010 is not in SRAM"):
        soc.run(max_cycles=1000)


def test_jump_to_a_misaligned_address():
    e = error_of([A.NOP, A.jal(0, 6)])
    assert "misaligned" in str(e) and "0x4000000a" in str(e)


def test_cycle_budget_stops_a_hung_program():
    soc = make_soc([A.jal(0, 0)])
    with pytest.raises(CycleBudgetExceeded, match="cycle budget of 1000 cycles"):
        soc.run(max_cycles=1000)
    assert 1000 <= soc.cycle < 1003


def test_mulhsu_is_reported_as_an_erratum():
    soc = make_soc([*A.li(11, -3), *A.li(12, 5), A.r("mulhsu", 10, 11, 12), *exit_with(10)])
    with pytest.warns(MulhsuErratum, match="MULHSU executed 1 times"):
        result = soc.run()
    assert result.exit_code == 0xFFFFFFFF  # RISC-V: high word of -3 * 5 = -15 is 0xffffffff (the exit word)


def test_error_names_the_symbol_of_a_compiled_program(tmp_path):
    from robosoc.toolchain import build_elf

    src = tmp_path / "bad.c"
    src.write_text(
        textwrap.dedent(
            """
            volatile unsigned *const nowhere = (unsigned *)0x30000000u;
            __attribute__((noinline)) unsigned peek(void) { return *nowhere; }
            int main(void) { return (int)peek(); }
            """
        )
    )
    elf = build_elf([src], mul=True)
    with pytest.raises(CoreError) as info:
        run_elf(elf)
    assert "load from unmapped address 0x30000000" in str(info.value)
    assert "(peek+0x" in str(info.value)


def test_an_interrupt_vector_outside_the_code_is_an_error_not_a_crash():
    # IRQ_VECTOR left at 0 (the boot ROM, not SRAM): the first interrupt must stop the run with an
    # error naming the address, not read the predecode table out of bounds
    words = [
        *A.li(28, 0xF0000000),
        *A.li(29, 0xE1020800),
        *A.li(6, 1),
        A.store("sw", 6, 29, 0x400),  # TIMERMASK: TIMER0 bit 16 cause ...
        A.store("sw", 6, 29, 0x000),  # ... inverted: the line is high at once
        A.store("sw", 6, 28, 0x20),  # IRQ_MASK
        A.store("sw", 6, 28, 0x30),  # IRQ_STATUS: enable
        *[A.NOP] * 20,
        *exit_with(0),
    ]
    soc = make_soc(words)
    with pytest.raises(CoreError, match="instruction fetch outside memory: pc 0x00000000 is not in SRAM"):
        soc.run(max_cycles=10_000)


def test_running_without_a_program_is_an_error():
    with pytest.raises(CoreError, match=r"pc 0x00000000 .* is not an instruction of the loaded code"):
        SingleCoreSoC().run(max_cycles=100)
