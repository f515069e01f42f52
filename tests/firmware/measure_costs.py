"""Cycle costs on the simulated core for docs/firmware-libraries.md (a script, not a test).

    PYTHONPATH=src python tests/firmware/measure_costs.py

Prints markdown tables: the Q16.16 and float functions (mean cycles per call, call overhead
subtracted) with and without the multiplier, the matrix and quaternion routines in the four
builds, and the EKF step over 10 s of a recorded flight in the four builds, with the accuracy
figures of that flight.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from flight_data import (
    build_harness_elf,
    build_harness_native,
    golden_replay,
    parse_output,
    record_flight,
    write_data_header,
)
from lib_reference import lib_check_sources, max_errors, mean_cycles, parse_lines
from real_reference import INCLUDE_DIRS, real_check_sources
from real_reference import mean_cycles as real_mean_cycles

from robosoc.chip.single import run_elf
from robosoc.firmware import ARITHS, MATH_DIR, arith_defines
from robosoc.toolchain import build_elf, run_native

BUILDS = [(arith, mul) for arith in ARITHS for mul in (True, False)]


def _name(arith: str, mul: bool) -> str:
    return f"{arith} {'mul' if mul else 'no-mul'}"


def library_table() -> None:
    costs = {}
    errors = {}
    for mul in (True, False):
        elf = build_elf(lib_check_sources(), mul=mul, include_dirs=[MATH_DIR], defines={"CHECK_COUNT": 300})
        lines = parse_lines(run_elf(elf, mul=mul).output.decode())
        costs[mul] = mean_cycles(lines)
        errors[mul] = max_errors(lines)
    print("| function | mul | no-mul | largest error seen |")
    print("|---|---|---|---|")
    for op in costs[True]:
        print(f"| {op} | {costs[True][op]:.0f} | {costs[False][op]:.0f} | {errors[True][op][0]:.3g} |")


def routine_table() -> None:
    costs = {}
    for arith, mul in BUILDS:
        defines = {"CHECK_COUNT": 6, **arith_defines(arith)}
        elf = build_elf(real_check_sources(), mul=mul, include_dirs=INCLUDE_DIRS, defines=defines)
        costs[arith, mul] = real_mean_cycles(run_elf(elf, mul=mul).output.decode(), arith)
    print("| routine | " + " | ".join(_name(a, m) for a, m in BUILDS) + " |")
    print("|---|" + "---|" * len(BUILDS))
    for op in costs[BUILDS[0]]:
        print(f"| {op} | " + " | ".join(f"{costs[b][op]:.0f}" for b in BUILDS) + " |")


def ekf_table(seconds: float) -> None:
    record = record_flight(seconds)
    folder = Path(tempfile.mkdtemp(prefix="ekf-costs-"))
    write_data_header(record, folder)
    golden, _ = golden_replay(record)
    runs = {}
    print(f"EKF: {record.steps} steps")
    print("| build | mean cycles/step | min | max | program cycles |")
    print("|---|---|---|---|---|")
    for arith, mul in BUILDS:
        result = run_elf(build_harness_elf(folder, arith, mul), mul=mul, max_cycles=10**11)
        run = parse_output(result.output.decode(), arith)
        runs[arith] = run
        c = run.cycles
        print(f"| {_name(arith, mul)} | {c.mean():.0f} | {c.min()} | {c.max()} | {result.cycles} |")
    host = {arith: parse_output(run_native(build_harness_native(folder, arith))[1].decode(), arith) for arith in ARITHS}
    for arith in ARITHS:
        assert np.array_equal(host[arith].states, runs[arith].states)
    fixed, flt = runs["fixed"].states, runs["float"].states
    print("fixed vs float, mean |error| per component (w x y z):", np.mean(np.abs(fixed[:, :4] - flt[:, :4]), axis=0))
    print("fixed vs float, largest |error| per component:", np.max(np.abs(fixed[:, :4] - flt[:, :4]), axis=0))
    print("float vs float64, largest |error| (q, b):", np.max(np.abs(flt - golden)))
    print("float vs float64, mean |error| per component:", np.mean(np.abs(flt - golden), axis=0))
    print("fixed vs float64, mean |error| per component:", np.mean(np.abs(fixed - golden), axis=0))


if __name__ == "__main__":
    library_table()
    print()
    routine_table()
    print()
    ekf_table(float(sys.argv[1]) if len(sys.argv) > 1 else 10.0)
