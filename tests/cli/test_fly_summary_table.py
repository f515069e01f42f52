"""The table ``robosoc fly`` prints at the end, from a hand-written ``summary.json`` content: every
figure in its unit and rounding, the step rows, the tasks, several vehicles side by side, and the
real-time line (incomplete runs say why)."""

from __future__ import annotations

import io
from typing import Any

from rich.console import Console

from robosoc.cli.fly import print_summary


def _vehicle(scale: float = 1.0) -> dict[str, Any]:
    return {
        "flight": {
            "hover_rms_m": 0.0123 * scale,
            "hover_max_m": 0.0456 * scale,
            "overshoot_m": 0.007 * scale,
            "tracking_rms_deg": {"roll": 1.234 * scale, "pitch": None, "yaw": float("nan")},
            "step_rise_s": [
                {"axis": "roll", "time_s": 2.0, "rise_s": 0.3104 * scale},
                {"axis": "pitch", "time_s": 4.5, "rise_s": None},
                {"axis": "yaw", "time_s": 9.0, "rise_s": 0.2},  # after the end of a 6 s flight: not shown
            ],
            "attitude_estimate_rms_deg": 0.2222 * scale,
            "height_estimate_rms_m": 0.0031 * scale,
        },
        "tasks": {
            "ekf": {
                "jobs": 600,
                "response_us_mean": 41.26 * scale,
                "response_us_max": 80.04,
                "exec_cycles_mean": 9876.4,
                "energy_nj_mean": 123.45,
            },
            "pid": {
                "jobs": 600,
                "response_us_mean": 5.0,
                "response_us_max": 9.96,
                "exec_cycles_mean": 1234.6,
                "energy_nj_mean": 12.0,
            },
        },
        "deadline_misses": 0,
        "energy": {"total_uj": 4321.0 * scale},
    }


def _lines(summary: dict[str, Any]) -> list[str]:
    console = Console(file=io.StringIO(), width=160, record=True, color_system=None)
    print_summary(console, summary)
    return [" ".join(line.replace("│", " ").replace("┃", " ").split()) for line in console.export_text().splitlines()]


def test_one_vehicle() -> None:
    lines = _lines({**_vehicle(), "simulated_s": 6.0, "host_s": 3.04, "real_time_factor": 1.9737})
    assert "flight summary" in lines[0]
    assert "figure value" in lines
    for row in (
        "hover height error RMS 1.23 cm",
        "hover height error max 4.56 cm",
        "overshoot 0.70 cm",
        "roll tracking RMS 1.23 deg",
        "pitch tracking RMS n/a",
        "yaw tracking RMS n/a",
        "roll step at 2 s: 90 % after 310 ms",
        "pitch step at 4.5 s: 90 % after n/a",
        "attitude estimate RMS 0.22 deg",
        "height estimate RMS 0.31 cm",
        "ekf jobs 600",
        "ekf response mean / max 41.3 / 80.0 us",
        "ekf cycles per job (mean) 9876",
        "ekf energy per job (mean) 123.5 nJ",
        "pid response mean / max 5.0 / 10.0 us",
        "pid cycles per job (mean) 1235",
        "deadline misses 0",
        "chip energy 4.32 mJ",
    ):
        assert row in lines, row
    assert not any("yaw step" in line for line in lines)
    assert lines.index("ekf jobs 600") < lines.index("pid jobs 600") < lines.index("deadline misses 0")
    assert lines[-1] == "real-time factor 1.97 (6 s simulated in 3.0 s)"


def test_several_vehicles_side_by_side_and_an_incomplete_run() -> None:
    summary = {
        "vehicles": [_vehicle(), _vehicle(2.0)],
        "simulated_s": 6.0,
        "host_s": 10.0,
        "real_time_factor": 0.6,
        "min_separation_m": 1.5,
        "complete": False,
        "stopped": "interrupted",
    }
    lines = _lines(summary)
    assert "figure vehicle 1 vehicle 2" in lines
    assert "hover height error RMS 1.23 cm 2.46 cm" in lines
    assert "roll step at 2 s: 90 % after 310 ms 621 ms" in lines
    assert "chip energy 4.32 mJ 8.64 mJ" in lines
    assert (
        lines[-1]
        == "real-time factor 0.60 (6 s simulated in 10.0 s); closest approach 1.50 m (incomplete: interrupted)"
    )


def test_a_host_controller_flight_has_no_task_rows() -> None:
    vehicle = _vehicle()
    del vehicle["tasks"]
    lines = _lines({**vehicle, "flight": {}, "simulated_s": 1.0, "host_s": 0.5, "real_time_factor": None})
    assert "hover height error RMS n/a" in lines
    assert not any(line.startswith(("deadline", "chip energy", "ekf")) for line in lines)
    assert lines[-1] == "real-time factor n/a (1 s simulated in 0.5 s)"


def test_a_vehicle_without_flight_figures_shows_n_a_in_each_row() -> None:
    crashed = {**_vehicle(), "flight": None}
    lines = _lines({"vehicles": [_vehicle(), crashed], "simulated_s": 6.0, "host_s": 1.0, "real_time_factor": 6.0})
    assert "roll step at 2 s: 90 % after 310 ms n/a" in lines
    assert "pitch step at 4.5 s: 90 % after n/a n/a" in lines
    assert "hover height error RMS 1.23 cm n/a" in lines and "height estimate RMS 0.31 cm n/a" in lines
    assert "ekf jobs 600 600" in lines


def test_the_table_title_and_right_aligned_values() -> None:
    console = Console(file=io.StringIO(), width=160, record=True, color_system=None)
    print_summary(console, {**_vehicle(), "simulated_s": 6.0, "host_s": 3.04, "real_time_factor": 1.9737})
    raw = console.export_text().splitlines()
    assert raw[0].strip() == "flight summary"
    header = next(line for line in raw if "figure" in line)
    assert header.startswith("figure")  # no edge, no padding at the edge
    rms = next(line for line in raw if line.startswith("hover height error RMS"))
    jobs = next(line for line in raw if line.startswith("ekf jobs"))
    assert rms.rstrip().endswith("1.23 cm") and jobs.rstrip().endswith("600")
    assert len(rms.rstrip()) == len(jobs.rstrip()) == len(header.rstrip())  # values end at the column's right edge
