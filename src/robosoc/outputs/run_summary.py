"""The ``summary.json`` of a ``robosoc fly`` run: what a flight achieved and what its tasks cost.

One JSON object per vehicle (schema 1, shared with the other run kinds; floats in the SI unit its
key names, NaN written as ``null``)::

    {"schema": 1, "complete": true, "scenario": "default", "seed": 1, "controller": "chip",
     "mode": "lockstep", "firmware": {...} | null, "chip": {...} | null,
     "simulated_s": 10.0, "host_s": 4.2, "real_time_factor": 2.4,
     "flight": {"hover_rms_m", "hover_max_m", "overshoot_m", "tracking_rms_deg": {"roll", "pitch", "yaw"},
                "step_rise_s": [{"axis", "time_s", "rise_s"}], "attitude_estimate_rms_deg",
                "height_estimate_rms_m"},
     "tasks": {"estimator": {...}, "pid": {...}} | null, "deadline_misses": 0 | null,
     "energy": {"total_uj", "tiles_uj": {"x,y": ...}, "noc_uj"} | null,
     "cycles": {"chip", "tiles": {"x,y": ...}} | null,
     "no_actuator_command": {"seconds", "from_s", "periods"},   # only when the firmware went quiet
     "mission": {"waypoints": [{"x", "y", "z", "arrive_s", "leave_s", "horizontal_error_max_m",
                 "horizontal_error_mean_m", "height_error_max_m", "reached"}], "reached",
                 "acceptance_m", "horizontal_error_max_m", "landed", "landed_s", "landed_x",
                 "landed_y", "landing_error_m"},   # only with a mission: robosoc.control.mission
     "power": {...}}      # a battery flight only (power_figures, docs/power.md)

``complete`` is false for a flight that was interrupted or crashed: the figures are those of the
rows flown so far, and ``"stopped"`` says why.  The flight figures are
:func:`robosoc.control.flight.flight_metrics` of the rows; the task figures are
:func:`robosoc.outputs.run_summary.task_summary` of the job records (the same records ``jobs.csv`` holds);
``cycles`` holds the chip's last cycle and each application tile's core cycles (what its energy
and a profile's rows add up to, docs/profile.md); the estimate figures are NaN (null) while the
controller's estimate is not visible in the rows.
A run of several vehicles has one such object per vehicle and a top-level one
(:func:`fleet_summary`) with the shared fields and ``"vehicles": [...]``.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from robosoc import output_files
from robosoc.config.chip import ChipConfig
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.power import PowerConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.control.flight import ROW_FIELDS, column, flight_metrics
from robosoc.control.mission import mission_figures
from robosoc.cosim.firmware_run import ReplayResult
from robosoc.physics.power import endurance_s
from robosoc.records import ENERGY_PARTS, POWER_CONSUMERS, JobRecord, PowerSample

SCHEMA = 1
MODE_LOCKSTEP = "lockstep"
TASK_KEYS = (
    "jobs",
    "response_us_mean",
    "response_us_max",
    "exec_cycles_mean",
    "exec_cycles_max",
    "energy_nj_mean",
    *(f"energy_nj_{part}_mean" for part in ENERGY_PARTS),
    "deadline_misses",
)
"""The figures of one task in ``summary.json`` (a subset of :func:`task_summary`'s)."""
HOST_TIMING_KEYS = ("host_s", "real_time_factor")
"""The fields that depend on the host's speed (every other field is the same for the same scenario)."""

__all__ = [
    "HOST_TIMING_KEYS",
    "SCHEMA",
    "TASK_KEYS",
    "SummaryError",
    "check_summary",
    "chip_figures",
    "cycle_figures",
    "energy_figures",
    "firmware_figures",
    "fleet_summary",
    "flight_summary",
    "json_safe",
    "load_summary",
    "metric_error",
    "task_figures",
    "vehicle_summary",
    "write_summary",
]


def flight_summary(rows: np.ndarray, scenario: ScenarioConfig, rest_height: float) -> dict[str, Any] | None:
    """The ``flight`` figures of ``rows`` (None without a row)."""
    if len(rows) == 0:
        return None
    m = flight_metrics(rows, scenario.flight, rest_height)
    armed = column(rows, "armed") > 0.5
    seen = not np.isnan(rows[armed][:, [ROW_FIELDS.index(f"est_q{c}") for c in "wxyz"]]).any()
    return {
        "hover_rms_m": m.hover_rms,
        "hover_max_m": m.hover_max,
        "overshoot_m": m.overshoot,
        "tracking_rms_deg": dict(zip(("roll", "pitch", "yaw"), m.tracking_rms, strict=True)),
        "step_rise_s": [{"axis": axis, "time_s": at, "rise_s": rise} for axis, at, rise in m.step_rise],
        "attitude_estimate_rms_deg": m.ekf_rms if seen else math.nan,
        "height_estimate_rms_m": m.height_estimate_rms,
    }


def task_summary(jobs: Sequence[JobRecord], clock_ns: float) -> dict[str, dict[str, float]]:
    """Per task that has jobs, in the order of their first job: job count, mean/max execution cycles and
    response time [us], mean energy per job [nJ] in all and per part (:data:`ENERGY_PARTS`), the
    kernel's share of it, deadline misses."""
    summary: dict[str, dict[str, float]] = {}
    for name in dict.fromkeys(j.task for j in jobs):
        mine = [j for j in jobs if j.task == name]
        if not mine:
            continue
        exec_c = [j.exec_cycles for j in mine]
        resp = [j.response_cycles for j in mine]
        energy = [j.energy_total_pj for j in mine]
        summary[name] = {
            "jobs": len(mine),
            "exec_cycles_mean": sum(exec_c) / len(mine),
            "exec_cycles_max": max(exec_c),
            "response_us_mean": sum(resp) / len(mine) * clock_ns / 1000,
            "response_us_max": max(resp) * clock_ns / 1000,
            "energy_nj_mean": sum(energy) / len(mine) / 1000,
            **{
                f"energy_nj_{part}_mean": sum(j.energy_pj[part] for j in mine) / len(mine) / 1000
                for part in ENERGY_PARTS
            },
            "kernel_energy_share": sum(j.energy_pj["kernel"] for j in mine) / max(1e-12, sum(energy)),
            "deadline_misses": sum(not j.deadline_met for j in mine),
        }
    return summary


def task_figures(result: ReplayResult) -> dict[str, dict[str, float]]:
    """The ``tasks`` object: per task its jobs' response, execution and energy figures."""
    figures = task_summary(result.jobs, result.clock_ns)
    return {name: {key: values[key] for key in TASK_KEYS} for name, values in figures.items()}


def firmware_figures(fw: FirmwareConfig) -> dict[str, Any]:
    """The ``firmware`` object: the build, the project ("" for the shipped quadrotor project) and
    the tile each of its tasks ran on."""
    project = fw.load_project()
    mapping = fw.mapping
    tiles = {t.name: list(mapping.get(t.name, (int(t.tile[0]), int(t.tile[1])))) for t in project.tasks}
    return {"build": fw.label, "arith": fw.arith, "multiplier": fw.multiplier, "release": fw.release,
            "scheduler": fw.scheduler, "project": fw.project, "tiles": tiles}  # fmt: skip


def chip_figures(chip: ChipConfig, result: ReplayResult | None) -> dict[str, Any]:
    """The ``chip`` object: mesh and clock (and the DVFS point's voltage, when the chip lists points)."""
    clock = result.clock_ns if result is not None else chip.tile.clock_period_ns
    figures: dict[str, Any] = {"width": chip.width, "height": chip.height, "clock_ns": clock}
    volts = chip.dvfs.voltage_at(chip.tile.clock_period_ns)
    if volts is not None:  # a DVFS operating point (docs/power.md)
        figures["dvfs_v"] = volts
    clocks = {}
    for t in range(chip.n_tiles):  # the tiles whose core runs on its own clock (docs/power.md, "Per-tile clock")
        xy = chip.tile_xy(t)
        if chip.is_powered(xy) and xy != tuple(chip.io_tile) and chip.tile_divider(xy) > 1:
            own: dict[str, Any] = {"clock_ns": chip.tile_config(xy).clock_period_ns, "divider": chip.tile_divider(xy)}
            if chip.tile_volts(xy) is not None:
                own["dvfs_v"] = chip.tile_volts(xy)
            clocks[f"{xy[0]},{xy[1]}"] = own
    if clocks:
        figures["tile_clocks"] = clocks
    return figures


def energy_figures(result: ReplayResult) -> dict[str, Any]:
    """The ``energy`` object: per tile and NoC, and their total."""
    tiles = {f"{x},{y}": result.energy_pj[f"tile {(x, y)}"] / 1e6 for x, y in result.counters}
    noc = result.energy_pj["noc"] / 1e6
    return {"total_uj": sum(tiles.values()) + noc, "tiles_uj": tiles, "noc_uj": noc}


def cycle_figures(result: ReplayResult) -> dict[str, Any]:
    """The ``cycles`` object: the chip's cycle at the end and each tile's core cycles."""
    return {"chip": result.cycles, "tiles": {f"{x},{y}": c["cycles"] for (x, y), c in result.counters.items()}}


def command_silence(result: ReplayResult, timeout_periods: int) -> dict[str, Any] | None:
    """The longest run of sensor periods in which no actuator command reached the I/O tile, if it
    is ``timeout_periods`` or longer (else None): ``{"seconds", "from_s", "periods"}``, the time
    counted from the start of its first period to the end of its last (the motors held the last
    command all along).  A period is [sample k's injection, sample k + 1's); the last one ends
    where the run ended."""
    samples = result.samples
    if not samples:
        return None
    ends = [s.cycle for s in samples[1:]] + [max(result.cycles, samples[-1].cycle)]
    arrivals = sorted(c.cycle for c in result.commands)
    longest = (0, 0)  # (periods, first period)
    run, first, j = 0, 0, 0
    for k, (sample, end) in enumerate(zip(samples, ends, strict=True)):
        while j < len(arrivals) and arrivals[j] < sample.cycle:
            j += 1
        answered = j < len(arrivals) and arrivals[j] < end
        if answered:
            run = 0
            continue
        if run == 0:
            first = k
        run += 1
        if run > longest[0]:
            longest = (run, first)
    periods, k0 = longest
    if periods < timeout_periods:
        return None
    seconds = (ends[k0 + periods - 1] - samples[k0].cycle) * result.clock_ns * 1e-9
    return {"seconds": seconds, "from_s": samples[k0].time_s, "periods": periods}


ENDURANCE_ASSUMPTIONS = (
    "hover from a full pack until the reserve state of charge (or the cut-off voltage, if first) at a constant "
    "power: the flight's mean power from take-off (motors + chip + avionics) drawn through Tremblay's model of the "
    "pack (docs/power.md); no temperature, ageing or recovery effects, ideal ESCs and converters, the vehicle's "
    "mass (pack included) unchanged"
)
"""What the endurance estimate of ``summary.json`` assumes, written beside it."""
LANDING_SPEED_MPS = 1.0
"""Fastest descent [m/s] at touchdown still counted as a landing (faster: the vehicle fell)."""
GROUND_MARGIN_M = 0.05
"""Height [m] above its resting height within which a vehicle counts as on the ground."""


def power_figures(
    samples: Sequence[PowerSample], end: PowerSample, rows: np.ndarray, power: PowerConfig, rest_height: float
) -> dict[str, Any]:
    """The ``power`` object of a battery flight: energy by consumer, the chip's share, the pack's
    state, the endurance estimate with its assumptions, and, if the pack ran empty, what became of
    the vehicle.

    Args:
        samples: the power system's state at each row (:func:`robosoc.cosim.lockstep.fly_lockstep_fleet`).
        end: its state after the last step (the flight's totals).
        rows: the flight rows (their ``armed`` column marks the take-off).
    """
    energy = dict(end.energy_j)
    total = sum(energy.values())
    armed = np.flatnonzero(column(rows, "armed") > 0.5) if len(rows) else np.array([], dtype=int)
    first = samples[int(armed[0])] if len(armed) and int(armed[0]) < len(samples) else None
    if first is not None and end.t > first.t:
        mean_w = (total - sum(first.energy_j.values())) / (end.t - first.t)
    else:
        mean_w = total / end.t if end.t > 0 else math.nan
    hover_s, ended_by = endurance_s(power.battery, mean_w, power.reserve_soc) if mean_w > 0 else (math.nan, "")
    volts = [s.pack_v for s in samples if s.pack_v > 0] + ([end.pack_v] if end.pack_v > 0 else [])
    return {
        "supply": power.supply,
        "energy_j": {**energy, "total": total},
        "chip_share": energy["chip"] / total if total > 0 else math.nan,
        "mean_power_w": mean_w,
        "pack": {
            "cells": power.battery.cells,
            "capacity_ah": power.battery.capacity_ah,
            "initial_soc": power.battery.initial_soc,
            "final_soc": end.soc,
            "min_v": min(volts) if volts else math.nan,
            "final_v": end.pack_v,
            "max_a": max([s.pack_a for s in samples] + [end.pack_a]),
        },
        "endurance": {
            "hover_s": hover_s,
            "at_power_w": mean_w,
            "from_soc": 1.0,
            "to_soc": power.reserve_soc,
            "ended_by": ended_by,
            "assumptions": ENDURANCE_ASSUMPTIONS,
        },
        "empty_at_s": end.empty_at_s,
        "after_empty": after_empty(rows, rest_height, end.empty_at_s),
        "failsafe": None
        if end.low_at_s is None
        else {
            "reserve_soc": power.reserve_soc,
            "at_s": end.low_at_s,
            "height_m": power.failsafe_height_m,
            "hold_s": power.failsafe_hold_s,
            "reached_s": reached(rows, power.failsafe_height_m, end.low_at_s),
            "outcome": touchdown(rows, rest_height, end.low_at_s, "the pack reached its reserve"),
        },
    }


FAILSAFE_REACHED_M = 0.1
"""How close to the failsafe's hover height the vehicle must come for ``power.failsafe.reached_s``."""


def reached(rows: np.ndarray, height_m: float, since_s: float) -> float | None:
    """The first row's time at or after ``since_s`` at which the vehicle's height is within
    :data:`FAILSAFE_REACHED_M` of ``height_m`` (None: never)."""
    t, z = column(rows, "t"), column(rows, "z")
    k = int(np.searchsorted(t, since_s))
    near = np.flatnonzero(np.abs(z[k:] - height_m) <= FAILSAFE_REACHED_M)
    return float(t[k + int(near[0])]) if len(near) else None


def after_empty(rows: np.ndarray, rest_height: float, empty_at_s: float | None) -> str | None:
    """What the vehicle did once its pack ran empty at ``empty_at_s`` (None: it did not): see
    :func:`touchdown`."""
    if empty_at_s is None:
        return None
    return touchdown(rows, rest_height, empty_at_s, "the pack emptied", still="falling")


def touchdown(rows: np.ndarray, rest_height: float, since_s: float, event: str, still: str = "in the air") -> str:
    """How the vehicle reached the ground after ``since_s`` (when ``event`` happened): ``"on the
    ground"`` (it was), ``"landed"`` (it touched down at most :data:`LANDING_SPEED_MPS` fast),
    ``"fell"`` (faster), or ``still`` (in the air when the flight ended); with the touchdown time and
    speed (from the rows' heights)."""
    t, z = column(rows, "t"), column(rows, "z")
    ground = rest_height + GROUND_MARGIN_M
    k = int(np.searchsorted(t, since_s))
    if k >= len(t):
        return f"the flight ended as {event}"
    if z[k] <= ground:
        return f"on the ground when {event} at {since_s:.3f} s"
    down = np.flatnonzero(z[k:] <= ground)
    if not len(down):
        return f"{still}: still {z[-1] - rest_height:.2f} m up when the flight ended"
    j = k + int(down[0])
    speed = (z[j - 1] - z[j]) / (t[j] - t[j - 1]) if j > 0 else 0.0
    verdict = "landed" if speed <= LANDING_SPEED_MPS else "fell"
    return f"{verdict}: touched down at {t[j]:.2f} s at {speed:.2f} m/s"


def vehicle_summary(
    scenario: ScenarioConfig,
    rows: np.ndarray,
    rest_height: float,
    result: ReplayResult | None,
    simulated_s: float,
    host_s: float,
    *,
    complete: bool = True,
    stopped: str | None = None,
    power: tuple[Sequence[PowerSample], PowerSample] | None = None,
) -> dict[str, Any]:
    """The summary of one vehicle's flight (``result``: its firmware run, None for the host controller).

    Args:
        scenario: the resolved scenario (its controller, firmware and chip are named).
        rows: the vehicle's flight rows (columns :data:`robosoc.control.flight.ROW_FIELDS`).
        rest_height: the vehicle's (fixes the take-off climb of the flight plan).
        simulated_s, host_s: simulated time flown and the host time it took.
        complete: false for an interrupted or crashed flight; ``stopped`` then says why.
        power: a battery flight's power samples (one per row) and its end state: the summary gets a
            ``power`` object (:func:`power_figures`); a flight on a constant supply has none.
    """
    chip = scenario.controller == "chip"
    summary: dict[str, Any] = {
        **_identity(scenario, complete),
        "firmware": firmware_figures(scenario.firmware) if chip else None,
        "chip": chip_figures(scenario.chip, result) if chip else None,
        **_pace(simulated_s, host_s),
        "flight": flight_summary(rows, scenario, rest_height),
        "tasks": task_figures(result) if result is not None else None,
        "deadline_misses": result.deadline_misses if result is not None else None,
        "energy": energy_figures(result) if result is not None else None,
        "cycles": cycle_figures(result) if result is not None else None,
    }
    silence = command_silence(result, scenario.firmware.command_timeout_periods) if result is not None else None
    if silence is not None:
        summary["no_actuator_command"] = silence  # the run is marked: the firmware went quiet
    if scenario.flight.mission is not None and len(rows):
        summary["mission"] = mission_figures(rows, scenario.flight, rest_height)
    if power is not None:
        summary["power"] = power_figures(power[0], power[1], rows, scenario.power, rest_height)
    return _with_reason(summary, stopped)


def fleet_summary(
    scenario: ScenarioConfig,
    vehicles: Sequence[dict[str, Any]],
    simulated_s: float,
    host_s: float,
    *,
    min_separation_m: float,
    complete: bool = True,
    stopped: str | None = None,
) -> dict[str, Any]:
    """The top-level summary of a run of several vehicles: the shared fields, the closest approach of
    any two vehicles (their body origins, in metres) and each vehicle's summary."""
    misses = sum(v["deadline_misses"] or 0 for v in vehicles) if scenario.controller == "chip" else None
    summary: dict[str, Any] = {
        **_identity(scenario, complete),
        **_pace(simulated_s, host_s),
        "deadline_misses": misses,
        "min_separation_m": min_separation_m,
        "vehicles": list(vehicles),
    }
    return _with_reason(summary, stopped)


def _identity(scenario: ScenarioConfig, complete: bool) -> dict[str, Any]:
    """The fields that say which run a summary is of."""
    return {
        "schema": SCHEMA,
        "complete": complete,
        "scenario": scenario.name,
        "seed": scenario.seed,
        "controller": scenario.controller,
        "mode": MODE_LOCKSTEP,
    }


def _pace(simulated_s: float, host_s: float) -> dict[str, float]:
    """Simulated and host time, and their ratio."""
    return {
        "simulated_s": simulated_s,
        "host_s": host_s,
        "real_time_factor": simulated_s / host_s if host_s > 0 else math.nan,
    }


def _with_reason(summary: dict[str, Any], stopped: str | None) -> dict[str, Any]:
    """``summary`` with why the flight stopped early, if it did."""
    if stopped is not None:
        summary["stopped"] = stopped
    return summary


def json_safe(value: Any) -> Any:
    """``value`` with every NaN (and infinity) replaced by None and numpy scalars made plain."""
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    return value


def write_summary(summary: dict[str, Any], path: Path) -> None:
    """Write ``summary`` as JSON (NaN as null) to a temporary name and rename it to ``path``, so that
    a reader never sees half a file."""
    text = json.dumps(json_safe(summary), indent=2, allow_nan=False) + "\n"
    output_files.write_atomic(path, text)


# --- reading a summary.json back ----------------------------------------------------------------
#
# A summary.json read back (robosoc report, robosoc profile, a sweep's records) is input: its
# shape is checked here, in one place, before anything uses it.  Every field robosoc writes has a
# kind; a field may be missing (an older robosoc, a host flight) or null (NaN), and fields robosoc
# does not know are kept as they are.  The same table says which dotted names a sweep can tabulate.

MAX_JSON_DEPTH = 32
"""Deepest nesting of objects and lists accepted in a summary (robosoc writes 4 levels)."""


class SummaryError(ValueError):
    """A ``summary.json`` that is not one: ``"<file>: <dotted.field>: <reason>"``."""


class _Kind:
    """A JSON value kind: a name for messages, a test, and (objects and maps) what is inside."""

    def __init__(self, name: str, test=None, fields=None, each=None, keys=None, keys_text: str = "") -> None:
        self.name, self.test, self.fields, self.each, self.keys, self.keys_text = (
            name,
            test,
            fields,
            each,
            keys,
            keys_text,
        )

    def metric(self) -> bool:
        """Whether a value of this kind can be a sweep metric (a number or a flag)."""
        return self.name in (NUMBER.name, INTEGER.name, BOOLEAN.name)


def _is_number(v: object) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool)


