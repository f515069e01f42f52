"""``robosoc run``: run bare-metal programs on one HF-RISCV core or on the MPSoC."""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from robosoc import output_files
from robosoc.chip.engines import INTERP, resolve_engine
from robosoc.cli import exit_codes, files, options
from robosoc.cli.engine_option import Engine
from robosoc.cli.errors import CliError
from robosoc.cli.gdb_option import GDB_HELP, TILE_HELP, check_gdb_options, gdb_session
from robosoc.cli.typer_apps import app
from robosoc.config.chip import DEFAULT_ENGINE
from robosoc.config.ranges import MAX_CYCLES

if TYPE_CHECKING:
    from robosoc.chip.energy import EnergyModel

ERRATA_CHOICES = ("spec", "rtl")
EXIT_CODE_CHOICES = (exit_codes.EXIT_CODE_STATUS, exit_codes.EXIT_CODE_PROGRAM)

Programs = Annotated[
    list[Path], typer.Argument(help="ELF file(s) built for the core (robosoc cc).", show_default=False)
]
Mul = Annotated[bool, typer.Option("--mul/--no-mul", help="Cores with or without the iterative multiplier.")]
MaxCycles = Annotated[
    int,
    typer.Option(
        "--max-cycles",
        help="Cycle budget, 1..2**62: stop a hung program (exit code 3).",
        callback=options.int_range(1, MAX_CYCLES, "cycles"),
    ),
]
Stats = Annotated[Path | None, typer.Option("--stats", help="Write counters and energy to this JSON file.")]
Energy = Annotated[Path | None, typer.Option("--energy", help="Energy coefficients (TOML) to use.")]
SramSize = Annotated[
    int,
    typer.Option(
        "--sram-size", help="SRAM bytes (per tile), a multiple of 4 in 4096..2**30.", callback=options.sram_bytes()
    ),
]
Mesh = Annotated[str | None, typer.Option("--mesh", help="Run on a WxH MPSoC (I/O tile at 0,0), 2 to 256 tiles.")]
Chip = Annotated[Path | None, typer.Option("--chip", help="MPSoC configuration file (TOML).")]
Off = Annotated[list[str] | None, typer.Option("--off", help="Power off tile X,Y (repeatable).")]
Trace = Annotated[
    int,
    typer.Option(
        "--trace",
        help="Print the first N instructions to stderr (one core; within the cycle budget).",
        callback=options.int_range(0, MAX_CYCLES),
    ),
]
Profile = Annotated[
    int,
    typer.Option(
        "--profile",
        help="Sample the pc every ~N cycles (0: off); print cycles by function (one core).",
        callback=options.int_range(0, MAX_CYCLES // 2, "cycles"),
    ),
]
Errata = Annotated[
    str,
    typer.Option(
        "--errata",
        help="spec: RISC-V results, report each HF-RISCV RTL erratum hit; rtl: reproduce the RTL's errata.",
        callback=options.choice(*ERRATA_CHOICES),
    ),
]
ExitCode = Annotated[
    str,
    typer.Option(
        "--exit-code",
        help="status: 0 if the program exited with 0, 4 if with another code, 3 if the simulator stopped it; "
        "program: the program's own exit code (mod 256).",
        callback=options.choice(*EXIT_CODE_CHOICES),
    ),
]


def _write_json(path: Path, record: dict) -> None:
    try:
        output_files.write_atomic(path, json.dumps(record, indent=2) + "\n")
    except OSError as exc:  # checked at the start; the disk may still fill up or the folder vanish
        raise CliError(f"--stats: {path}: cannot write: {exc.strerror or exc}") from exc


def exit_status(code: int, mode: str) -> int:
    """The exit status of ``robosoc run`` for a program that exited with ``code`` (its exit word)."""
    if mode == exit_codes.EXIT_CODE_PROGRAM:
        return code & 0xFF
    return exit_codes.OK if code == 0 else exit_codes.PROGRAM_FAILED


def _exit_note(code: int, mode: str) -> str | None:
    if mode == exit_codes.EXIT_CODE_PROGRAM and code != 0 and code & 0xFF == 0:
        return f"the program's exit code {code} (0x{code:08x}) reads as 0 modulo 256; use --exit-code status"
    return None


RUN_HELP = (
    "Run bare-metal programs on one HF-RISCV core, or on the MPSoC with --mesh/--chip.\n\n"
    "Program output (debug port, UART) goes to stdout, prefixed by the tile on the MPSoC; a summary "
    "with the program's exit code goes to stderr.\n\n"
    "On the MPSoC one ELF runs on every core tile (tiles tell themselves apart by reading NI_TILE), "
    "or one ELF per core tile in tile order (x fastest)."
)


@app.command("run", help=RUN_HELP, epilog=exit_codes.RUN_EPILOG)
def run(
    ctx: typer.Context,
    programs: Programs,
    mul: Mul = True,
    max_cycles: MaxCycles = 10**10,
    stats: Stats = None,
    energy: Energy = None,
    sram_size: SramSize = 2 * 1024 * 1024,
    mesh: Mesh = None,
    chip: Chip = None,
    off: Off = None,
    trace: Trace = 0,
    profile: Profile = 0,
    errata: Errata = "spec",
    exit_code: ExitCode = exit_codes.EXIT_CODE_STATUS,
    engine: Engine = None,
    gdb: Annotated[int | None, typer.Option("--gdb", help=GDB_HELP, callback=options.int_range(0, 65535, ""))] = None,
    tile: Annotated[str | None, typer.Option("--tile", help=TILE_HELP)] = None,
) -> None:
    """``robosoc run`` (help: :data:`RUN_HELP`)."""
    from robosoc.chip.energy import EnergyModel
    from robosoc.config import ConfigError

    on_chip = mesh is not None or chip is not None or bool(off)
    check_gdb_options(gdb, tile, one_core=not on_chip, trace=trace, profile=profile)
    if not on_chip and len(programs) != 1:
        raise CliError("several programs need --mesh WxH or --chip FILE")
    if on_chip and (trace or profile):
        raise options.fail("--trace" if trace else "--profile", "works on one core (without --mesh/--chip/--off)")
    options.exclusive(mesh=mesh is not None, chip=chip is not None)
    if engine is not None and resolve_engine(engine).translates and gdb is not None:
        raise options.fail("--engine", f"{engine} runs without --gdb (the debugger uses the interpreter)")
    if chip is not None:
        for name, field in (("sram_size", "tile.sram_bytes"), ("mul", "tile.multiplier")):
            if options.given(ctx, name):
                option = "--sram-size" if name == "sram_size" else "--mul/--no-mul"
                raise options.fail(option, f"has no effect with --chip: set {field} in {chip}")
    inputs = [files.input_file(p, None, "ELF file") for p in programs]
    if energy is not None:
        files.read_toml(energy, "--energy")
        inputs.append(energy)
    try:
        model = EnergyModel.load(energy)
    except ConfigError as exc:
        raise CliError(f"--energy: {exc}") from exc
    if chip is not None:
        inputs.append(chip)
    if on_chip:
        _run_chip(ctx, programs, mul, max_cycles, stats, model, sram_size, mesh, chip, off or [], errata,
                  exit_code, inputs, gdb=gdb, gdb_tile=tile, engine=engine)  # fmt: skip
    else:
        _run_single(programs[0], mul, max_cycles, stats, model, sram_size, trace, profile, errata, exit_code,
                    inputs, gdb=gdb, engine=engine or (DEFAULT_ENGINE if gdb is None else INTERP.name))  # fmt: skip


def _run_single(
    program: Path,
    mul: bool,
    max_cycles: int,
    stats: Path | None,
    model: EnergyModel,
    sram_size: int,
    trace: int,
    profile_every: int,
    errata: str,
    exit_mode: str,
    inputs: list[Path],
    gdb: int | None,
    engine: str,
) -> None:
    from robosoc.chip.single import RtlErratum, SingleCoreSoC

    try:
        soc = SingleCoreSoC(mul=mul, sram_size=sram_size, errata=errata, engine=engine)
    except ValueError as exc:
        raise CliError(str(exc)) from exc
    soc.load(files.load_program(program, None, soc.regions()))
    if stats is not None:
        stats = files.output_file(stats, "--stats", inputs=inputs)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RtlErratum)  # reported below, in the summary's words
        _simulate_single(soc, program, mul, max_cycles, stats, model, trace, profile_every, errata, exit_mode, gdb)


