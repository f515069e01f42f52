"""``robosoc run``: the exit status of a mesh run whatever the order in which tiles finish or fail, and
the complete set of counters in ``--stats`` (single core and mesh).

Exit rule (``robosoc run --help``): the program's exit code; on the MPSoC the first non-zero one, and
3 when a tile fails.  A tile that exits 0 must never hide one that exits non-zero or fails later.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from robosoc.chip.counters import counters_dict
from robosoc.cli import app
from robosoc.kernels.core_layout import CTR_SIZE, OPC_SIZE
from robosoc.toolchain import build_elf

TILE_PROGRAM = r"""
#include <stdint.h>
int main(void) {
    for (volatile int i = 0; i < DELAY; i++) {
    }
#if FAULT
    return *(volatile int *)0x20000000;  /* nothing is mapped there: the tile fails */
#else
    return CODE;
#endif
}
"""

FAST, SLOW = 50, 20000  # delay-loop iterations: a slow tile finishes long after a fast one


@pytest.fixture(scope="module")
def programs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    src = tmp_path_factory.mktemp("tiles") / "tile.c"
    src.write_text(TILE_PROGRAM)
    variants = {
        "ok-fast": (FAST, 0, 0),
        "ok-slow": (SLOW, 0, 0),
        "seven-fast": (FAST, 7, 0),
        "seven-slow": (SLOW, 7, 0),
        "five-slow": (SLOW, 5, 0),
        "fault-fast": (FAST, 0, 1),
        "fault-slow": (SLOW, 0, 1),
    }
    return {
        name: build_elf([src], defines={"DELAY": delay, "CODE": code, "FAULT": fault})
        for name, (delay, code, fault) in variants.items()
    }


# core tiles of a 2x2 mesh in tile order (x fastest, the I/O tile (0,0) excluded): (1,0), (0,1), (1,1)
EXIT_CASES = [
    (("ok-fast", "seven-slow", "ok-fast"), 7),  # a later tile exits 7 after an earlier one exited 0
    (("seven-slow", "ok-fast", "ok-fast"), 7),  # the first tile in order is the last to finish
    (("ok-fast", "ok-fast", "seven-slow"), 7),
    (("ok-slow", "ok-slow", "seven-fast"), 7),  # exits 7 first, the zeros come later
    (("ok-slow", "seven-fast", "ok-fast"), 7),
    (("ok-fast", "ok-slow", "ok-fast"), 0),
    (("ok-fast", "fault-slow", "ok-fast"), 3),  # a tile fails after another exited 0
    (("fault-slow", "ok-fast", "ok-fast"), 3),
    (("ok-slow", "ok-slow", "fault-fast"), 3),
    (("ok-fast", "seven-fast", "fault-slow"), 3),  # a failure wins over a non-zero exit
]


@pytest.mark.parametrize(("order", "status"), EXIT_CASES)
def test_mesh_exit_status_whatever_the_tile_order(
    programs: dict[str, Path], tmp_path: Path, order: tuple[str, str, str], status: int
) -> None:
    stats = tmp_path / "stats.json"
    args = ["run", *(str(programs[name]) for name in order), "--mesh", "2x2", "--stats", str(stats)]
    args += ["--exit-code", "program"]  # the programs' own codes (the default reports 0/4)
    result = CliRunner().invoke(app, args)
    assert result.exit_code == status, (order, result.stderr)
    record = json.loads(stats.read_text())
    tiles = ["1,0", "0,1", "1,1"]
    failed = [tile for tile, name in zip(tiles, order, strict=True) if name.startswith("fault")]
    if failed:
        assert record["error"] is not None and f"({failed[0].replace(',', ', ')})" in record["error"]
        assert record["tiles"][failed[0]]["state"] == "failed"
    else:
        assert record["error"] is None
        want = {tile: {"ok": 0, "seven": 7}[name.split("-")[0]] for tile, name in zip(tiles, order, strict=True)}
        assert record["exit_codes"] == want


def test_mesh_exit_status_with_two_non_zero_tiles_is_one_of_them(programs: dict[str, Path]) -> None:
    for order in (("seven-slow", "ok-fast", "five-slow"), ("five-slow", "seven-slow", "ok-fast")):
        result = CliRunner().invoke(
            app, ["run", *(str(programs[n]) for n in order), "--mesh", "2x2", "--exit-code", "program"]
        )
        assert result.exit_code in (5, 7), order


# --- the complete set of counters -----------------------------------------------------------------

# docs/platform.md, "Counters": per core
CORE_COUNTERS = {
    "jump", "branch", "memory", "add", "logic", "other", "mul", "system",  # energy classes
    "branch_cycle", "memory_cycle", "mul_cycle", "entry_cycle",  # stall cycles
    "taken_branches", "interrupts", "interrupts_lost", "traps", "device_accesses",  # events
    "cycles", "instructions",
}  # fmt: skip
# an MPSoC tile adds its sleep and DMA cycles (energy stall kinds) and its packets
TILE_EXTRA = {"sleep_cycle", "dma_cycle", "packets_sent", "packets_received"}
TASK_EXTRA = {"sleep_cycle", "dma_cycle"}
NOC_COUNTERS = {
    "router_cycles", "router_busy_cycles", "port_busy_cycles", "port_idle_cycles",
    "flit_hops", "flits_injected", "packets_delivered", "rtl_lost_headers",
    "router_gated_cycles", "router_wakeups",  # clock gating (docs/noc.md): zero unless it is on
}  # fmt: skip
ENERGY_KEYS = CORE_COUNTERS - {"taken_branches", "interrupts", "interrupts_lost", "traps", "device_accesses",
                               "cycles", "instructions"} | {"dma_cycle", "sleep_cycle"}  # fmt: skip


def test_counters_dict_produces_exactly_the_documented_names() -> None:
    produced = counters_dict(np.zeros(CTR_SIZE, np.int64), np.zeros(OPC_SIZE, np.int64), 0)
    assert set(produced) == CORE_COUNTERS


def _check_core_counters(c: dict[str, int]) -> None:
    classes = ("jump", "branch", "memory", "add", "logic", "other", "mul", "system")
    assert c["instructions"] == sum(c[k] for k in classes) > 0
    assert all(isinstance(v, int) and v >= 0 for v in c.values())


def test_single_core_stats_hold_every_counter(programs: dict[str, Path], tmp_path: Path) -> None:
    stats = tmp_path / "stats.json"
    result = CliRunner().invoke(
        app, ["run", str(programs["seven-fast"]), "--stats", str(stats), "--exit-code", "program"]
    )
    assert result.exit_code == 7
    record = json.loads(stats.read_text())
    c = record["counters"]
    assert set(c) == CORE_COUNTERS
    _check_core_counters(c)
    # platform.md §1: cycles = 3 + instructions + the stall cycles
    stalls = c["branch_cycle"] + c["memory_cycle"] + c["mul_cycle"] + c["entry_cycle"]
    assert c["cycles"] == 3 + c["instructions"] + stalls
    assert c["memory_cycle"] == 2 * c["memory"] and c["device_accesses"] >= 1  # the exit store
    # the delay loop takes a branch back every iteration; jumps add their 2 cycles on top
    assert c["taken_branches"] >= FAST - 1 and c["branch_cycle"] >= 2 * c["taken_branches"]
    assert c["branch_cycle"] % 2 == 0 and c["mul_cycle"] == c["entry_cycle"] == c["traps"] == 0
    assert set(record["energy_pj"]) == ENERGY_KEYS


def test_mesh_stats_hold_every_counter(programs: dict[str, Path], tmp_path: Path) -> None:
    stats = tmp_path / "stats.json"
    order = ("ok-fast", "seven-fast", "ok-slow")
    result = CliRunner().invoke(
        app,
        ["run", *(str(programs[n]) for n in order), "--mesh", "2x2", "--stats", str(stats), "--exit-code", "program"],
    )
    assert result.exit_code == 7
    record = json.loads(stats.read_text())
    assert set(record["tiles"]) == {"1,0", "0,1", "1,1"}
    for tile in record["tiles"].values():
        assert set(tile["counters"]) == CORE_COUNTERS | TILE_EXTRA
        _check_core_counters(tile["counters"])
        assert tile["tasks"] and all(set(t["counters"]) == CORE_COUNTERS | TASK_EXTRA for t in tile["tasks"].values())
    assert set(record["noc"]["counters"]) == NOC_COUNTERS
    assert set(record["noc"]["energy_pj"]) == {"buffers", "control", "leakage"}


def test_stats_are_two_space_json_and_a_failed_write_names_the_file(
    programs: dict[str, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from robosoc.cli import run as run_cli
    from robosoc.cli.errors import CliError

    stats = tmp_path / "stats.json"
    result = CliRunner().invoke(app, ["run", str(programs["ok-fast"]), "--stats", str(stats)])
    assert result.exit_code == 0, result.output
    text = stats.read_text()
    assert text == json.dumps(json.loads(text), indent=2) + "\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["stats.json"]  # no temporary file left

    def full(self, *args, **kwargs):  # type: ignore[no-untyped-def]
        raise OSError(28, "No space left on device")

    from robosoc import output_files

    monkeypatch.setattr(output_files, "write_atomic", full)  # the one writer of outputs
    with pytest.raises(CliError) as caught:
        run_cli._write_json(tmp_path / "again.json", {"a": 1})
    assert caught.value.message == f"--stats: {tmp_path / 'again.json'}: cannot write: No space left on device"


def test_a_mesh_that_is_not_square(programs: dict[str, Path], tmp_path: Path) -> None:
    stats = tmp_path / "stats.json"
    tiles = ("ok-fast", "seven-fast", "ok-fast", "ok-fast", "ok-fast")  # 3x2: five core tiles
    args = ["run", *(str(programs[n]) for n in tiles), "--mesh", "3x2", "--stats", str(stats)]
    result = CliRunner().invoke(app, [*args, "--exit-code", "program"])
    assert result.exit_code == 7, result.output
    assert set(json.loads(stats.read_text())["tiles"]) == {"1,0", "2,0", "0,1", "1,1", "2,1"}
