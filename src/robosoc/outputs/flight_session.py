"""One ``robosoc fly`` run as a library call: fly a scenario, write its run folder, return its summary.

:func:`fly_scenario` is what the CLI, the tests and a sweep call.  It flies every vehicle of the
scenario in one world under one clock (:func:`robosoc.cosim.lockstep.fly_lockstep_fleet`), each
with its own controller: the firmware on its own chip (``controller = "chip"``) or the float64
host controller (``"host"``).  The run folder (``out``) gets, as the flight goes:

* ``scenario.toml``: the resolved scenario, every field (loads back to the same scenario);
* ``flight.csv``: one row per sensor sample, flushed row by row (after the flight's columns, a
  battery flight's power columns, then one column per telemetry value the firmware publishes
  under a name of its own, :mod:`robosoc.host.telemetry`);

and at the end (or when the flight is interrupted or crashes, with ``"complete": false``):

* ``summary.json`` (:mod:`robosoc.outputs.run_summary`), ``jobs.csv`` (chip: the job records,
  :func:`robosoc.outputs.run_folder.write_jobs_csv`) and ``flight.png``.

With several vehicles each has a sub-folder ``vehicle-1/``, ``vehicle-2/``, ... holding its own
``flight.csv``, ``jobs.csv``, ``summary.json`` and ``flight.png``, and the top-level
``summary.json`` lists them all (:func:`robosoc.outputs.run_summary.fleet_summary`).

Vehicles: vehicle i (from 0) is the scenario's preset named ``quad`` (one vehicle) or
``quad<i+1>``, spawned on a square grid :data:`SPACING_M` apart, vehicle 1 at the origin.  One
seed drives all of them; each vehicle's sensor noise comes from its own stream
(:meth:`robosoc.physics.World.reset`).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from robosoc import output_files
from robosoc.config.scenario import ScenarioConfig, scenario_toml
from robosoc.config.vehicle import VehicleConfig, vehicle_preset
from robosoc.control.flight import ROW_FIELDS
from robosoc.control.flight_log import CsvFlightLog
from robosoc.control.host import HostController
from robosoc.cosim.firmware_run import ReplayResult
from robosoc.cosim.interrupts import InterruptedAfterFlight, deferred_interrupt, remove_partials
from robosoc.cosim.lockstep import (
    ChipController,
    HostLockstepController,
    LockstepController,
    fly_lockstep_fleet,
)
from robosoc.outputs.run_folder import (
    FLIGHT_CSV,
    FLIGHT_MCAP,
    FLIGHT_PNG,
    JOBS_CSV,
    REPORT_HTML,
    RUN_FILES,
    SCENARIO_TOML,
    SUMMARY_JSON,
    write_jobs_csv,
    write_profile,
)
from robosoc.outputs.run_summary import fleet_summary, vehicle_summary, write_summary
from robosoc.physics import World
from robosoc.physics.clock import FlightClock
from robosoc.physics.power import lift_problem
from robosoc.records import POWER_FIELDS, PowerSample

EXTRA_FILES = (FLIGHT_PNG, FLIGHT_MCAP, REPORT_HTML)
"""What :func:`fly_scenario` writes after the summary (a chip flight recording its timeline also
``chip-trace.json``): an interruption there leaves the flight complete without them."""
SCRATCH_FILES = tuple(name for name in RUN_FILES if name != FLIGHT_CSV)  # the log is written row by row
"""The files of a run folder written to a scratch name first (whose leftovers are removed)."""

SPACING_M = 3.0
"""Distance between neighbouring spawn points of a fleet [m]: the vehicles fly the same plan, so
they drift alike; 3 m leaves room for what their noise makes them differ by (the closest approach
is in the summary, ``min_separation_m``)."""

__all__ = [
    "SPACING_M",
    "ScenarioFlight",
    "fleet_vehicles",
    "fly_scenario",
    "min_separation",
    "vehicle_folder",
]


def fleet_vehicles(scenario: ScenarioConfig) -> list[VehicleConfig]:
    """The vehicles of ``scenario``: its preset, named and spawned on a grid (see the module's docstring)."""
    if scenario.vehicles == 1:
        return [scenario.vehicle_config()]
    side = math.ceil(math.sqrt(scenario.vehicles))
    base = scenario.vehicle_config()
    x0, y0, z0 = base.spawn_position
    return [
        dataclasses.replace(
            base, name=f"quad{i + 1}", spawn_position=(x0 + SPACING_M * (i % side), y0 + SPACING_M * (i // side), z0)
        )
        for i in range(scenario.vehicles)
    ]


def vehicle_folder(out: Path, index: int, count: int) -> Path:
    """The folder of vehicle ``index`` (from 0) of ``count``: ``out`` itself for a single vehicle."""
    return out if count == 1 else out / f"vehicle-{index + 1}"


@dataclass
class ScenarioFlight:
    """A flown scenario: its top-level summary, each vehicle's rows and firmware run, and where it
    is; each vehicle's telemetry under names of its own (name -> one value per row, NaN before the first)."""

    summary: dict[str, Any]
    rows: list[np.ndarray]
    results: list[ReplayResult | None]
    out: Path | None
    telemetry: list[dict[str, np.ndarray]] = field(default_factory=list)


def _controllers(
    scenario: ScenarioConfig, on_status: Callable[[str], None], profile: bool, timeline: bool
) -> list[LockstepController]:
    """The scenario's controllers, one per vehicle (``timeline``: their chips record it for a trace)."""
    canonical = vehicle_preset(scenario.vehicle)  # the control parameters do not depend on name or spawn
    if scenario.controller == "host":
        return [
            HostLockstepController(HostController.for_scenario(scenario, canonical)) for _ in range(scenario.vehicles)
        ]
    on_status(f"building the firmware ({scenario.firmware.label}; cached after the first build) ...")
    from robosoc.cosim.chip_warmup import prepare_chip
    from robosoc.host.scenario_image import scenario_image

    image = prepare_chip(scenario.chip, lambda: scenario_image(scenario, canonical), on_status)
    return [
        ChipController(scenario, canonical, image=image, profile=profile, timeline=timeline)
        for _ in range(scenario.vehicles)
    ]


def min_separation(rows: list[np.ndarray]) -> float:
    """The closest approach of any two vehicles' body origins [m] (NaN for fewer than two)."""
    if len(rows) < 2 or len(rows[0]) == 0:
        return math.nan
    xyz = [ROW_FIELDS.index(n) for n in ("x", "y", "z")]
    positions = np.stack([r[:, xyz] for r in rows])  # vehicle, sample, axis
    gaps = np.linalg.norm(positions[:, None] - positions[None, :], axis=-1)
    n = len(rows)
    return float(min(gaps[i, j].min() for i in range(n) for j in range(i + 1, n)))


def fly_scenario(
    scenario: ScenarioConfig,
    out: Path | None = None,
    *,
    on_sample: Callable[[World, int], None] | None = None,
    on_status: Callable[[str], None] | None = None,
    on_row: Callable[[int, np.ndarray, dict[str, float]], None] | None = None,
    plot: bool = True,
    logs: bool = True,
    profile: bool = False,
    threads: int | None = None,
) -> ScenarioFlight:
    """Fly ``scenario`` and write the run folder ``out``.

    Args:
        scenario: the resolved scenario.
        out: the run folder (created); None writes nothing.
        on_sample: called once per sensor sample with the world and the sample index (progress, video).
        on_status: told what is being done before the flight (building, compiling), for a newcomer
            who would otherwise watch a silent terminal.
        on_row: called with the vehicle index, each row as soon as it is complete and the
            firmware's telemetry under names of its own at that row (name -> value; a live view).
        plot: also write ``flight.png`` per vehicle.
        logs: also write ``flight.mcap``, ``chip-trace.json`` (chip) and ``report.html`` per vehicle
            (:func:`robosoc.outputs.run_logs.write_run_logs`; docs/results-logs.md).
        profile: count every instruction per firmware function, tile and task (chip controller) and
            write ``profile.json`` and ``profile.csv`` per vehicle (docs/profile.md); the results'
            ``profile`` holds it.
        threads: how many host threads run the vehicles' chips at once
            (:func:`robosoc.cosim.lockstep.fly_lockstep_fleet`; default: one per host core).

    Raises:
        KeyboardInterrupt, or whatever stopped the flight (a firmware fault: ChipError, CoreError),
        after ``summary.json`` with ``"complete": false`` has been written next to the rows flown.
        ValueError: the scenario's battery cannot fly its vehicle (before anything is flown or written).
        robosoc.cosim.interrupts.InterruptedAfterFlight: Ctrl-C after the flight was complete and
        its ``summary.json`` (``"complete": true``) written, while the plots and logs were being
        written (it names those not written).  Either way no scratch file (``*.partial``) is left.
    """
    say = on_status or (lambda _text: None)
    vehicles = fleet_vehicles(scenario)
    problem = lift_problem(vehicles[0])
    if problem is not None:
        raise ValueError(f"{problem[0]}: {problem[1]}")
    count = len(vehicles)
    folders = [vehicle_folder(out, i, count) for i in range(count)] if out is not None else []
    for folder in {*folders, *([out] if out is not None else [])}:  # an earlier run's summary must not
        (folder / SUMMARY_JSON).unlink(missing_ok=True)  # speak for this one, even if it stops at once
    controllers = _controllers(scenario, say, profile, timeline=out is not None and logs)  # (the trace's)
    battery = scenario.power.battery_on
    names = [c.telemetry_names if isinstance(c, ChipController) else () for c in controllers]
    csv_logs: list[CsvFlightLog] = []
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        output_files.write_atomic(out / SCENARIO_TOML, scenario_toml(scenario))
        csv_logs = [
            CsvFlightLog(folder / FLIGHT_CSV, (*(POWER_FIELDS if battery else ()), *names[i]))
            for i, folder in enumerate(folders)
        ]
    flown: list[list[np.ndarray]] = [[] for _ in vehicles]
    told: list[list[tuple[float, ...]]] = [[] for _ in vehicles]  # own-name telemetry, one per row
    powered: list[list[PowerSample]] = [[] for _ in vehicles]  # a battery flight: one per row, then the end

    def keep_power(i: int, sample: PowerSample) -> None:
        powered[i].append(sample)

    def keep_row(i: int, row: np.ndarray) -> None:
        controller = controllers[i]
        values = controller.telemetry_values() if names[i] and isinstance(controller, ChipController) else ()
        if names[i]:
            told[i].append(values)  # before the row: never fewer values than rows (an interruption)
        flown[i].append(row.copy())
        if csv_logs:
            csv_logs[i].write(row, (*(powered[i][-1].columns if battery else ()), *values))
        if on_row is not None:
            on_row(i, row, dict(zip(names[i], values, strict=True)))

    start = time.perf_counter()
    try:
        on_power = keep_power if battery else None
        fly_lockstep_fleet(
            scenario, vehicles, controllers, on_row=keep_row, on_sample=on_sample, on_power=on_power, threads=threads
        )
    except BaseException as exc:
        host_s = time.perf_counter() - start
        for log in csv_logs:
            log.close()
        stopped = "interrupted" if isinstance(exc, KeyboardInterrupt) else f"{type(exc).__name__}: {exc}"
        try:
            so_far = _summarize(scenario, vehicles, controllers, flown, host_s, stopped, folders, out, powered)
            so_far.telemetry = _telemetry(names, told, so_far.rows)
            _extras(scenario, vehicles, controllers, so_far, folders, plot, logs)
        except KeyboardInterrupt:  # a second Ctrl-C: the summary (complete false) is written first
            pass
        except Exception as inner:
            exc.add_note(f"the summary of the flight so far could not be written: {type(inner).__name__}: {inner}")
        finally:
            remove_partials([*folders, *([out] if out is not None else [])], SCRATCH_FILES)
        raise
    host_s = time.perf_counter() - start
    for log in csv_logs:
        log.close()
    flight: ScenarioFlight | None = None
    try:
        flight = _summarize(scenario, vehicles, controllers, flown, host_s, None, folders, out, powered)
        flight.telemetry = _telemetry(names, told, flight.rows)
        _extras(scenario, vehicles, controllers, flight, folders, plot, logs)
    except KeyboardInterrupt:
        if out is not None and not (out / SUMMARY_JSON).exists():
            raise  # not after the summary: an ordinary interruption
        wanted = [n for n in EXTRA_FILES if (plot and n == FLIGHT_PNG) or (logs and n != FLIGHT_PNG)]
        missing = [name for name in wanted if any(not (f / name).exists() for f in folders)]
        raise InterruptedAfterFlight(missing) from None
    finally:
        remove_partials([*folders, *([out] if out is not None else [])], SCRATCH_FILES)
    assert flight is not None
    return flight


def _telemetry(
    names: list[tuple[str, ...]], told: list[list[tuple[float, ...]]], rows: list[np.ndarray]
) -> list[dict[str, np.ndarray]]:
    """Each vehicle's own-name telemetry as columns (name -> one value per row flown)."""
    out: list[dict[str, np.ndarray]] = []
    for own, values, flown in zip(names, told, rows, strict=True):
        if not own:
            out.append({})
            continue
        table = np.array(values, dtype=float).reshape(-1, len(own))[: len(flown)]
        out.append({name: table[:, c].copy() for c, name in enumerate(own)})
    return out


@deferred_interrupt()  # Ctrl-C waits until they are written: a summary.json always says what the flight was
def _summarize(
    scenario: ScenarioConfig,
    vehicles: list[VehicleConfig],
    controllers: list[LockstepController],
    flown: list[list[np.ndarray]],
    host_s: float,
    stopped: str | None,
    folders: list[Path],
    out: Path | None,
    powered: list[list[PowerSample]],
) -> ScenarioFlight:
    """Summaries (complete or not) and job records of the rows flown; ``summary.json``, ``jobs.csv``
    and the profile written when ``out`` is set.  ``powered``: a battery flight's power samples
    per vehicle, one per row and then (a complete flight) the end state."""
    complete = stopped is None
    rows = [np.array(r).reshape(-1, len(ROW_FIELDS)) for r in flown]
    samples = min(len(r) for r in rows)
    simulated_s = FlightClock.of(scenario).simulated_s(samples)
    results: list[ReplayResult | None] = []
    summaries = []
    for i, (vehicle, controller) in enumerate(zip(vehicles, controllers, strict=True)):
        result = None
        note = stopped
        if isinstance(controller, ChipController):
            try:
                result = controller.result if complete else controller.result_so_far()
            except Exception as exc:  # the chip's state after a crash may not give job records
                note = f"{stopped}; no task figures: {type(exc).__name__}: {exc}"
        results.append(result)
        power = None
        if powered[i]:
            series = powered[i][: len(rows[i])]
            power = (series, powered[i][-1])
        summary = vehicle_summary(
            scenario, rows[i], vehicle.rest_height, result, simulated_s, host_s, complete=complete, stopped=note,
            power=power,
        )  # fmt: skip
        summaries.append(summary)
        if out is None:
            continue
        folder = folders[i]
        if result is not None:
            write_jobs_csv(result.jobs, folder / JOBS_CSV)
            if result.profile is not None:
                write_profile(result.profile, folder)  # before the report, which shows it
        write_summary(summary, folder / SUMMARY_JSON)
    if len(vehicles) == 1:
        top = summaries[0]
    else:
        top = fleet_summary(
            scenario,
            summaries,
            simulated_s,
            host_s,
            min_separation_m=min_separation(rows),
            complete=complete,
            stopped=stopped,
        )
        if out is not None:
            write_summary(top, out / SUMMARY_JSON)
    return ScenarioFlight(top, rows, results, out)


def _extras(
    scenario: ScenarioConfig,
    vehicles: list[VehicleConfig],
    controllers: list[LockstepController],
    flight: ScenarioFlight,
    folders: list[Path],
    plot: bool,
    logs: bool,
) -> None:
    """The files people open, from the rows and the written summary: ``flight.png`` and the logs
    (``flight.mcap``, ``chip-trace.json``, ``report.html``); interruptible."""
    for i, (folder, controller) in enumerate(zip(folders, controllers, strict=False)):
        rows, result = flight.rows[i], flight.results[i]
        if plot and len(rows):
            from robosoc.control.flight_plot import plot_flight

            title = f"{scenario.name}, seed {scenario.seed}" + (f", vehicle {i + 1}" if len(vehicles) > 1 else "")
            plot_flight(rows, folder / FLIGHT_PNG, title=title)
        if logs and len(rows):
            from robosoc.outputs.run_logs import write_run_logs

            run = controller.run if isinstance(controller, ChipController) else None
            metadata = {"scenario": scenario.name, "seed": scenario.seed, "vehicle": i + 1}
            telemetry = flight.telemetry[i] if i < len(flight.telemetry) else None
            write_run_logs(folder, rows, run, result, metadata, telemetry)
