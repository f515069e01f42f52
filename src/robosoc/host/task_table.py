"""The kernel's task table (``os_tcb`` in kernel/os_internal.h) as the host reads it, by DWARF.

Which TASK_IDs a tile's kernel holds (:meth:`TaskTable.created`: every task ``main`` created) and
whether a task's job is active (:meth:`TaskTable.job_active`: released and not completed).  Host
reads: they cost the chip no cycle.  The layout (the table's address and length, an entry's size,
the offsets of ``id`` and ``job_active``) comes from the ELF's symbol table and debug information,
so the C struct stays its only description.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from robosoc.cache import dwarf_dir
from robosoc.program.dwarf import debug_index
from robosoc.program.elf import load_elf

if TYPE_CHECKING:
    from robosoc.chip.core_state import CoreState
    from robosoc.chip.mpsoc import MPSoC

__all__ = ["TCB_SYMBOL", "TaskTable"]

TCB_SYMBOL = "os_tcb"
"""The kernel's task table: ``os_tcb_t os_tcb[OS_MAX_TASKS + 1]``, [0] the idle task."""
TCB_TYPE = "os_tcb"
COUNT_SYMBOL = "os_ntasks"
"""Entries of ``os_tcb`` in use (the idle task's included)."""

Tile = tuple[int, int]


@dataclass(frozen=True)
class TaskTable:
    """Where ``os_tcb`` lies in one firmware image and how its entries are laid out."""

    address: int
    count_address: int
    entries: int
    entry_bytes: int
    id_offset: int
    active_offset: int

    @classmethod
    def of(cls, elf: Path) -> TaskTable:
        """The table of the kernel image ``elf``.

        Raises:
            ElfError: not a kernel image built with debug information.
        """
        program = load_elf(elf)
        index = debug_index(elf, dwarf_dir())
        entry_bytes = index.type_size(TCB_TYPE)
        return cls(
            address=program.address_of(TCB_SYMBOL),
            count_address=program.address_of(COUNT_SYMBOL),
            entries=index.variable_field(TCB_SYMBOL)[1] // entry_bytes,
            entry_bytes=entry_bytes,
            id_offset=index.member_offset(TCB_TYPE, "id")[0],
            active_offset=index.member_offset(TCB_TYPE, "job_active")[0],
        )

    def _entries(self, cores: CoreState, t: int) -> bytes:
        """The whole table as it stands on the tile of index ``t`` (one host read)."""
        return cores.read(self.address, self.entries * self.entry_bytes, tile=t)

    def created(self, chip: MPSoC, tile: Tile) -> list[int]:
        """The TASK_IDs of the tasks created on ``tile`` (the idle task's excluded), in table order."""
        t = chip.config.tile_index(tile)
        used = int.from_bytes(chip.cores.read(self.count_address, 4, tile=t), "little")
        table = self._entries(chip.cores, t)
        return [table[i * self.entry_bytes + self.id_offset] for i in range(1, min(used, self.entries))]

    def job_active(self, chip: MPSoC, tile: Tile, task_id: int) -> bool:
        """Whether task ``task_id`` has a job released and not completed on ``tile`` now (True for a
        task not created: there is nothing consistent to read of it)."""
        return self.job_active_at(chip.cores, chip.config.tile_index(tile), task_id)

    def flag_offsets(self, cores: CoreState, t: int) -> tuple[list[int], list[int]]:
        """Where the ``id`` and the ``job_active`` byte of each entry but the idle task's lie in the
        tile of index ``t``'s row of ``cores.m8`` (a reader that looks at every sample period).

        Raises:
            ValueError: the table is not all in the tile's SRAM.
        """
        base = cores.offset(self.address, self.entries * self.entry_bytes, t)
        entries = [base + i * self.entry_bytes for i in range(1, self.entries)]
        return [e + self.id_offset for e in entries], [e + self.active_offset for e in entries]

    def job_active_at(self, cores: CoreState, t: int, task_id: int) -> bool:
        """:meth:`job_active` on the tile of index ``t`` of ``cores``."""
        table = self._entries(cores, t)
        for i in range(1, self.entries):  # [0] is the idle task
            entry = i * self.entry_bytes
            if table[entry + self.id_offset] == task_id:
                return table[entry + self.active_offset] != 0
        return True
