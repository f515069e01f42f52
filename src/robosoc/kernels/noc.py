"""Hermes-style mesh NoC with per-tile network-interface datapath, as numba kernels over integer arrays.

Model (see docs/noc.md for the full description and the latency formula):

* A ``width`` × ``height`` mesh of 5-port routers (ports EAST, WEST, NORTH, SOUTH, LOCAL, Hermes order),
  an input FIFO of ``depth`` flits per port, XY routing, wormhole switching and credit flow control.
* Two router models (``cfg[C_ARBITER]``): ``ARB_HERMES``, the Hermes RTL's single switch-control state
  machine per router (request, select, route and check, connect, cross: at most one new connection
  every 5 cycles, a failed attempt 3 cycles, output released 2 cycles after the tail), and
  ``ARB_PER_OUTPUT``, an idealised router with one round-robin arbiter per output port and a routing
  latency of ``cfg[C_RLAT]`` cycles.
* Two-phase semantics: :func:`noc_step` first decides every request, grant and flit move from the state
  at the start of the cycle, then commits all moves (the cycle edge). A flit moves at most one hop per
  cycle and the result does not depend on the order in which routers are evaluated (``cfg[C_REVERSE]``
  flips that order, for tests).
* Per tile, an NI with a 64-flit send memory (injected into the router's local input at 1 flit/cycle
  when credits allow) and a 64-flit receive memory (filled from the local output at 1 flit/cycle; when
  a packet is complete a delivery event is recorded and the memory is held until freed).

State: eight arrays, bundled in :class:`NocState` (a NamedTuple, so ``noc_step(*state, cycle)`` works
and :func:`noc_snapshot` / :func:`noc_restore` copy it). Column indices are the module constants below.

======  ===============================  ===================================================
array   shape, dtype                     contents
======  ===============================  ===================================================
cfg     (CFG_SIZE,) int64                constants: C_WIDTH, C_HEIGHT, C_DEPTH, C_RLAT, ...
glob    (GLOB_SIZE,) int64               G_CYCLE (next cycle), G_STATUS, G_ERR_*, counters
buf     (tiles, 5, depth) int64          input FIFOs, circular
port    (tiles, 5, PORT_COLS) int64      per port: FIFO head/count, input routing state, output
                                         owner/round-robin/credits, scratch, energy counters
tile    (tiles, TILE_COLS) int64         per tile: router flit count, NI send and receive state
mem     (tiles, 2, 64) int64             NI send memory ``[t, SEND]``, receive memory ``[t, RECV]``
ev      (capacity, EV_COLS) int64        delivery events: tile, cycle, length, first cycle, flits
queue   (rows, Q_COLS) int64             optional per-tile packet queue feeding the send memory
======  ===============================  ===================================================

Tile index ``t = y * width + x``; NoC address ``(x << 4) | y``; NORTH is ``y + 1``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from robosoc.config.chip import ARBITERS
from robosoc.config.chip import MIN_PACKET_FLITS as MIN_PACKET_FLITS  # the chip kernel reads it here
from robosoc.kernels.borrowed import UNCOUNTED
from robosoc.kernels.core_layout import NEVER

# ports (Hermes order)
EAST, WEST, NORTH, SOUTH, LOCAL = 0, 1, 2, 3, 4
NPORTS = 5
PORT_NAMES = ("east", "west", "north", "south", "local")
MEM_FLITS = 64
SEND, RECV = 0, 1
NONE = -1
BIG = NEVER  # the same 'never' as the rest of the chip: times are compared across kernels

# router models (cfg[C_ARBITER]), numbered as named in the chip configuration
ARB_HERMES = ARBITERS.index("hermes")
ARB_PER_OUTPUT = ARBITERS.index("per-output")

# Hermes switch control (one state machine per router; RTL states in brackets). A buffer raises its
# request the cycle after its header arrived at an idle buffer (or the second cycle after the previous
# tail left it, if the header was queued behind that tail). SC_IDLE [S1] moves on when some request is
# up; SC_SELECT [S2] picks, among the requests up in that cycle, the first input in cyclic port order
# after the last one selected; SC_ROUTE [S3] computes the XY output and checks that it is free, else
# goes back to SC_IDLE (a failed attempt: 3 cycles); SC_CONNECT [S4-S6] connects input and output;
# in SC_CROSS [S7] the header crosses. Hence 5 cycles per connection, and an uncontended header that
# arrived in cycle a crosses in a + 5 (requests a + 1, S1 a + 1 ... S7 a + 5): routing latency 4.
SC_IDLE, SC_SELECT, SC_ROUTE, SC_CONNECT, SC_CROSS = range(5)
HERMES_RELEASE = 2  # an output whose tail crossed in cycle c is free for a new connection from c + 2
HERMES_MIN_ROUTER_CYCLES = 4  # request up in a cycle the controller is in SC_SELECT: crosses 3 later

# cfg: constants
C_WIDTH, C_HEIGHT, C_NTILES, C_DEPTH, C_RLAT, C_MAXPKT, C_FLITMASK, C_REVERSE, C_ARBITER, C_READ_POINTER = range(10)
# C_READ_POINTER: 1 = the Hermes buffer's read-pointer timing (tail credit, bubble), see noc_alloc
C_GATE = 10  # clock gating: a router that held no flit for this many cycles stops its clock (NONE: never)
C_WAKE = 11  # clock gating: cycles a stopped router needs to restart its clock when a flit arrives
CFG_SIZE = 12

# glob: scalars that change
G_CYCLE = 0  # next cycle to simulate
G_STATUS = 1  # first error (STATUS_*), 0 if none; sticky until the caller clears it
G_ERR_TILE = 2
G_ERR_CYCLE = 3
G_NEV = 4  # rows used in ev
G_INFLIGHT = 5  # flits in router buffers
G_SENDING = 6  # NIs currently injecting
G_DELIVERED = 7  # packets delivered (all time)
G_HOPS = 8  # router-to-router flit moves (all time)
G_INJECTED = 9  # flits injected by NIs (all time)
G_EJECTED = 10  # flits written into receive memories (all time)
G_CYCLE0 = 11  # cycle at which the counters started
G_RTL_LOST = 12  # headers that would have been lost on the RTL (no room downstream in their crossing cycle)
GLOB_SIZE = 13

# port columns; an index p is both input port p and output port p of the router
P_HEAD = 0  # input FIFO head slot
P_COUNT = 1  # input FIFO occupancy
P_WAIT = 2  # per-output: cycles the header at the head has waited for routing
P_CONN = 3  # output port this input is connected to, or NONE
P_SENT = 4  # flits of the current packet already forwarded by this input
P_TOTAL = 5  # flits of the current packet (known once flit 1 has passed), BIG before
P_REQ = 6  # scratch: output requested this cycle, or NONE
P_OWNER = 7  # input port holding this output, or NONE
P_RR = 8  # per-output: round-robin pointer of this output: first input considered at the next grant
P_CREDIT = 9  # free slots in the downstream buffer as known to this output
P_MOVE = 10  # scratch: this output moves a flit this cycle
P_FLITS_IN = 11  # energy: flits written into this input buffer
P_FLITS_OUT = 12  # energy: flits sent through this output
P_BUSY = 13  # energy: cycles this input buffer held at least one flit at the cycle start
P_HREQ = 14  # hermes: first cycle this input's request is up (its header at the head), BIG if none
P_IDLE_AT = 15  # hermes: first cycle this input buffer was idle after its last tail left
P_FREE_AT = 16  # hermes: first cycle this output may be connected again after its last tail
# The Hermes buffer's read pointer (cfg[C_READ_POINTER]; docs/noc.md, "The buffer's read pointer"): the slot
# of a packet's last flit, and of a flit that left the buffer empty in the middle of a packet, comes back
# late; and a flit arriving into a buffer that ran empty in the middle of a packet leaves a cycle late.
P_HELD_UNTIL = 17  # hermes: the upstream may not use one of this buffer's free slots before this cycle
P_DRY_AT = 18  # hermes: cycle this buffer ran empty in the middle of a packet (its slot held), BIG if not
P_READY_AT = 19  # hermes: first cycle the flit at the head may leave (the bubble after running empty)
PORT_COLS = 20

# tile columns
T_POWERED = 0  # core, memory and NI on (the router is always on)
T_RFLITS = 1  # flits in this router's input buffers
T_MOVES = 2  # scratch: some output of this router moves a flit this cycle
T_BUSY = 3  # energy: cycles the router held at least one flit at the cycle start (control logic active)
T_SEND_STATE = 4  # SEND_IDLE, SEND_PENDING, SEND_ACTIVE
T_SEND_LEN = 5
T_SEND_POS = 6  # next send-memory flit to inject
T_SEND_START = 7  # first cycle the NI may inject
T_SEND_ROW = 8  # queue row being sent, or NONE
T_NI_CREDIT = 9  # free slots in the router's local input buffer as known to the NI
T_NI_MOVE = 10  # scratch: the NI injects a flit this cycle
T_RX_STATE = 11  # RX_ACCEPT or RX_HELD
T_RX_COUNT = 12  # flits in the receive memory
T_RX_TOTAL = 13  # length of the packet being received (BIG until flit 1 arrived)
T_RX_FIRST = 14  # cycle flit 0 of the packet being received was written
T_RX_AUTO = 15  # NONE: software frees the receive memory; d >= 0: freed automatically d cycles later
T_RX_FREE_AT = 16  # cycle from which an automatically freed memory accepts again, or NONE
T_Q_HEAD = 17  # next queue row to load into the send memory, or NONE
T_Q_TAIL = 18  # last queue row of this tile (for appending), or NONE
T_SENT_PKTS = 19
T_RECV_PKTS = 20
T_SEND_FIRST = 21  # cycle the first flit of the last started packet entered the router
T_SEND_DONE = 22  # first cycle after the last flit of the last packet entered the router
T_SC_STATE = 23  # hermes: switch-control state SC_* of this cycle
T_SC_SEL = 24  # hermes: input selected last (the selection starts after it)
T_SC_OUT = 25  # hermes: output of the connection being made
T_RTL_LOST = 26  # headers that would have been lost on the RTL at this router (see G_RTL_LOST)
T_RX_STALL_FROM = 27  # the receive memory accepts no flit in cycles [T_RX_STALL_FROM, T_RX_STALL_UNTIL)
T_RX_STALL_UNTIL = 28
T_TX_STALL_FROM = 29  # the NI injects no flit in cycles [T_TX_STALL_FROM, T_TX_STALL_UNTIL)
T_TX_STALL_UNTIL = 30
# clock gating (cfg[C_GATE], docs/noc.md "Clock gating"): only read and written by _clock_gate
T_LAST_FLIT = 31  # last cycle this router held a flit at the cycle start (-1 before any)
T_WAKE_AT = 32  # first cycle this router's clock runs again after a wake-up (NONE: not waking)
T_GATED = 33  # energy: cycles this router's clock was stopped, up to its last wake-up
T_WAKES = 34  # wake-ups of this router
TILE_COLS = 35

SEND_IDLE, SEND_PENDING, SEND_ACTIVE = 0, 1, 2
RX_ACCEPT, RX_HELD = 0, 1

# queue rows (a per-tile linked list, in the order the NI sends them)
Q_TILE, Q_READY, Q_LEN, Q_NEXT, Q_START, Q_END = range(6)
Q_FLITS = 6
Q_COLS = Q_FLITS + MEM_FLITS

# delivery events
EV_TILE, EV_CYCLE, EV_LEN, EV_FIRST = range(4)
EV_FLITS = 4
EV_COLS = EV_FLITS + MEM_FLITS

# status codes
STATUS_OK = 0
STATUS_DEST_OFF = 1  # destination tile is powered off
STATUS_DEST_SELF = 2  # destination is the sending tile
STATUS_DEST_OUTSIDE = 3  # destination address is not a tile of the mesh
STATUS_BAD_LENGTH = 4  # size flit inconsistent with the send length, or too long / too short
STATUS_SRC_OFF = 5  # the sending tile is powered off
STATUS_NI_BUSY = 6  # send requested while the NI is still sending
STATUS_EVENTS_FULL = 7  # a delivery event was lost: the ev array was full
STATUS_SHORT_PACKET = 8  # fewer than MIN_PACKET_FLITS flits
STATUS_TEXT = {
    STATUS_OK: "ok",
    STATUS_DEST_OFF: "destination tile is powered off",
    STATUS_DEST_SELF: "packet addressed to its own tile",
    STATUS_DEST_OUTSIDE: "destination address is outside the mesh",
    STATUS_BAD_LENGTH: "size flit does not match the packet length",
    STATUS_SRC_OFF: "sending tile is powered off",
    STATUS_NI_BUSY: "network interface is still sending",
    STATUS_EVENTS_FULL: "delivery event buffer overflowed",
    STATUS_SHORT_PACKET: f"packet shorter than {MIN_PACKET_FLITS} flits (destination, size, at least one payload "
    "flit): on the Hermes RTL it would keep its connection open and swallow the next packet",
}


class NocState(NamedTuple):
    """The complete NoC state; pass it to the kernels as ``*state``."""

    cfg: np.ndarray
    glob: np.ndarray
    buf: np.ndarray
    port: np.ndarray
    tile: np.ndarray
    mem: np.ndarray
    ev: np.ndarray
    queue: np.ndarray


def noc_alloc(
    width: int,
    height: int,
    depth: int,
    routing_latency: int,
    max_packet_flits: int = MEM_FLITS,
    flit_bits: int = 16,
    powered: np.ndarray | None = None,
    event_capacity: int = 1024,
    queue_rows: int = 0,
    rx_auto_free: int = NONE,
    reverse: bool = False,
    arbiter: str = "hermes",
    read_pointer: bool = True,
    gate_after: int = NONE,
    wake_cycles: int = 0,
) -> NocState:
    """Allocate an empty, idle NoC at cycle 0 (plain numpy; parameters are checked by ChipConfig).

    Args:
        powered: bool per tile index (default all on).
        event_capacity: rows of the delivery-event array.
        queue_rows: rows of the packet queue (0 if the caller drives the send memories itself).
        rx_auto_free: NONE to let software free receive memories, else the delay in cycles.
        reverse: evaluate routers in reverse index order (test hook; results must not change).
        arbiter: router model, one of ``config.chip.ARBITERS``.
        read_pointer: Hermes only: the RTL buffer's read-pointer timing (a tail's slot usable two cycles
            after it left, the slot of a flit that left the buffer empty mid-packet held until the next
            flit is presented, and that flit one cycle late). False gives the model before issue 38
            (every freed slot usable the next cycle, no bubble), kept for `robosoc bench noc`'s
            before/after comparison.
        gate_after: clock gating: a router that held no flit for this many cycles stops its clock
            (NONE: no gating).
        wake_cycles: clock gating: cycles a stopped router takes to restart when a flit arrives.
    """
    n = width * height
    cfg = np.zeros(CFG_SIZE, np.int64)
    cfg[C_WIDTH], cfg[C_HEIGHT], cfg[C_NTILES] = width, height, n
    cfg[C_DEPTH], cfg[C_RLAT], cfg[C_MAXPKT] = depth, routing_latency, max_packet_flits
    cfg[C_FLITMASK] = (1 << flit_bits) - 1
    cfg[C_REVERSE] = int(reverse)
    cfg[C_ARBITER] = ARBITERS.index(arbiter)
    cfg[C_READ_POINTER] = int(read_pointer and arbiter == "hermes")
    cfg[C_GATE], cfg[C_WAKE] = gate_after, wake_cycles
    glob = np.zeros(GLOB_SIZE, np.int64)
    buf = np.zeros((n, NPORTS, depth), np.int64)
    port = np.zeros((n, NPORTS, PORT_COLS), np.int64)
    port[:, :, P_CONN] = NONE
    port[:, :, P_TOTAL] = BIG
    port[:, :, P_REQ] = NONE
    port[:, :, P_OWNER] = NONE
    port[:, :, P_CREDIT] = depth
    port[:, :, P_HREQ] = BIG
    port[:, :, P_DRY_AT] = BIG
    tile = np.zeros((n, TILE_COLS), np.int64)
    tile[:, T_POWERED] = 1 if powered is None else np.asarray(powered, dtype=np.int64)
    tile[:, T_SEND_ROW] = NONE
    tile[:, T_NI_CREDIT] = depth
    tile[:, T_RX_TOTAL] = BIG
    tile[:, T_RX_FIRST] = NONE
    tile[:, T_RX_AUTO] = rx_auto_free
    tile[:, T_RX_FREE_AT] = NONE
    tile[:, T_Q_HEAD] = NONE
    tile[:, T_Q_TAIL] = NONE
    tile[:, T_SEND_FIRST] = NONE
    tile[:, T_SC_STATE] = SC_IDLE
    tile[:, T_SC_SEL] = EAST  # after reset the selection starts after EAST
    tile[:, T_LAST_FLIT] = -1
    tile[:, T_WAKE_AT] = NONE
    mem = np.zeros((n, 2, MEM_FLITS), np.int64)
    ev = np.zeros((max(event_capacity, 1), EV_COLS), np.int64)
    queue = np.zeros((queue_rows, Q_COLS), np.int64)
    return NocState(cfg, glob, buf, port, tile, mem, ev, queue)


def noc_snapshot(state: NocState) -> NocState:
    """A deep copy of the state (a few ``memcpy``s)."""
    return NocState(*(a.copy() for a in state))


def noc_restore(state: NocState, snapshot: NocState) -> None:
    """Copy ``snapshot`` back into ``state`` in place (arrays keep their identity)."""
    for dst, src in zip(state, snapshot, strict=True):
        np.copyto(dst, src)


def min_router_cycles(arbiter: int, routing_latency: int) -> int:
    """Fewest cycles from a header's arrival in a router's input buffer to its crossing (docs/noc.md).

    Per-output: the header waits ``routing_latency`` cycles at the head, then crosses. Hermes: its
    request is up the cycle after it arrives and, if the switch controller is already in SC_SELECT then
    (another input asked a cycle earlier), it crosses 3 cycles later: one cycle less than uncontended.
    This is also the router's lookahead: a packet entering in cycle s changes no other flit move before
    s + min_router_cycles.
    """
    if arbiter == ARB_HERMES:
        return HERMES_MIN_ROUTER_CYCLES
    return routing_latency + 1


@njit(cache=True)
def noc_address(width, t):
    """NoC address ``(x << 4) | y`` of tile index ``t``."""
    return ((t % width) << 4) | (t // width)


@njit(cache=True)
def _route(width, t, dest):
    """XY routing: output port at router ``t`` for a header addressed to ``dest``."""
    x = t % width
    y = t // width
    dx = (dest >> 4) & 0xF
    dy = dest & 0xF
    if dx > x:
        return EAST
    if dx < x:
        return WEST
    if dy > y:
        return NORTH
    if dy < y:
        return SOUTH
    return LOCAL


@njit(cache=True)
def _neighbour(width, t, p):
    """Tile on the other side of port ``p`` of router ``t`` (never LOCAL)."""
    if p == EAST:
        return t + 1
    if p == WEST:
        return t - 1
    if p == NORTH:
        return t + width
    return t - width


@njit(cache=True)
def _opposite(p):
    """The input port of the neighbour that output ``p`` feeds (EAST <-> WEST, NORTH <-> SOUTH)."""
    return p ^ 1


@njit(cache=True)
def noc_check_packet(cfg, tile, mem, t, length):
    """Validate the packet in tile ``t``'s send memory; returns a STATUS_* code (0 if it may be sent)."""
    if tile[t, T_POWERED] == 0:
        return STATUS_SRC_OFF
    if length < MIN_PACKET_FLITS:
        return STATUS_SHORT_PACKET
    if length > cfg[C_MAXPKT] or mem[t, SEND, 1] + 2 != length:
        return STATUS_BAD_LENGTH
    dest = mem[t, SEND, 0]
    dx = dest >> 4
    dy = dest & 0xF
    if dest < 0 or dx >= cfg[C_WIDTH] or dy >= cfg[C_HEIGHT]:
        return STATUS_DEST_OUTSIDE
    d = dy * cfg[C_WIDTH] + dx
    if d == t:
        return STATUS_DEST_SELF
    if tile[d, T_POWERED] == 0:
        return STATUS_DEST_OFF
    return STATUS_OK


