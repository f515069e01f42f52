"""Messages across a 3x3 mesh: multi-packet messages, order, blocking receive, powered-off tiles."""

import struct

import pytest
from kernel_harness import BUILDS, build, run

from robosoc.chip.mpsoc import ChipError
from robosoc.config.chip import ChipConfig
from robosoc.host.images import read_stats, reassemble, tile_address

MESH = ChipConfig(width=3, height=3)  # I/O tile (0, 0), eight core tiles
NMSG, MAXLEN, BIG, BIG_FROM = 6, 900, 2000, (2, 2)


def lengths(seed: int) -> list[int]:
    """mesh.c's message lengths for a sender at address `seed`."""
    out, n = [], 2 + (seed & 255)
    for _ in range(NMSG):
        out.append(n)
        n += 151
        if n > MAXLEN:
            n -= MAXLEN - 1
    return out


@pytest.mark.parametrize("mul", BUILDS)
def test_multi_packet_ring_traffic_on_a_3x3_mesh(mul):
    elf = build("mesh.c", mul, OS_TICK_CYCLES=32768, OS_MSG_MAX_BYTES=1024, NMSG=NMSG, MAXLEN=MAXLEN, BIG=BIG)
    tiles = [MESH.tile_xy(t) for t in range(MESH.n_tiles) if MESH.tile_xy(t) != MESH.io_tile]
    chip, result = run(dict.fromkeys(tiles, elf), config=MESH, max_cycles=20_000_000)
    assert result.exit_codes == dict.fromkeys(tiles, 0)
    messages = reassemble(result.io_received)
    reports = {m.src_tile: struct.unpack("<4I", m.data) for m in messages if m.port == 3}
    ring = [tile_address(xy) for xy in tiles]  # index order, as mesh.c builds it
    assert sorted(reports) == sorted(ring)
    for i, addr in enumerate(ring):
        prev = ring[i - 1]
        assert reports[addr] == (addr, NMSG, 0, sum(lengths(prev))), f"tile 0x{addr:02x}"
    [big] = [m for m in messages if m.port == 4]
    assert big.src_tile == tile_address(BIG_FROM)
    assert big.data == bytes(i % 251 for i in range(BIG))
    for xy in tiles:
        stats = read_stats(chip, xy)
        assert (stats.pkt_malformed, stats.msg_dropped) == (0, 0)
        assert stats.msg_received == NMSG + 1  # the ring's and its own
        # one packet carries up to 116 bytes: the ring messages need ceil(len / 116) packets each
        prev = ring[ring.index(tile_address(xy)) - 1]
        assert stats.pkt_received == sum(-(-n // 116) for n in lengths(prev))
        assert chip.counters(xy)["sleep_cycle"] > 0, "receivers sleep while they wait"


@pytest.mark.parametrize("mul", BUILDS)
def test_message_to_a_powered_off_tile_is_a_chip_error(mul):
    config = ChipConfig(width=3, height=3, powered_off=((1, 1),))
    elf = build("send_to.c", mul, OS_TICK_CYCLES=32768, DEST=0x11)
    with pytest.raises(ChipError) as info:
        run({(2, 1): elf}, config=config)
    text = str(info.value)
    assert info.value.tile == (2, 1)
    assert "powered off" in text and "tile (1, 1)" in text and "os_send" in text
