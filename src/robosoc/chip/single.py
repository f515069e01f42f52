"""The single-core HF-RISCV SoC (platform.md §2): one core, its SRAM and devices, run from an ELF.

soc = SingleCoreSoC(mul=True)
soc.load(load_elf("prog.elf", soc.regions()))
result = soc.run(max_cycles=10**9, on_output=sys.stdout.buffer.write)
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from robosoc.chip.core_state import DEFAULT_SRAM_SIZE, SRAM_BASE, CoreState
from robosoc.chip.counters import counters_dict
from robosoc.chip.engines import Engine, resolve_engine
from robosoc.config.chip import DEFAULT_ENGINE
from robosoc.config.ranges import DEVICE_MAP_BASE, MAX_CYCLES, check_int, check_memory, format_bytes
from robosoc.isa.disasm import disassemble
from robosoc.kernels.core import run_cores
from robosoc.kernels.core_layout import (
    ADDRESS_ERRORS,
    ERR_FETCH,
    ERRATA_MODES,
    ERROR_TEXT,
    RUN_ERROR,
    RUN_EXIT,
    RUN_MAX_CYCLES,
    S_CYCLE,
    S_ERR,
    S_ERR_ADDR,
    S_ERR_INSN,
    S_ERR_PC,
    S_EXIT_CODE,
    S_IRQMUL_COUNT,
    S_IRQMUL_PC,
    S_MAX_CYCLES,
    S_MULHSU_COUNT,
    S_MULHSU_PC,
    S_OUT_LEN,
    S_PC,
    S_RUN,
)
from robosoc.program.elf import Program, Region, load_elf

if TYPE_CHECKING:
    from robosoc.chip.profile import Sampler
    from robosoc.jit.engine import TranslatingCore

CHUNK_CYCLES = 1 << 24
_TILE0 = np.zeros(1, dtype=np.int64)  # host returns between slices: output is flushed, Ctrl-C is seen


class RtlErratum(UserWarning):
    """The program did something the HF-RISCV RTL gets wrong (platform.md §1, §3)."""


class MulhsuErratum(RtlErratum):
    """The program used MULHSU, which the HF-RISCV RTL computes as MULHU."""


class IrqDuringMulErratum(RtlErratum):
    """An interrupt request met a multiply in the window the RTL mishandles."""


def errata_report(
    st: np.ndarray, symbolize: Callable[[int], str], mode: str, where: str = ""
) -> dict[str, tuple[int, str]]:
    """The errata a core hit: name -> (count, sentence naming the first pc and symbol).

    ``st`` is the core's state row; ``mode`` the errata mode it ran in ("spec" or "rtl").
    """
    spec = mode == "spec"
    out: dict[str, tuple[int, str]] = {}
    n = int(st[S_MULHSU_COUNT])
    if n:
        pc = int(st[S_MULHSU_PC])
        effect = "robosoc computed the RISC-V result, the RTL returns" if spec else "returned, as the RTL does,"
        out["mulhsu"] = (
            n,
            f"{where}MULHSU executed {n} times (first at pc 0x{pc:08x}, {symbolize(pc)}): {effect} the MULHU result",
        )
    n = int(st[S_IRQMUL_COUNT])
    if n:
        pc = int(st[S_IRQMUL_PC])
        effect = (
            "robosoc entered at the end of the multiply; the RTL would have run the shadow instruction first "
            "or the multiply twice (platform.md §3)"
            if spec
            else "handled as the RTL does (shadow instruction, repeated multiply or lost vector, platform.md §3)"
        )
        out["irq_during_mul"] = (
            n,
            f"{where}an interrupt met a multiply {n} times (first at pc 0x{pc:08x}, {symbolize(pc)}): {effect}",
        )
    return out


ERRATUM_WARNINGS: dict[str, type[RtlErratum]] = {"mulhsu": MulhsuErratum, "irq_during_mul": IrqDuringMulErratum}


def errata_counts(report: dict[str, tuple[int, str]]) -> dict[str, int]:
    """Every erratum's count (0 for those not hit) from an :func:`errata_report`."""
    return {name: report[name][0] if name in report else 0 for name in ERRATUM_WARNINGS}