# an explicit signature: called with a constant code too, numba would compile it once more for that literal
@njit("void(int64[::1], int64, int64, int64)", cache=True)
def _report(glob, code, t, cycle):
    if glob[G_STATUS] == STATUS_OK:
        glob[G_STATUS] = code
        glob[G_ERR_TILE] = t
        glob[G_ERR_CYCLE] = cycle


@njit(cache=True)
def noc_send(cfg, glob, tile, mem, t, length, start_cycle):
    """Arm tile ``t``'s NI to inject the ``length`` flits already in ``mem[t, SEND]`` from ``start_cycle``.

    Returns a STATUS_* code; on error nothing is armed (the caller decides, e.g. a bus error).
    """
    if tile[t, T_SEND_STATE] != SEND_IDLE:
        return STATUS_NI_BUSY
    code = noc_check_packet(cfg, tile, mem, t, length)
    if code != STATUS_OK:
        return code
    tile[t, T_SEND_STATE] = SEND_PENDING
    tile[t, T_SEND_LEN] = length
    tile[t, T_SEND_POS] = 0
    tile[t, T_SEND_START] = start_cycle
    tile[t, T_SEND_ROW] = NONE
    return STATUS_OK


@njit(cache=True)
def noc_rx_free(tile, t):
    """Software has copied the received packet: tile ``t``'s receive memory accepts flits again."""
    tile[t, T_RX_STATE] = RX_ACCEPT
    tile[t, T_RX_COUNT] = 0
    tile[t, T_RX_TOTAL] = BIG
    tile[t, T_RX_FIRST] = NONE
    tile[t, T_RX_FREE_AT] = NONE


