"""Compiler options for the HF-RISCV core and for the host, as plain data."""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from robosoc.toolchain.errors import ToolchainError

TARGET = "riscv32-freestanding-none"
#: No multiplier: plain RV32I; multiplication goes through compiler-rt's __mulsi3.
MCPU_NO_MUL = "generic_rv32"
#: Iterative multiplier: RV32I + Zmmul (MUL/MULH/MULHSU/MULHU, never DIV).
MCPU_MUL = "generic_rv32+zmmul"
#: Appended to -mcpu so that zig also builds compiler-rt without x27 (s11), not only our C files.
RESERVE_X27 = "+reserve_x27"

OPT_LEVELS = ("0", "1", "2", "3", "s", "z")

#: Flags shared by the core and host builds, so both compute the same thing.
COMMON_FLAGS = (
    "-std=c11",
    "-Wall",
    "-Wextra",
    "-ffp-contract=off",  # the host may fuse a*b+c into an FMA; the core never does
    "-fno-strict-aliasing",
)

#: Flags of every core build.
CORE_FLAGS = (
    "-ffreestanding",
    "-g",  # zig strips the symbol table at -Os/-Oz otherwise; debug info does not change the code
    "-ffixed-x27",  # s11 is reserved for the interrupt return sequence
    "-fomit-frame-pointer",
    "-fno-unwind-tables",
    "-fno-asynchronous-unwind-tables",
    "-ffunction-sections",
    "-fdata-sections",
    "-Wl,--gc-sections",
)


def normalize_opt(opt: str) -> str:
    """``"-O2"``, ``"O2"`` or ``"2"`` → ``"-O2"``.

    Raises:
        ToolchainError: not one of -O0 -O1 -O2 -O3 -Os -Oz.
    """
    level = opt.removeprefix("-").removeprefix("O")
    if level not in OPT_LEVELS:
        choices = " ".join(f"-O{o}" for o in OPT_LEVELS)
        raise ToolchainError(f"optimisation level '{opt}' is not one of {choices}")
    return f"-O{level}"


def mcpu(mul: bool) -> str:
    """The -mcpu value of a core with or without the multiplier (x27 reserved in both)."""
    return (MCPU_MUL if mul else MCPU_NO_MUL) + RESERVE_X27


def define_flags(defines: Mapping[str, str | int | None] | Sequence[str]) -> list[str]:
    """``{"N": 10, "DEBUG": None}`` or ``["N=10", "DEBUG"]`` → ``["-DN=10", "-DDEBUG"]``."""
    if isinstance(defines, Mapping):
        items = [name if value is None else f"{name}={value}" for name, value in defines.items()]
    else:
        items = list(defines)
    for item in items:
        if not item or item.startswith("-") or "=" in item.split("=", 1)[0] or " " in item.split("=")[0]:
            raise ToolchainError(f"bad preprocessor define '{item}' (expected NAME or NAME=VALUE)")
    return [f"-D{item}" for item in items]


@dataclass(frozen=True)
class CoreBuildOptions:
    """Everything besides the sources that decides a core ELF (and so its cache key)."""

    mul: bool
    opt: str = "-O2"
    defines: tuple[str, ...] = ()
    include_dirs: tuple[str, ...] = ()
    sram_base: int = 0x4000_0000
    sram_size: int = 2 * 1024 * 1024
    stack_min: int = 16 * 1024
    runtime: bool = True
    extra_flags: tuple[str, ...] = field(default=())

    def compiler_flags(self) -> list[str]:
        """Flags for zig cc, without sources, linker script and output."""
        return [
            "-target",
            TARGET,
            f"-mcpu={mcpu(self.mul)}",
            normalize_opt(self.opt),
            *COMMON_FLAGS,
            *CORE_FLAGS,
            *self.defines,
            *(f"-I{d}" for d in self.include_dirs),
            *self.extra_flags,
        ]