NUMBER = _Kind("a number or null", lambda v: v is None or _is_number(v))
INTEGER = _Kind("an integer or null", lambda v: v is None or (isinstance(v, int) and not isinstance(v, bool)))
BOOLEAN = _Kind("true or false", lambda v: isinstance(v, bool))
TEXT = _Kind("a string", lambda v: isinstance(v, str))
ANY = _Kind("any value", lambda v: True)
TILE_KEY = re.compile(r"\d+,\d+")
TASK_KEY = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def _object(fields: dict[str, _Kind], nullable: bool = True) -> _Kind:
    return _Kind(
        "an object" + (" or null" if nullable else ""),
        lambda v: (nullable and v is None) or isinstance(v, dict),
        fields=fields,
    )


def _map(each: _Kind, keys: re.Pattern[str] | tuple[str, ...] | None = None, keys_text: str = "") -> _Kind:
    return _Kind(
        "an object or null", lambda v: v is None or isinstance(v, dict), each=each, keys=keys, keys_text=keys_text
    )


def _list(each: _Kind) -> _Kind:
    return _Kind("a list", lambda v: isinstance(v, list), each=each)


_TASK = _object({key: INTEGER if key in ("jobs", "deadline_misses") else NUMBER for key in TASK_KEYS} | {
    "exec_cycles_max": NUMBER, "kernel_energy_share": NUMBER})  # fmt: skip