@njit(cache=True)
def _ni_load(cfg, glob, tile, mem, queue, t, cycle):
    """Tile ``t``'s NI is idle and its next queued packet is ready: copy it into the send memory."""
    row = tile[t, T_Q_HEAD]
    tile[t, T_Q_HEAD] = queue[row, Q_NEXT]
    if queue[row, Q_NEXT] == NONE:
        tile[t, T_Q_TAIL] = NONE
    length = queue[row, Q_LEN]
    for k in range(length):
        mem[t, SEND, k] = queue[row, Q_FLITS + k]
    code = noc_check_packet(cfg, tile, mem, t, length)
    if code != STATUS_OK:
        _report(glob, code, t, cycle)
        queue[row, Q_START] = NONE
        queue[row, Q_END] = NONE
        return
    tile[t, T_SEND_STATE] = SEND_ACTIVE
    tile[t, T_SEND_LEN] = length
    tile[t, T_SEND_POS] = 0
    tile[t, T_SEND_START] = cycle
    tile[t, T_SEND_ROW] = row
    glob[G_SENDING] += 1


@njit(cache=True)
def _deliver(glob, tile, mem, ev, t, cycle):
    """The last flit of a packet reached tile ``t``'s receive memory: record it and hold the memory."""
    tile[t, T_RX_STATE] = RX_HELD
    tile[t, T_RECV_PKTS] += 1
    glob[G_DELIVERED] += 1
    length = tile[t, T_RX_COUNT]
    n = glob[G_NEV]
    if n < ev.shape[0]:
        ev[n, EV_TILE] = t
        ev[n, EV_CYCLE] = cycle
        ev[n, EV_LEN] = length
        ev[n, EV_FIRST] = tile[t, T_RX_FIRST]
        for k in range(length):
            ev[n, EV_FLITS + k] = mem[t, RECV, k]
        for k in range(length, MEM_FLITS):
            ev[n, EV_FLITS + k] = 0
        glob[G_NEV] = n + 1
    else:
        _report(glob, STATUS_EVENTS_FULL, t, cycle)
    if tile[t, T_RX_AUTO] != NONE:
        tile[t, T_RX_FREE_AT] = cycle + 1 + tile[t, T_RX_AUTO]