class CoreError(RuntimeError):
    """The program did something the hardware cannot do; the message names pc, symbol and instruction."""

    def __init__(self, message: str, *, kind: str, pc: int, addr: int | None, word: int, cycle: int) -> None:
        super().__init__(message)
        self.kind = kind
        self.pc = pc
        self.addr = addr
        self.word = word
        self.cycle = cycle


def core_error(st: np.ndarray, symbolize: Callable[[int], str], sram_size: int, where: str = "") -> CoreError:
    """The :class:`CoreError` for a core that stopped with RUN_ERROR (``st``: its state row).

    ``where`` prefixes the message (the MPSoC names the tile there).
    """
    code = int(st[S_ERR])
    pc = int(st[S_ERR_PC])
    word = int(st[S_ERR_INSN]) & 0xFFFFFFFF
    addr = int(st[S_ERR_ADDR]) & 0xFFFFFFFF
    cycle = int(st[S_CYCLE])
    text = ERROR_TEXT.get(code, f"error {code}")
    if code == ERR_FETCH and addr == pc:
        detail = f"{text}: pc 0x{pc:08x} is not in SRAM 0x{SRAM_BASE:08x}..0x{SRAM_BASE + sram_size:08x}"
        return CoreError(f"{where}{detail}, cycle {cycle}", kind=text, pc=pc, addr=addr, word=0, cycle=cycle)
    has_addr = code in ADDRESS_ERRORS
    target = ""
    if has_addr:
        target = f" 0x{addr:08x}" if text.endswith("address") else f" (address 0x{addr:08x})"
    msg = (
        f"{where}{text}{target} at pc 0x{pc:08x} ({symbolize(pc)}): "
        f"instruction 0x{word:08x} `{disassemble(word, pc)}`, cycle {cycle}"
    )
    return CoreError(msg, kind=text, pc=pc, addr=addr if has_addr else None, word=word, cycle=cycle)


def check_pc(state: CoreState, tile: int, symbolize: Callable[[int], str], where: str = "") -> None:
    """Raise a :class:`CoreError` unless the tile's pc is a word of its loaded code."""
    pc = int(state.st[tile, S_PC])
    off = pc - state.base
    if off % 4 == 0 and 0 <= off < state.code_size(tile):
        return
    code_end = state.base + state.code_size(tile)
    raise CoreError(
        f"{where}pc 0x{pc:08x} ({symbolize(pc)}) is not an instruction of the loaded code "
        f"0x{state.base:08x}..0x{code_end:08x} (was a program loaded?)",
        kind="bad pc", pc=pc, addr=pc, word=0, cycle=int(state.st[tile, S_CYCLE]),
    )  # fmt: skip


class CycleBudgetExceeded(RuntimeError):
    """The program did not exit within the cycle budget."""

    def __init__(self, message: str, *, pc: int, cycle: int) -> None:
        super().__init__(message)
        self.pc = pc
        self.cycle = cycle


def exit_word(value: int) -> int:
    """An exit code as the program stored it: the 32-bit word, 0..0xffffffff (``return -1`` gives 0xffffffff)."""
    return int(value) & 0xFFFFFFFF


def check_budget(max_cycles: int | None, chunk: int) -> None:
    """The arguments of the ``run`` methods: a budget of 1..2**62 cycles or ``None``, a chunk of at least 1."""
    if max_cycles is not None:
        check_int("max_cycles", max_cycles, 1, MAX_CYCLES, "cycles")
    check_int("chunk", chunk, 1, MAX_CYCLES, "cycles")


@dataclass
class RunResult:
    #: the exit word the program stored, unsigned (0..0xffffffff); a shell would see ``exit_code & 0xff``
    exit_code: int
    output: bytes
    counters: dict[str, int]
    host_seconds: float
    warnings: list[str] = field(default_factory=list)
    #: how many times each RTL erratum was hit ("mulhsu", "irq_during_mul"); in "spec" mode: would have been
    errata: dict[str, int] = field(default_factory=dict)

    @property
    def cycles(self) -> int:
        return self.counters["cycles"]

    @property
    def instructions(self) -> int:
        return self.counters["instructions"]


