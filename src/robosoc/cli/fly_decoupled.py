"""``robosoc fly --decoupled``: the flight with the physics and the chip in two processes over UDP.

Called from :mod:`robosoc.cli.fly` once the scenario, firmware and run folder are resolved; thin
over :func:`robosoc.outputs.decoupled_flight.fly_decoupled` (docs/decoupled.md).
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

from rich.console import Console

from robosoc.cli import exit_codes, options
from robosoc.cli.console import note, plain
from robosoc.cli.errors import CliError
from robosoc.cli.link_report import end_of_side, print_link_counts
from robosoc.config.link import LinkConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.cosim.link import Address

if TYPE_CHECKING:
    from robosoc.outputs.decoupled_flight import DecoupledFlight

__all__ = ["fly_decoupled_run"]


def _number(value: float | None, scale: float, unit: str) -> str:
    return "n/a" if value is None or not math.isfinite(value) else f"{value * scale:.2f} {unit}"


def _print_fleet(console: Console, flight: DecoupledFlight) -> None:
    """Each vehicle's hover figures, commands and datagram counts."""
    for i, summary in enumerate(flight.summary["vehicles"]):
        f = summary.get("flight") or {}
        c = (summary.get("link") or {}).get("commands") or {}
        console.print(
            f"vehicle {i + 1}: hover height error (RMS, after the climb) {_number(f.get('hover_rms_m'), 100, 'cm')} "
            f"(max {_number(f.get('hover_max_m'), 100, 'cm')}); commands applied {c.get('received', 0)} "
            f"(late {c.get('late', 0)}, missed {c.get('missed', 0)})"
        )
        lk = summary.get("link") or {}
        if lk.get("to_chip") and lk.get("to_physics"):
            print_link_counts(console, {"to chip": lk["to_chip"], "to physics": lk["to_physics"]})
    sep = flight.summary.get("min_separation_m")
    console.print(f"closest approach of two vehicles: {_number(sep, 1, 'm')}")