_VEHICLE_FIELDS: dict[str, _Kind] = {
    "schema": INTEGER,
    "complete": BOOLEAN,
    "stopped": _Kind("a string or null", lambda v: v is None or isinstance(v, str)),
    "scenario": TEXT,
    "seed": INTEGER,
    "controller": TEXT,
    "mode": TEXT,
    "firmware": _Kind(  # an object (fly), the build's label (firmware replay --out) or null (host)
        "an object, a string or null",
        lambda v: v is None or isinstance(v, dict | str),
        fields={
            "build": TEXT,
            "arith": TEXT,
            "multiplier": BOOLEAN,
            "release": TEXT,
            "scheduler": TEXT,
            "project": TEXT,
            "tiles": _map(_list(INTEGER), TASK_KEY, "TASK: a task of the project"),
        },
    ),
    "chip": _object(
        {
            "width": INTEGER,
            "height": INTEGER,
            "clock_ns": NUMBER,
            "dvfs_v": NUMBER,
            "tile_clocks": _map(
                _object({"clock_ns": NUMBER, "divider": INTEGER, "dvfs_v": NUMBER}, nullable=False), TILE_KEY, "X,Y"
            ),
        }
    ),
    "simulated_s": NUMBER,
    "host_s": NUMBER,
    "real_time_factor": NUMBER,
    "flight": _object(
        {
            "hover_rms_m": NUMBER,
            "hover_max_m": NUMBER,
            "overshoot_m": NUMBER,
            "tracking_rms_deg": _object({"roll": NUMBER, "pitch": NUMBER, "yaw": NUMBER}),
            "step_rise_s": _list(_object({"axis": TEXT, "time_s": NUMBER, "rise_s": NUMBER}, nullable=False)),
            "attitude_estimate_rms_deg": NUMBER,
            "height_estimate_rms_m": NUMBER,
        }
    ),
    "tasks": _map(_TASK, TASK_KEY, "TASK: estimator, pid or a firmware project's task"),
    "deadline_misses": INTEGER,
    "energy": _object({"total_uj": NUMBER, "tiles_uj": _map(NUMBER, TILE_KEY, "X,Y"), "noc_uj": NUMBER}),
    "cycles": _object({"chip": INTEGER, "tiles": _map(INTEGER, TILE_KEY, "X,Y")}),
    "min_separation_m": NUMBER,
    "no_actuator_command": _object({"seconds": NUMBER, "from_s": NUMBER, "periods": INTEGER}),
    "mission": _object(
        {
            "waypoints": _list(
                _object(
                    {
                        **dict.fromkeys(("x", "y", "z", "arrive_s", "leave_s"), NUMBER),
                        **dict.fromkeys(
                            ("horizontal_error_max_m", "horizontal_error_mean_m", "height_error_max_m"), NUMBER
                        ),
                        "reached": BOOLEAN,
                    },
                    nullable=False,
                )
            ),
            "reached": INTEGER,
            "acceptance_m": NUMBER,
            "horizontal_error_max_m": NUMBER,
            "landed": BOOLEAN,
            **dict.fromkeys(("landed_s", "landed_x", "landed_y", "landing_error_m"), NUMBER),
        }
    ),
    "power": _object(
        {
            "supply": TEXT,
            "energy_j": _map(NUMBER, (*POWER_CONSUMERS, "total"), "motors, chip, avionics or total"),
            "chip_share": NUMBER,
            "mean_power_w": NUMBER,
            "pack": _object(
                {key: NUMBER for key in ("capacity_ah", "initial_soc", "final_soc", "min_v", "final_v", "max_a")}
                | {"cells": INTEGER}
            ),
            "endurance": _object(
                {key: NUMBER for key in ("hover_s", "at_power_w", "from_soc", "to_soc")}
                | {"ended_by": TEXT, "assumptions": TEXT}
            ),
            "empty_at_s": NUMBER,
            "after_empty": _Kind("a string or null", lambda v: v is None or isinstance(v, str)),
            "failsafe": _object(
                {
                    "reserve_soc": NUMBER,
                    "at_s": NUMBER,
                    "height_m": NUMBER,
                    "hold_s": NUMBER,
                    "reached_s": NUMBER,
                    "outcome": TEXT,
                }
            ),
        }
    ),
}
SUMMARY = _object(_VEHICLE_FIELDS, nullable=False)
_VEHICLE_FIELDS["vehicles"] = _list(SUMMARY)