@njit(cache=True, inline="always")
def _held(port, t, p, cycle):
    """One of the free slots of router ``t``'s input buffer ``p`` is not usable by its upstream in ``cycle``:
    the buffer's read pointer still stands on it (a tail that left two cycles ago or less, or a flit that
    left the buffer empty in the middle of a packet and whose successor is not presented yet)."""
    return port[t, p, P_DRY_AT] < cycle or cycle < port[t, p, P_HELD_UNTIL]


@njit(cache=True, inline="always")
def _room(port, tile, width, t, o, cycle):
    """Output ``o`` of router ``t`` may send a flit this cycle: a usable credit, or a receive memory
    accepting (not held by software, not stalled)."""
    if o == LOCAL:
        return (
            tile[t, T_RX_STATE] == RX_ACCEPT
            and tile[t, T_RX_COUNT] < MEM_FLITS
            and not (tile[t, T_RX_STALL_FROM] <= cycle < tile[t, T_RX_STALL_UNTIL])
        )
    credit = port[t, o, P_CREDIT]
    if credit != 1:
        return credit > 1  # a held slot is at most one of them
    return not _held(port, _neighbour(width, t, o), _opposite(o), cycle)


@njit(cache=True, inline="always")
def _ni_room(port, tile, t, cycle):
    """Tile ``t``'s NI may inject a flit into its router's local input buffer this cycle."""
    if tile[t, T_TX_STALL_FROM] <= cycle < tile[t, T_TX_STALL_UNTIL]:
        return False
    credit = tile[t, T_NI_CREDIT]
    if credit != 1:
        return credit > 1
    return not _held(port, t, LOCAL, cycle)