def fly_decoupled_run(
    console: Console, scenario: ScenarioConfig, out: Path | None, link: LinkConfig, bind: Address | None
) -> None:
    """Fly, print the flight figures and the datagram counts, write the run folder (or a temporary one).

    Raises:
        CliError: the scenario has more than one vehicle, or a side failed.
    """
    from robosoc.config.vehicle import vehicle_preset

    if scenario.power.battery_on:
        raise options.fail("--decoupled", "flies on the constant supply only (power.supply = \"battery\" is not "
                           "modelled across the two processes): fly the battery in lockstep")  # fmt: skip
    vehicle, fw, seed = vehicle_preset(scenario.vehicle), scenario.firmware, scenario.seed
    from rich.markup import escape
    from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

    from robosoc.control.flight_log import read_flight_log
    from robosoc.control.flight_plot import plot_flight
    from robosoc.outputs.decoupled_flight import SideFailed, fly_decoupled
    from robosoc.outputs.flight_session import vehicle_folder
    from robosoc.outputs.mcap_log import flight_csv_to_mcap
    from robosoc.outputs.run_folder import FLIGHT_CSV, FLIGHT_MCAP, FLIGHT_PNG

    samples = scenario.samples
    console.print(
        f"flying scenario [bold]{escape(scenario.name)}[/bold] for {scenario.duration_s:g} s, "
        f"vehicle {scenario.vehicle}, "
        f"controller chip ({fw.label}, decoupled: two processes over UDP, pace {link.pace}, hold {link.hold}, "
        f"resend {link.resend}), seed {seed}"
    )
    if link.faults.any:
        console.print(
            "injected faults per datagram, each direction: "
            + ", ".join(f"{k} {v:g}" for k, v in link.faults.as_dict().items() if v)
        )
    temporary: tempfile.TemporaryDirectory[str] | None = None
    if out is None:
        temporary = tempfile.TemporaryDirectory(prefix="robosoc-decoupled-")
        folder = Path(temporary.name)
    else:
        folder = out
    progress = Progress(
        TextColumn("flight"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeRemainingColumn(),
        console=console,
        transient=True,
    )
    task = progress.add_task("fly", total=samples)
    try:
        with progress:
            flight = fly_decoupled(
                scenario, vehicle, link, folder, bind=bind,
                on_status=lambda text: progress.console.print(escape(text), style="dim"),
                on_progress=lambda done, total: progress.update(task, completed=done),
            )  # fmt: skip
    except SideFailed as exc:
        if temporary is not None:
            temporary.cleanup()
        if exc.kind == "link" and exc.side == "physics":
            raise options.fail("--bind", exc.message) from None
        if exc.kind in ("link", "build"):
            raise CliError(f"{exc.side} side: {exc.message}") from None
        raise CliError(f"the {exc.side} side failed:\n{exc.message}", code=exit_codes.INTERNAL_ERROR) from None
    summary = flight.summary
    if flight.vehicles:
        _print_fleet(console, flight)
        if out is not None:
            for i in range(len(flight.vehicles)):
                folder = vehicle_folder(out, i, len(flight.vehicles))
                rows = read_flight_log(folder / FLIGHT_CSV) if (folder / FLIGHT_CSV).exists() else None
                if rows is not None and len(rows):
                    title = f"{scenario.name}, seed {seed}, decoupled, vehicle {i + 1}"
                    plot_flight(rows, folder / FLIGHT_PNG, title=title)
                    flight_csv_to_mcap(folder / FLIGHT_CSV, folder / FLIGHT_MCAP)
            plain(console, f"run folder: {out} (summary.json, vehicle-N/ with each vehicle's files)")
        elif temporary is not None:
            temporary.cleanup()
        if flight.ended != "done":
            note(console, f"{flight.message}")
        end_of_side(flight.ended, flight.message, str(out) if out else "")
        return
    f = summary["flight"]
    if f:
        t = f["tracking_rms_deg"]
        console.print(
            f"hover height error (RMS, after the climb): {_number(f['hover_rms_m'], 100, 'cm')}  "
            f"(max {_number(f['hover_max_m'], 100, 'cm')})"
        )
        console.print(
            "attitude tracking error (RMS, 0.5 s after steps excluded): "
            + ", ".join(f"{axis} {_number(t[axis], 1, 'deg')}" for axis in ("roll", "pitch", "yaw"))
        )
    for name, s in (summary.get("tasks") or {}).items():
        console.print(
            f"  {name:<9} {s['jobs']} jobs: response mean {s['response_us_mean']:.1f} us, "
            f"max {s['response_us_max']:.1f} us; "
            f"deadline misses {s['deadline_misses']}"
        )
    lk = summary["link"]
    r, c = lk.get("readings") or {}, lk.get("commands") or {}
    if r and c:  # each side's counts have all their keys (cosim/decoupled_chip.py, decoupled_physics.py)
        console.print(
            f"readings injected {r['injected']} (late {r['late']}, stale {r['stale']}); "
            f"commands applied {c['received']} (late {c['late']}, missed {c['missed']}); "
            f"real-time factor {summary['real_time_factor'] or 0:.2f}"
        )
    told = lk.get("telemetry") or {}
    if told.get("received") or told.get("refused"):
        console.print(f"telemetry entries logged {told['received']} (datagrams refused {told['refused']})")
    if "cpu_s" in flight.physics and "cpu_s" in flight.chip:
        console.print(
            f"CPU time while flying: physics {flight.physics['cpu_s']:.1f} s, chip {flight.chip['cpu_s']:.1f} s "
            f"(real time needs each below the flight's {summary['simulated_s']:g} s, on a core of its own)"
        )
    print_link_counts(console, {"to chip": lk["to_chip"], "to physics": lk["to_physics"]})
    if out is not None:
        rows_path = out / FLIGHT_CSV
        if rows_path.exists():
            rows = read_flight_log(rows_path)
            if len(rows):
                plot_flight(rows, out / FLIGHT_PNG, title=f"{scenario.name}, seed {seed}, decoupled")
                flight_csv_to_mcap(rows_path, out / FLIGHT_MCAP)  # the telemetry's topics among the flight's
        plain(console, f"run folder: {out} (flight.csv, flight.mcap, jobs.csv, summary.json, link-*.log)")
    elif temporary is not None:  # (always, without an out folder)
        temporary.cleanup()
    if flight.ended != "done":
        note(console, f"{flight.message}")
    end_of_side(flight.ended, flight.message, str(out) if out else "")
