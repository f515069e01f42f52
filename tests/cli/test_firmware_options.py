"""``robosoc firmware``'s configuration: defaults, then the ``--config`` file, then the options the
user typed (a default of ``--mul/--no-mul`` does not override the file); errors name ``--config``."""

from __future__ import annotations

from pathlib import Path

import click
import pytest
from click.core import ParameterSource

from robosoc.cli.errors import CliError
from robosoc.cli.firmware import _firmware
from robosoc.config.firmware import FirmwareConfig


def _ctx(mul_typed: bool) -> click.Context:
    command = click.Command("build", params=[click.Option(["--mul/--no-mul"], default=None)])
    ctx = click.Context(command)
    ctx.set_parameter_source("mul", ParameterSource.COMMANDLINE if mul_typed else ParameterSource.DEFAULT)
    return ctx


@pytest.fixture
def config(tmp_path: Path) -> Path:
    path = tmp_path / "fw.toml"
    path.write_text('arith = "float"\nmultiplier = false\nperiod_ticks = 5\n')
    return path


def test_defaults_without_file_or_options() -> None:
    assert _firmware(_ctx(False), None, None, None) == FirmwareConfig()


def test_the_file_then_the_typed_options(config: Path) -> None:
    from_file = _firmware(_ctx(False), config, None, None)
    assert (from_file.arith, from_file.multiplier, from_file.period_ticks) == ("float", False, 5)
    assert _firmware(_ctx(False), config, None, True).multiplier is False  # a default value is not typed
    typed = _firmware(_ctx(True), config, "fixed", True)
    assert (typed.arith, typed.multiplier, typed.period_ticks) == ("fixed", True, 5)


def test_a_bad_file_is_named_by_its_option(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("period_ticks = 0\n")
    with pytest.raises(CliError) as caught:
        _firmware(_ctx(False), bad, None, None)
    assert caught.value.message.startswith(f"--config: {bad}: period_ticks: ")
