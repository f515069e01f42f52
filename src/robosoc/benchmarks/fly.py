"""``robosoc bench fly``: real-time factor of the lockstep co-simulation (physics + firmware on the chip).

Flies the default scenario (shortened to ``duration_s``) with :func:`robosoc.outputs.flight_session.fly_scenario`,
writing nothing, once per firmware build, after the host controller as the reference.  The firmware
is built, the chip kernels compiled and ``auto``'s translations entered before each timed flight,
in a flight of :data:`WARM_UP_S` (a first run says so).  Prints per
build the real-time factor (simulated seconds per host second; and per CPU second of this
process, which a busy shared machine does not lower), its ratio to the host controller's flight
in the same run (``of host``, when the host controller flies: a loaded machine slows both alike),
the simulated chip cycles per host second, the hover error, the slowest roll/pitch step (to 90 %),
the RMS difference of the true height from the host controller's flight with the same seed (from
take-off on), the deadline misses, and last the line ``fly: <x>× real time`` of the last build
flown (fixed point with the multiplier by default).  A build flown while ``auto`` was translating
its whole code in a second process (:mod:`robosoc.chip.whole_code`: once per build and host) is
marked with ``*`` and a note: its figure is not yet the steady one.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
from rich.console import Console
from rich.table import Table

from robosoc.chip.whole_code import whole_code_translations
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.control.flight import column
from robosoc.outputs.flight_session import fly_scenario


def with_engine(scenario: ScenarioConfig, engine: str | None) -> ScenarioConfig:
    """``scenario`` with its chip on ``engine`` (None: as it is).

    Raises:
        ValueError: ``engine`` names none (:data:`robosoc.config.chip.ENGINE_CHOICES`).
    """
    return (
        scenario
        if engine is None
        else dataclasses.replace(scenario, chip=dataclasses.replace(scenario.chip, engine=engine))
    )


#: Simulated seconds of the flight before each timed one (at most the timed one's): the firmware
#: is built and the kernels loaded, and the chip loop runs long enough (about 0.02 s of host time
#: on the fixed + mul build) for ``auto`` to enter the translations of the firmware's code
#: (:mod:`robosoc.chip.whole_code`), about 0.1 s once per process, which a flight of 0.01 s left to
#: the timed flight (0.66 s instead of 0.57 s for the 10 s fixed + mul flight).
WARM_UP_S = 2.0

#: The builds flown when none is chosen, the reference build (fixed + multiplier) last.
ALL_BUILDS = (
    FirmwareConfig(arith="float", multiplier=False),
    FirmwareConfig(arith="float", multiplier=True),
    FirmwareConfig(arith="fixed", multiplier=False),
    FirmwareConfig(arith="fixed", multiplier=True),
)


def run_fly_benchmark(
    builds: tuple[FirmwareConfig, ...] = ALL_BUILDS,
    duration_s: float = 10.0,
    host: bool = True,
    console: Console | None = None,
    vehicles: int = 1,
    engine: str | None = None,
    runs: int = 1,
) -> float:
    """Fly the default scenario for ``duration_s`` with each build (and the host controller first if
    ``host``), ``runs`` timed flights each after a warm-up; print the figures of each one's median
    flight (by real-time factor: this shared host's speed varies from one second to the next) and
    the last line; the last build's median real-time factor.  With
    ``vehicles`` > 1 every flight flies that many vehicles in one world (their chips on the host's
    cores at once, :func:`robosoc.cosim.lockstep.fly_lockstep_fleet`): the real-time factor is the
    fleet's, the chip cycles all chips', the flight figures the first vehicle's.  ``engine``: the
    chips' engine (default: the default scenario's chip's).

    Raises:
        ValueError: ``duration_s`` is not a whole number of ms of at least one sensor period, no
            build, or ``engine`` names none.
    """
    if not builds:
        raise ValueError("builds: at least one firmware build")
    if runs < 1:
        raise ValueError(f"runs: at least 1, got {runs}")
    console = console or Console()
    base = with_engine(ScenarioConfig(duration_s=duration_s, vehicles=vehicles), engine)
    fleet = f", {vehicles} vehicles per flight" if vehicles > 1 else ""
    median = f", the median of {runs} flights each" if runs > 1 else ""
    console.print(
        f"lockstep flight of the default scenario, {duration_s:g} s simulated per build{fleet}, seed {base.seed}, "
        f"chip engine {base.chip.engine}{median}"
    )
    table = Table(show_edge=False, pad_edge=False)
    headers = (
        "controller", "real time", "of host", "per CPU second", "chip Mcycles/s", "hover RMS",
        "slowest roll/pitch 90 %", "height vs host RMS", "deadline misses",
    )  # fmt: skip
    for header in headers:
        table.add_column(header, justify="left" if header == "controller" else "right")
    flights = [("host", dataclasses.replace(base, controller="host"))] if host else []
    flights += [(f"chip {fw.label}", dataclasses.replace(base, firmware=fw)) for fw in builds]
    factor = math.nan
    host_factor = math.nan
    host_z = None
    unsteady = False
    for name, scenario in flights:
        # first call: build, compile and load outside the timing
        warm_up = dataclasses.replace(scenario, duration_s=min(WARM_UP_S, scenario.duration_s))
        fly_scenario(warm_up, None, on_status=console.print, plot=False)
        translating = whole_code_translations().running() is not None
        timed = []
        for _ in range(runs):
            cpu = time.process_time()
            flown = fly_scenario(scenario, None, plot=False)
            timed.append((flown.summary["real_time_factor"], time.process_time() - cpu, flown))
            translating = translating or whole_code_translations().running() is not None
        _, cpu, flight = sorted(timed, key=lambda run: run[0])[len(timed) // 2]  # the median flight
        if translating:
            name += " *"
            unsteady = True
        summary = flight.summary
        first = summary["vehicles"][0] if vehicles > 1 else summary
        z = column(flight.rows[0], "z")
        if scenario.controller == "host":
            host_z = z
        armed = column(flight.rows[0], "armed") > 0.5
        versus = math.sqrt(float(np.mean((z - host_z)[armed] ** 2))) if host_z is not None and armed.any() else math.nan
        rises = [s["rise_s"] for s in (first["flight"] or {}).get("step_rise_s", []) if s["axis"] != "yaw"]
        slowest = max((math.inf if r is None or math.isnan(r) else r for r in rises), default=math.nan)
        factor = summary["real_time_factor"]
        if scenario.controller == "host":
            host_factor = factor
        mcycles = "-"
        if scenario.controller == "chip":
            cycles = vehicles * summary["simulated_s"] * 1e9 / first["chip"]["clock_ns"]
            mcycles = f"{cycles / summary['host_s'] / 1e6:.0f}"
        hover = (first["flight"] or {}).get("hover_rms_m", math.nan)
        table.add_row(
            name,
            f"{factor:.2f}×",
            "-" if math.isnan(host_factor) else f"{factor / host_factor:.2f}",
            f"{summary['simulated_s'] / cpu:.2f}×",
            mcycles,
            "n/a" if math.isnan(hover) else f"{hover * 100:.2f} cm",
            "n/a" if math.isnan(slowest) else "never" if math.isinf(slowest) else f"{slowest * 1000:.0f} ms",
            "-" if math.isnan(versus) or scenario.controller == "host" else f"{versus * 100:.2f} cm",
            str(summary["deadline_misses"]) if summary["deadline_misses"] is not None else "-",
        )
    console.print(table)
    if unsteady:
        console.print(
            "* auto was still translating the firmware's whole code in a second process during this flight "
            "(once per build and host, docs/translation.md): run again for its steady speed"
        )
    print(f"fly: {factor:.2f}× real time")
    return factor
