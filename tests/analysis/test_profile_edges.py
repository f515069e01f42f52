"""The profile at its edges: code without symbols, tasks without names or counters, a run that was not
profiled, and the check of a profile's totals against a summary, sentence by sentence."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import pytest

from robosoc.chip.energy import EnergyModel
from robosoc.chip.function_profile import (
    ENTRY_ROW,
    NOC_ROW,
    OTHER_ROWS,
    RESET_ROW,
    SLEEP_ROW,
    FunctionProfile,
    ProfileRow,
    core_profile,
    profile_totals,
    summary_mismatches,
    tile_rows,
)
from robosoc.chip.single import SingleCoreSoC
from robosoc.kernels.core_layout import PIPELINE_FILL
from robosoc.program.elf import load_elf
from robosoc.toolchain import build_elf

MODEL = EnergyModel.load()

# a loop of K addi/bnez pairs at known addresses, then the exit through the I/O port
LOOP = """
    .globl main
    .type main, @function
main:
    li t0, {k}
1:  addi t0, t0, -1
    bnez t0, 1b
    li a0, 0
    ret
    .size main, .-main
"""
K = 40


@pytest.fixture(scope="module")
def loop_soc(tmp_path_factory) -> SingleCoreSoC:
    src = tmp_path_factory.mktemp("loop") / "loop.S"
    src.write_text(LOOP.format(k=K))
    soc = SingleCoreSoC()
    soc.load(load_elf(build_elf([src], mul=True, opt="-O1")))
    soc.enable_profile()
    soc.run()
    return soc


def _loop_addresses(soc: SingleCoreSoC) -> tuple[int, int]:
    main = soc.program.symbol("main")
    return main.addr + 4, main.addr + 8  # the addi, the bnez


def test_code_without_symbols_is_profiled_by_address(loop_soc: SingleCoreSoC) -> None:
    named = core_profile(loop_soc, MODEL)
    addi, bnez = _loop_addresses(loop_soc)
    stripped = dataclasses.replace(loop_soc.program, symbols=[])
    for program in (stripped, None):  # an ELF without a symbol table, and no program at all
        rows = tile_rows(loop_soc.state, 0, (0, 0), program, {0: loop_soc.counters()}, MODEL, {0: "bare"})
        by_name = {r.function: r for r in rows}
        # every executed word is its own row, named by its address
        assert by_name[f"0x{addi:08x}"].instructions == K and by_name[f"0x{addi:08x}"].cycles == K
        assert by_name[f"0x{bnez:08x}"].instructions == K
        assert by_name[f"0x{bnez:08x}"].cycles == 3 * (K - 1) + 1  # taken costs 3, the last falls through
        assert {r.task_name for r in rows} == {"bare"}
        bare = profile_totals(FunctionProfile(rows, MODEL.clock_ns))[(0, 0)]
        assert bare == profile_totals(named)[(0, 0)]  # the same totals as with the names
        code_rows = [r for r in rows if r.function not in OTHER_ROWS]
        assert all(r.function.startswith("0x") and len(r.function) == 10 for r in code_rows)
        assert all(r.instructions > 0 for r in code_rows)


def test_a_task_without_a_name_or_counters_still_gets_its_rows(loop_soc: SingleCoreSoC) -> None:
    rows = tile_rows(loop_soc.state, 0, (2, 1), loop_soc.program, {}, MODEL, {})
    assert rows and {(r.tile, r.task, r.task_name) for r in rows} == {((2, 1), 0, "task 0")}
    functions = {r.function for r in rows}
    assert "main" in functions
    # without counters the only row that is not a function is task 0's reset (the pipeline fill)
    reset = [r for r in rows if r.function in OTHER_ROWS]
    assert [(r.function, r.cycles, r.instructions) for r in reset] == [(RESET_ROW, PIPELINE_FILL, 0)]
    named = core_profile(loop_soc, MODEL, task_name="firmware")
    assert {r.task_name for r in named.rows} == {"firmware"} and {r.task for r in named.rows} == {0}
    assert named.clock_ns == MODEL.clock_ns


def test_each_counter_gives_its_own_row(loop_soc: SingleCoreSoC) -> None:
    counters = {0: {"sleep_cycle": 1234, "entry_cycle": 7, "dma_cycle": 0}}
    rows = tile_rows(loop_soc.state, 0, (0, 0), loop_soc.program, counters, MODEL, {})
    other = [(r.function, r.cycles, r.instructions, r.counts) for r in rows if r.function in OTHER_ROWS]
    assert other == [  # in the order of OTHER_ROWS; a counter at zero gives no row
        (ENTRY_ROW, 7, 0, {"entry_cycle": 7}),
        (SLEEP_ROW, 1234, 0, {"sleep_cycle": 1234}),
        (RESET_ROW, PIPELINE_FILL, 0, {}),
    ]
    sleep = next(r for r in rows if r.function == SLEEP_ROW)
    assert sleep.energy_pj == pytest.approx(1234 * MODEL.stall["sleep_cycle"].pj, rel=1e-12)


def test_a_run_that_was_not_profiled_is_refused(tmp_path: Path) -> None:
    src = tmp_path / "loop.S"
    src.write_text(LOOP.format(k=3))
    soc = SingleCoreSoC()
    soc.load(load_elf(build_elf([src], mul=True, opt="-O1")))
    soc.run()
    with pytest.raises(RuntimeError, match=r"^profiling is off: enable it before the run$"):
        core_profile(soc, MODEL)


def _profile() -> FunctionProfile:
    rows = [
        ProfileRow((0, 1), 1, "ekf", "step", 900, 500, {}, 2_000_000.0),
        ProfileRow((1, 0), 1, "pid", "step", 300, 200, {}, 1_000_000.0),
        ProfileRow(None, None, "", NOC_ROW, 0, 0, {}, 500_000.0),
    ]
    return FunctionProfile(rows, 4.0)


def _summary() -> dict:
    return {
        "cycles": {"tiles": {"0,1": 900, "1,0": 300}},
        "energy": {"total_uj": 3.5, "noc_uj": 0.5, "tiles_uj": {"0,1": 2.0, "1,0": 1.0}},
    }


def test_summary_check_names_each_disagreement() -> None:
    profile = _profile()
    assert summary_mismatches(profile, _summary()) == []
    summary = _summary()
    summary["cycles"]["tiles"]["1,0"] = 301
    summary["energy"]["total_uj"] = 3.6
    summary["energy"]["tiles_uj"]["0,1"] = 2.1
    assert summary_mismatches(profile, summary) == [
        "tile 1,0: 300 cycles in the profile, 301 in summary.json",
        "total_uj: 3.5 uJ in the profile, 3.6 in summary.json",
        "tile 0,1: 2.0 uJ in the profile, 2.1 in summary.json",
    ]
    # a tile of the summary the profile does not have, and a value that is not a number
    summary = _summary()
    summary["energy"]["tiles_uj"]["3,3"] = 0.0
    summary["energy"]["noc_uj"] = "0.5"
    assert summary_mismatches(profile, summary) == [
        "noc_uj: 0.5 uJ in the profile, '0.5' in summary.json",
        "tile 3,3: None uJ in the profile, 0.0 in summary.json",
    ]


def test_summary_check_tolerance_and_older_summaries() -> None:
    profile = _profile()
    near = _summary()
    near["energy"]["total_uj"] = 3.5 * (1 + 5e-10)  # inside the default 1e-9
    assert summary_mismatches(profile, near) == []
    assert summary_mismatches(profile, near, rel=1e-10) == [
        f"total_uj: 3.5 uJ in the profile, {3.5 * (1 + 5e-10)!r} in summary.json"
    ]
    # a zero next to a tiny one: equal within the absolute floor of 1e-12 uJ
    tiny = FunctionProfile([ProfileRow((0, 0), 0, "t", "f", 1, 1, {}, 1e-7)], 4.0)
    assert summary_mismatches(tiny, {"energy": {"total_uj": 0.0, "noc_uj": 0.0}}) == []
    assert summary_mismatches(tiny, {"energy": {"total_uj": 2e-12, "noc_uj": 0.0}}) == [
        f"total_uj: {1e-7 / 1e6!r} uJ in the profile, 2e-12 in summary.json"
    ]
    # an older summary: no cycles, no per-tile energy; only the totals are compared
    older = {"energy": {"total_uj": 3.5, "noc_uj": 0.5}}
    assert summary_mismatches(profile, older) == []
    assert summary_mismatches(profile, {"energy": {"total_uj": 3.5, "noc_uj": 0.5, "tiles_uj": None}}) == []
    assert math.isclose(profile.to_json()["totals"]["total_uj"], 3.5)
    missing = summary_mismatches(profile, {})
    assert missing == [
        "total_uj: 3.5 uJ in the profile, None in summary.json",
        "noc_uj: 0.5 uJ in the profile, None in summary.json",
    ]