@njit(cache=True, inline="always")
def _arrive(port, nb, q, cycle):
    """A flit is written into buffer ``q`` of router ``nb`` at the edge of ``cycle`` (read-pointer timing).

    If the buffer had run empty in the middle of a packet, the RTL's read pointer moves onto the new flit
    only in the next cycle (the held slot comes back then) and presents it the cycle after: the flit
    leaves in ``cycle + 2`` at the earliest, one cycle later than a flit arriving behind another.
    """
    dry = port[nb, q, P_DRY_AT]
    if dry != BIG:
        if dry <= cycle:
            port[nb, q, P_READY_AT] = cycle + 2
            port[nb, q, P_HELD_UNTIL] = cycle + 2
        port[nb, q, P_DRY_AT] = BIG


# ---------------------------------------------------------------------------------- clock gating
@njit(cache=True, inline="always")
def _clock_gate(cfg, port, tile, t, cycle):
    """Clock gating of router ``t``, which holds a flit at the start of ``cycle``: whether its clock is
    still restarting in this cycle (then the router only holds its flits: no request, move or switch
    state changes, and its buffers count as active).

    A router that held no flit in the ``cfg[C_GATE]`` cycles before ``cycle`` has stopped its clock;
    the flit that arrived wakes it, and it runs again from ``cycle + cfg[C_WAKE]``: every decision it
    would have taken from ``cycle`` on comes exactly ``cfg[C_WAKE]`` cycles later.  The cycles its clock
    was stopped (the empty cycles after the first ``cfg[C_GATE]``) are counted in ``T_GATED``.
    """
    idle = cycle - 1 - tile[t, T_LAST_FLIT]  # cycles without a flit just before this one
    if idle >= cfg[C_GATE]:
        tile[t, T_GATED] += idle - cfg[C_GATE]
        tile[t, T_WAKE_AT] = cycle + cfg[C_WAKE]
        tile[t, T_WAKES] += 1
    tile[t, T_LAST_FLIT] = cycle
    if cycle < tile[t, T_WAKE_AT]:
        for p in range(NPORTS):
            if port[t, p, P_COUNT] > 0:
                port[t, p, P_BUSY] += 1
        return True
    return False


@njit(cache=True, inline="always")
def _gated(cfg, glob, tile, t: int) -> int:
    """The cycles router ``t``'s clock has been stopped up to now (``glob[G_CYCLE]``): those counted
    at its wake-ups and those of the stretch it is in (0 without clock gating)."""
    gate = cfg[C_GATE]
    if gate == NONE:
        return 0
    return tile[t, T_GATED] + max(0, glob[G_CYCLE] - 1 - tile[t, T_LAST_FLIT] - gate)


