"""Code and data sizes of an ELF, per section and per function."""

from pathlib import Path

import pytest

from robosoc.analysis.code_size import code_size
from robosoc.chip.elf import ElfError
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
