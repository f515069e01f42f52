"""Cycle costs and accuracy of the PID task and the altitude filter for docs/firmware-libraries.md
(a script, not a test).

    PYTHONPATH=src python tests/firmware/measure_pid_costs.py [seconds]

Runs the recorded flight (10 s after take-off by default) on the core in the four builds and
prints per step: cycles of pid_packet_step (of which mix_pwm) and of alt_step, mean, min and max,
and against the float64 golden models the share of samples within one PWM count, the largest
count difference, the largest output and altitude-filter differences.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from pid_data import (
    build_harness_elf,
    build_harness_native,
    golden_altitude,
    golden_pid,
    parse_output,
    record_flight,
    write_data_header,
)

from robosoc.chip.single import run_elf
from robosoc.firmware import ARITHS
from robosoc.host.control_params import ALT_P_SHIFT
from robosoc.toolchain import run_native

BUILDS = [(arith, mul) for arith in ARITHS for mul in (True, False)]


def main(seconds: float) -> None:
    record = record_flight(seconds)
    folder = Path(tempfile.mkdtemp(prefix="pid-costs-"))
    write_data_header(record, folder)
    golden = golden_pid(record)
    golden_alt = golden_altitude(record)
    print(f"{record.steps} steps")
    print("| build | PID step mean | min | max | of which mixer | altitude step mean | min | max |")
    print("|---|---|---|---|---|---|---|---|")
    for arith, mul in BUILDS:
        result = run_elf(build_harness_elf(folder, arith, mul), mul=mul, max_cycles=10**11, errata="rtl")
        assert result.errata["mulhsu"] == 0
        run = parse_output(result.output.decode(), arith, ALT_P_SHIFT)
        host = parse_output(run_native(build_harness_native(folder, arith))[1].decode(), arith, ALT_P_SHIFT)
        assert np.array_equal(run.pwm, host.pwm) and np.array_equal(run.alt, host.alt)
        p, m, a = run.pid_cycles, run.mix_cycles, run.alt_cycles
        name = f"{arith} {'mul' if mul else 'no-mul'}"
        pid = f"{p.mean():.0f} | {p.min()} | {p.max()} | {m.mean():.0f}"
        print(f"| {name} | {pid} | {a.mean():.0f} | {a.min()} | {a.max()} |")
    for arith in ARITHS:
        run = parse_output(run_native(build_harness_native(folder, arith))[1].decode(), arith, ALT_P_SHIFT)
        diff = np.abs(run.pwm - golden.pwm)
        within = np.mean(diff.max(axis=1) <= 1)
        exact = np.mean(diff.max(axis=1) == 0)
        print(f"{arith}: samples within 1 count {within:.2%}, all four exact {exact:.2%}, largest {diff.max()}")
        print(f"  largest |u - golden| (u_z, roll, pitch, yaw): {np.max(np.abs(run.u - golden.u), axis=0)}")
        alt = np.abs(run.alt - golden_alt.states)
        print(f"  altitude largest |error| (h, v, b): {alt.max(axis=0)}, mean {alt.mean(axis=0)}")
        rel = np.abs(np.diag(run.covariance) / np.diag(golden_alt.covariance) - 1)
        print(f"  final P diagonal, relative error: {rel}")


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else 10.0)
