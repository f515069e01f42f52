"""``robosoc run --mesh``: one program on every tile, per-tile output prefixes, stats, determinism."""

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from robosoc.cli import app
from robosoc.toolchain import build_elf

PINGPONG = r"""
#include "hf_noc.h"
#include "hf_print.h"
static uint16_t tx[8], rx[8];
int main(void) {
    uint32_t me = hf_tile(), a = 0x10, b = 0x01;   /* tiles (1,0) and (0,1) */
    if (me != a && me != b) { hf_printf("idle\n"); return 0; }
    uint16_t value = 0;
    for (int round = 0; round < 4; round++) {
        if (me == a) {
            hf_set_task(1);
            uint16_t p[1] = {value};
            hf_ni_send_to(b, p, 1, tx);
            hf_set_task(0);
            hf_ni_recv_wait(rx);
            value = rx[2];
        } else {
            hf_ni_recv_wait(rx);
            hf_set_task(2);
            uint16_t p[1] = {(uint16_t)(rx[2] + 1)};
            hf_ni_send_to(a, p, 1, tx);
            hf_set_task(0);
        }
    }
    hf_printf("tile %x value %d\n", me, value);
    return me == a ? value : 0;
}
"""


@pytest.fixture(scope="module")
def elf(tmp_path_factory: pytest.TempPathFactory) -> Path:
    src = tmp_path_factory.mktemp("pp") / "pingpong.c"
    src.write_text(PINGPONG)
    return build_elf([src], mul=True)


def run(elf: Path, tmp_path: Path, *extra: str):
    stats = tmp_path / "stats.json"
    mesh = [] if "--mesh" in extra or "--off" in extra else ["--mesh", "2x2"]
    result = CliRunner().invoke(app, ["run", str(elf), *mesh, "--stats", str(stats), "--exit-code", "program", *extra])
    return result, json.loads(stats.read_text())


def test_mesh_run_prefixes_output_and_reports_per_tile_and_task(elf: Path, tmp_path: Path):
    result, stats = run(elf, tmp_path)
    assert result.exit_code == 4
    assert "[1,0] tile 10 value 4" in result.stdout
    assert "[0,1] tile 1 value 0" in result.stdout
    assert "[1,1] idle" in result.stdout
    t10 = stats["tiles"]["1,0"]
    assert t10["counters"]["packets_sent"] == 4 and stats["tiles"]["0,1"]["counters"]["packets_received"] == 4
    assert set(t10["tasks"]) == {"0", "1"} and set(stats["tiles"]["0,1"]["tasks"]) == {"0", "2"}
    task_sum = sum(t["counters"]["instructions"] for t in t10["tasks"].values())
    assert task_sum == t10["counters"]["instructions"]
    assert stats["noc"]["counters"]["packets_delivered"] == 8
    assert stats["energy_nj"] == pytest.approx(
        sum(t["energy_nj"] for t in stats["tiles"].values()) + stats["noc"]["energy_nj"]
    )


def test_two_runs_are_bit_identical(elf: Path, tmp_path: Path):
    first, a = run(elf, tmp_path)
    second, b = run(elf, tmp_path)
    assert first.stdout == second.stdout
    assert a == b


def test_powered_off_tile_and_bad_mesh(elf: Path, tmp_path: Path):
    result, stats = run(elf, tmp_path, "--off", "1,1")
    assert result.exit_code == 4 and "1,1" not in stats["tiles"]
    bad = CliRunner().invoke(app, ["run", str(elf), "--mesh", "2by2"])
    assert bad.exit_code == 2 and "WxH" in bad.output


def test_each_tile_and_task_gets_its_energy_and_a_summary_line(elf: Path, tmp_path: Path):
    from robosoc.chip.energy import EnergyModel

    model = EnergyModel.load()
    result, stats = run(elf, tmp_path)
    for name, tile in stats["tiles"].items():
        c = tile["counters"]
        assert tile["state"] == "exited" and tile["errata"] == {"irq_during_mul": 0, "mulhsu": 0}
        assert tile["energy_nj"] == pytest.approx(model.total_nj(c))
        for task in tile["tasks"].values():
            assert task["energy_nj"] == pytest.approx(model.total_nj(task["counters"]))
        assert sum(t["energy_nj"] for t in tile["tasks"].values()) == pytest.approx(tile["energy_nj"])
        x, y = name.split(",")
        code = stats["exit_codes"][name]
        line = (
            f"robosoc: tile ({x}, {y}): exited with exit code {code}, {c['cycles']} cycles, "
            f"{c['instructions']} instructions, CPI {c['cycles'] / c['instructions']:.3f}, "
            f"sleep {c['sleep_cycle']}, energy {tile['energy_nj']:.3f} nJ"
        )
        assert line + "\n" in result.stderr
    assert stats["exit_codes"]["1,0"] == 4 and stats["error"] is None


