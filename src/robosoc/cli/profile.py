"""``robosoc profile RUN_DIR``: the exact per-function profile of a fly run, by flying it again.

The run folder's ``scenario.toml`` (with its seed) is flown once more with profiling on; a flight is
deterministic, so the re-run is the run, and its totals are checked against the folder's
``summary.json`` (docs/profile.md).  ``robosoc fly --profile`` profiles during the flight instead;
both print the table below and write ``profile.json`` and ``profile.csv``.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from robosoc.cli import exit_codes, files, options
from robosoc.cli.console import make_console, note, plain
from robosoc.cli.errors import CliError
from robosoc.cli.typer_apps import app

if TYPE_CHECKING:
    from rich.console import Console, JustifyMethod

    from robosoc.chip.function_profile import FunctionProfile

MAX_TOP = 1000
RunDir = Annotated[Path, typer.Argument(help="A run folder of robosoc fly (scenario.toml, summary.json ...).")]
Top = Annotated[
    int, typer.Option(help=f"Functions shown per task, 1..{MAX_TOP}.", callback=options.int_range(1, MAX_TOP))
]


def print_profile(console: Console, profile: FunctionProfile, top: int = 10, title: str = "") -> None:
    """Per tile and task, its ``top`` functions: cycles, share of the task's cycles, instructions, energy."""
    from rich.table import Table

    from robosoc.chip.function_profile import profile_totals

    totals = profile_totals(profile)
    for xy in profile.tiles():
        tasks = sorted({r.task for r in profile.rows if r.tile == xy and r.task is not None})
        table = Table(
            title=f"{title}tile {xy[0]},{xy[1]}: {totals[xy]['cycles']:,} cycles, "
            f"{totals[xy]['energy_pj'] / 1e6:.3f} uJ",
            title_justify="left",
        )
        columns: tuple[tuple[str, JustifyMethod], ...] = (
            ("task", "left"), ("function", "left"), ("cycles", "right"), ("%", "right"), ("instructions", "right"),
            ("energy nJ", "right"),
        )  # fmt: skip
        for name, justify in columns:
            table.add_column(name, justify=justify)
        for task in tasks:
            mine = [r for r in profile.rows if r.tile == xy and r.task == task]
            task_cycles = sum(r.cycles for r in mine) or 1
            shown = profile.top(xy, task, top)
            for r in shown:
                share = f"{100 * r.cycles / task_cycles:.1f}"
                table.add_row(f"{r.task_name} ({task})", r.function, f"{r.cycles:,}", share, f"{r.instructions:,}",
                              f"{r.energy_pj / 1000:,.1f}")  # fmt: skip
            if len(mine) > len(shown):
                rest = [r for r in mine if r not in shown]
                table.add_row("", f"({len(rest)} more)", f"{sum(r.cycles for r in rest):,}",
                              f"{100 * sum(r.cycles for r in rest) / task_cycles:.1f}",
                              f"{sum(r.instructions for r in rest):,}",
                              f"{sum(r.energy_pj for r in rest) / 1000:,.1f}", style="dim")  # fmt: skip
            table.add_section()
        console.print(table)
    if None in totals:
        plain(console, f"NoC (routers): {totals[None]['energy_pj'] / 1e6:.3f} uJ")


def _read_summary(path: Path) -> dict[str, Any]:
    """A vehicle's ``summary.json``, its shape checked before anything is flown."""
    from robosoc.outputs.run_folder import RunFolderError, read_summary

    files.read_text(path, None, "JSON file")  # readable UTF-8, or an error naming the file
    try:
        return read_summary(path)
    except RunFolderError as exc:
        raise CliError(str(exc)) from None


@app.command("profile", epilog=exit_codes.EPILOG)
def profile_command(run_dir: RunDir, top: Top = 10) -> None:
    """Cycles, instructions and energy per firmware function, per tile and task, exactly (not
    sampled): flies the run folder's scenario again with profiling on and writes profile.json and
    profile.csv into it."""
    from robosoc.chip.function_profile import summary_mismatches
    from robosoc.chip.mpsoc import ChipError
    from robosoc.chip.single import CoreError
    from robosoc.cli.fly import FlightProgress
    from robosoc.cli.project_check import check_project
    from robosoc.cli.scenario import load_scenario
    from robosoc.outputs.flight_session import fly_scenario, vehicle_folder
    from robosoc.outputs.run_folder import PROFILE_CSV, PROFILE_JSON, SCENARIO_TOML, SUMMARY_JSON, write_profile
    from robosoc.toolchain import ToolchainError

    folder = files.input_dir(run_dir, None)
    for name in (SCENARIO_TOML, SUMMARY_JSON):
        if not (folder / name).exists():
            raise CliError(f"{run_dir}: has no {name}: not a robosoc fly run folder")
    config, _ = load_scenario(folder / SCENARIO_TOML, None)
    check_project(config, f"{folder / SCENARIO_TOML}: firmware.project")
    if config.controller != "chip":
        raise CliError(f"{run_dir}: flown with controller = {config.controller!r}: no firmware to profile")
    count = config.vehicles
    folders = [vehicle_folder(folder, i, count) for i in range(count)]
    summaries = [_read_summary(f / SUMMARY_JSON) for f in folders]
    for f in folders:  # before the re-flight: each profile file must be writable (and a regular file)
        for name in (PROFILE_JSON, PROFILE_CSV):
            files.output_file(f / name, None)
    console = make_console()
    console.print(
        f"profiling {run_dir}: flying scenario {config.name} again for {config.duration_s:g} s "
        f"(seed {config.seed}, {config.firmware.label}) with every instruction counted"
    )
    progress = FlightProgress(console, config.duration_s, config.sensors.rate_hz)
    try:
        flight = fly_scenario(
            config, None, on_sample=lambda _w, k: progress.sample(k), on_status=progress.status, profile=True
        )
    except KeyboardInterrupt:
        progress.stop()
        note(console, "interrupted; nothing written")
        raise typer.Exit(exit_codes.INTERRUPTED) from None
    except (ChipError, CoreError) as exc:
        raise CliError(f"the firmware failed on the chip: {exc}", code=exit_codes.SIMULATOR_STOP) from exc
    except ToolchainError as exc:  # the project's C edited since the flight
        raise CliError(f"the firmware does not build: {exc}") from exc
    finally:
        progress.stop()
    for i, (result, where, summary) in enumerate(zip(flight.results, folders, summaries, strict=True)):
        if result is None or result.profile is None:
            raise CliError(f"{where}: the re-run gave no profile")  # a chip run always has one
        title = f"vehicle {i + 1}, " if count > 1 else ""
        print_profile(console, result.profile, top, title)
        differences = summary_mismatches(result.profile, summary)
        compared = "energy" if summary.get("cycles") is None else "cycles per tile and energy"
        if differences:
            result.profile.notes.append("the re-run's totals differ from summary.json: " + "; ".join(differences))
            note(
                console,
                f"THE RE-RUN DIFFERS from {where / 'summary.json'} (made by another robosoc version, or edited?); "
                "the profile is of the re-run: " + "; ".join(differences),
            )
        else:
            plain(console, f"the profile's totals equal {where / 'summary.json'}'s ({compared})")
        if summary.get("cycles") is None:
            note(console, f"{where / 'summary.json'} has no per-tile cycles (an older robosoc): cycles not compared")
        json_path, csv_path = write_profile(result.profile, where)
        plain(console, f"profile: {json_path}, {csv_path}")
