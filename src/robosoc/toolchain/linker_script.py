"""The SoC linker script, generated from the template with the configured SRAM geometry."""

from pathlib import Path

from robosoc.firmware import LINKER_SCRIPT_TEMPLATE
from robosoc.toolchain.errors import ToolchainError

SRAM_BASE = 0x4000_0000
DEFAULT_SRAM_SIZE = 2 * 1024 * 1024
#: The link fails when code + data leave less than this for the stack.
DEFAULT_STACK_MIN = 16 * 1024


def render_linker_script(
    sram_base: int = SRAM_BASE, sram_size: int = DEFAULT_SRAM_SIZE, stack_min: int = DEFAULT_STACK_MIN
) -> str:
    """Linker script text for SRAM at ``sram_base`` of ``sram_size`` bytes, stack at its top.

    Raises:
        ToolchainError: the geometry is not word-aligned, not positive, or leaves the 32-bit space.
    """
    if sram_base % 16 or sram_size % 16 or sram_size <= 0 or sram_base < 0:
        raise ToolchainError(f"SRAM base 0x{sram_base:x} and size {sram_size} must be positive multiples of 16")
    if sram_base + sram_size > 1 << 32:
        raise ToolchainError(f"SRAM 0x{sram_base:x} + {sram_size} bytes leaves the 32-bit address space")
    if not 0 <= stack_min < sram_size:
        raise ToolchainError(f"minimum stack {stack_min} does not fit in SRAM of {sram_size} bytes")
    text = LINKER_SCRIPT_TEMPLATE.read_text()
    for name, value in (
        ("@SRAM_BASE@", f"0x{sram_base:08x}"),
        ("@SRAM_SIZE@", f"0x{sram_size:x}"),
        ("@STACK_MIN@", f"0x{stack_min:x}"),
    ):
        text = text.replace(name, value)
    return text


def write_linker_script(path: Path, **geometry: int) -> Path:
    """Write the rendered linker script to ``path`` and return it."""
    path.write_text(render_linker_script(**geometry))
    return path