def _simulate_single(
    soc, program, mul, max_cycles, stats, model, trace, profile_every, errata, exit_mode, gdb=None
) -> None:
    from robosoc.chip.profile import Profile, Sampler
    from robosoc.chip.single import CoreError, CycleBudgetExceeded, errata_counts, errata_report

    def write_out(data: bytes) -> None:
        sys.stdout.buffer.write(data)
        sys.stdout.buffer.flush()

    failure: BaseException | None = None
    result = None
    seconds = 0.0
    profile = Profile(profile_every) if profile_every > 0 else None
    try:
        if trace > 0:
            from robosoc.chip.trace import trace as trace_steps

            typer.echo(f"{'cycle':>10}  {'pc':8}  {'word':8}  {'instruction':<28} {'symbol':<24} writes", err=True)
            for record in trace_steps(soc, trace):
                typer.echo(str(record), err=True)
                if soc.cycle >= max_cycles:
                    break  # the budget holds for the trace too: run() reports it
            write_out(soc.drain_output())
        sampler = Sampler(soc, profile) if profile is not None else None
        with gdb_session(gdb, soc, program) as advance:
            result = soc.run(max_cycles=max_cycles, on_output=write_out, sampler=sampler, advance=advance)
        seconds = result.host_seconds
    except (CoreError, CycleBudgetExceeded) as exc:
        failure = exc
    except KeyboardInterrupt:
        failure = KeyboardInterrupt("interrupted")
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
    typer.echo(
        f"robosoc: {cycles} cycles, {instr} instructions, {cpi_text(cycles, instr)}, "
        f"energy {total_nj:.3f} nJ{host_speed(instr, seconds, gdb is not None)}{_errata_summary(errata_hit)}"
        + (f"; exit code {_code_text(result.exit_code)}" if result else ""),
        err=True,
    )
    for note in result.warnings if result else []:
        typer.echo(f"robosoc run: erratum: {note}", err=True)
    if failure is not None:
        typer.echo(f"robosoc run: {failure}", err=True)
        raise typer.Exit(
            exit_codes.INTERRUPTED if isinstance(failure, KeyboardInterrupt) else exit_codes.SIMULATOR_STOP
        )
    assert result is not None
    note = _exit_note(result.exit_code, exit_mode)
    if note:
        typer.echo(f"robosoc run: {note}", err=True)
    raise typer.Exit(exit_status(result.exit_code, exit_mode))