@njit(cache=True)
def gated_cycles(cfg: np.ndarray, glob: np.ndarray, tile: np.ndarray) -> np.ndarray:
    """Per router, :func:`_gated`: the cycles its clock has been stopped up to now."""
    out = np.zeros(tile.shape[0], np.int64)
    for t in range(tile.shape[0]):
        out[t] = _gated(cfg, glob, tile, t)
    return out


#: :func:`router_counts`' values, in order
ROUTER_COUNTS = (
    "cycles", "port_busy_cycles", "router_busy_cycles", "router_gated_cycles", "router_wakeups",
    "flit_hops", "flits_injected", "packets_delivered", "rtl_lost_headers",
)  # fmt: skip


@njit(cache=True)
def router_counts(cfg, glob, tile, port, off, out) -> None:
    """The routers' counters summed over the mesh into ``out`` (:data:`ROUTER_COUNTS`): the cycles
    counted, input-buffer and router cycles with a flit, stopped-clock cycles (:func:`gated_cycles`)
    of the routers not switched off (``off[t]`` zero), wake-ups, and the mesh's flit and packet
    counts (one call: numpy's sums cost a flight's period close some 15 µs)."""
    busy_ports = busy = gated = wakes = 0
    for t in range(tile.shape[0]):
        for p in range(port.shape[1]):
            busy_ports += port[t, p, P_BUSY]
        busy += tile[t, T_BUSY]
        if off[t] == 0:
            gated += _gated(cfg, glob, tile, t)
        wakes += tile[t, T_WAKES]
    out[0] = glob[G_CYCLE] - glob[G_CYCLE0]
    out[1] = busy_ports
    out[2] = busy
    out[3] = gated
    out[4] = wakes
    out[5] = glob[G_HOPS]
    out[6] = glob[G_INJECTED]
    out[7] = glob[G_DELIVERED]
    out[8] = glob[G_RTL_LOST]


