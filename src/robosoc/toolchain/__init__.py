"""Firmware toolchain: C/assembly → RV32 ELF for the HF-RISCV core with the ``ziglang`` package.

Public API:

- :func:`build_elf` — compile and link for one core (with or without the multiplier), cached.
- :func:`compile_native` / :func:`run_native` — the same C for the host, to compare results.
- :func:`render_linker_script` — the SoC linker script for an SRAM geometry.
- :func:`find_x27_writes` — the post-link check that only the interrupt entry writes s11.
- :class:`CompileError`, :class:`ToolchainError`, :class:`FixedRegisterWarning`, :class:`CompilerWarning`.
"""

from robosoc.cache import cache_root
from robosoc.toolchain.build import build_elf
from robosoc.toolchain.errors import CompileError, CompilerWarning, FixedRegisterWarning, ToolchainError
from robosoc.toolchain.linker_script import DEFAULT_SRAM_SIZE, SRAM_BASE, render_linker_script
from robosoc.toolchain.native import compile_native, run_native
from robosoc.toolchain.options import MCPU_MUL, MCPU_NO_MUL
from robosoc.toolchain.x27_check import X27Write, find_x27_writes

__all__ = [
    "DEFAULT_SRAM_SIZE",
    "MCPU_MUL",
    "MCPU_NO_MUL",
    "SRAM_BASE",
    "CompileError",
    "CompilerWarning",
    "FixedRegisterWarning",
    "ToolchainError",
    "X27Write",
    "build_elf",
    "cache_root",
    "compile_native",
    "find_x27_writes",
    "render_linker_script",
    "run_native",
]