def _code_text(code: int) -> str:
    """``"3"``, or ``"3507801690 (0xd114ce5a)"`` for an exit word beyond a byte."""
    return str(code) if code <= 0xFF else f"{code} (0x{code:08x})"


def cpi_text(cycles: int, instructions: int) -> str:
    """``"CPI 1.619"``, or ``"CPI n/a"`` before the first instruction (a run GDB killed at once: no
    "CPI nan")."""
    return f"CPI {cycles / instructions:.3f}" if instructions else "CPI n/a"


def host_speed(instructions: int, seconds: float, debugged: bool) -> str:
    """``", host 120 MIPS"`` for the summary line, or nothing when the host time says nothing of the
    simulator's speed: under GDB (it is the debugging session's time) or not measured (a run cut short)."""
    if debugged or not seconds > 0:
        return ""
    return f", host {instructions / seconds / 1e6:.0f} MIPS"


def _errata_summary(errata: dict[str, int]) -> str:
    """``", RTL errata: mulhsu 2"`` for the summary line (empty when none was hit)."""
    hit = ", ".join(f"{name} {n}" for name, n in errata.items() if n)
    return f", RTL errata: {hit}" if hit else ""


def _chip_config(ctx: typer.Context, mul: bool, sram_size: int, mesh: str | None, chip_file: Path | None,
                 off: list[str], errata: str):  # fmt: skip
    from robosoc.config.chip import ChipConfig, TileConfig

    if chip_file is not None:
        config, _ = files.load_toml(ChipConfig, chip_file, "--chip")
    else:
        w, h = options.parse_mesh("--mesh", "2x2" if mesh is None else mesh)
        try:
            config = ChipConfig(width=w, height=h, tile=TileConfig(multiplier=mul, sram_bytes=sram_size))
        except ValueError as exc:  # the only rule across the two: the SRAM of all tiles together
            raise options.fail("--sram-size", f"{exc.args[0].partition(': ')[2]} (with --mesh {w}x{h})") from exc
    changes: dict[str, tuple[str, Any]] = {}
    if off:
        changes["--off"] = ("powered_off", tuple(options.parse_tile("--off", t) for t in off))
    if chip_file is None or options.given(ctx, "errata"):
        changes["--errata"] = ("errata", errata)
    return options.override(config, changes, [str(chip_file)] if chip_file else ())