def _describe(value: object) -> str:
    kind = {dict: "an object", list: "a list", str: "the string", bool: "", type(None): ""}.get(type(value), "")
    shown = json.dumps(value, allow_nan=True)
    if len(shown) > 40:
        shown = shown[:37] + "..."
    return f"{kind} {shown}".strip() if kind in ("the string", "") else kind


def _check(value: object, kind: _Kind, where: str, field: str) -> None:
    if not kind.test(value):
        raise SummaryError(f"{where}: {field or '(top level)'}: expected {kind.name}, got {_describe(value)}")
    if isinstance(value, float) and not math.isfinite(value):
        raise SummaryError(f"{where}: {field}: expected a finite number or null, got {value}")
    if isinstance(value, dict):
        for key, item in value.items():
            inner = kind.fields.get(key) if kind.fields is not None else kind.each
            if inner is not None:
                _check(item, inner, where, _field_of(field, key))
    elif isinstance(value, list) and kind.each is not None:
        for i, item in enumerate(value):
            _check(item, kind.each, where, f"{field}[{i}]")


def _field_of(field: str, key: str) -> str:
    """The dotted name of member ``key`` of ``field``; a key that would not read as one part of it
    (a dot, a bracket, a line break or another unprintable character) as a quoted JSON string in
    brackets, so the message stays on one line and says which key."""
    if key and key.isprintable() and not any(c in key for c in '.[]"'):
        return f"{field}.{key}" if field else key
    return f"{field}[{json.dumps(key)}]"


