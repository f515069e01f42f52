"""``robosoc run``: run bare-metal programs on one HF-RISCV core or on the MPSoC."""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from robosoc.cli.app import app
from robosoc.cli.gdb_option import GDB_HELP, TILE_HELP, check_gdb_options, gdb_session

if TYPE_CHECKING:
    from robosoc.analysis.energy import EnergyModel


def _write_json(path: Path, record: dict) -> None:
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps(record, indent=2) + "\n")
    tmp.replace(path)


def _parse_mesh(mesh: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in mesh.lower().split("x"))
    except ValueError as exc:
        raise typer.BadParameter(f"expected WxH such as 2x2, got {mesh!r}", param_hint="--mesh") from exc
    return w, h


def _parse_tile(text: str) -> tuple[int, int]:
    try:
        x, y = (int(v) for v in text.split(","))
    except ValueError as exc:
        raise typer.BadParameter(f"expected X,Y such as 1,1, got {text!r}", param_hint="--off") from exc
    return x, y


@app.command("run")
def run(
    programs: Annotated[list[Path], typer.Argument(help="ELF file(s) built for the core (robosoc cc).")],
    mul: Annotated[bool, typer.Option("--mul/--no-mul", help="Cores with or without the iterative multiplier.")] = True,
    max_cycles: Annotated[int, typer.Option("--max-cycles", help="Cycle budget: stop a hung program.")] = 10**10,
    stats: Annotated[Path | None, typer.Option("--stats", help="Write counters and energy to this JSON file.")] = None,
    energy: Annotated[Path | None, typer.Option("--energy", help="Energy coefficients (TOML) to use.")] = None,
    sram_size: Annotated[int, typer.Option("--sram-size", help="SRAM bytes (per tile).")] = 2 * 1024 * 1024,
    mesh: Annotated[str | None, typer.Option("--mesh", help="Run on a WxH MPSoC (I/O tile at 0,0).")] = None,
    chip: Annotated[Path | None, typer.Option("--chip", help="MPSoC configuration file (TOML).")] = None,
    off: Annotated[list[str] | None, typer.Option("--off", help="Power off tile X,Y (repeatable).")] = None,
    trace: Annotated[int, typer.Option("--trace", help="Print the first N instructions to stderr (one core).")] = 0,
    profile: Annotated[
        int, typer.Option("--profile", help="Sample the pc every ~N cycles; print cycles by function (one core).")
    ] = 0,
    errata: Annotated[
        str,
        typer.Option(
            "--errata",
            help="spec: RISC-V results, report each HF-RISCV RTL erratum hit; rtl: reproduce the RTL's errata.",
        ),
    ] = "spec",
    gdb: Annotated[int | None, typer.Option("--gdb", help=GDB_HELP)] = None,
    tile: Annotated[str | None, typer.Option("--tile", help=TILE_HELP)] = None,
) -> None:
    """Run bare-metal programs on one HF-RISCV core, or on the MPSoC with --mesh/--chip.

    Program output (debug port, UART) goes to stdout, prefixed by the tile on the MPSoC; a
    summary goes to stderr; the exit code is the program's (the first non-zero one on the MPSoC).
    On the MPSoC one ELF runs on every core tile (tiles tell themselves apart by reading
    NI_TILE), or one ELF per core tile in tile order (x fastest).
    """
    from robosoc.analysis.energy import EnergyModel
    from robosoc.config import ConfigError
    from robosoc.config.chip import ERRATA_CHOICES

    if errata not in ERRATA_CHOICES:
        typer.echo(f"robosoc run: --errata: must be one of {', '.join(ERRATA_CHOICES)}, got {errata!r}", err=True)
        raise typer.Exit(2)
    try:
        model = EnergyModel.load(energy)
    except ConfigError as exc:
        typer.echo(f"robosoc run: {exc}", err=True)
        raise typer.Exit(2) from exc
    check_gdb_options(gdb, tile, one_core=mesh is None and chip is None and not off, trace=trace, profile=profile)
    if mesh is None and chip is None and not off:
        if len(programs) != 1:
            typer.echo("robosoc run: several programs need --mesh WxH or --chip FILE", err=True)
            raise typer.Exit(2)
        _run_single(programs[0], mul, max_cycles, stats, model, sram_size, trace, profile, errata,
                    gdb=gdb)  # fmt: skip
    else:
        if trace or profile:
            typer.echo("robosoc run: --trace and --profile work on one core (without --mesh/--chip/--off)", err=True)
            raise typer.Exit(2)
        _run_chip(programs, mul, max_cycles, stats, model, sram_size, mesh, chip, off or [], errata,
                  gdb=gdb, gdb_tile=tile)  # fmt: skip


