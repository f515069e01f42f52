"""Memory is counted before it is allocated (issue 34, item 3): a chip whose SRAM does not fit, a sweep
grid of 10**10 points and an ELF segment of 4 GiB are refused with the figure and exit 2, before
numpy or a list is asked for it."""

from __future__ import annotations

import struct
import time
from pathlib import Path

import pytest
from elftools.elf.elffile import ELFFile
from typer.testing import CliRunner

from robosoc.chip import core_state, mpsoc
from robosoc.chip.single import SingleCoreSoC
from robosoc.cli import app, exit_codes
from robosoc.config import ranges
from robosoc.config.chip import ChipConfig, TileConfig, TileOverride
from robosoc.config.ranges import MAX_CHIP_SRAM_BYTES, check_memory, format_bytes
from robosoc.config.sweep import SweepConfig, load_sweep
from robosoc.program.elf import ElfError, load_elf

runner = CliRunner()


def invoke(*args: object):
    return runner.invoke(app, [str(a) for a in args])


# --- the chip's SRAM ------------------------------------------------------------------------------------


def test_a_chip_whose_sram_together_is_too_large_is_refused_with_the_figure() -> None:
    with pytest.raises(ValueError, match=r"^tile.sram_bytes: 256 tiles x 1 GiB of SRAM = 256 GiB to simulate, more"):
        ChipConfig(width=16, height=16, tile=TileConfig(sram_bytes=2**30))
    with pytest.raises(ValueError, match=r"^tiles\[1\].sram_bytes: 256 tiles x 256 MiB of SRAM = 64 GiB"):
        ChipConfig(
            width=16,
            height=16,
            tile=TileConfig(sram_bytes=4096),
            tiles=(TileOverride(0, 0, sram_bytes=8192), TileOverride(1, 1, sram_bytes=2**28)),
        )
    largest = ChipConfig(width=16, height=16, tile=TileConfig(sram_bytes=MAX_CHIP_SRAM_BYTES // 256))
    assert largest.n_tiles * largest.tile.sram_bytes == MAX_CHIP_SRAM_BYTES


def test_run_refuses_the_chip_file_and_the_options_before_allocating(tmp_path: Path, monkeypatch) -> None:
    def no_allocation(*args, **kwargs):
        raise AssertionError("the SRAM was allocated")

    monkeypatch.setattr(core_state.CoreState, "new", no_allocation)
    chip = tmp_path / "big.toml"
    chip.write_text("width = 16\nheight = 16\n[tile]\nsram_bytes = 1073741824\n")
    elf = tmp_path / "never-read.elf"
    elf.write_bytes(b"\x7fELF")
    result = invoke("run", elf, "--chip", chip)
    assert result.exit_code == exit_codes.USAGE, result.output
    assert result.output.splitlines()[0] == (
        f"robosoc run: --chip: {chip}: tile.sram_bytes: 256 tiles x 1 GiB of SRAM = 256 GiB to simulate, "
        "more than 16 GiB (every tile gets the largest tile's SRAM)"
    )
    result = invoke("run", elf, "--mesh", "16x16", "--sram-size", 2**30)
    assert result.exit_code == exit_codes.USAGE, result.output
    assert result.output.startswith("robosoc run: --sram-size: 256 tiles x 1 GiB of SRAM = 256 GiB"), result.output
    assert "(with --mesh 16x16)" in result.output


def test_a_chip_larger_than_this_machine_is_refused_before_allocating(monkeypatch) -> None:
    monkeypatch.setattr(ranges, "host_memory_bytes", lambda: 2**30)

    def no_allocation(*args, **kwargs):
        raise AssertionError("the SRAM was allocated")

    monkeypatch.setattr(mpsoc.CoreState, "new", no_allocation)
    config = ChipConfig(width=4, height=4, tile=TileConfig(sram_bytes=2**27))
    with pytest.raises(ValueError, match=r"^sram_bytes: 16 tiles x 128 MiB of SRAM needs 2 GiB of memory, more than"):
        mpsoc.MPSoC(config)
    with pytest.raises(ValueError, match=r"^sram_size: an SRAM of 2 GiB needs 2 GiB of memory, more than this"):
        SingleCoreSoC(sram_size=2**31)
    check_memory("x", 2**30, "it")  # exactly what there is: fine
    assert format_bytes(3 * 2**29) == "1.5 GiB" and format_bytes(4096) == "4 KiB" and format_bytes(12) == "12 bytes"


# --- the sweep grid -----------------------------------------------------------------------------------


def test_a_sweep_grid_of_ten_billion_points_is_counted_not_built(tmp_path: Path, monkeypatch) -> None:
    fields = [
        "wind.gust_sigma", "duration_s", "flight.takeoff_s", "flight.climb_s", "flight.climb_rate_mps",
        "flight.descent_rate_mps", "sensors.accel_bias", "sensors.gyro_bias", "sensors.baro_sigma", "sensors.mag_sigma",
    ]  # fmt: skip
    values = ", ".join(str(1.0 + i / 10) for i in range(10))
    sweep = tmp_path / "huge.toml"
    sweep.write_text("[grid]\n" + "".join(f'"{f}" = [{values}]\n' for f in fields))

    def no_product(self):
        raise AssertionError("the grid's product was built")

    monkeypatch.setattr(SweepConfig, "assignments", no_product)
    start = time.monotonic()
    result = invoke("sweep", sweep, "--out", tmp_path / "out")
    assert time.monotonic() - start < 30
    assert result.exit_code == exit_codes.USAGE, result.output
    assert result.output.splitlines()[0] == (
        f"robosoc sweep: {sweep}: grid: 10000000000 runs (10 × 10 × 10 × 10 × 10 × 10 × 10 × 10 × 10 × 10 points "
        "× 1 seeds), more than 100000"
    )


def test_a_sweep_counts_its_points_as_it_builds_them(tmp_path: Path) -> None:
    sweep = tmp_path / "s.toml"
    sweep.write_text(
        'seeds = [1, 2]\n[grid]\n"wind.gust_sigma" = [0.0, 1.0, 2.0]\n"flight.height_m" = [1.0, 2.0]\n'
        '[[points]]\n"sensors.baro_sigma" = 0.2\n[[points]]\n"sensors.baro_sigma" = 0.3\n'
    )
    config = load_sweep(sweep)
    assert config.point_count() == len(config.assignments()) == 12


# --- ELF segments -------------------------------------------------------------------------------------


def test_the_largest_elf_segment_is_the_largest_sram() -> None:
    from robosoc.config.ranges import MAX_SRAM_BYTES
    from robosoc.program.elf import MAX_SEGMENT_BYTES

    assert MAX_SEGMENT_BYTES == MAX_SRAM_BYTES


def _with_memsz(elf: Path, out: Path, memsz: int) -> Path:
    data = bytearray(elf.read_bytes())
    with elf.open("rb") as handle:
        parsed = ELFFile(handle)
        index = [i for i, s in enumerate(parsed.iter_segments()) if s["p_type"] == "PT_LOAD"][-1]
        offset = parsed["e_phoff"] + index * parsed["e_phentsize"] + 20  # Elf32_Phdr.p_memsz
    struct.pack_into("<I", data, offset, memsz)
    out.write_bytes(data)
    return out


@pytest.mark.parametrize(
    ("memsz", "reason"),
    [
        (0xFFFFFFF0, "ends beyond the 32-bit address space"),
        (0x7FFFFFF0, "has memsz 2147483632 bytes (2 GiB), more than any tile's SRAM (1 GiB)"),
    ],
)
def test_an_elf_segment_larger_than_memory_is_refused_by_every_reader(
    memsz: int, reason: str, elves: dict[str, Path], tmp_path: Path
) -> None:
    elf = _with_memsz(elves["ok"], tmp_path / "huge.elf", memsz)
    with pytest.raises(ElfError, match=reason.replace("(", r"\(").replace(")", r"\)")):
        load_elf(elf)
    result = invoke("firmware", "size", elf)
    assert result.exit_code == exit_codes.USAGE, result.output
    assert result.output.startswith(f"robosoc firmware size: {elf}: segment ") and reason in result.output
    result = invoke("run", elf)
    assert result.exit_code == exit_codes.USAGE, result.output
    assert "Traceback" not in result.output
