"""``robosoc firmware build|size|replay``: the control firmware's builds, their size, a replay on the chip."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from robosoc import output_files
from robosoc.cli import exit_codes, files, options
from robosoc.cli.console import make_console, plain
from robosoc.cli.errors import CliError
from robosoc.cli.project_check import check_firmware
from robosoc.cli.scenario_flags import FIRMWARE, ScenarioFlags, resolve_section, takes_scenario
from robosoc.cli.typer_apps import firmware_app
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.project import IO_PACKETS

if TYPE_CHECKING:
    from robosoc.cosim.firmware_run import ReplayResult

Config = Annotated[Path | None, typer.Option("--config", help="Firmware configuration (TOML, docs/firmware-app.md).")]


def _firmware(flags: ScenarioFlags, config: Path | None, *, replay: bool = False) -> FirmwareConfig:
    """The configuration: defaults, the file's fields, then the options the user gave; a firmware
    project it names (``--firmware DIR``) checked before anything is built (for a ``replay``, that
    it takes nothing but the sensor packets a flight log holds)."""
    fw = files.load_toml(FirmwareConfig, config, "--config")[0] if config is not None else FirmwareConfig()
    fw = resolve_section(flags, fw, "firmware")
    sends = ("sensor",) if replay else IO_PACKETS
    what = "a replay of a flight log (robosoc fly flies it)"
    check_firmware(fw, None, "--firmware", sends=sends, what=what)
    return fw


def _build(fw: FirmwareConfig) -> Path:
    """The ELF of ``fw``: the project it names (the shipped quadrotor project by default).

    Raises:
        CliError: the compiler failed (file and line) or the program cannot fit.
    """
    from robosoc.host.scenario_image import firmware_image
    from robosoc.toolchain import ToolchainError

    try:
        return firmware_image(fw).elf
    except ToolchainError as exc:
        raise CliError(f"the firmware does not build: {exc}") from exc


@firmware_app.command("build", epilog=exit_codes.EPILOG)
@takes_scenario(FIRMWARE, scenario_file=False)
def firmware_build(
    ctx: typer.Context,
    flags: ScenarioFlags,
    config: Config = None,
    output: Annotated[Path | None, typer.Option("--output", "-o", help="Copy the ELF here.")] = None,
) -> None:
    """Build the flight firmware (estimator and PID tasks on the kernel) for the chip; print the ELF's path.

    Builds are cached: the same configuration returns the same file without compiling.
    """

    out = files.output_file(output, "--output") if output is not None else None
    fw = _firmware(flags, config)
    elf = _build(fw)
    if out is not None:
        output_files.write_atomic(out, elf.read_bytes())
        elf = out
    print(f"{fw.label}: {elf}")


@firmware_app.command("size", epilog=exit_codes.EPILOG)
@takes_scenario(FIRMWARE, scenario_file=False)
def firmware_size(
    ctx: typer.Context,
    flags: ScenarioFlags,
    elf: Annotated[Path | None, typer.Argument(help="An ELF to measure (default: build the firmware).")] = None,
    config: Config = None,
    top: Annotated[
        int, typer.Option(help="Functions and objects to list, 1..10000.", callback=options.int_range(1, 10_000))
    ] = 25,
) -> None:
    """Code and data size of the firmware per section and per function (largest first)."""
    from robosoc.analysis.code_size import code_size
    from robosoc.program.elf import ElfError

    if elf is not None:
        for name in [flag.option for flag in flags.given()] + (["--config"] if config is not None else []):
            raise options.fail(name, f"chooses a build: it cannot be combined with an ELF ({elf})")
        path = files.input_file(elf, None, "ELF file")
        label = str(path)
    else:
        fw = _firmware(flags, config)
        path, label = _build(fw), fw.label
    try:
        size = code_size(path)
    except ElfError as exc:
        raise CliError(str(exc)) from exc
    console = make_console()
    plain(console, f"{label}: code {size.code_bytes} bytes, data {size.data_bytes} bytes")
    for s in size.sections:
        plain(console, f"  {s.name:<24} 0x{s.addr:08x} {s.size:>9} bytes  {s.kind}")
    plain(console, f"largest functions and objects ({min(top, len(size.symbols))} of {len(size.symbols)}):")
    for sym in size.symbols[:top]:
        plain(console, f"  {sym.size:>9} {sym.kind:<6} {sym.name}")


@firmware_app.command("replay", epilog=exit_codes.EPILOG)
@takes_scenario(FIRMWARE, scenario_file=False)
def firmware_replay(
    ctx: typer.Context,
    flags: ScenarioFlags,
    log: Annotated[
        Path | None, typer.Argument(help="A flight log (flight.csv of robosoc fly); default: built in.")
    ] = None,
    config: Config = None,
    seconds: Annotated[
        float,
        typer.Option(
            help="Built-in stream: seconds of the default flight, 0.02..600.",
            callback=options.float_range(0.02, 600.0, unit="s"),
        ),
    ] = 10.0,
    seed: Annotated[int, typer.Option(help="Built-in stream: the flight's seed.", callback=options.seed())] = 1,
    out: Annotated[Path | None, typer.Option("--out", help="Folder for jobs.csv and summary.json.")] = None,
) -> None:
    """Replay a flight's sensor samples into the firmware on the chip: per-job records, response times, energy.

    Each sample is injected from the I/O tile at the cycle of its timestamp; the estimator and PID
    tasks run on their tiles; their jobs are timed by the kernel and costed by the simulator.
    """
    from rich.progress import Progress

    from robosoc.control.flight_log import FlightLogError, read_flight_log
    from robosoc.cosim.replay import built_in_rows, replay
    from robosoc.outputs.run_folder import JOBS_CSV, SUMMARY_JSON

    folder = files.output_dir(out, "--out", names=(JOBS_CSV, SUMMARY_JSON)) if out is not None else None
    fw = _firmware(flags, config, replay=True)
    if log is not None:
        options.exclusive(
            LOG=True, **{"--seconds": options.given(ctx, "seconds"), "--seed": options.given(ctx, "seed")}
        )
        path = files.input_file(log, None, "flight log")
        files.read_text(path, None, "flight log")  # a readable UTF-8 file, or an error naming it
        try:
            rows = read_flight_log(path)
        except FlightLogError as exc:
            raise CliError(str(exc)) from None
        if len(rows) == 0:
            raise CliError(f"{path}: no rows after the header: nothing to replay")
    else:
        rows = built_in_rows(seconds, seed)
    console = make_console(stderr=True)
    with Progress(console=console, transient=True) as progress:
        task = progress.add_task(f"replaying into {fw.label}", total=len(rows))
        result = replay(rows, fw, on_sample=lambda done, _: progress.update(task, completed=done))
    _report(result, folder)


def _report(result: ReplayResult, folder: Path | None) -> None:
    ns = result.clock_ns
    console = make_console()
    plain(
        console,
        f"{result.firmware.label}: {len(result.samples)} samples, {len(result.commands)} PWM commands, "
        f"{result.deadline_misses} deadline misses, {result.cycles} cycles "
        f"({result.cycles * ns * 1e-9:.2f} s simulated in {result.host_seconds:.1f} s)",
    )
    from robosoc.outputs.run_folder import JOBS_CSV, SUMMARY_JSON, write_jobs_csv
    from robosoc.outputs.run_summary import task_summary

    summary = task_summary(result.jobs, ns)
    for name, s in summary.items():
        plain(
            console,
            f"  {name:<9} {s['jobs']} jobs: exec mean {s['exec_cycles_mean']:.0f} max {s['exec_cycles_max']} "
            f"cycles; response mean {s['response_us_mean']:.1f} max {s['response_us_max']:.1f} us; "
            f"energy {s['energy_nj_mean']:.1f} nJ/job (kernel {s['kernel_energy_share']:.1%}); "
            f"misses {s['deadline_misses']}",
        )
    if folder is None:
        return
    write_jobs_csv(result.jobs, folder / JOBS_CSV)
    record = {
        "firmware": result.firmware.label,
        "samples": len(result.samples),
        "commands": len(result.commands),
        "cycles": result.cycles,
        "clock_ns": ns,
        "tasks": summary,
        "energy_pj": result.energy_pj,
    }
    output_files.write_atomic(folder / SUMMARY_JSON, json.dumps(record, indent=2) + "\n")
    plain(console, f"wrote {folder / 'jobs.csv'} and {folder / 'summary.json'}")
