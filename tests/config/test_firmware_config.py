"""The firmware configuration: defaults, validation with the field named, TOML loading, the seed's chip."""

from pathlib import Path

import pytest

from robosoc.config import ConfigError
from robosoc.config.chip import ChipConfig
from robosoc.config.firmware import FirmwareConfig, Placement, load_firmware_config


def test_defaults_are_the_seed_case_study():
    fw = FirmwareConfig()
    assert (fw.arith, fw.multiplier, fw.release, fw.label) == ("fixed", True, "event", "fixed+mul")
    chip = fw.seed_chip()
    assert (chip.width, chip.height, chip.io_tile, chip.powered_off) == (2, 2, (0, 0), ((1, 1),))
    fw.check_chip(chip)


@pytest.mark.parametrize(
    "changes,message",
    [
        ({"arith": "double"}, "arith: must be one of 'float', 'fixed', got 'double'"),
        ({"release": "sometimes"}, "release: must be one of 'event', 'periodic'"),
        ({"scheduler": "fifo"}, "scheduler: must be one of 'edf', 'rm'"),
        ({"tick_cycles": 1000}, "tick_cycles: must be a multiple of 16 from 4096"),
        ({"tick_cycles": 262145}, "tick_cycles: must be a multiple of 16"),
        ({"period_ticks": 0}, "period_ticks: must be between 1 and 1000000"),
        ({"placement": (Placement("estimator", (0, 1)), Placement("estimator", (1, 0)))}, r"placement\[1\].task"),
        ({"command_timeout_periods": 0}, "command_timeout_periods: must be between 1 and 1000000"),
    ],
)
def test_bad_values_name_the_field(changes, message):
    with pytest.raises(ValueError, match=message):
        FirmwareConfig(**changes)


def test_a_task_on_the_io_tile_or_a_powered_off_tile_is_refused():
    def placed(task: str, tile: tuple[int, int]) -> FirmwareConfig:
        return FirmwareConfig(placement=(Placement(task, tile),))

    with pytest.raises(ValueError, match=r"placement\[0\].tile: \[0, 0\] \(pid\) is the I/O tile"):
        placed("pid", (0, 0)).check_chip(ChipConfig())
    with pytest.raises(ValueError, match=r"placement\[0\].tile: \[1, 1\] \(estimator\) is powered off"):
        placed("estimator", (1, 1)).check_chip(ChipConfig(powered_off=((1, 1),)))
    with pytest.raises(ValueError, match=r"placement\[0\].tile: \[3, 0\] \(estimator\) is outside the 2x2 mesh"):
        placed("estimator", (3, 0)).check_chip(ChipConfig())
    # a task the placement leaves where its project puts it is checked there
    with pytest.raises(ValueError, match=r"tasks\[1\].tile: \[1, 0\] \(pid\) is powered off"):
        placed("estimator", (1, 1)).check_chip(ChipConfig(powered_off=((1, 0),)))
    assert placed("estimator", (1, 1)).seed_chip().powered_off == ((0, 1),)  # the unused tile is off


def test_toml_overrides_only_what_it_names(tmp_path: Path):
    path = tmp_path / "fw.toml"
    path.write_text('arith = "float"\nmultiplier = false\n')
    fw = load_firmware_config(path)
    assert (fw.arith, fw.multiplier, fw.release, fw.tick_cycles) == ("float", False, "event", 262144)
    path.write_text("tick_cycles = 12\n")
    with pytest.raises(ConfigError, match=r"fw.toml: tick_cycles: must be a multiple of 16"):
        load_firmware_config(path)
