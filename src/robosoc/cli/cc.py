"""``robosoc cc``: compile C/assembly for one HF-RISCV core into an ELF."""

import warnings
from pathlib import Path
from typing import Annotated

import typer

from robosoc.cli.app import app

Files = Annotated[list[Path], typer.Argument(help="C (.c) and assembly (.S, .s) sources.")]
Output = Annotated[Path, typer.Option("--output", "-o", help="The ELF file to write.")]
Mul = Annotated[bool, typer.Option("--mul/--no-mul", help="Core with the iterative multiplier (Zmmul).")]
Opt = Annotated[str, typer.Option("--opt", "-O", help="Optimisation level: 0 1 2 3 s z (-O2, -Os, ...).")]
Define = Annotated[list[str] | None, typer.Option("--define", "-D", help="Preprocessor NAME[=VALUE].")]
Include = Annotated[list[Path] | None, typer.Option("--include", "-I", help="Extra include folder.")]
SramSize = Annotated[int, typer.Option(help="SRAM size in bytes (the stack starts at its top).")]
NoRuntime = Annotated[bool, typer.Option("--no-runtime", help="Do not link crt0, IRQ entry, print library.")]


@app.command("cc")
def cc(
    files: Files,
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

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            elf = build_elf(
                files,
                output,
                mul=mul,
                opt=opt,
                defines=define or [],
                include_dirs=include or [],
                sram_size=sram_size,
                runtime=not no_runtime,
            )
        except CompileError as exc:
            typer.echo(str(exc), err=True)
            raise typer.Exit(1) from exc
        except ToolchainError as exc:
            typer.echo(f"robosoc cc: {exc}", err=True)
            raise typer.Exit(2) from exc
    for warning in caught:
        typer.echo(f"warning: {warning.message}", err=True)
    typer.echo(str(elf))
