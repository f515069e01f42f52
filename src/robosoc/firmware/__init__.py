"""The bare-metal runtime shipped with robosoc, and where its files are.

Layout (all plain files inside the package):

- ``link/hfriscv.ld``: linker script template, filled in by :mod:`robosoc.toolchain.linker_script`.
- ``crt/crt0.S``: ``_start`` (stack, gp, .bss, IRQ_VECTOR, ``main``, exit trap).
- ``crt/irq_entry.S``: interrupt/trap entry and the s11 return sequence.
- ``crt/irq_default.c``: the weak default ``irq_handler``.
- ``include/hfriscv.h``: SoC register addresses and inline helpers.
- ``include/hf_print.h`` + ``lib/hf_print.c``: debug-port text output (host: stdout).
- ``libc/include/string.h`` + ``libc/string.c``: memcpy, memset, strlen, ... for core builds.
- ``bench/matrix_bench.c``: the EKF-like 7x7 matrix workload of ``robosoc bench core``.
- ``kernel/``: the portable real-time kernel (``os.h``, ``os_config.h``, tasks, messaging).
- ``port/``: its HF-RISCV port (context switch and interrupt entry, tick timer, NI driver).
  Kernel images link these instead of ``crt/irq_entry.S`` and ``crt/irq_default.c``
  (:mod:`robosoc.firmware.images`).
"""

from pathlib import Path

FIRMWARE_DIR = Path(__file__).resolve().parent
INCLUDE_DIR = FIRMWARE_DIR / "include"
LINKER_SCRIPT_TEMPLATE = FIRMWARE_DIR / "link" / "hfriscv.ld"
CRT_SOURCES: tuple[Path, ...] = (
    FIRMWARE_DIR / "crt" / "crt0.S",
    FIRMWARE_DIR / "crt" / "irq_entry.S",
    FIRMWARE_DIR / "crt" / "irq_default.c",
)
LIB_SOURCES: tuple[Path, ...] = (FIRMWARE_DIR / "lib" / "hf_print.c",)
#: Headers only core builds see (``string.h``; host builds use the host's libc).
LIBC_INCLUDE_DIR = FIRMWARE_DIR / "libc" / "include"
LIBC_SOURCES: tuple[Path, ...] = (FIRMWARE_DIR / "libc" / "string.c",)
MATRIX_BENCH_SOURCE = FIRMWARE_DIR / "bench" / "matrix_bench.c"
KERNEL_DIR = FIRMWARE_DIR / "kernel"
PORT_DIR = FIRMWARE_DIR / "port"
KERNEL_SOURCES: tuple[Path, ...] = (KERNEL_DIR / "os_task.c", KERNEL_DIR / "os_msg.c")
PORT_SOURCES: tuple[Path, ...] = (PORT_DIR / "port_asm.S", PORT_DIR / "port_hfriscv.c")

#: Symbol of the interrupt entry: the one place allowed to write x27 (s11).
IRQ_ENTRY_SYMBOL = "_irq_entry"


def runtime_sources() -> tuple[Path, ...]:
    """Sources linked into every RISC-V program: start-up code, interrupt entry, print library."""
    return CRT_SOURCES + LIB_SOURCES + LIBC_SOURCES


def kernel_runtime_sources() -> tuple[Path, ...]:
    """Sources linked into every kernel image: start-up code, the port's interrupt entry in place of
    the runtime's, the kernel, the print library and libc (build with ``runtime=False``)."""
    return (CRT_SOURCES[0], *PORT_SOURCES, *KERNEL_SOURCES, *LIB_SOURCES, *LIBC_SOURCES)


def host_sources() -> tuple[Path, ...]:
    """Runtime sources that also build for the host (the print library)."""
    return LIB_SOURCES


__all__ = [
    "CRT_SOURCES",
    "FIRMWARE_DIR",
    "INCLUDE_DIR",
    "IRQ_ENTRY_SYMBOL",
    "KERNEL_DIR",
    "KERNEL_SOURCES",
    "LIBC_INCLUDE_DIR",
    "LIBC_SOURCES",
    "LIB_SOURCES",
    "LINKER_SCRIPT_TEMPLATE",
    "MATRIX_BENCH_SOURCE",
    "PORT_DIR",
    "PORT_SOURCES",
    "host_sources",
    "kernel_runtime_sources",
    "runtime_sources",
]
