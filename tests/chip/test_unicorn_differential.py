"""Differential test against an independent RISC-V implementation (the unicorn engine, RV32).

Random straight-line programs with forward branches, loads and stores run on both; registers and
the data region must agree exactly.  Programs use only behaviour both define identically.
"""

import random

import numpy as np
import pytest

import rv32_asm as A
from core_harness import exit_with, make_soc

unicorn = pytest.importorskip("unicorn")
from unicorn import riscv_const as R  # noqa: E402

CODE = 0x40000000
DATA = 0x40010000  # s0 (x8) points here and is never written
DATA_SIZE = 0x1000
ALU_R = ["add", "sub", "sll", "slt", "sltu", "xor", "srl", "sra", "or", "and"]
MUL_R = ["mul", "mulh", "mulhu", "mulhsu"]
ALU_I = ["addi", "slti", "sltiu", "xori", "ori", "andi"]
EDGE = [0, 1, -1, 2, 0x7FFFFFFF, -0x80000000, 0x80000000, 0xFFFF, 0x10000, 31, 32, 33, -2048, 2047]


def random_program(rng: random.Random, n: int, mul: bool) -> list[int]:
    dests = [r for r in range(1, 32) if r not in (8, 31)]  # s0 = data base, t6 = exit helper
    srcs = list(range(0, 31))
    words: list[int] = []
    for k in range(n):
        kind = rng.random()
        rd, rs1, rs2 = rng.choice(dests), rng.choice(srcs), rng.choice(srcs)
        if kind < 0.35:
            words.append(A.r(rng.choice(ALU_R + (MUL_R if mul else [])), rd, rs1, rs2))
        elif kind < 0.55:
            words.append(A.i(rng.choice(ALU_I), rd, rs1, rng.randint(-2048, 2047)))
        elif kind < 0.62:
            words.append(A.shift(rng.choice(["slli", "srli", "srai"]), rd, rs1, rng.randint(0, 31)))
        elif kind < 0.67:
            words.append(A.lui(rd, rng.getrandbits(20)))
        elif kind < 0.70:
            words.append(A.auipc(rd, rng.getrandbits(20)))
        elif kind < 0.80:
            name = rng.choice(list(A.LOAD_OPS))
            width = {"lb": 1, "lbu": 1, "lh": 2, "lhu": 2, "lw": 4}[name]
            words.append(A.load(name, rd, 8, rng.randrange(0, 2040 // width) * width))
        elif kind < 0.90:
            name = rng.choice(list(A.STORE_OPS))
            width = {"sb": 1, "sh": 2, "sw": 4}[name]
            words.append(A.store(name, rs2, 8, rng.randrange(0, 2040 // width) * width))
        else:
            skip = rng.randint(1, min(5, n - k))  # forward only: always terminates
            words.append(A.branch(rng.choice(list(A.BRANCH_OPS)), rs1, rs2, 4 * skip))
    return words


def initial_registers(rng: random.Random) -> list[int]:
    regs = [0] * 32
    for r in range(1, 32):
        regs[r] = (rng.choice(EDGE) if rng.random() < 0.4 else rng.getrandbits(32)) & 0xFFFFFFFF
    regs[8] = DATA
    return regs


def run_unicorn(code: bytes, end: int, regs: list[int], data: bytes) -> tuple[list[int], bytes]:
    uc = unicorn.Uc(unicorn.UC_ARCH_RISCV, unicorn.UC_MODE_RISCV32)
    uc.mem_map(CODE, 0x20000)
    uc.mem_write(CODE, code)
    uc.mem_write(DATA, data)
    for r in range(1, 32):
        uc.reg_write(getattr(R, f"UC_RISCV_REG_X{r}"), regs[r])
    uc.emu_start(CODE, end)
    out = [0] + [uc.reg_read(getattr(R, f"UC_RISCV_REG_X{r}")) & 0xFFFFFFFF for r in range(1, 32)]
    return out, bytes(uc.mem_read(DATA, DATA_SIZE))


# the random programs use MULHSU, whose RISC-V result (spec mode) unicorn computes too
@pytest.mark.filterwarnings("ignore::robosoc.chip.single.MulhsuErratum")
@pytest.mark.parametrize("mul", [True, False], ids=["mul", "nomul"])
@pytest.mark.parametrize("seed", range(12))
def test_random_programs_match_unicorn(seed: int, mul: bool):
    rng = random.Random(seed * 7919 + mul)
    body = random_program(rng, 300, mul)
    regs = initial_registers(rng)
    data = bytes(rng.getrandbits(8) for _ in range(DATA_SIZE))

    want_regs, want_data = run_unicorn(A.words_to_bytes(body), CODE + 4 * len(body), regs, data)

    soc = make_soc([*body, *exit_with(0)], mul=mul, sram_size=0x20000)
    soc.state.write(DATA, data)
    soc.regs[1:32] = np.array(regs[1:32], dtype=np.uint32).view(np.int32)
    soc.run(max_cycles=100_000)
    got_regs = [0] + [int(v) & 0xFFFFFFFF for v in soc.regs[1:32]]
    got_regs[31] = want_regs[31]  # t6 is the exit helper in robosoc's run only
    for r in range(32):
        assert got_regs[r] == want_regs[r], f"x{r}: robosoc 0x{got_regs[r]:08x}, unicorn 0x{want_regs[r]:08x}"
    assert soc.state.read(DATA, DATA_SIZE) == want_data