def test_a_cycle_budget_stops_the_mesh_and_keeps_the_stats(elf: Path, tmp_path: Path):
    result, stats = run(elf, tmp_path, "--max-cycles", "1000")  # the run needs about 1500
    assert result.exit_code == 3  # exit_codes.SIMULATOR_STOP
    assert stats["cycles"] == 1000
    assert stats["error"].startswith("cycle budget of 1000 cycles exhausted; still running: ")
    assert f"robosoc run: {stats['error']}" in result.stderr
    assert stats["tiles"]["1,0"]["state"] == "running" and "1,0" not in stats["exit_codes"]


def test_the_chip_line_adds_the_noc_and_goes_to_stderr(elf: Path, tmp_path: Path):
    result, stats = run(elf, tmp_path)
    noc = stats["noc"]
    assert noc["energy_nj"] == pytest.approx(sum(noc["energy_pj"].values()) / 1000)
    line = (
        f"robosoc: NoC 8 packets, {noc['counters']['flit_hops']} flit-hops, energy {noc['energy_nj']:.3f} nJ; "
        f"chip {stats['cycles']} cycles, energy {stats['energy_nj']:.3f} nJ\n"
    )
    assert line in result.stderr and "robosoc" not in result.stdout
    assert "headers found no room" not in result.stderr  # none lost on this run


def test_ctrl_c_during_a_mesh_run_keeps_the_stats(elf: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    from robosoc.chip.mpsoc import MPSoC

    def interrupted(self, *args, **kwargs):
        self.step(500)  # some of the run, then Ctrl-C
        raise KeyboardInterrupt

    monkeypatch.setattr(MPSoC, "run", interrupted)
    result, stats = run(elf, tmp_path)
    assert result.exit_code == 130  # exit_codes.INTERRUPTED
    assert stats["error"] == "interrupted" and stats["cycles"] == 500 and stats["exit_codes"] == {}
    assert "robosoc run: interrupted\n" in result.stderr


MULTIPLY = (
    '#include "hf_print.h"\nint main(void) { volatile unsigned a = 7, b = 6; hf_printf("%u\\n", a * b); return 5; }\n'
)


@pytest.fixture(scope="module")
def multiply(tmp_path_factory: pytest.TempPathFactory) -> Path:
    src = tmp_path_factory.mktemp("mul") / "multiply.c"
    src.write_text(MULTIPLY)
    return build_elf([src], mul=True)


def test_mesh_size_multiplier_and_sram_reach_every_tile(multiply: Path, tmp_path: Path):
    result, stats = run(multiply, tmp_path, "--mesh", "3x2")
    assert stats["mesh"] == [3, 2] and len(stats["tiles"]) == 5  # six tiles, one of them the I/O tile
    assert result.stdout.count("] 42\n") == 5
    no_mul, stats = run(multiply, tmp_path, "--mesh", "3x2", "--no-mul")
    assert no_mul.exit_code == 3 and "multiply instruction on a core without the multiplier" in stats["error"]
    small, stats = run(multiply, tmp_path, "--mesh", "3x2", "--sram-size", "4096")
    assert small.exit_code == 3 and "store to unmapped address 0x40000ffc" not in stats["error"]
    assert "store to unmapped address 0x401ffffc" in stats["error"]  # the stack of a 2 MiB build: past 4 KiB


def test_off_without_mesh_is_the_default_2x2_and_mesh_errors_name_the_option(multiply: Path, tmp_path: Path):
    _, stats = run(multiply, tmp_path, "--off", "1,0")
    assert stats["mesh"] == [2, 2] and set(stats["tiles"]) == {"0,1", "1,1"}
    bad = CliRunner().invoke(app, ["run", str(multiply), "--mesh", "2by2"])
    assert bad.exit_code == 2 and "robosoc run: --mesh: " in bad.stderr


def test_a_program_that_does_not_fit_the_tiles_sram_is_refused_before_running(tmp_path: Path):
    src = tmp_path / "big.c"
    src.write_text("volatile char big[8192] = {1};\nint main(void) { return big[0]; }\n")
    big = build_elf([src], mul=True)
    for programs in ([big], [big, big, big]):  # one for every tile, or one per tile
        result = CliRunner().invoke(app, ["run", *map(str, programs), "--mesh", "2x2", "--sram-size", "4096"])
        assert result.exit_code == 2, result.output
        assert f"robosoc run: {big}: segment " in result.stderr
        assert "is outside the allowed memory (" in result.stderr


def test_stats_may_not_overwrite_the_program(multiply: Path, tmp_path: Path):
    copy = tmp_path / "m.elf"
    copy.write_bytes(multiply.read_bytes())
    result = CliRunner().invoke(app, ["run", str(copy), "--mesh", "2x2", "--stats", str(copy)])
    assert result.exit_code == 2 and "robosoc run: --stats: " in result.stderr
    assert copy.read_bytes() == multiply.read_bytes()
