"""The instruction table: encodings do not overlap, decode and disassembly agree with the spec."""

import random

import rv32_asm as A
from robosoc.isa.disasm import disassemble
from robosoc.isa.table import INSTRUCTIONS, OP, OP_FETCH_FAULT, OP_ILLEGAL, lookup


def test_no_two_encodings_overlap_except_the_system_catch_all():
    rows = [ins for ins in INSTRUCTIONS if ins.name != "system"]
    for k, a in enumerate(rows):
        for b in rows[k + 1 :]:
            common = a.mask & b.mask
            assert (a.match & common) != (b.match & common), f"{a.name} overlaps {b.name}"
    catch_all = INSTRUCTIONS[-1]
    assert catch_all.name == "system"
    # every specific SYSTEM row precedes the catch-all, so it wins in lookup()
    for name in ("ecall", "ebreak", "mret", "wfi"):
        assert OP[name] < OP["system"]


def test_operation_numbers_fit_a_byte_and_sentinels_are_distinct():
    assert OP_ILLEGAL < 0x80 and OP_FETCH_FAULT < 0x80
    assert len(set(OP.values())) == len(INSTRUCTIONS)
    assert OP_ILLEGAL not in OP.values() and OP_FETCH_FAULT not in OP.values()


def test_lookup_recognises_assembled_words():
    cases = {
        A.r("add", 1, 2, 3): "add", A.r("sub", 1, 2, 3): "sub", A.r("mulhsu", 5, 6, 7): "mulhsu",
        A.r("divu", 5, 6, 7): "divu", A.i("sltiu", 1, 2, -1): "sltiu", A.shift("srai", 1, 2, 31): "srai",
        A.load("lhu", 1, 2, -4): "lhu", A.store("sb", 1, 2, 7): "sb", A.branch("bgeu", 1, 2, -8): "bgeu",
        A.lui(1, 0xFFFFF): "lui", A.auipc(1, 1): "auipc", A.jal(1, -2048): "jal", A.jalr(0, 1, 0): "jalr",
        A.ECALL: "ecall", A.EBREAK: "ebreak", A.FENCE: "fence", 0x30200073: "mret", 0x34102573: "system",
    }  # fmt: skip
    for word, name in cases.items():
        ins = lookup(word)
        assert ins is not None and ins.name == name, (hex(word), name)
    assert lookup(0xFFFFFFFF) is None
    assert lookup(0x00000000) is None


def test_lookup_finds_the_first_matching_row_of_the_whole_table():
    """lookup() scans only the rows of the word's major opcode: the same row as a scan of every
    row in table order, for random words and for every row's encodings with random free bits."""
    rng = random.Random(7)

    def first_match(word: int):  # type: ignore[no-untyped-def]
        return next((ins for ins in INSTRUCTIONS if word & ins.mask == ins.match), None)

    words = [rng.getrandbits(32) for _ in range(20_000)]
    words += [ins.match | (rng.getrandbits(32) & ~ins.mask & 0xFFFFFFFF) for ins in INSTRUCTIONS for _ in range(200)]
    assert all(lookup(w) is first_match(w) for w in words)


def test_disassembly_shows_operands_and_absolute_targets():
    assert disassemble(A.i("addi", 2, 2, -16)) == "addi sp, sp, -16"
    assert disassemble(A.load("lw", 10, 2, 12)) == "lw a0, 12(sp)"
    assert disassemble(A.store("sw", 1, 2, -4)) == "sw ra, -4(sp)"
    assert disassemble(A.branch("bne", 10, 0, -8), pc=0x40000010) == "bne a0, zero, 0x40000008"
    assert disassemble(A.jal(1, 0x100), pc=0x40000000) == "jal ra, 0x40000100"
    assert disassemble(A.lui(10, 0xE1024)) == "lui a0, 0xe1024"
    assert disassemble(A.shift("slli", 5, 6, 3)) == "slli t0, t1, 3"
    assert disassemble(0xFFFFFFFF) == ".word 0xffffffff"
