"""Powered-off and self-addressed packets are clear errors (Python API and kernel); the I/O tile helpers."""

import numpy as np
import pytest

from robosoc.chip.noc import Mesh, NocError
from robosoc.config.chip import HERMES_ROUTING_LATENCY, ChipConfig
from robosoc.kernels import noc as k


def test_python_api_rejects_bad_packets():
    mesh = Mesh(ChipConfig(width=3, height=2, powered_off=((2, 1),)))
    with pytest.raises(ValueError, match="own tile"):
        mesh.inject((1, 0), (1, 0), [1], at_cycle=0)
    with pytest.raises(ValueError, match=r"dst: tile \(2, 1\) is powered off"):
        mesh.inject((0, 0), (2, 1), [1], at_cycle=0)
    with pytest.raises(ValueError, match=r"src: tile \(2, 1\) is powered off"):
        mesh.inject((2, 1), (0, 0), [1], at_cycle=0)
    with pytest.raises(ValueError, match="outside"):
        mesh.inject((0, 0), (3, 0), [1], at_cycle=0)
    with pytest.raises(ValueError, match="max 64"):
        mesh.inject((0, 0), (1, 0), [1] * 63, at_cycle=0)
    with pytest.raises(ValueError, match="flit values"):
        mesh.inject((0, 0), (1, 0), [1 << 16], at_cycle=0)
    mesh.inject((0, 0), (1, 0), [1] * 62, at_cycle=0)  # 64 flits: fine
    mesh.run(10)
    with pytest.raises(ValueError, match="in the past"):
        mesh.inject((0, 0), (1, 0), [1], at_cycle=5)


def kernel_state():
    # 3x1 mesh, tile 2 powered off, Hermes routers
    return k.noc_alloc(3, 1, 4, HERMES_ROUTING_LATENCY, powered=np.array([1, 1, 0]), queue_rows=4)


@pytest.mark.parametrize(
    ("flits", "tile", "code"),
    [
        ([0x20, 1, 7], 0, k.STATUS_DEST_OFF),
        ([0x10, 1, 7], 1, k.STATUS_DEST_SELF),
        ([0x30, 1, 7], 0, k.STATUS_DEST_OUTSIDE),
        ([0x01, 1, 7], 0, k.STATUS_DEST_OUTSIDE),
        ([0x10, 5, 7], 0, k.STATUS_BAD_LENGTH),
        ([0x10, 0], 0, k.STATUS_SHORT_PACKET),
        ([0x00, 1, 7], 2, k.STATUS_SRC_OFF),
    ],
)
def test_kernel_send_reports_errors_immediately(flits, tile, code):
    st = kernel_state()
    st.mem[tile, k.SEND, : len(flits)] = flits
    assert k.noc_send(st.cfg, st.glob, st.tile, st.mem, tile, len(flits), 0) == code
    assert st.tile[tile, k.T_SEND_STATE] == k.SEND_IDLE  # nothing armed
    assert k.noc_idle(*st)


def test_kernel_send_while_busy_and_manual_receive():
    st = kernel_state()
    st.tile[:, k.T_RX_AUTO] = k.NONE
    st.mem[0, k.SEND, :4] = [0x10, 2, 7, 8]
    assert k.noc_send(st.cfg, st.glob, st.tile, st.mem, 0, 4, 5) == k.STATUS_OK
    assert k.noc_send(st.cfg, st.glob, st.tile, st.mem, 0, 4, 5) == k.STATUS_NI_BUSY
    assert k.noc_run(*st, 1000, 1) == k.STATUS_OK
    # stopped right after the delivery: 5 + 2 * 5 + 3 = 18 (one hop, 5 cycles per router)
    assert st.glob[k.G_CYCLE] == 19 and st.glob[k.G_NEV] == 1
    assert st.ev[0, : k.EV_FLITS + 4].tolist() == [1, 18, 4, 15, 0x10, 2, 7, 8]
    assert st.tile[1, k.T_RX_STATE] == k.RX_HELD and st.mem[1, k.RECV, :4].tolist() == [0x10, 2, 7, 8]
    assert k.noc_idle(*st)
    k.noc_rx_free(st.tile, 1)
    assert st.tile[1, k.T_RX_STATE] == k.RX_ACCEPT


def test_kernel_queue_error_is_reported_not_hung():
    st = kernel_state()
    row = [0, 10, 3, k.NONE, k.NONE, k.NONE, 0x20, 1, 9]  # tile 0 -> (2,0), powered off, ready at 10
    st.queue[0, : len(row)] = row
    st.tile[0, k.T_Q_HEAD] = st.tile[0, k.T_Q_TAIL] = 0
    assert k.noc_run(*st, 1_000_000, 100) == k.STATUS_DEST_OFF
    assert st.glob[k.G_ERR_TILE] == 0 and st.glob[k.G_ERR_CYCLE] == 10 and st.glob[k.G_CYCLE] == 11
    assert st.glob[k.G_INJECTED] == 0 and k.noc_idle(*st)


def test_mesh_raises_kernel_errors():
    mesh = Mesh(ChipConfig(width=3, height=1, powered_off=((2, 0),)))
    pid = mesh.inject((0, 0), (1, 0), [1, 2], at_cycle=4)
    mesh.state.queue[pid, k.Q_FLITS] = 0x20  # corrupt the destination as buggy firmware would
    with pytest.raises(NocError, match=r"cycle 4, tile \(0, 0\): destination tile is powered off") as err:
        mesh.run(100)
    assert err.value.code == k.STATUS_DEST_OFF and err.value.tile == (0, 0)
    mesh.run(100)  # the packet was dropped; the mesh keeps working
    assert mesh.deliveries() == [] and mesh.idle


def test_io_tile_door():
    """Default 2x2 with (1,0) powered off: the outside sends to (1,1) through (1,0)'s router, which keeps
    forwarding, and (0,1) and (1,1) send to the I/O tile. 5 cycles per router:

    * I/O tile -> (1,1), 6 flits in 100, 2 hops (via (1,0)): 100 + 3 * 5 + 5 = 120;
    * (0,1) -> (0,0), 10 flits in 50, 1 hop: header crosses (0,1) in 55, tail 64; 50 + 2 * 5 + 9 = 69;
    * (1,1) -> (0,0), 4 flits in 60, 2 hops via (0,1) (x first): crosses (1,1) in 65, arrives at (0,1)
      in 65 and requests in 66 (its SOUTH output free from 66), crosses 70; (0,0)'s NORTH buffer was left
      by the first packet's tail in 69, so it arrives in 70 at an idle buffer: crosses 75, tail 78.
    """
    mesh = Mesh(ChipConfig(powered_off=((1, 0),)))
    assert mesh.io_tile == (0, 0)
    mesh.io_send((1, 1), [1, 2, 3, 4], at_cycle=100)
    mesh.inject((0, 1), (0, 0), [9] * 8, at_cycle=50)
    mesh.inject((1, 1), (0, 0), [8] * 2, at_cycle=60)
    mesh.run(1000)
    assert mesh.io_received() == [(69, (0x00, 8, *[9] * 8)), (78, (0x00, 2, 8, 8))]
    assert [(d.dst, d.cycle) for d in mesh.deliveries() if d.dst != (0, 0)] == [((1, 1), 120)]
    with pytest.raises(ValueError, match="powered off"):
        mesh.io_send((1, 0), [1], at_cycle=2000)