@njit(**UNCOUNTED)
def noc_step(cfg, glob, buf, port, tile, mem, ev, queue, cycle):
    """Simulate one NoC cycle ``cycle``: decide everything from the cycle-start state, then commit.

    Phase 1 (per tile, any order): the NI applies what was scheduled for this edge (automatic receive
    free, loading a queued packet, a pending send reaching its start cycle) and decides whether it
    injects; the router raises requests, decides which connected outputs move a flit (owner has a flit,
    downstream has a credit) and advances its arbitration: the Hermes switch controller by one state
    (a connection it makes carries flits from the next cycle), or, per output, each free output grants
    one request round-robin (its header moves in the same cycle). Only the router's own state changes.
    Phase 2 (per tile, any order): the moves are committed. Every buffer sees at most one pop (its own
    connection) and one push (its single upstream), and pushes were allowed by the cycle-start credits,
    so commits of different tiles commute.

    (The phases are written out in one function on purpose: a numba call passing several arrays costs
    tens of nanoseconds of reference counting, more than the work of an idle router.  The function is
    compiled without reference counts, ``_nrt=False`` (:mod:`robosoc.kernels.borrowed`), and called,
    not inlined, by :func:`noc_run`: numba's ``inline="always"`` copied its 218 blocks' IR at 9 s of
    compile time, 2026-11-28.)

    Returns ``glob[G_STATUS]`` (0 unless an error was reported, now or earlier).
    """
    n = cfg[C_NTILES]
    width = cfg[C_WIDTH]
    depth = cfg[C_DEPTH]
    rlat = cfg[C_RLAT]
    reverse = cfg[C_REVERSE] != 0
    hermes = cfg[C_ARBITER] == ARB_HERMES
    read_pointer = cfg[C_READ_POINTER] != 0
    # ---------------------------------------------------------------- phase 1: decide
    for i in range(n):
        t = n - 1 - i if reverse else i
        # NI: changes scheduled for this edge, then the injection decision
        if tile[t, T_RX_FREE_AT] != NONE and tile[t, T_RX_FREE_AT] <= cycle:
            noc_rx_free(tile, t)
        send_state = tile[t, T_SEND_STATE]
        if send_state == SEND_IDLE:
            row = tile[t, T_Q_HEAD]
            if row != NONE and queue[row, Q_READY] <= cycle:
                _ni_load(cfg, glob, tile, mem, queue, t, cycle)
        elif send_state == SEND_PENDING and tile[t, T_SEND_START] <= cycle:
            tile[t, T_SEND_STATE] = SEND_ACTIVE
            glob[G_SENDING] += 1
        tile[t, T_NI_MOVE] = 1 if tile[t, T_SEND_STATE] == SEND_ACTIVE and _ni_room(port, tile, t, cycle) else 0
        # router
        tile[t, T_MOVES] = 0
        if tile[t, T_RFLITS] == 0:
            continue  # (an empty router's switch controller is idle: it only serves headers present)
        tile[t, T_BUSY] += 1
        if cfg[C_GATE] != NONE and _clock_gate(cfg, port, tile, t, cycle):
            continue  # its clock is restarting: nothing moves, nothing is decided
        if hermes:
            asking = False  # some input's request is up in this cycle
            for p in range(NPORTS):
                if port[t, p, P_COUNT] > 0:
                    port[t, p, P_BUSY] += 1
                    if port[t, p, P_CONN] == NONE:
                        if port[t, p, P_HREQ] == BIG:
                            # a header is at the head for the first time: the request is up now, or
                            # next cycle if the buffer only became idle now (queued behind a tail)
                            port[t, p, P_HREQ] = cycle + 1 if port[t, p, P_IDLE_AT] == cycle else cycle
                        if port[t, p, P_HREQ] <= cycle:
                            asking = True
            # flit moves of the existing connections
            for o in range(NPORTS):
                owner = port[t, o, P_OWNER]
                count = port[t, owner, P_COUNT] if owner != NONE else 0
                if count > 0 and port[t, owner, P_READY_AT] <= cycle and _room(port, tile, width, t, o, cycle):
                    port[t, o, P_MOVE] = 1
                    tile[t, T_MOVES] = 1
                    if read_pointer and count == 1:
                        # the buffer runs empty: unless this is the tail, the read pointer stays on the
                        # flit's slot until the next flit arrives (_arrive). A header leaving alone is
                        # followed without a bubble by a flit 1 arriving in this same cycle (the RTL's
                        # S_HEADER looks at rx), hence cycle + 1 (a later flit 1 would leave the RTL
                        # stuck; robosoc's sources never leave that gap: docs/noc.md)
                        sent = port[t, owner, P_SENT]
                        if sent == 0:
                            port[t, owner, P_DRY_AT] = cycle + 1
                        elif sent + 1 < port[t, owner, P_TOTAL]:
                            port[t, owner, P_DRY_AT] = cycle
            # the switch controller (its connection takes effect from the next cycle)
            sc = tile[t, T_SC_STATE]
            if sc == SC_IDLE:
                if asking:
                    sc = SC_SELECT
            elif sc == SC_SELECT:
                sc = SC_IDLE  # (unreachable: a request stays up until its connection is made)
                last = tile[t, T_SC_SEL]
                for k in range(1, NPORTS + 1):
                    p = last + k
                    if p >= NPORTS:
                        p -= NPORTS
                    if port[t, p, P_HREQ] <= cycle:
                        tile[t, T_SC_SEL] = p
                        sc = SC_ROUTE
                        break
            elif sc == SC_ROUTE:
                p = tile[t, T_SC_SEL]
                o = _route(width, t, buf[t, p, port[t, p, P_HEAD]])
                if port[t, o, P_OWNER] == NONE and port[t, o, P_FREE_AT] <= cycle:
                    tile[t, T_SC_OUT] = o
                    sc = SC_CONNECT
                else:
                    sc = SC_IDLE  # failed attempt: the output is still held
            elif sc == SC_CONNECT:
                p = tile[t, T_SC_SEL]
                o = tile[t, T_SC_OUT]
                port[t, o, P_OWNER] = p
                port[t, p, P_CONN] = o
                port[t, p, P_HREQ] = BIG
                sc = SC_CROSS
            else:  # SC_CROSS: the header crosses now; on the RTL it is lost if there is no room
                if port[t, tile[t, T_SC_OUT], P_MOVE] == 0:
                    tile[t, T_RTL_LOST] += 1
                    glob[G_RTL_LOST] += 1
                sc = SC_IDLE
            tile[t, T_SC_STATE] = sc
            continue
        requested = 0  # bit o: some input requests output o
        for p in range(NPORTS):
            port[t, p, P_REQ] = NONE
            if port[t, p, P_COUNT] > 0:
                port[t, p, P_BUSY] += 1
                if port[t, p, P_CONN] == NONE:
                    if port[t, p, P_WAIT] < rlat:
                        port[t, p, P_WAIT] += 1
                    else:
                        o = _route(width, t, buf[t, p, port[t, p, P_HEAD]])
                        port[t, p, P_REQ] = o
                        requested |= 1 << o
        for o in range(NPORTS):
            owner = port[t, o, P_OWNER]
            granted = False
            if owner == NONE and (requested >> o) & 1:
                first = port[t, o, P_RR]
                for k in range(NPORTS):
                    p = first + k
                    if p >= NPORTS:
                        p -= NPORTS
                    if port[t, p, P_REQ] == o:
                        owner = p
                        granted = True
                        port[t, o, P_OWNER] = p
                        port[t, p, P_CONN] = o
                        port[t, p, P_REQ] = NONE  # scratch left clean: empty routers are skipped
                        port[t, o, P_RR] = p + 1 if p + 1 < NPORTS else 0
                        break
            if owner != NONE and port[t, owner, P_COUNT] > 0:
                if _room(port, tile, width, t, o, cycle):
                    port[t, o, P_MOVE] = 1
                    tile[t, T_MOVES] = 1
                elif granted:  # the header would cross in its grant cycle: lost on the RTL
                    tile[t, T_RTL_LOST] += 1
                    glob[G_RTL_LOST] += 1
    # ---------------------------------------------------------------- phase 2: commit at the edge
    for i in range(n):
        t = n - 1 - i if reverse else i
        if tile[t, T_NI_MOVE] != 0:
            # NI: one send-memory flit into the router's local input
            k = tile[t, T_SEND_POS]
            tail = port[t, LOCAL, P_HEAD] + port[t, LOCAL, P_COUNT]
            if tail >= depth:
                tail -= depth
            buf[t, LOCAL, tail] = mem[t, SEND, k]
            if read_pointer:
                _arrive(port, t, LOCAL, cycle)
            port[t, LOCAL, P_COUNT] += 1
            port[t, LOCAL, P_FLITS_IN] += 1
            tile[t, T_RFLITS] += 1
            tile[t, T_NI_CREDIT] -= 1
            glob[G_INFLIGHT] += 1
            glob[G_INJECTED] += 1
            row = tile[t, T_SEND_ROW]
            if k == 0:
                tile[t, T_SEND_FIRST] = cycle
                if row != NONE:
                    queue[row, Q_START] = cycle
            k += 1
            tile[t, T_SEND_POS] = k
            if k == tile[t, T_SEND_LEN]:
                tile[t, T_SEND_STATE] = SEND_IDLE
                tile[t, T_SEND_DONE] = cycle + 1
                tile[t, T_SENT_PKTS] += 1
                glob[G_SENDING] -= 1
                if row != NONE:
                    queue[row, Q_END] = cycle
                tile[t, T_SEND_ROW] = NONE
        if tile[t, T_MOVES] == 0:
            continue
        for o in range(NPORTS):
            if port[t, o, P_MOVE] == 0:
                continue
            port[t, o, P_MOVE] = 0  # scratch left clean
            p = port[t, o, P_OWNER]
            head = port[t, p, P_HEAD]
            f = buf[t, p, head]
            head += 1
            if head == depth:
                head = 0
            port[t, p, P_HEAD] = head
            port[t, p, P_COUNT] -= 1
            tile[t, T_RFLITS] -= 1
            port[t, o, P_FLITS_OUT] += 1
            # the freed slot goes back as a credit to whoever feeds input p
            if p == LOCAL:
                tile[t, T_NI_CREDIT] += 1
            else:
                port[_neighbour(width, t, p), _opposite(p), P_CREDIT] += 1
            if o == LOCAL:
                # ejection into the receive memory
                k = tile[t, T_RX_COUNT]
                mem[t, RECV, k] = f
                tile[t, T_RX_COUNT] = k + 1
                glob[G_INFLIGHT] -= 1
                glob[G_EJECTED] += 1
                if k == 0:
                    tile[t, T_RX_FIRST] = cycle
                elif k == 1:
                    tile[t, T_RX_TOTAL] = f + 2
                if k + 1 == tile[t, T_RX_TOTAL]:
                    _deliver(glob, tile, mem, ev, t, cycle)
            else:
                nb = _neighbour(width, t, o)
                q = _opposite(o)
                tail = port[nb, q, P_HEAD] + port[nb, q, P_COUNT]
                if tail >= depth:
                    tail -= depth
                buf[nb, q, tail] = f
                if read_pointer:
                    _arrive(port, nb, q, cycle)
                port[nb, q, P_COUNT] += 1
                port[nb, q, P_FLITS_IN] += 1
                tile[nb, T_RFLITS] += 1
                port[t, o, P_CREDIT] -= 1
                glob[G_HOPS] += 1
            # wormhole: the connection is released after the packet's last flit
            sent = port[t, p, P_SENT]
            if sent == 1:
                port[t, p, P_TOTAL] = f + 2
            sent += 1
            if sent == port[t, p, P_TOTAL]:
                port[t, o, P_OWNER] = NONE
                port[t, o, P_FREE_AT] = cycle + HERMES_RELEASE
                port[t, p, P_CONN] = NONE
                port[t, p, P_TOTAL] = BIG
                port[t, p, P_WAIT] = 0
                port[t, p, P_IDLE_AT] = cycle + 1
                if read_pointer:  # the tail's slot: the read pointer leaves it in the next cycle
                    port[t, p, P_HELD_UNTIL] = cycle + 2
                sent = 0
            port[t, p, P_SENT] = sent
    glob[G_CYCLE] = cycle + 1
    return glob[G_STATUS]


