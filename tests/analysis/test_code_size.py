"""Code and data sizes of an ELF, per section and per function."""

import dataclasses
from pathlib import Path

import pytest
from elftools.common.exceptions import ELFError

import robosoc.analysis.code_size as code_size_module
from robosoc.analysis.code_size import code_size
from robosoc.program.elf import ElfError, load_elf
from robosoc.toolchain import build_elf

PROGRAM = """
#include <stdint.h>
static volatile uint32_t table[1000];                      /* 4000 bytes of .bss */
const uint32_t constants[16] = {1, 2, 3, 4, 5, 6, 7, 8};   /* 64 bytes of read-only data */
__attribute__((noinline, used)) uint32_t sum_table(void) {
    uint32_t s = 0;
    for (int i = 0; i < 1000; i++) s += table[i] * constants[i & 15];
    return s;
}
int main(void) { return (int)sum_table(); }
"""


def test_sections_and_symbols_of_a_known_program(tmp_path: Path):
    src = tmp_path / "p.c"
    src.write_text(PROGRAM)
    size = code_size(build_elf([src], mul=True, opt="-O1"))
    kinds = {s.name: s for s in size.sections}
    assert kinds[".text"].kind == "code" and kinds[".text"].size > 0
    by_name = {s.name: s for s in size.symbols}
    assert by_name["table"].size == 4000 and by_name["table"].kind == "object"
    assert by_name["constants"].size == 64
    assert by_name["sum_table"].kind == "func" and by_name["sum_table"].size > 0
    bss = sum(s.size for s in size.sections if s.kind == "zero-initialised data")
    assert bss >= 4000
    assert size.code_bytes + size.data_bytes == sum(s.size for s in size.sections)
    assert [s.size for s in size.symbols] == sorted((s.size for s in size.symbols), reverse=True)


def test_a_file_that_is_not_an_elf_is_named_in_the_error(tmp_path: Path):
    bad = tmp_path / "notes.txt"
    bad.write_text("not an ELF")
    with pytest.raises(ElfError, match=r"notes\.txt"):
        code_size(bad)


KINDS = """
#include <stdint.h>
volatile uint32_t counter = 7;                               /* initialised, writable: data */
volatile uint8_t big_state[300] = {1};                       /* data, past the small-data limit */
static volatile uint32_t zeros[50];                          /* zero-initialised data */
__attribute__((used)) const char one_byte = 3;               /* a 1-byte object */
__attribute__((used)) const uint32_t table[64] = {1, 2, 3};  /* read-only data */
void bare_label(void);                                       /* label.S: no .size */
int main(void) {
    bare_label();
    const volatile uint32_t *t = table;
    const volatile char *b = &one_byte;
    return (int)(counter + big_state[1] + zeros[2] + *b + t[counter]);
}
"""


def test_every_section_gets_its_kind_and_only_allocated_ones_count(tmp_path: Path):
    src = tmp_path / "kinds.c"
    src.write_text(KINDS)
    label = tmp_path / "label.S"  # a function label without a .size: size 0 in the symbol table
    label.write_text(".text\n.globl bare_label\n.type bare_label, @function\nbare_label:\n    ret\n")
    elf = build_elf([src, label], mul=True, opt="-O1")
    size = code_size(elf)
    assert size.path == elf
    kinds: dict[str, set[str]] = {}
    for s in size.sections:
        kinds.setdefault(s.kind, set()).add(s.name)
        assert s.size > 0  # empty sections are left out
    assert ".text" in kinds["code"]
    assert kinds["data"] & {".data", ".sdata"}
    assert kinds["read-only data"] & {".rodata", ".srodata"}
    assert kinds["zero-initialised data"] & {".bss", ".sbss"}
    assert not kinds["data"] & {".rodata", ".srodata", ".bss", ".sbss", ".text"}
    names = {s.name for s in size.sections}
    assert not names & {".symtab", ".strtab", ".shstrtab", ".comment"}  # not loaded: not counted
    assert [s.addr for s in size.sections] == sorted(s.addr for s in size.sections)
    program = load_elf(elf)
    by_name = {s.name: s for s in size.symbols}
    assert by_name["one_byte"].size == 1 and by_name["one_byte"].kind == "object"
    assert by_name["big_state"].size == 300 and by_name["table"].size == 256
    for name in ("main", "counter", "table", "one_byte"):
        assert by_name[name].addr == program.address_of(name)
    assert all(s.size > 0 for s in size.symbols)
    assert program.symbol("bare_label").size == 0 and "bare_label" not in by_name  # size unknown: left out


def test_a_symbol_listed_twice_is_counted_once(tmp_path: Path, monkeypatch):
    src = tmp_path / "p.c"
    src.write_text(PROGRAM)
    elf = build_elf([src], mul=True, opt="-O1")
    program = load_elf(elf)
    twice = dataclasses.replace(program, symbols=program.symbols + program.symbols)
    monkeypatch.setattr(code_size_module, "load_elf", lambda path: twice)
    names = [s.name for s in code_size(elf).symbols]
    assert names.count("sum_table") == 1 and len(names) == len(set(names))


def test_sections_that_cannot_be_read_are_named(tmp_path: Path, monkeypatch):
    src = tmp_path / "p.c"
    src.write_text(PROGRAM)
    elf = build_elf([src], mul=True, opt="-O1")

    def broken(handle):
        raise ELFError("section table truncated")

    monkeypatch.setattr(code_size_module, "ELFFile", broken)
    with pytest.raises(ElfError) as caught:
        code_size(elf)
    assert str(caught.value) == f"{elf}: cannot read sections: section table truncated"
