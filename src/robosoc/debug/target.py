"""What the GDB stub debugs: one core of a :class:`SingleCoreSoC` or one tile of an :class:`MPSoC`.

A target reads and writes the core's registers and memory, marks instructions to stop before
(breakpoints, and the loads/stores watchpoints look at) and runs: either on until a marked
instruction, or one instruction (a step).  Simulated time only advances inside :meth:`run`, so
however long the core stays halted nothing else in the simulation moves either: on the MPSoC a
stop suspends the whole chip in the middle of its time quantum and the next run continues it
exactly, and a flight loop that drives the stub stops its physics with it.

Stepping.  On one core the kernel executes exactly one instruction when asked to run to the
next cycle.  A tile of the MPSoC cannot run alone (its network accesses happen in global order
inside the chip loop), so a step marks every other word of the tile's code and runs the chip:
the tile stops before the next instruction it fetches, wherever control went (branch, jump,
trap, interrupt entry).  The marks are taken away afterwards, exactly as they were.
"""

from __future__ import annotations

import signal
from abc import ABC, abstractmethod
from dataclasses import dataclass
from enum import Enum

import numpy as np

from robosoc.chip.core_state import CoreState
from robosoc.chip.mpsoc import MPSoC
from robosoc.chip.single import SingleCoreSoC
from robosoc.debug.devices import ni_register, soc_register
from robosoc.isa.table import OP_BREAK
from robosoc.kernels import chip as kc
from robosoc.kernels.core_layout import (
    ERR_FETCH,
    ERR_FETCH_DATA,
    ERR_FETCH_MISALIGNED,
    ERR_ILLEGAL,
    ERR_LOAD_MISALIGNED,
    ERR_LOAD_UNMAPPED,
    ERR_NO_MUL,
    ERR_STORE_MISALIGNED,
    ERR_STORE_READONLY,
    ERR_STORE_UNMAPPED,
    ERR_UNSUPPORTED,
    RUN_BREAK,
    RUN_CHUNK,
    RUN_ERROR,
    RUN_EXIT,
    RUN_MAX_CYCLES,
    RUN_OUTPUT,
    S_CYCLE,
    S_ERR,
    S_EXIT_CODE,
    S_MEM_SIZE,
    S_PC,
)
from robosoc.kernels.ni_registers import NI_BASE, NI_END

M32 = 0xFFFFFFFF

#: The signal GDB is told for each kind of core error.
ERROR_SIGNALS = {
    ERR_ILLEGAL: signal.SIGILL, ERR_UNSUPPORTED: signal.SIGILL, ERR_NO_MUL: signal.SIGILL,
    ERR_LOAD_MISALIGNED: signal.SIGBUS, ERR_STORE_MISALIGNED: signal.SIGBUS, ERR_FETCH_MISALIGNED: signal.SIGBUS,
    ERR_LOAD_UNMAPPED: signal.SIGSEGV, ERR_STORE_UNMAPPED: signal.SIGSEGV, ERR_STORE_READONLY: signal.SIGSEGV,
    ERR_FETCH: signal.SIGSEGV, ERR_FETCH_DATA: signal.SIGSEGV,
}  # fmt: skip


class Outcome(Enum):
    """How a :meth:`Target.run` call ended."""

    STOPPED = "stopped"  # before an instruction not executed yet: a marked one, or the step is done
    SLICE = "slice"  # reached the cycle asked for
    HOST = "host"  # the run loop must handle the status (drain output) and call again
    EXITED = "exited"  # the debugged core stored its exit code
    FAILED = "failed"  # the debugged core (or the chip) failed, or ran out of cycles: the run ends


@dataclass(frozen=True)
class Progress:
    outcome: Outcome
    #: the status the simulator's run loop expects from a step (RUN_* on one core, CHIP_* on the MPSoC)
    status: int


class MemoryRefused(Exception):
    """GDB asked for a memory write the stub does not do (device registers)."""


