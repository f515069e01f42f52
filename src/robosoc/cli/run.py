"""``robosoc run``: run a bare-metal program on one HF-RISCV core."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated

import typer

from robosoc.cli.app import app


@app.command("run")
def run(
    program: Annotated[Path, typer.Argument(help="ELF file built for the core (robosoc cc).")],
    mul: Annotated[bool, typer.Option("--mul/--no-mul", help="Core with or without the iterative multiplier.")] = True,
    max_cycles: Annotated[int, typer.Option("--max-cycles", help="Cycle budget: stop a hung program.")] = 10**10,
    stats: Annotated[Path | None, typer.Option("--stats", help="Write counters and energy to this JSON file.")] = None,
    energy: Annotated[Path | None, typer.Option("--energy", help="Energy coefficients (TOML) to use.")] = None,
    sram_size: Annotated[int, typer.Option("--sram-size", help="SRAM bytes.")] = 2 * 1024 * 1024,
) -> None:
    """Run PROGRAM on one core: its debug-port and UART output goes to stdout, the summary to stderr,
    and the exit code is the program's."""
    from robosoc.analysis.energy import EnergyModel
    from robosoc.chip.elf import ElfError, load_elf
    from robosoc.chip.single import CoreError, CycleBudgetExceeded, SingleCoreSoC
    from robosoc.config import ConfigError

    try:
        model = EnergyModel.load(energy)
        soc = SingleCoreSoC(mul=mul, sram_size=sram_size)
        soc.load(load_elf(program, soc.regions()))
    except (ConfigError, ElfError, ValueError, OSError) as exc:
        typer.echo(f"robosoc run: {exc}", err=True)
        raise typer.Exit(2) from exc

    def write_out(data: bytes) -> None:
        sys.stdout.buffer.write(data)
        sys.stdout.buffer.flush()

    failure: Exception | None = None
    result = None
    try:
        result = soc.run(max_cycles=max_cycles, on_output=write_out)
        counters = result.counters
        seconds = result.host_seconds
    except (CoreError, CycleBudgetExceeded) as exc:
        failure = exc
        counters = soc.counters()
        seconds = 0.0
    except KeyboardInterrupt:
        failure = KeyboardInterrupt("interrupted")
        counters = soc.counters()
        seconds = 0.0

    energy_pj = model.breakdown_pj(counters)
    total_nj = sum(energy_pj.values()) / 1000.0
    if stats is not None:
        record = {
            "program": str(program),
            "mul": mul,
            "exit_code": result.exit_code if result else None,
            "error": str(failure) if failure else None,
            "counters": counters,
            "energy_pj": energy_pj,
            "energy_nj": total_nj,
            "energy_model": model.path,
            "warnings": result.warnings if result else [],
        }
        tmp = stats.with_suffix(stats.suffix + ".tmp")
        tmp.write_text(json.dumps(record, indent=2) + "\n")
        tmp.replace(stats)

    cycles = counters["cycles"]
    instr = counters["instructions"]
    cpi = cycles / instr if instr else float("nan")
    mips = instr / seconds / 1e6 if seconds > 0 else float("nan")
    typer.echo(
        f"robosoc: {cycles} cycles, {instr} instructions, CPI {cpi:.3f}, "
        f"energy {total_nj:.3f} nJ, host {mips:.0f} MIPS",
        err=True,
    )
    if failure is not None:
        typer.echo(f"robosoc run: {failure}", err=True)
        raise typer.Exit(130 if isinstance(failure, KeyboardInterrupt) else 3)
    assert result is not None
    raise typer.Exit(result.exit_code & 0xFF)
