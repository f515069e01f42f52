"""The exact profile: its totals are the run's, a tiny program's counts are the hand-derived ones,
tasks get their own functions, and counting changes nothing of the run."""

from __future__ import annotations

import csv
import json
import math
import re
from pathlib import Path

import pytest

from headless_chromium import BROWSER, load
from robosoc.chip.energy import INSTRUCTION_CLASSES, STALL_KINDS, EnergyModel
from robosoc.chip.function_profile import (
    COUNT_NAMES,
    CSV_FIELDS,
    NOC_ROW,
    RESET_ROW,
    core_profile,
    profile_totals,
    summary_mismatches,
)
from robosoc.chip.single import SingleCoreSoC
from robosoc.config.scenario import FlightPlan, ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.control.flight import fly
from robosoc.control.host import HostController
from robosoc.cosim.replay import replay
from robosoc.kernels.core_layout import PIPELINE_FILL
from robosoc.outputs.report import write_report
from robosoc.outputs.run_folder import write_profile
from robosoc.program.elf import load_elf
from robosoc.toolchain import build_elf

MODEL = EnergyModel.load()


@pytest.fixture(scope="module")
def replays() -> tuple:
    """The fixed-point firmware (multiplier: mul stalls too) replayed for a short flight (calibration,
    then the EKF from take-off at 0.3 s), with and without the profile."""
    scenario = ScenarioConfig(duration_s=0.8, flight=FlightPlan(takeoff_s=0.3, steps=()))
    vehicle = vehicle_preset(scenario.vehicle)
    rows = fly(scenario, vehicle, HostController.for_scenario(scenario, vehicle))
    return tuple(replay(rows, scenario=scenario, vehicle=vehicle, profile=p) for p in (True, False))


def _pj(counts: dict[str, int]) -> float:
    """Energy by the coefficients, written out here: Σ instructions × class pJ + stall cycles × kind pJ."""
    return math.fsum(counts.get(k, 0) * MODEL.instruction[k].pj for k in INSTRUCTION_CLASSES) + math.fsum(
        counts.get(k, 0) * MODEL.stall[k].pj for k in STALL_KINDS
    )


def test_replay_profile_totals_equal_the_run_totals(replays) -> None:
    result, _ = replays
    totals = profile_totals(result.profile)
    assert set(totals) == {*result.counters, None}
    for xy, counters in result.counters.items():
        got = totals[xy]
        assert got["cycles"] == counters["cycles"] > 0
        assert got["instructions"] == counters["instructions"] > 0
        for name in COUNT_NAMES:  # instructions per class and cycles per stall kind, exactly
            assert got["counts"][name] == counters[name], (xy, name)
        assert got["energy_pj"] == pytest.approx(result.energy_pj[f"tile {xy}"], rel=1e-12)
        assert got["energy_pj"] == pytest.approx(_pj(counters), rel=1e-12)
    assert totals[None]["energy_pj"] == pytest.approx(result.energy_pj["noc"], rel=1e-12)
    (noc,) = [r for r in result.profile.rows if r.tile is None]
    assert (noc.task, noc.task_name, noc.function, noc.cycles, noc.instructions, noc.counts) == (
        None, "", NOC_ROW, 0, 0, {}
    )  # fmt: skip
    assert result.profile.rows[-1] is noc and result.profile.clock_ns == result.clock_ns
    # and per task: each task's rows add up to its own counters
    for (xy, task), pj in result.task_energy_pj.items():
        mine = [r for r in result.profile.rows if r.tile == xy and r.task == task]
        assert math.fsum(r.energy_pj for r in mine) == pytest.approx(pj, rel=1e-12)


def test_rows_are_consistent_and_other_rows_hold_no_instructions(replays) -> None:
    result, _ = replays
    for r in result.profile.rows:
        if r.function in (RESET_ROW, NOC_ROW):  # the pipeline fill costs no energy; the routers no core cycle
            assert r.counts == {} and r.instructions == 0
            assert r.energy_pj == 0 if r.function == RESET_ROW else r.energy_pj > 0 and r.cycles == 0
            continue
        assert r.cycles == r.instructions + sum(r.counts.get(k, 0) for k in STALL_KINDS), r
        assert r.instructions == sum(r.counts.get(k, 0) for k in INSTRUCTION_CLASSES), r
        assert r.energy_pj == pytest.approx(_pj(r.counts), rel=1e-12)
        if r.function.startswith("("):
            assert r.instructions == 0, r
    resets = [r for r in result.profile.rows if r.function == RESET_ROW]
    assert [(r.task, r.cycles) for r in resets] == [(0, PIPELINE_FILL)] * len(result.counters)


