"""Properties of kernel images: the reserved registers, no multiply in the kernel, overheads."""

import pytest
from kernel_harness import BUILDS, build
from measure_overhead import measure

from robosoc.isa.disasm import disassemble
from robosoc.program.elf import load_elf
from robosoc.toolchain import find_x27_writes

KERNEL_PREFIXES = ("os_", "port_", "_irq_entry")


@pytest.mark.parametrize("mul", BUILDS)
def test_only_the_port_entry_writes_s11_and_tp(mul):
    program = load_elf(build("mesh.c", mul))
    assert find_x27_writes(program) == []
    entry = program.symbol("_irq_entry")
    # the voluntary switch and the shared exit lie inside the entry's symbol (the allowed range)
    for name in ("port_yield", "port_restore", "port_start_first"):
        assert entry.addr <= program.address_of(name) < entry.addr + entry.size


def kernel_multiplies(program) -> list[str]:
    found = []
    for seg in program.segment_info:
        if not seg.executable:
            continue
        for off in range(0, len(seg.data) - 3, 4):
            addr = seg.addr + off
            where = program.symbolize(addr)
            text = disassemble(int.from_bytes(seg.data[off : off + 4], "little"), addr)
            if where.startswith(KERNEL_PREFIXES) and text.split()[0] in ("mul", "mulh", "mulhu", "mulhsu"):
                found.append(f"{where}: {text}")
    return found


def test_the_kernel_never_multiplies_so_its_overhead_is_the_same_in_both_builds():
    # with the iterative multiplier a MUL costs 16..37 cycles; the task table is indexed by shifts
    assert kernel_multiplies(load_elf(build("mesh.c", True))) == []
    with_mul, without = measure(True), measure(False)
    assert with_mul == without
    assert with_mul["voluntary switch (semaphore handover)"] < 1000
    assert with_mul["tick to job start, preempting (interrupt path)"] < 1200
