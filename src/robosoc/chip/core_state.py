"""One core's state as numpy arrays (registers, memory, predecode table, counters, devices).

This is the data half of a core; the behaviour is :func:`robosoc.kernels.core.run_core`.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from robosoc.isa.table import OP_BREAK, OP_FETCH_FAULT
from robosoc.kernels.core import CoreArrays
from robosoc.kernels.core_layout import (
    CTR_SIZE,
    ERRATA_SPEC,
    NEVER,
    OPC_SIZE,
    OUT_CAPACITY,
    PIPELINE_FILL,
    S_CODE_SIZE,
    S_CYCLE,
    S_ERRATA,
    S_EXT_RISE,
    S_IRQ_CHECK,
    S_IRQ_RISE,
    S_IRQ_SCAN,
    S_IRQMUL_PC,
    S_MAX_CYCLES,
    S_MEM_BASE,
    S_MEM_SIZE,
    S_MUL,
    S_MULHSU_PC,
    S_PC,
    S_PROF_BASE,
    S_PROF_STRIDE,
    S_T1_CTC,
    ST_SIZE,
)

SRAM_BASE = 0x40000000
DEFAULT_SRAM_SIZE = 2 * 1024 * 1024


@dataclass
class CoreState:
    """Arrays of a set of cores, one row per core (tile).

    ``m8``, ``m16`` and ``m32`` are views of the same SRAM bytes.  The
    single-core SoC uses one row; the MPSoC one per tile.  Accessors without a tile argument
    refer to row 0.
    """

    st: np.ndarray
    ctr: np.ndarray
    opc: np.ndarray
    regs: np.ndarray
    m8: np.ndarray
    m16: np.ndarray
    m32: np.ndarray
    dec: np.ndarray
    out: np.ndarray
    _bundle: CoreArrays | None = field(default=None, init=False, repr=False, compare=False)

    @classmethod
    def new(
        cls,
        *,
        mul: bool | list[bool],
        sram_size: int = DEFAULT_SRAM_SIZE,
        base: int = SRAM_BASE,
        tiles: int = 1,
        errata: int = ERRATA_SPEC,
        code_size: int | None = None,
    ) -> CoreState:
        """Fresh cores after reset; ``mul`` may be given per tile.

        ``code_size`` bytes from the base get predecode rows (default: the whole SRAM; loading a
        program shrinks it to the program's code with :meth:`set_code_size`).
        """
        if sram_size <= 0 or sram_size % 4:
            raise ValueError(f"sram_size: must be a positive multiple of 4 bytes, got {sram_size}")
        muls = mul if isinstance(mul, list) else [mul] * tiles
        m8 = np.zeros((tiles, sram_size), dtype=np.uint8)
        st = np.zeros((tiles, ST_SIZE), dtype=np.int64)
        st[:, S_MEM_BASE] = base
        st[:, S_MEM_SIZE] = sram_size
        st[:, S_MUL] = [1 if m else 0 for m in muls]
        st[:, S_CYCLE] = PIPELINE_FILL
        st[:, S_MAX_CYCLES] = -1
        st[:, S_IRQ_RISE] = -1
        st[:, S_IRQ_SCAN] = NEVER  # interrupts are off after reset: nothing to look at yet
        st[:, S_IRQ_CHECK] = NEVER
        st[:, S_EXT_RISE] = NEVER
        st[:, S_MULHSU_PC] = -1
        st[:, S_IRQMUL_PC] = -1
        st[:, S_T1_CTC] = 0xFFFF
        st[:, S_ERRATA] = errata
        state = cls(
            st=st,
            ctr=np.zeros((tiles, CTR_SIZE), dtype=np.int64),
            opc=np.zeros((tiles, OPC_SIZE), dtype=np.int64),
            regs=np.zeros((tiles, 33), dtype=np.int32),
            m8=m8,
            m16=m8.view(np.uint16),
            m32=m8.view(np.int32),
            dec=np.zeros((tiles, 2), dtype=np.int32),
            out=np.zeros((tiles, OUT_CAPACITY), dtype=np.uint8),
        )
        state.set_code_size(sram_size if code_size is None else code_size)
        return state

    def set_code_size(self, nbytes: int, tile: int | None = None) -> None:
        """Give predecode rows to the first ``nbytes`` of SRAM (rounded up to a word) of one tile or all.

        Execution beyond them is an error (``execution past the loaded code``); stores there are
        data stores.  Each word has two int32; a sentinel row after the last stops execution.
        The tile's earlier predecoded rows are forgotten.
        """
        tiles = range(self.tiles) if tile is None else [tile]
        for t in tiles:
            words = min(max(0, -(-nbytes // 4)), int(self.st[t, S_MEM_SIZE]) // 4)
            self.st[t, S_CODE_SIZE] = 4 * words
        need = 2 * (int(self.st[:, S_CODE_SIZE].max()) // 4 + 1)
        if tile is None or need > self.dec.shape[1]:
            old = self.dec
            self.dec = np.zeros((self.tiles, need), dtype=np.int32)
            if tile is not None:
                keep = min(old.shape[1], need)
                self.dec[:, :keep] = old[:, :keep]
        for t in tiles:
            end = 2 * (int(self.st[t, S_CODE_SIZE]) // 4)
            self.dec[t, :] = 0
            self.dec[t, end] = OP_FETCH_FAULT
        if self.profiling and self.profile_stride != self.dec.shape[1] // 2 + 1:  # another program: afresh
            banks = self.prof.shape[1] // self.profile_stride
            self.st[:, S_PROF_STRIDE] = 0
            self.enable_profile(banks)

    # --- the exact profile (robosoc.chip.function_profile reads it) -------------------------------
    @property
    def profiling(self) -> bool:
        return bool(self.st[0, S_PROF_STRIDE] != 0)

    @property
    def prof(self) -> np.ndarray:
        """The profile's flow counts per tile (rows) and task bank x word of code (columns): a view of
        the ``opc`` rows (the running sum over a bank is the executions, :meth:`executions`)."""
        half = (self.opc.shape[1] - OPC_SIZE) // 2
        return self.opc[:, OPC_SIZE : OPC_SIZE + half]

    def executions(self, tile: int = 0) -> np.ndarray:
        """Executions of each word of code per task bank of a tile, shape (banks, stride)."""
        return np.cumsum(self.prof[tile].reshape(-1, self.profile_stride), axis=1)

    @property
    def pext(self) -> np.ndarray:
        """Dynamic extra cycles (taken branches, multiplier steps), laid out as :attr:`prof`."""
        half = (self.opc.shape[1] - OPC_SIZE) // 2
        return self.opc[:, OPC_SIZE + half :]

    @property
    def profile_stride(self) -> int:
        """Columns of one task bank of ``prof``: one per word of the largest loaded code, its sentinel
        and one more (a trap in the last word moves the flow two words on); while profiling, as it
        was when profiling was enabled."""
        return int(self.st[0, S_PROF_STRIDE]) or self.dec.shape[1] // 2 + 1

    def enable_profile(self, banks: int = 1) -> None:
        """Count every instruction's executions and extra cycles per word of code, in ``banks`` banks
        (one per task id; the running task's is chosen by ``S_PROF_BASE``, bank 0 from here on).

        The counts extend the ``opc`` rows (a new array: take :meth:`arrays` again).  Counting starts
        from zero: enable it before the run for a profile whose totals are the run's.
        """
        if banks < 1:
            raise ValueError(f"banks: at least 1, got {banks}")
        stride = self.profile_stride
        opc = np.zeros((self.tiles, OPC_SIZE + 2 * banks * stride), dtype=np.int64)
        opc[:, :OPC_SIZE] = self.opc[:, :OPC_SIZE]
        self.opc = opc
        self.st[:, S_PROF_STRIDE] = stride
        self.st[:, S_PROF_BASE] = OPC_SIZE

    def set_breakpoint(self, addr: int, on: bool, tile: int = 0) -> None:
        """Mark (or unmark) the instruction at ``addr``: the core stops before it (RUN_BREAK).

        The mark lives in the predecode row, so it costs nothing while not hit; a store into the
        word clears it with the row (a debugger sets it again).  Raises ValueError for an address
        that is not a word of the loaded code.
        """
        off = addr - self.base
        if off % 4 or not 0 <= off < self.code_size(tile):
            raise ValueError(
                f"0x{addr:08x} is not an instruction of the loaded code "
                f"(0x{self.base:08x}..0x{self.base + self.code_size(tile):08x}, word aligned)"
            )
        self.dec[tile, 2 * (off // 4)] = OP_BREAK if on else 0

    def op_rows(self, tile: int = 0) -> np.ndarray:
        """The operation row of every word of a tile's loaded code (a view, one int32 per word).

        0 is a word not decoded yet (the core decodes it when it gets there, at no cycle cost) and
        OP_BREAK a breakpoint; a debugger may write either (robosoc.debug marks many words at once).
        """
        return self.dec[tile, 0 : 2 * (self.code_size(tile) // 4) : 2]

    def code_size(self, tile: int = 0) -> int:
        """Bytes of a tile's SRAM that have predecode rows (the loaded code)."""
        return int(self.st[tile, S_CODE_SIZE])

    def arrays(self) -> CoreArrays:
        """The arrays as the numba kernels take them (a named bundle, no copies): the same bundle
        until one of them is replaced (:class:`robosoc.chip.kernel_entry.KernelEntry` types a kernel's
        arguments once for the same objects)."""
        b = self._bundle
        if (
            b is None
            or b.st is not self.st
            or b.ctr is not self.ctr
            or b.opc is not self.opc
            or b.regs is not self.regs
            or b.m8 is not self.m8
            or b.m16 is not self.m16
            or b.m32 is not self.m32
            or b.dec is not self.dec
            or b.out is not self.out
        ):
            b = self._bundle = CoreArrays(
                self.st, self.ctr, self.opc, self.regs, self.m8, self.m16, self.m32, self.dec, self.out
            )
        return b

    @property
    def tiles(self) -> int:
        return int(self.st.shape[0])

    @property
    def base(self) -> int:
        return int(self.st[0, S_MEM_BASE])

    @property
    def size(self) -> int:
        return int(self.st[0, S_MEM_SIZE])

    @property
    def pc(self) -> int:
        return int(self.st[0, S_PC])

    @pc.setter
    def pc(self, value: int) -> None:
        self.st[0, S_PC] = value & 0xFFFFFFFF

    def write(self, addr: int, data: bytes, tile: int = 0) -> None:
        """Copy bytes into a tile's SRAM (and forget any predecoded instructions there)."""
        off = addr - self.base
        size = int(self.st[tile, S_MEM_SIZE])
        if off < 0 or off + len(data) > size:
            raise ValueError(
                f"address 0x{addr:08x}+{len(data)} is outside SRAM 0x{self.base:08x}..0x{self.base + size:08x}"
            )
        self.m8[tile, off : off + len(data)] = np.frombuffer(data, dtype=np.uint8)
        words = self.code_size(tile) // 4
        self.dec[tile, 2 * min(off // 4, words) : 2 * min((off + len(data) + 3) // 4, words)] = 0

    def read(self, addr: int, length: int, tile: int = 0) -> bytes:
        off = addr - self.base
        if off < 0 or off + length > int(self.st[tile, S_MEM_SIZE]):
            raise ValueError(f"address 0x{addr:08x}+{length} is outside SRAM")
        return self.m8[tile, off : off + length].tobytes()

    def unpack(self, layout: struct.Struct, addr: int, tile: int = 0) -> tuple[Any, ...]:
        """``layout.unpack`` of the bytes at ``addr`` of a tile's SRAM, read in place (the host's
        reads of every sample period: job records, telemetry)."""
        return layout.unpack_from(self.m8[tile], self.offset(addr, layout.size, tile))

    def offset(self, addr: int, length: int, tile: int = 0) -> int:
        """Where the ``length`` bytes at ``addr`` lie in a tile's row of :attr:`m8`.

        Raises:
            ValueError: they are not all in the tile's SRAM.
        """
        off = addr - self.base
        if off < 0 or off + length > int(self.st[tile, S_MEM_SIZE]):
            raise ValueError(f"address 0x{addr:08x}+{length} is outside SRAM")
        return off

    def word(self, addr: int, tile: int = 0) -> int:
        return int.from_bytes(self.read(addr, 4, tile), "little")