def test_each_task_shows_its_own_functions(replays) -> None:
    result, _ = replays
    ekf, pid = (0, 1), (1, 0)  # the quadrotor project's tiles (its robosoc.toml)

    def functions(tile, task_name):
        return {r.function for r in result.profile.rows if r.tile == tile and r.task_name == task_name}

    estimator, controller = functions(ekf, "estimator"), functions(pid, "pid")
    assert {"ekf_predict", "ekf_update"} <= estimator, sorted(estimator)
    assert "pid_step" in controller and "pid_step" not in estimator
    assert not {f for f in controller if f.startswith("ekf_")}
    kernel = functions(ekf, "kernel")
    assert "_irq_entry" in kernel and not {"ekf_predict", "ekf_update"} & kernel  # (it initialises the EKF at boot)
    idle = [r for r in result.profile.rows if r.tile == ekf and r.task_name == "idle"]
    assert max(idle, key=lambda r: r.cycles).function == "(sleep)"


def test_profiling_changes_nothing_of_the_run(replays) -> None:
    profiled, plain = replays
    assert plain.profile is None
    assert profiled.cycles == plain.cycles
    assert profiled.counters == plain.counters
    assert [(c.seq, c.pwm, c.cycle) for c in profiled.commands] == [(c.seq, c.pwm, c.cycle) for c in plain.commands]
    assert [(j.task, j.release_cycle, j.completion_cycle) for j in profiled.jobs] == [
        (j.task, j.release_cycle, j.completion_cycle) for j in plain.jobs
    ]


ASM = """
    .text
    .globl main
    .type main, @function
main:
    addi sp, sp, -16
    sw ra, 12(sp)
    li t1, {n}
1:  jal ra, spin
    addi t1, t1, -1
    bnez t1, 1b
    lw ra, 12(sp)
    addi sp, sp, 16
    li a0, 0
    ret
    .size main, .-main

    .globl spin
    .type spin, @function
spin:
    li t0, {k}
2:  addi t0, t0, -1
    bnez t0, 2b
    ret
    .size spin, .-spin
"""


def test_a_tiny_program_gives_the_hand_derived_counts(tmp_path: Path) -> None:
    n, k = 7, 50
    src = tmp_path / "spin.S"
    src.write_text(ASM.format(n=n, k=k))
    soc = SingleCoreSoC()
    soc.load(load_elf(build_elf([src], mul=True, opt="-O1")))
    soc.enable_profile()
    result = soc.run()
    rows = {r.function: r for r in core_profile(soc, MODEL).rows}
    # spin, per call: li (1) + k addi (1) + k bnez (taken 3, the last 1) + ret (3)
    spin = rows["spin"]
    assert spin.instructions == n * (2 * k + 2)
    assert spin.cycles == n * (1 + k + 3 * (k - 1) + 1 + 3)
    assert spin.counts["add"] == n * (k + 1) and spin.counts["branch"] == n * k and spin.counts["jump"] == n
    assert spin.counts["branch_cycle"] == n * (2 * (k - 1) + 2)  # taken branches and the ret
    # main: prologue addi, sw, li; n × (jal, addi, bnez); epilogue lw, addi, li, ret
    main = rows["main"]
    assert main.instructions == 3 * n + 7
    assert main.cycles == (1 + 3 + 1) + n * (3 + 1) + 3 * (n - 1) + 1 + (3 + 1 + 1 + 3)
    assert main.counts["memory"] == 2 and main.counts["memory_cycle"] == 4
    # the whole program, start-up code included, adds up to the run's counters
    total = profile_totals(core_profile(soc, MODEL))[(0, 0)]
    assert total["cycles"] == result.cycles
    assert total["instructions"] == result.instructions
    assert total["energy_pj"] == pytest.approx(_pj(result.counters), rel=1e-12)


def test_files_round_trip_and_summary_check(replays, tmp_path: Path) -> None:
    result, _ = replays
    profile = result.profile
    json_path, csv_path = write_profile(profile, tmp_path)
    data = json.loads(json_path.read_text())
    with csv_path.open(newline="") as handle:
        table = list(csv.DictReader(handle))
    assert tuple(table[0]) == CSV_FIELDS
    assert len(table) == len(data["rows"]) == len(profile.rows)
    for tile, cycles in data["totals"]["cycles"].items():
        assert sum(int(r["cycles"]) for r in table if r["tile"] == tile) == cycles
    assert not list(tmp_path.glob("*.partial"))
    summary = {
        "cycles": {"tiles": {f"{x},{y}": c["cycles"] for (x, y), c in result.counters.items()}},
        "energy": {
            "tiles_uj": {f"{x},{y}": result.energy_pj[f"tile {(x, y)}"] / 1e6 for (x, y) in result.counters},
            "noc_uj": result.energy_pj["noc"] / 1e6,
            "total_uj": sum(result.energy_pj.values()) / 1e6,
        },
    }
    assert summary_mismatches(profile, summary) == []
    tile = next(iter(summary["cycles"]["tiles"]))
    summary["cycles"]["tiles"][tile] += 1
    summary["energy"]["noc_uj"] *= 1.001
    found = summary_mismatches(profile, summary)
    assert len(found) == 2 and found[0].startswith(f"tile {tile}:") and found[1].startswith("noc_uj")