def _run_chip(
    ctx: typer.Context, programs: list[Path], mul: bool, max_cycles: int, stats: Path | None, model: EnergyModel,
    sram_size: int, mesh: str | None, chip_file: Path | None, off: list[str], errata: str, exit_mode: str,
    inputs: list[Path], gdb: int | None = None, gdb_tile: str | None = None, engine: str | None = None,
) -> None:  # fmt: skip
    from robosoc.chip.mpsoc import MPSoC
    from robosoc.chip.single import RtlErratum

    config = _chip_config(ctx, mul, sram_size, mesh, chip_file, off, errata)
    try:
        chip = MPSoC(config, engine=engine)  # None: the chip file's engine
    except ValueError as exc:
        raise CliError(f"{chip_file}: {exc}" if chip_file else str(exc)) from exc
    tiles = chip.core_tiles()
    if not tiles:
        where = "--off" if off else "--chip"
        raise options.fail(where, f"no core tile left to run on the {config.width}x{config.height} mesh "
                                  f"(I/O tile {config.io_tile}, powered off: {list(config.powered_off)})")  # fmt: skip
    if len(programs) == 1:
        chip.load_all(files.load_program(programs[0], None, chip.regions()))
    elif len(programs) == len(tiles):
        for xy, path in zip(tiles, programs, strict=True):
            chip.load(xy, files.load_program(path, None, chip.regions(xy)))
    else:
        raise CliError(
            f"{len(programs)} programs for {len(tiles)} core tiles {tiles}: give one program, or one per tile"
        )
    if stats is not None:
        stats = files.output_file(stats, "--stats", inputs=inputs)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RtlErratum)  # reported below, in the summary's words
        _simulate_chip(chip, config, programs, max_cycles, stats, model, exit_mode, gdb, gdb_tile)


def _simulate_chip(chip, config, programs, max_cycles, stats, model, exit_mode, gdb=None, gdb_tile=None) -> None:
    from robosoc.chip.mpsoc import ChipError
    from robosoc.chip.single import CoreError, errata_counts

    tiles = chip.core_tiles()
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

    failure: BaseException | None = None
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
        state = chip.state(xy)
        exited = f" with exit code {_code_text(chip.exit_code(xy))}" if state == "exited" else ""
        typer.echo(
            f"robosoc: tile {xy}: {state}{exited}, {c['cycles']} cycles, {c['instructions']} instructions, "
            f"{cpi_text(c['cycles'], c['instructions'])}, sleep {c['sleep_cycle']}, "
            f"energy {e:.3f} nJ{_errata_summary(hit)}",
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
    exit_words = result.exit_codes if result else {}
    if stats is not None:
        _write_json(
            stats,
            {
                "programs": [str(p) for p in programs],
                "mesh": [config.width, config.height],
                "cycles": chip.cycle,
                "exit_codes": {f"{x},{y}": v for (x, y), v in exit_words.items()},
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
        raise typer.Exit(
            exit_codes.INTERRUPTED if isinstance(failure, KeyboardInterrupt) else exit_codes.SIMULATOR_STOP
        )
    code = next((v for v in exit_words.values() if v), 0)
    note = _exit_note(code, exit_mode)
    if note:
        typer.echo(f"robosoc run: {note}", err=True)
    raise typer.Exit(exit_status(code, exit_mode))