class SingleCoreSoC:
    """One HF-RISCV core with its SRAM at 0x40000000 and the SoC devices."""

    def __init__(
        self,
        *,
        mul: bool = True,
        sram_size: int = DEFAULT_SRAM_SIZE,
        errata: str = "spec",
        engine: str | Engine = DEFAULT_ENGINE,
    ) -> None:
        """A core after reset.

        Args:
            mul: with the iterative multiplier.
            sram_size: bytes of SRAM at 0x40000000, a multiple of 4 ending below the devices at 0xe0000000.
            errata: "spec" (RISC-V results, each RTL erratum the program hits is counted and warned
                about) or "rtl" (reproduce the RTL's errata, still counted).
            engine: an engine or its name (:func:`robosoc.chip.engines.resolve_engine`): "interp"
                (the interpreter), "jit" (translate regions at their first arrival) or "auto"
                (translate the regions that turn hot); every engine gives the same cycles,
                counters, outputs and errors (docs/translation.md).
        """
        if errata not in ERRATA_MODES:
            raise ValueError(f"errata: must be one of {', '.join(map(repr, ERRATA_MODES))}, got {errata!r}")
        self.engine = resolve_engine(engine)
        check_int("sram_size", sram_size, 4, DEVICE_MAP_BASE - SRAM_BASE, "bytes")
        check_memory("sram_size", sram_size, f"an SRAM of {format_bytes(sram_size)}")
        self.mul = mul
        self.errata = errata
        self.state = CoreState.new(mul=mul, sram_size=sram_size, base=SRAM_BASE, errata=ERRATA_MODES[errata])
        self.program: Program | None = None
        self.translator: TranslatingCore | None = self.engine.translator(self.state)

    def regions(self) -> list[Region]:
        return [Region(SRAM_BASE, self.state.size, "SRAM")]

    def load(self, program: Program) -> None:
        """Copy the program into SRAM (predecode rows only for its code) and point the pc at its entry."""
        self.state.set_code_size(program.code_end(SRAM_BASE))
        for addr, data in program.segments:
            self.state.write(addr, data)
        self.state.pc = program.entry
        self.program = program
        self.forget_translations()

    def enable_profile(self) -> None:
        """Count every instruction's executions and extra cycles per word of code from here on (the
        exact profile, :func:`robosoc.chip.function_profile.core_profile`; load the program
        first).  Translated code does not count: the core runs on the interpreter from here on."""
        self.forget_translations()
        self.translator = None
        self.state.enable_profile()

    def forget_translations(self) -> None:
        """Drop translated code: needed after writing the core's memory from outside (``state.write``)."""
        if self.translator is not None:
            self.translator.forget()

    def symbolize(self, pc: int) -> str:
        if self.program is None:
            return f"0x{pc:08x}"
        return self.program.symbolize(pc)

    @property
    def regs(self) -> np.ndarray:
        """The register file x0..x31 (a view: writes change the core)."""
        return self.state.regs[0, :32]

    @property
    def cycle(self) -> int:
        return int(self.state.st[0, S_CYCLE])

    def counters(self) -> dict[str, int]:
        return counters_dict(self.state.ctr[0], self.state.opc[0], self.cycle)

    def step_until(self, until: int) -> int:
        """Run the kernel to cycle ``until`` (or an event); returns its RUN_* status.

        Raises:
            CoreError: the pc is not an instruction of the loaded code (nothing loaded, or a pc
                set from outside); the kernel itself trusts the pc it starts from.
        """
        check_pc(self.state, 0, self.symbolize)
        if self.translator is not None:
            return self.translator.step_until(until)
        run_cores(self.state.arrays(), _TILE0, until)
        return int(self.state.st[0, S_RUN])

    def set_breakpoint(self, addr: int, on: bool = True) -> None:
        """Stop before the instruction at ``addr``: ``step_until`` then returns RUN_BREAK.

        Translated code does not see breakpoints: the core runs on the interpreter from here on.
        """
        self.forget_translations()
        self.translator = None
        self.state.set_breakpoint(addr, on)

    def drain_output(self) -> bytes:
        n = int(self.state.st[0, S_OUT_LEN])
        data = self.state.out[0, :n].tobytes()
        self.state.st[0, S_OUT_LEN] = 0
        return data

    def _error(self) -> CoreError:
        return core_error(self.state.st[0], self.symbolize, self.state.size)

    def run(
        self,
        max_cycles: int | None = None,
        on_output: Callable[[bytes], object] | None = None,
        chunk: int = CHUNK_CYCLES,
        sampler: Sampler | None = None,
        advance: Callable[[int], int] | None = None,
    ) -> RunResult:
        """Run until the program exits.

        Args:
            max_cycles: cycle budget, 1..2**62 (None: none).
            on_output: called with output bytes as they come.
            chunk: cycles per kernel call (output and Ctrl-C are seen between calls).
            sampler: a profiler (:class:`robosoc.chip.profile.Sampler`): the run is sliced at its
                sample points and it is called after each slice.
            advance: what runs the core to a cycle and returns its RUN_* status, in place of
                :meth:`step_until`: a debugger's (:meth:`robosoc.debug.GdbServer.advance`), which
                holds the core while it is halted and may return before the cycle.

        Raises:
            ValueError: ``max_cycles`` or ``chunk`` out of range.
            CoreError: illegal/unsupported instruction, bad access or fetch (with pc and symbol).
            CycleBudgetExceeded: ``max_cycles`` reached before the exit.
        """
        check_budget(max_cycles, chunk)
        st = self.state.st[0]
        st[S_MAX_CYCLES] = -1 if max_cycles is None else max_cycles
        output = bytearray()
        self.step_until(self.cycle)  # loads the compiled kernel (not counted as simulation time)
        advance = advance or self.step_until
        start = time.perf_counter()
        try:
            step = chunk if sampler is None else sampler.first()
            while True:
                status = advance(self.cycle + step)
                if sampler is not None:
                    step = sampler()
                data = self.drain_output()
                if data:
                    output += data
                    if on_output is not None:
                        on_output(data)
                if status == RUN_EXIT:
                    break
                if status == RUN_ERROR:
                    raise self._error()
                if status == RUN_MAX_CYCLES:
                    pc = self.state.pc
                    raise CycleBudgetExceeded(
                        f"cycle budget of {max_cycles} cycles exhausted at pc 0x{pc:08x} ({self.symbolize(pc)}): "
                        "the program did not exit (raise --max-cycles if it is just slow)",
                        pc=pc,
                        cycle=self.cycle,
                    )
        finally:
            elapsed = time.perf_counter() - start
        errata = errata_report(st, self.symbolize, self.errata)
        if self.errata == "spec":
            for name, (_, note) in errata.items():
                warnings.warn(note, ERRATUM_WARNINGS[name], stacklevel=2)
        return RunResult(
            exit_code=exit_word(st[S_EXIT_CODE]),
            output=bytes(output),
            counters=self.counters(),
            host_seconds=elapsed,
            warnings=[note for _, note in errata.values()],
            errata=errata_counts(errata),
        )


def run_elf(
    path: str | Path,
    mul: bool = True,
    max_cycles: int | None = None,
    sram_size: int = DEFAULT_SRAM_SIZE,
    on_output: Callable[[bytes], object] | None = None,
    errata: str = "spec",
    engine: str | Engine = DEFAULT_ENGINE,
) -> RunResult:
    """Load an ELF into a fresh single-core SoC and run it to its exit."""
    soc = SingleCoreSoC(mul=mul, sram_size=sram_size, errata=errata, engine=engine)
    soc.load(load_elf(path, soc.regions()))
    return soc.run(max_cycles=max_cycles, on_output=on_output)
