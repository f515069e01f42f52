"""ELF loading: segments, entry point, symbols and the error paths."""

import struct
from pathlib import Path

import pytest

from robosoc.firmware import MATRIX_BENCH_SOURCE
from robosoc.program.elf import ElfError, Region, load_elf
from robosoc.toolchain import build_elf

SRAM = Region(0x40000000, 2 * 1024 * 1024, "SRAM")


@pytest.fixture(scope="module")
def bench_elf() -> Path:
    return build_elf([MATRIX_BENCH_SOURCE], mul=True, defines={"BENCH_ITERATIONS": 1})


def test_entry_segments_and_symbols(bench_elf: Path) -> None:
    program = load_elf(bench_elf, [SRAM])
    assert program.entry == 0x40000000 == program.address_of("_start")
    first_addr, first_data = program.segments[0]
    assert first_addr == 0x40000000
    # The first instruction of _start is the stack setup: auipc/lui sp (rd = x2).
    word = int.from_bytes(first_data[:4], "little")
    assert word & 0x7F in (0x17, 0x37) and (word >> 7) & 0x1F == 2
    main = program.symbol("main")
    assert main.size > 0
    assert program.symbolize(main.addr) == "main"
    assert program.symbolize(main.addr + 8) == "main+0x8"
    assert program.symbolize(0x40000004) == "_start+0x4"
    # IRQ entry: NOP first (it executes twice on the hardware).
    entry = program.address_of("_irq_entry")
    assert program.read(entry, 4) == struct.pack("<I", 0x00000013)
    with pytest.raises(ElfError, match="no_such_symbol"):
        program.address_of("no_such_symbol")


def test_bss_is_zero_filled(bench_elf: Path) -> None:
    program = load_elf(bench_elf)
    a_f = program.symbol("a_f")
    assert a_f.kind == "object" and a_f.size == 7 * 7 * 4
    assert program.read(a_f.addr, a_f.size) == bytes(a_f.size)


def test_compiler_rt_names_are_plain(bench_elf: Path) -> None:
    program = load_elf(bench_elf)
    addr = program.address_of("__divsf3")
    assert program.symbolize(addr + 4) == "__divsf3+0x4"


def test_not_an_elf(tmp_path: Path) -> None:
    bad = tmp_path / "text.elf"
    bad.write_text("hello")
    with pytest.raises(ElfError, match=r"text\.elf.*not an ELF"):
        load_elf(bad)


def test_wrong_class_and_machine(tmp_path: Path, bench_elf: Path) -> None:
    data = bytearray(bench_elf.read_bytes())
    wrong_machine = tmp_path / "x86.elf"
    data[18:20] = struct.pack("<H", 3)  # EM_386
    wrong_machine.write_bytes(bytes(data))
    with pytest.raises(ElfError, match=r"x86\.elf.*EM_RISCV"):
        load_elf(wrong_machine)
    wrong_class = tmp_path / "elf64.elf"
    data = bytearray(bench_elf.read_bytes())
    data[4] = 2  # ELFCLASS64
    wrong_class.write_bytes(bytes(data))
    with pytest.raises(ElfError, match=r"elf64\.elf"):
        load_elf(wrong_class)


def test_segment_outside_memory(bench_elf: Path) -> None:
    small = Region(0x40000000, 0x100, "SRAM")
    with pytest.raises(ElfError, match=r"segment .* at 0x40000000.*outside.*SRAM 0x40000000-0x400000ff"):
        load_elf(bench_elf, [small])
    with pytest.raises(ElfError, match="outside"):
        load_elf(bench_elf, [(0x0, 0x1000)])