def _run_single(
    program: Path,
    mul: bool,
    max_cycles: int,
    stats: Path | None,
    model: EnergyModel,
    sram_size: int,
    trace: int = 0,
    profile_every: int = 0,
    errata: str = "spec",
    gdb: int | None = None,
) -> None:
    from robosoc.chip.elf import ElfError, load_elf
    from robosoc.chip.single import (
        CoreError,
        CycleBudgetExceeded,
        RtlErratum,
        SingleCoreSoC,
        errata_counts,
        errata_report,
    )

    warnings.simplefilter("ignore", RtlErratum)  # reported below, in the summary's words
    try:
        soc = SingleCoreSoC(mul=mul, sram_size=sram_size, errata=errata)
        soc.load(load_elf(program, soc.regions()))
    except (ElfError, ValueError, OSError) as exc:
        typer.echo(f"robosoc run: {exc}", err=True)
        raise typer.Exit(2) from exc

    def write_out(data: bytes) -> None:
        sys.stdout.buffer.write(data)
        sys.stdout.buffer.flush()

    if trace > 0:
        from robosoc.chip.trace import trace as trace_steps

        typer.echo(f"{'cycle':>10}  {'pc':8}  {'word':8}  {'instruction':<28} {'symbol':<24} writes", err=True)
        for record in trace_steps(soc, trace):
            typer.echo(str(record), err=True)
        write_out(soc.drain_output())

    from robosoc.chip.profile import Profile, Sampler

    profile = Profile(profile_every) if profile_every > 0 else None
    sampler = Sampler(soc, profile) if profile is not None else None
    failure: Exception | None = None
    result = None
    try:
        with gdb_session(gdb, soc, program) as advance:
            result = soc.run(max_cycles=max_cycles, on_output=write_out, sampler=sampler, advance=advance)
        seconds = result.host_seconds
    except (CoreError, CycleBudgetExceeded) as exc:
        failure, seconds = exc, 0.0
    except KeyboardInterrupt:
        failure, seconds = KeyboardInterrupt("interrupted"), 0.0
    counters = soc.counters()
    errata_hit = result.errata if result else errata_counts(errata_report(soc.state.st[0], soc.symbolize, errata))
    energy_pj = model.breakdown_pj(counters)
    total_nj = sum(energy_pj.values()) / 1000.0
    if stats is not None:
        _write_json(
            stats,
            {
                "program": str(program),
                "mul": mul,
                "exit_code": result.exit_code if result else None,
                "error": str(failure) if failure else None,
                "counters": counters,
                "energy_pj": energy_pj,
                "energy_nj": total_nj,
                "energy_model": model.path,
                "errata_mode": errata,
                "errata": errata_hit,
                "warnings": result.warnings if result else [],
                "profile": dict(profile.shares()) if profile is not None else None,
            },
        )
    cycles, instr = counters["cycles"], counters["instructions"]
    if profile is not None:
        typer.echo(profile.table(cycles), err=True)
    cpi = cycles / instr if instr else float("nan")
    mips = instr / seconds / 1e6 if seconds > 0 else float("nan")
    typer.echo(
        f"robosoc: {cycles} cycles, {instr} instructions, CPI {cpi:.3f}, "
        f"energy {total_nj:.3f} nJ, host {mips:.0f} MIPS{_errata_summary(errata_hit)}",
        err=True,
    )
    for note in result.warnings if result else []:
        typer.echo(f"robosoc run: erratum: {note}", err=True)
    if failure is not None:
        typer.echo(f"robosoc run: {failure}", err=True)
        raise typer.Exit(130 if isinstance(failure, KeyboardInterrupt) else 3)
    assert result is not None
    raise typer.Exit(result.exit_code & 0xFF)


def _errata_summary(errata: dict[str, int]) -> str:
    """``", RTL errata: mulhsu 2"`` for the summary line (empty when none was hit)."""
    hit = ", ".join(f"{name} {n}" for name, n in errata.items() if n)
    return f", RTL errata: {hit}" if hit else ""


