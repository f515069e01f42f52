"""``robosoc cc``: compile C/assembly for one HF-RISCV core into an ELF."""

import re
import warnings
from pathlib import Path
from typing import Annotated

import typer

from robosoc.cli import exit_codes, files, options
from robosoc.cli.errors import CliError
from robosoc.cli.typer_apps import app


def _opt_level(value: str) -> str:
    """``2``, ``O2`` or ``-O2`` -> ``-O2`` (anything else is left for the choice check to refuse)."""
    match = re.fullmatch(r"(-?O)?([0123sz])", value)
    return f"-O{match[2]}" if match else value


Files = Annotated[
    list[Path], typer.Argument(metavar="FILES", help="C (.c) and assembly (.S, .s) sources.", show_default=False)
]
Output = Annotated[Path, typer.Option("--output", "-o", help="The ELF file to write.", show_default=False)]
Mul = Annotated[bool, typer.Option("--mul/--no-mul", help="Core with the iterative multiplier (Zmmul).")]
Opt = Annotated[
    str,
    typer.Option(
        "--opt",
        "-O",
        help="Optimisation level: 0 1 2 3 s z (-O2, -Os, ...).",
        callback=options.choice("-O0", "-O1", "-O2", "-O3", "-Os", "-Oz", normalize=_opt_level),
    ),
]
Define = Annotated[
    list[str] | None,
    typer.Option(
        "--define",
        "-D",
        help="Preprocessor NAME[=VALUE] (NAME a C identifier).",
        callback=options.pattern(r"[A-Za-z_]\w*(=.*)?", "NAME or NAME=VALUE with NAME a C identifier"),
    ),
]
Include = Annotated[list[Path] | None, typer.Option("--include", "-I", help="Extra include folder.")]
SramSize = Annotated[
    int,
    typer.Option(
        help="SRAM size in bytes, a multiple of 4 in 4096..2**30 (the stack starts at its top).",
        callback=options.sram_bytes(),
    ),
]
NoRuntime = Annotated[bool, typer.Option("--no-runtime", help="Do not link crt0, IRQ entry, print library.")]

SOURCE_SUFFIXES = (".c", ".S", ".s")


@app.command("cc", epilog=exit_codes.EPILOG + " A program that does not compile is an input error (2).")
def cc(
    files_: Files,
    output: Output,
    mul: Mul = True,
    opt: Opt = "2",
    define: Define = None,
    include: Include = None,
    sram_size: SramSize = 2 * 1024 * 1024,
    no_runtime: NoRuntime = False,
) -> None:
    """Compile FILES for the HF-RISCV core (RV32I, soft-float) and link them into OUTPUT."""
    from robosoc.toolchain import CompileError, ToolchainError, build_elf

    sources = [files.input_file(f, None, "C or assembly source") for f in files_]
    for f in sources:
        if f.suffix not in SOURCE_SUFFIXES:
            raise CliError(f"{f}: unsupported source type '{f.suffix}' (expected .c, .S or .s)")
    includes = [files.input_dir(d, "--include") for d in include or []]
    target = files.output_file(output, "--output", inputs=sources)

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            elf = build_elf(
                sources,
                target,
                mul=mul,
                opt=opt,
                defines=define or [],
                include_dirs=includes,
                sram_size=sram_size,
                runtime=not no_runtime,
            )
        except CompileError as exc:
            raise CliError(str(exc)) from exc
        except ToolchainError as exc:
            raise CliError(str(exc)) from exc
    for warning in caught:
        typer.echo(f"warning: {warning.message}", err=True)
    typer.echo(str(elf))