def _depth(value: object) -> int:
    """How deeply ``value`` nests (iteratively: a hostile file cannot exhaust the stack)."""
    deepest, todo = 0, [(value, 1)]
    while todo:
        node, level = todo.pop()
        if isinstance(node, dict | list):
            deepest = max(deepest, level)
            if level <= MAX_JSON_DEPTH:
                todo.extend((v, level + 1) for v in (node.values() if isinstance(node, dict) else node))
    return deepest


def check_summary(data: object, where: str) -> dict[str, Any]:
    """``data`` if it has the shape of a run's ``summary.json`` (module docstring), else
    :class:`SummaryError` naming ``where`` and the dotted field: ``runs/x/summary.json: chip: expected
    an object or null, got the string "2x2"``."""
    if _depth(data) > MAX_JSON_DEPTH:
        raise SummaryError(f"{where}: nested more than {MAX_JSON_DEPTH} levels deep: not a robosoc summary")
    if not isinstance(data, dict):
        raise SummaryError(f"{where}: expected a JSON object (a run's summary.json)")
    _check(data, SUMMARY, where, "")
    return data


def _no_constant(name: str) -> None:
    raise ValueError(f"{name} is not a JSON number (robosoc writes null)")


def load_summary(text: str, where: str) -> dict[str, Any]:
    """The summary in ``text`` (a ``summary.json``'s contents), checked by :func:`check_summary`.

    Raises:
        SummaryError: not JSON, NaN or Infinity in it, or a field of the wrong kind (names ``where``).
    """
    try:
        data = json.loads(text, parse_constant=_no_constant)
    except RecursionError:
        raise SummaryError(f"{where}: nested too deeply: not a robosoc summary") from None
    except ValueError as exc:  # JSONDecodeError, and NaN / Infinity
        raise SummaryError(f"{where}: not JSON: {exc}") from None
    return check_summary(data, where)


def metric_error(name: str) -> str | None:
    """Why ``name`` is not a dotted number field of ``summary.json`` a sweep can tabulate, or None."""
    kind = SUMMARY
    parts = name.split(".")
    for i, part in enumerate(parts):
        parent = ".".join(parts[:i]) or "summary.json"
        if kind.fields is not None:
            inner = kind.fields.get(part) if part != "vehicles" else None
            known = ", ".join(k for k in kind.fields if k != "vehicles")
        elif kind.each is not None and kind.keys is not None:
            fits = kind.keys.fullmatch(part) if isinstance(kind.keys, re.Pattern) else part in kind.keys
            inner = kind.each if fits else None
            known = kind.keys_text
        else:
            inner, known = None, ""
        if inner is None:
            has = f" ({parent} has: {known})" if known else f" ({parent} is a single value)"
            return f"{name!r} is not a field of summary.json{has}"
        kind = inner
    if not kind.metric():
        return f"{name!r} is not a number of summary.json (it is {kind.name}): name one of its fields"
    return None