def test_the_report_shows_the_profile_and_renders(replays, chip_run: Path, tmp_path: Path) -> None:
    write_profile(replays[0].profile, chip_run)
    text = write_report(chip_run).read_text()
    assert re.findall(r'<figure class="plot" data-plot="([^"]+)"', text).count("profile") == 1
    for name in ("estimator", "pid"):  # the table names each task's costliest function
        rows = [r for r in replays[0].profile.rows if r.task_name == name]
        assert f"<td>{max(rows, key=lambda r: r.cycles).function}</td>" in text
    if BROWSER is None:
        pytest.skip("chromium is not installed (.ci/run installs it)")
    page = load(chip_run / "report.html", tmp_path)
    assert page.console == []
    assert page.body_attribute("data-rendered") == page.body_attribute("data-plots")


def test_a_bad_profile_json_is_noted_not_fatal(chip_run: Path) -> None:
    (chip_run / "profile.json").write_text('{"rows": [{"tile": "0,1"}]}')
    text = write_report(chip_run).read_text()
    assert 'data-plot="profile"' not in text and "profile.json: skipped: not a robosoc profile" in text


def test_top_ranks_one_task_on_one_tile_by_cycles_then_energy_then_name() -> None:
    from robosoc.chip.function_profile import FunctionProfile, ProfileRow

    def row(tile, task, name, cycles, pj):
        return ProfileRow(tile, task, f"task{task}", name, cycles, cycles // 2, {}, pj)

    rows = [
        row((0, 1), 1, "a", 100, 5.0),
        row((0, 1), 1, "b", 300, 1.0),
        row((0, 1), 1, "c", 100, 9.0),
        row((0, 1), 1, "d", 100, 9.0),
        row((0, 1), 2, "other-task", 999, 0.0),
        row((1, 0), 1, "other-tile", 999, 0.0),
        row(None, None, "noc", 0, 3.0),
    ]
    profile = FunctionProfile(rows, 4.0)
    assert [r.function for r in profile.top((0, 1), 1)] == ["b", "c", "d", "a"]
    assert [r.function for r in profile.top((0, 1), 1, n=2)] == ["b", "c"]
    assert profile.top((1, 1), 1) == []
    assert profile.tiles() == [(0, 1), (1, 0)]


def test_profile_json_and_csv_of_a_hand_made_profile(tmp_path) -> None:
    from robosoc.chip.function_profile import COUNT_NAMES, CSV_FIELDS, NOC_ROW, FunctionProfile, ProfileRow

    first, second = COUNT_NAMES[0], COUNT_NAMES[-1]
    rows = [
        ProfileRow((0, 1), 1, "estimator", "ekf_step", 900, 500, {first: 400, second: 7, COUNT_NAMES[1]: 0}, 2500.0),
        ProfileRow((0, 1), 0, "kernel", "tick", 100, 60, {first: 60}, 500.0),
        ProfileRow((1, 0), 2, "pid", "pid_step", 300, 200, {}, 1000.0),
        ProfileRow(None, None, "", NOC_ROW, 0, 0, {}, 3000.0),
    ]
    profile = FunctionProfile(rows, 4.0, notes=["a note"])
    data = profile.to_json()
    assert data["schema"] == 1 and data["clock_ns"] == 4.0 and data["notes"] == ["a note"]
    assert data["totals"] == {
        "cycles": {"0,1": 1000, "1,0": 300},
        "instructions": {"0,1": 560, "1,0": 200},
        "tiles_uj": {"0,1": pytest.approx(0.003), "1,0": pytest.approx(0.001)},
        "noc_uj": pytest.approx(0.003),
        "total_uj": pytest.approx(0.007),
    }
    assert data["rows"][0] == {
        "tile": "0,1", "task": 1, "task_name": "estimator", "function": "ekf_step", "cycles": 900,
        "instructions": 500, "energy_nj": 2.5, "counts": {first: 400, second: 7},
    }  # fmt: skip
    assert data["rows"][3]["tile"] == "" and data["rows"][3]["task"] is None
    no_noc = FunctionProfile(rows[:3], 4.0).to_json()["totals"]
    assert no_noc["noc_uj"] == 0.0 and no_noc["total_uj"] == pytest.approx(0.004)

    table = list(csv.reader(profile.csv_text().splitlines()))
    assert tuple(table[0]) == CSV_FIELDS
    assert table[1][:7] == ["0,1", "1", "estimator", "ekf_step", "900", "500", "2.500000"]
    assert table[1][7] == "400" and table[1][-1] == "7" and table[1][8] == "0"
    assert table[4][:7] == ["", "", "", NOC_ROW, "0", "0", "3.000000"]
    assert table[4][7:] == ["0"] * len(COUNT_NAMES)
    assert profile.csv_text().endswith("\n") and "\r" not in profile.csv_text()

    json_path, csv_path = write_profile(profile, tmp_path)
    assert (json_path.name, csv_path.name) == ("profile.json", "profile.csv")
    text = json_path.read_text(encoding="utf-8")
    assert text.endswith("}\n") and '\n "schema": 1,' in text  # indented by one space
    assert json.loads(text) == json.loads(json.dumps(data))
    assert csv_path.read_text(encoding="utf-8") == profile.csv_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["profile.csv", "profile.json"]
