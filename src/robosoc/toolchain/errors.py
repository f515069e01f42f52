"""Exceptions and warnings of the firmware toolchain."""

from pathlib import Path


class ToolchainError(RuntimeError):
    """The toolchain could not run (zig missing, bad option, unreadable source)."""


class CompileError(ToolchainError):
    """The compiler or linker rejected the program.

    Attributes:
        files: the source files the compiler's message is about (all sources when it names none).
        message: the compiler's own diagnostic text.
        command: the command line that failed.
    """

    def __init__(self, files: list[Path], message: str, command: list[str]) -> None:
        self.files = files
        self.message = message.strip()
        self.command = command
        names = ", ".join(str(f) for f in files) or "<no sources>"
        super().__init__(f"compile error in {names}:\n{self.message}")


class CompilerWarning(UserWarning):
    """The compiler printed warnings for a build that succeeded."""


class FixedRegisterWarning(UserWarning):
    """Code outside the interrupt entry writes x27 (s11), which the return sequence owns."""
