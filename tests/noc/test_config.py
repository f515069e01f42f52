"""Platform configuration: defaults, TOML loading, per-tile overrides, errors that name the field."""

from pathlib import Path

import pytest

from robosoc.config import ConfigError, from_mapping
from robosoc.config.chip import (
    ARBITERS,
    HERMES_ROUTING_LATENCY,
    ChipConfig,
    NocConfig,
    TileConfig,
    load_chip_config,
)


def test_defaults_match_the_paper_platform():
    """The paper's 16-flit buffers, the Hermes RTL's switch controller (5 cycles per router: a header waits
    4 cycles at the head of its buffer and crosses in the 5th, platform.md §4)."""
    cfg = ChipConfig()
    assert (cfg.width, cfg.height, cfg.io_tile, cfg.powered_off) == (2, 2, (0, 0), ())
    assert cfg.tile == TileConfig(multiplier=True, sram_bytes=2 * 1024 * 1024, clock_period_ns=4.0)
    assert cfg.noc == NocConfig(buffer_depth=16, flit_bits=16, max_packet_flits=64, routing_latency=4, arbiter="hermes")
    assert HERMES_ROUTING_LATENCY == 4
    assert ARBITERS == ("hermes", "per-output")
    # the idealised router keeps a free routing latency
    assert NocConfig(arbiter="per-output", routing_latency=0).routing_latency == 0


def test_toml_with_overrides(tmp_path: Path):
    path = tmp_path / "chip.toml"
    path.write_text(
        """
width = 4
height = 3
io_tile = [0, 0]
powered_off = [[3, 2], [1, 1]]

[tile]
clock_period_ns = 5.0

[[tiles]]
x = 2
y = 1
multiplier = false
sram_bytes = 65536

[noc]
buffer_depth = 4
routing_latency = 5
arbiter = "per-output"
"""
    )
    cfg = load_chip_config(path)
    assert (cfg.width, cfg.height, cfg.n_tiles) == (4, 3, 12)
    assert cfg.powered_off == ((3, 2), (1, 1))
    assert not cfg.is_powered((1, 1)) and cfg.is_powered((2, 1))
    assert cfg.tile_config((2, 1)) == TileConfig(multiplier=False, sram_bytes=65536, clock_period_ns=5.0)
    assert cfg.tile_config((0, 2)) == TileConfig(multiplier=True, sram_bytes=2 << 20, clock_period_ns=5.0)
    assert cfg.noc.buffer_depth == 4 and cfg.noc.routing_latency == 5 and cfg.noc.flit_bits == 16
    assert cfg.noc.arbiter == "per-output"
    assert cfg.tile_index((3, 2)) == 11 and cfg.tile_xy(11) == (3, 2)


@pytest.mark.parametrize(
    ("data", "field"),
    [
        ({"width": 0}, "width"),
        ({"height": 17}, "height"),
        ({"io_tile": [2, 0]}, "io_tile"),
        ({"powered_off": [[0, 0]]}, "powered_off[0]"),
        ({"powered_off": [[1, 1], [1, 1]]}, "powered_off[1]"),
        ({"powered_off": [[5, 1]]}, "powered_off[0]"),
        ({"tiles": [{"x": 1, "y": 0}, {"x": 1, "y": 0}]}, "tiles[1]"),
        ({"tiles": [{"x": 0, "y": 9}]}, "tiles[0]"),
        ({"tiles": [{"x": 0, "y": 0, "sram_bytes": 100}]}, "tiles[0].sram_bytes"),
        ({"tile": {"clock_period_ns": 0}}, "tile.clock_period_ns"),
        ({"noc": {"buffer_depth": 1}}, "noc.buffer_depth"),
        ({"noc": {"flit_bits": 8}}, "noc.flit_bits"),
        ({"noc": {"max_packet_flits": 65}}, "noc.max_packet_flits"),
        ({"noc": {"max_packet_flits": 2}}, "noc.max_packet_flits"),
        ({"noc": {"routing_latency": -1, "arbiter": "per-output"}}, "noc.routing_latency"),
        ({"noc": {"routing_latency": 2.5}}, "noc.routing_latency"),
        ({"noc": {"routing_latency": 6}}, "noc.routing_latency"),  # fixed by the Hermes switch controller
        ({"noc": {"arbiter": "crossbar"}}, "noc.arbiter"),
        ({"noc": {"depth": 4}}, "noc.depth"),
    ],
)
def test_bad_config_names_the_field(data, field):
    with pytest.raises(ConfigError) as err:
        from_mapping(ChipConfig, data, "chip.toml")
    assert err.value.field == field
    assert str(err.value).startswith(f"chip.toml: {field}: ")


def test_hermes_routing_latency_error_says_what_to_do():
    text = r"noc\.routing_latency: the Hermes switch controller fixes it at 4.*per-output"
    with pytest.raises(ConfigError, match=text):
        from_mapping(ChipConfig, {"noc": {"routing_latency": 6}}, "chip.toml")


def test_toml_error_names_file_and_field(tmp_path: Path):
    path = tmp_path / "bad.toml"
    path.write_text("width = 2\n[noc]\nbuffer_depth = 0\n")
    with pytest.raises(ConfigError, match=r"bad\.toml: noc\.buffer_depth: must be between 2 and 256"):
        load_chip_config(path)