def _run_chip(
    programs: list[Path], mul: bool, max_cycles: int, stats: Path | None, model: EnergyModel, sram_size: int,
    mesh: str | None, chip_file: Path | None, off: list[str], errata: str = "spec",
    gdb: int | None = None, gdb_tile: str | None = None,
) -> None:  # fmt: skip
    import dataclasses

    from robosoc.chip.elf import ElfError, load_elf
    from robosoc.chip.mpsoc import ChipError, MPSoC
    from robosoc.chip.single import CoreError, RtlErratum, errata_counts
    from robosoc.config import ConfigError
    from robosoc.config.chip import ChipConfig, TileConfig, load_chip_config

    try:
        if chip_file is not None:
            config = load_chip_config(chip_file)
        else:
            w, h = _parse_mesh(mesh or "2x2")
            config = ChipConfig(width=w, height=h, tile=TileConfig(multiplier=mul, sram_bytes=sram_size))
        if off:
            config = dataclasses.replace(config, powered_off=tuple(_parse_tile(t) for t in off))
        if chip_file is None or errata != "spec":
            config = dataclasses.replace(config, errata=errata)
        warnings.simplefilter("ignore", RtlErratum)  # reported below, in the summary's words
        chip = MPSoC(config)
        tiles = chip.core_tiles()
        if len(programs) == 1:
            chip.load_all(load_elf(programs[0], chip.regions()))
        elif len(programs) == len(tiles):
            for xy, path in zip(tiles, programs, strict=True):
                chip.load(xy, load_elf(path, chip.regions(xy)))
        else:
            raise ValueError(
                f"{len(programs)} programs for {len(tiles)} core tiles {tiles}: give one program, or one per tile"
            )
    except (ConfigError, ElfError, ValueError, OSError) as exc:
        typer.echo(f"robosoc run: {exc}", err=True)
        raise typer.Exit(2) from exc

    pending: dict[tuple[int, int], bytearray] = {}

    def write_out(xy: tuple[int, int], data: bytes) -> None:
        buf = pending.setdefault(xy, bytearray())
        buf.extend(data)
        *lines, rest = bytes(buf).split(b"\n")
        if lines:
            prefix = f"[{xy[0]},{xy[1]}] ".encode()
            sys.stdout.buffer.write(b"".join(prefix + line + b"\n" for line in lines))
            buf[:] = rest
        sys.stdout.buffer.flush()

    failure: Exception | None = None
    result = None
    try:
        with gdb_session(gdb, chip, programs[0], gdb_tile) as advance:
            result = chip.run(max_cycles=max_cycles, on_output=write_out, advance=advance)
    except (ChipError, CoreError) as exc:
        failure = exc
    except KeyboardInterrupt:
        failure = KeyboardInterrupt("interrupted")
    for xy, rest in pending.items():
        if rest:
            sys.stdout.buffer.write(f"[{xy[0]},{xy[1]}] ".encode() + bytes(rest) + b"\n")
    sys.stdout.buffer.flush()
    chip.finish_accounting()

    per_tile = {}
    total_nj = 0.0
    for xy in tiles:
        c = chip.counters(xy)
        e = sum(model.breakdown_pj(c).values()) / 1000.0
        total_nj += e
        tasks = {
            str(task): {"counters": tc, "energy_nj": sum(model.breakdown_pj(tc).values()) / 1000.0}
            for task, tc in chip.task_counters(xy).items()
        }
        report = chip.errata_report(xy)
        hit = errata_counts(report)
        per_tile[f"{xy[0]},{xy[1]}"] = {
            "state": chip.state(xy), "counters": c, "energy_nj": e, "tasks": tasks, "errata": hit,
        }  # fmt: skip
        cpi = c["cycles"] / c["instructions"] if c["instructions"] else float("nan")
        typer.echo(
            f"robosoc: tile {xy}: {chip.state(xy)}, {c['cycles']} cycles, {c['instructions']} instructions, "
            f"CPI {cpi:.3f}, sleep {c['sleep_cycle']}, energy {e:.3f} nJ{_errata_summary(hit)}",
            err=True,
        )
        for _, note in report.values():
            typer.echo(f"robosoc run: erratum: {note}", err=True)
    noc = chip.noc_counters()
    noc_pj = model.noc_pj(noc)
    noc_nj = sum(noc_pj.values()) / 1000.0
    lost = noc["rtl_lost_headers"]
    typer.echo(
        f"robosoc: NoC {noc['packets_delivered']} packets, {noc['flit_hops']} flit-hops, energy {noc_nj:.3f} nJ"
        + (f", {lost} headers found no room in their crossing cycle (lost on the Hermes RTL)" if lost else "")
        + f"; chip {chip.cycle} cycles, energy {total_nj + noc_nj:.3f} nJ",
        err=True,
    )
    exit_codes = result.exit_codes if result else {}
    if stats is not None:
        _write_json(
            stats,
            {
                "programs": [str(p) for p in programs],
                "mesh": [config.width, config.height],
                "cycles": chip.cycle,
                "exit_codes": {f"{x},{y}": v for (x, y), v in exit_codes.items()},
                "error": str(failure) if failure else None,
                "tiles": per_tile,
                "noc": {"counters": noc, "energy_pj": noc_pj, "energy_nj": noc_nj},
                "energy_nj": total_nj + noc_nj,
                "energy_model": model.path,
                "errata_mode": config.errata,
            },
        )
    if failure is not None:
        typer.echo(f"robosoc run: {failure}", err=True)
        raise typer.Exit(130 if isinstance(failure, KeyboardInterrupt) else 3)
    code = next((v for v in exit_codes.values() if v), 0)
    raise typer.Exit(code & 0xFF)
