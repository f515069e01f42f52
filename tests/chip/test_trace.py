"""The instruction trace: one record per instruction, with its start cycle and register writes."""

import rv32_asm as A
from core_harness import exit_with, make_soc
from robosoc.chip.trace import trace


def test_trace_shows_cycles_disassembly_and_writes():
    words = [
        A.i("addi", 10, 0, 5),
        *A.li(5, 0x40000000),
        A.load("lw", 11, 5, 0),
        A.branch("beq", 0, 0, 8),
        A.NOP,
        *exit_with(10),
    ]
    soc = make_soc(words)
    records = list(trace(soc, 6))
    assert [r.cycle for r in records] == [3, 4, 5, 6, 9, 12]  # addi, lui, addi: 1; lw 3; taken beq 3
    assert [r.pc - 0x40000000 for r in records] == [0, 4, 8, 12, 16, 24]
    assert records[0].text == "addi a0, zero, 5" and records[0].writes == ((10, 5),)
    assert records[3].writes == ((11, words[0]),)  # lw reads the first instruction word
    assert records[4].text == "beq zero, zero, 0x40000018" and records[4].writes == ()
    # the rest runs at full speed and exits normally
    assert soc.run().exit_code == 5


def test_trace_stops_at_the_exit():
    soc = make_soc([A.i("addi", 10, 0, 1), *exit_with(10)])
    assert len(list(trace(soc, 100))) == 4  # addi, lui, addi, sw (the exit store)