@njit(cache=True)
def noc_next_activity(cfg, glob, tile, queue):
    """First cycle >= ``glob[G_CYCLE]`` at which the NoC state can change, or BIG if never by itself.

    Returns ``glob[G_CYCLE]`` whenever a flit is in a router or an NI is injecting.
    """
    now = glob[G_CYCLE]
    if glob[G_INFLIGHT] != 0 or glob[G_SENDING] != 0:
        return now
    best = BIG
    for t in range(cfg[C_NTILES]):
        state = tile[t, T_SEND_STATE]
        if state == SEND_PENDING:
            c = tile[t, T_SEND_START]
        elif state == SEND_IDLE and tile[t, T_Q_HEAD] != NONE:
            c = queue[tile[t, T_Q_HEAD], Q_READY]
        else:
            c = BIG
        if c < best:
            best = c
        if tile[t, T_RX_STATE] == RX_HELD and tile[t, T_RX_FREE_AT] != NONE and tile[t, T_RX_FREE_AT] < best:
            best = tile[t, T_RX_FREE_AT]
    if best < now:
        best = now
    return best


@njit(cache=True)
def noc_idle(cfg, glob, buf, port, tile, mem, ev, queue):
    """No flit anywhere and nothing pending: the NoC will not change until someone sends or frees."""
    return noc_next_activity(cfg, glob, tile, queue) == BIG


@njit(cache=True)
def noc_run(cfg, glob, buf, port, tile, mem, ev, queue, until_cycle, max_events):
    """Advance from ``glob[G_CYCLE]`` up to (not including) ``until_cycle``, skipping idle time for free.

    Stops early after the cycle in which the ``max_events``-th delivery of this call happened, when an
    error is reported, or when fewer than ``tiles`` rows are left in ``ev`` (drain it: set
    ``glob[G_NEV] = 0``). Returns ``glob[G_STATUS]``; ``glob[G_CYCLE]`` is the next cycle to simulate.
    """
    n = cfg[C_NTILES]
    target = glob[G_DELIVERED] + max_events
    cycle = glob[G_CYCLE]
    while cycle < until_cycle:
        if glob[G_STATUS] != STATUS_OK or glob[G_DELIVERED] >= target or ev.shape[0] - glob[G_NEV] < n:
            break
        if glob[G_INFLIGHT] == 0 and glob[G_SENDING] == 0:
            nxt = noc_next_activity(cfg, glob, tile, queue)
            if nxt > cycle:
                cycle = nxt if nxt < until_cycle else until_cycle
                glob[G_CYCLE] = cycle
                continue
        noc_step(cfg, glob, buf, port, tile, mem, ev, queue, cycle)
        cycle += 1
    return glob[G_STATUS]