class Target(ABC):
    """One core: state access, marks, and running (one core or one tile of a chip)."""

    #: cycles per run call between which the stub looks for GDB's Ctrl-C
    slice_cycles: int = 1 << 20

    def __init__(self, cores: CoreState, tile: int) -> None:
        self.cores = cores
        self.t = tile

    # --- facts -----------------------------------------------------------------------------
    @property
    @abstractmethod
    def description(self) -> str:
        """What is being debugged, for GDB's thread list and ``monitor tile``."""

    @abstractmethod
    def now(self) -> int:
        """The simulation's time (what run loops compare their ``until`` with)."""

    @abstractmethod
    def monitor_cycles(self) -> str: ...

    @abstractmethod
    def monitor_task(self) -> str: ...

    @abstractmethod
    def failure_signal(self, status: int) -> int:
        """The signal to report to GDB for a FAILED run."""

    @property
    def cycle(self) -> int:
        """The core's cycle: the one its next instruction executes in."""
        return int(self.cores.st[self.t, S_CYCLE])

    @property
    def exit_code(self) -> int:
        return int(self.cores.st[self.t, S_EXIT_CODE])

    # --- registers -------------------------------------------------------------------------
    @property
    def pc(self) -> int:
        return int(self.cores.st[self.t, S_PC]) & M32

    def registers(self) -> list[int]:
        """x0..x31 and pc, unsigned."""
        return [int(v) & M32 for v in self.cores.regs[self.t, :32]] + [self.pc]

    def set_register(self, n: int, value: int) -> None:
        """Write register ``n`` (0..31: x0..x31, writes to x0 are ignored as the core does; 32: pc)."""
        value &= M32
        if n == 32:
            self.cores.st[self.t, S_PC] = value
        elif 0 < n < 32:
            self.cores.regs[self.t, n] = value - (1 << 32) if value >> 31 else value
        elif n != 0:
            raise IndexError(f"no register {n}")

    # --- memory ----------------------------------------------------------------------------
    @property
    def sram_size(self) -> int:
        return int(self.cores.st[self.t, S_MEM_SIZE])

    def in_sram(self, addr: int, length: int) -> bool:
        return self.cores.base <= addr and addr + length <= self.cores.base + self.sram_size

    def read_memory(self, addr: int, length: int) -> bytes:
        """The readable bytes from ``addr`` on (fewer than asked, or none, where memory ends)."""
        out = bytearray()
        while len(out) < length:
            a = (addr + len(out)) & M32
            if self.in_sram(a, 1):
                n = min(length - len(out), self.cores.base + self.sram_size - a)
                out += self.cores.read(a, n, self.t)
                continue
            word = self.device_word(a & ~3)
            if word is None:
                break
            chunk = word.to_bytes(4, "little")[a & 3 :]
            out += chunk[: length - len(out)]
        return bytes(out)

    def device_word(self, addr: int) -> int | None:
        """A device register word (no side effect) or None when nothing answers at ``addr``."""
        return soc_register(self.cores.st[self.t], addr, self.cycle)

    def write_memory(self, addr: int, data: bytes) -> None:
        """Write SRAM (the words' predecoded instructions and marks are dropped: mark again).

        Raises:
            MemoryRefused: any byte outside SRAM (device registers are not written from GDB).
        """
        if not data:
            return
        if not self.in_sram(addr, len(data)):
            raise MemoryRefused(f"0x{addr:08x}+{len(data)} is not SRAM")
        self.cores.write(addr, data, self.t)

    # --- marks -----------------------------------------------------------------------------
    @property
    def code_base(self) -> int:
        return self.cores.base

    def code_words(self) -> np.ndarray:
        """The loaded code as int32 words (a view)."""
        n = self.cores.code_size(self.t) // 4
        return self.cores.m32[self.t, :n]

    def is_code(self, addr: int) -> bool:
        off = addr - self.code_base
        return off % 4 == 0 and 0 <= off < self.cores.code_size(self.t)

    def word(self, addr: int) -> int | None:
        """The instruction word at ``addr`` if it is in SRAM."""
        if addr % 4 or not self.in_sram(addr, 4):
            return None
        return self.cores.word(addr, self.t)

    def apply_marks(self, mask: np.ndarray) -> None:
        """Stop before exactly the code words where ``mask`` is True."""
        rows = self.cores.op_rows(self.t)
        rows[(rows == OP_BREAK) & ~mask] = 0
        rows[mask] = OP_BREAK

    def is_marked(self, addr: int) -> bool:
        return self.is_code(addr) and int(self.cores.op_rows(self.t)[(addr - self.code_base) // 4]) == OP_BREAK

    # --- running ---------------------------------------------------------------------------
    @abstractmethod
    def start_step(self) -> None:
        """The next :meth:`run` calls execute the instruction at pc (marked or not) and stop before the next."""

    @abstractmethod
    def cancel_step(self) -> None:
        """Forget a step that has not finished (the marks are as before it)."""

    @abstractmethod
    def run(self, until: int) -> Progress:
        """Run until a marked instruction, the end of the step, ``until``, or an event."""


class SingleCoreTarget(Target):
    """The core of a :class:`SingleCoreSoC`."""

    slice_cycles = 1 << 22

    def __init__(self, soc: SingleCoreSoC) -> None:
        super().__init__(soc.state, 0)
        self.soc = soc
        self._stepping = False

    @property
    def description(self) -> str:
        return "single core"

    def now(self) -> int:
        return self.soc.cycle

    def monitor_cycles(self) -> str:
        c = self.soc.counters()
        return f"cycle {self.cycle} (the next instruction executes in it); {c['instructions']} instructions executed"

    def monitor_task(self) -> str:
        return "no task ids on a single core (TASK_ID is a network-interface register of MPSoC tiles)"

    def failure_signal(self, status: int) -> int:
        if status == RUN_MAX_CYCLES:
            return int(signal.SIGXCPU)
        return int(ERROR_SIGNALS.get(int(self.cores.st[0, S_ERR]), signal.SIGABRT))

    def start_step(self) -> None:
        self._stepping = True

    def cancel_step(self) -> None:
        self._stepping = False

    def run(self, until: int) -> Progress:
        if not self._stepping:
            return self._progress(self.soc.step_until(until))
        pc, cycle = self.pc, self.cycle
        marked = self.is_marked(pc)
        if marked:
            self.cores.set_breakpoint(pc, False)
        status = self.soc.step_until(cycle + 1)  # exactly one instruction (or the entry of an interrupt)
        if marked and self.is_code(pc):
            self.cores.set_breakpoint(pc, True)
        if status == RUN_OUTPUT and self.cycle == cycle:
            return Progress(Outcome.HOST, status)  # nothing executed: the output must be drained first
        self._stepping = False
        if status in (RUN_CHUNK, RUN_OUTPUT, RUN_BREAK):
            return Progress(Outcome.STOPPED, RUN_OUTPUT if status == RUN_OUTPUT else RUN_CHUNK)
        return self._progress(status)

    @staticmethod
    def _progress(status: int) -> Progress:
        if status == RUN_BREAK:
            return Progress(Outcome.STOPPED, RUN_CHUNK)
        if status == RUN_CHUNK:
            return Progress(Outcome.SLICE, status)
        if status == RUN_OUTPUT:
            return Progress(Outcome.HOST, status)
        if status == RUN_EXIT:
            return Progress(Outcome.EXITED, status)
        assert status in (RUN_ERROR, RUN_MAX_CYCLES), status
        return Progress(Outcome.FAILED, status)


class ChipTarget(Target):
    """One tile of an :class:`MPSoC`; every run call runs the whole chip."""

    slice_cycles = 1 << 18

    def __init__(self, chip: MPSoC, xy: tuple[int, int]) -> None:
        if xy not in chip.core_tiles():
            raise ValueError(f"tile {xy} has no core to debug (core tiles: {chip.core_tiles()})")
        super().__init__(chip.cores, chip.config.tile_index(xy))
        self.chip = chip
        self.xy = xy
        chip.allow_long_quanta(False)  # the other tiles stay within a short quantum of the halted one
        self._saved: np.ndarray | None = None  # predecode rows while a step has marked every word
        self._step_word = -1
        self._step_cycle = 0
        self._suspended = False  # the chip stopped mid-quantum at one of our marks

    @property
    def description(self) -> str:
        w, h = self.chip.config.width, self.chip.config.height
        return f"tile ({self.xy[0]},{self.xy[1]}) of the {w}x{h} mesh"

    def now(self) -> int:
        return self.chip.cycle

    def monitor_cycles(self) -> str:
        state = self.chip.state(self.xy)
        return (
            f"tile ({self.xy[0]},{self.xy[1]}) {state} at cycle {self.cycle}; "
            f"chip time {self.chip.cycle} (the start of the current time quantum)"
        )

    def monitor_task(self) -> str:
        return f"task {int(self.chip.cst[self.t, kc.K_TASK])}"

    def failure_signal(self, status: int) -> int:
        if int(self.chip.cst[self.t, kc.K_STATE]) != kc.K_FAULT:
            return int(signal.SIGABRT)  # another tile or the network failed, or nothing can happen any more
        if int(self.chip.cst[self.t, kc.K_ERR]) != kc.CE_NONE:
            return int(signal.SIGSEGV)  # misuse of the network interface
        return int(ERROR_SIGNALS.get(int(self.cores.st[self.t, S_ERR]), signal.SIGABRT))

    def device_word(self, addr: int) -> int | None:
        if NI_BASE <= addr < NI_END:
            return ni_register(self.chip, self.t, addr, self.cycle)
        return super().device_word(addr)

    def start_step(self) -> None:
        rows = self.cores.op_rows(self.t)
        self._saved = self.cores.dec[self.t, : 2 * len(rows)].copy()
        rows[:] = OP_BREAK
        self._step_word = (self.pc - self.code_base) // 4 if self.is_code(self.pc) else -1
        self._step_cycle = self.cycle
        if self._step_word >= 0:
            rows[self._step_word] = 0

    def cancel_step(self) -> None:
        if self._saved is None:
            return
        rows = self.cores.op_rows(self.t)
        stored = rows == 0  # words the program stored to since (their decode is stale: keep 0)
        i = self._step_word
        if i >= 0:
            stored[i] = False
        self.cores.dec[self.t, : len(self._saved)] = self._saved
        rows[stored] = 0
        if i >= 0 and rows[i] != OP_BREAK:
            rows[i] = 0  # the stepped word may have stored to itself: decode it again
        self._saved = None

    def run(self, until: int) -> Progress:
        if self._suspended:
            self.chip.resume_from_break()
            self._suspended = False
        why = self.chip.step(until)
        state = int(self.chip.cst[self.t, kc.K_STATE])
        if why == kc.CHIP_BREAK:
            if self.chip.break_tile() != self.xy:
                raise RuntimeError(f"tile {self.chip.break_tile()} stopped at a mark the debugger did not set")
            self._suspended = True
            self.cancel_step()
            return Progress(Outcome.STOPPED, kc.CHIP_UNTIL)
        if state == kc.K_EXITED:
            self.cancel_step()
            return Progress(Outcome.EXITED, why)
        if state == kc.K_FAULT or why in (kc.CHIP_ERROR, kc.CHIP_STUCK, kc.CHIP_DONE):
            self.cancel_step()
            return Progress(Outcome.FAILED, why)
        if why == kc.CHIP_UNTIL:
            if self._saved is not None and self._jumped_to_itself():
                self.cancel_step()
                return Progress(Outcome.STOPPED, why)
            return Progress(Outcome.SLICE, why)
        return Progress(Outcome.HOST, why)

    def _jumped_to_itself(self) -> bool:
        """Whether the stepped instruction ran and came back to itself (``j .``): the only fetch
        a step does not stop at.  The step then ends with the chip's time slice."""
        here = (self.pc - self.code_base) // 4 if self.is_code(self.pc) else -1
        return here == self._step_word >= 0 and self.cycle > self._step_cycle
