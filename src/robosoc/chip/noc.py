"""Standalone NoC: a Python :class:`Mesh` over the numba kernels of :mod:`robosoc.kernels.noc`.

Used by tests, the NoC benchmark and the I/O tile: packets are queued per source tile with the cycle
from which they may leave (:meth:`Mesh.inject`), the NI sends them in that order at 1 flit per cycle,
and :meth:`Mesh.run` collects the delivery events. The whole-chip simulator calls the kernels directly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from robosoc.config.chip import MIN_PACKET_FLITS, ChipConfig
from robosoc.kernels import noc as k

__all__ = ["Delivery", "Mesh", "NocError", "PacketInfo", "PortCounters"]

TAG_FLITS = 3  # tagged packets carry source address and a 32-bit packet id at the head of the payload


class NocError(RuntimeError):
    """The kernel reported an error (a packet to a powered-off tile, to itself, ...)."""

    def __init__(self, code: int, tile: tuple[int, int], cycle: int) -> None:
        self.code = code
        self.tile = tile
        self.cycle = cycle
        reason = k.STATUS_TEXT.get(code, "unknown error")
        super().__init__(f"NoC error at cycle {cycle}, tile {tile}: {reason} (code {code})")


@dataclass(frozen=True)
class Delivery:
    """A packet that reached a receive memory.

    Attributes:
        dst: the receiving tile.
        cycle: the cycle in which its last flit was written into the receive memory.
        first_cycle: the cycle in which its first flit was written.
        flits: every flit as received (destination, size, payload).
        src: the sending tile, if the mesh tags packets (else None).
        packet_id: the id returned by :meth:`Mesh.inject`, if the mesh tags packets (else None).
    """

    dst: tuple[int, int]
    cycle: int
    first_cycle: int
    flits: tuple[int, ...]
    src: tuple[int, int] | None = None
    packet_id: int | None = None

    @property
    def length(self) -> int:
        """Flits on the wire, header included."""
        return len(self.flits)

    @property
    def payload(self) -> tuple[int, ...]:
        """The user payload (without the header and, for tagged packets, without the tag)."""
        return self.flits[2 + (TAG_FLITS if self.packet_id is not None else 0) :]


@dataclass(frozen=True)
class PacketInfo:
    """Injection record of one packet.

    Attributes:
        src, dst: tiles.
        ready: the cycle from which the NI may send it.
        start: the cycle its first flit entered the source router (None while queued).
        end: the cycle its last flit entered the source router (None until then).
        length: flits on the wire.
    """

    src: tuple[int, int]
    dst: tuple[int, int]
    ready: int
    start: int | None
    end: int | None
    length: int


@dataclass(frozen=True)
class PortCounters:
    """Activity counters for router energy, indexed ``[x, y, port]`` (ports in :data:`PORT_NAMES` order).

    Attributes:
        cycles: cycles elapsed since the counters started.
        flits_in: flits written into each input buffer.
        flits_out: flits sent through each output port.
        busy_cycles: cycles each input buffer held at least one flit (buffer active).
        idle_cycles: ``cycles - busy_cycles`` (buffer idle).
        router_busy_cycles: cycles each router held at least one flit (control logic active), ``[x, y]``.
        rtl_lost_headers: headers each router could not send in their crossing cycle for lack of room
            downstream, ``[x, y]``: robosoc lets them wait, the Hermes RTL would have lost them.
        gated_cycles: cycles each router's clock was stopped (clock gating), ``[x, y]``.
        wakeups: each router's wake-ups from a stopped clock, ``[x, y]``.
    """

    cycles: int
    flits_in: np.ndarray
    flits_out: np.ndarray
    busy_cycles: np.ndarray
    idle_cycles: np.ndarray
    router_busy_cycles: np.ndarray
    rtl_lost_headers: np.ndarray
    gated_cycles: np.ndarray
    wakeups: np.ndarray

    def energy_counts(self) -> dict[str, int]:
        """The mesh's totals in the form :meth:`robosoc.chip.energy.EnergyModel.noc_pj` takes."""
        routers = int(self.router_busy_cycles.size)
        busy_ports = int(self.busy_cycles.sum())
        return {
            "router_cycles": self.cycles * routers,
            "router_busy_cycles": int(self.router_busy_cycles.sum()),
            "router_gated_cycles": int(self.gated_cycles.sum()),
            "port_busy_cycles": busy_ports,
            "port_idle_cycles": self.cycles * routers * len(PORT_NAMES) - busy_ports,
        }


PORT_NAMES = k.PORT_NAMES


class Mesh:
    """A mesh of Hermes routers with their network interfaces, simulated on its own.

    Args:
        config: the platform (mesh size, powered-off tiles, NoC parameters); default 2×2.
        rx_free_delay: receive memories are freed automatically this many cycles after a delivery
            (0: the next packet may enter in the following cycle); None: they stay held until
            :meth:`free_rx`, back-pressuring the network.
        tag_packets: :meth:`inject` prepends the source address and a 32-bit packet id to the
            payload (3 flits) so that deliveries name their source and id.
        event_capacity: delivery events buffered by the kernel between two drains.
        reverse_evaluation: evaluate routers in reverse order (results must be identical).
        read_pointer_timing: the Hermes buffer's read-pointer timing (docs/noc.md, "The buffer's read
            pointer"); False gives the Hermes model as it was before it (every freed slot usable the
            next cycle, no bubble), for `robosoc bench noc`'s before/after curves. No effect on
            per-output routers.
    """

    def __init__(
        self,
        config: ChipConfig | None = None,
        *,
        rx_free_delay: int | None = 0,
        tag_packets: bool = False,
        event_capacity: int = 4096,
        reverse_evaluation: bool = False,
        read_pointer_timing: bool = True,
    ) -> None:
        self.config = config or ChipConfig()
        if rx_free_delay is not None and rx_free_delay < 0:
            raise ValueError(f"rx_free_delay: must be >= 0 or None, got {rx_free_delay}")
        noc = self.config.noc
        powered = np.array(
            [self.config.is_powered(self.config.tile_xy(t)) for t in range(self.config.n_tiles)], dtype=bool
        )
        self.tag_packets = tag_packets
        self.state = k.noc_alloc(
            self.config.width,
            self.config.height,
            noc.buffer_depth,
            noc.routing_latency,
            noc.max_packet_flits,
            noc.flit_bits,
            powered,
            event_capacity=max(event_capacity, 2 * self.config.n_tiles),
            queue_rows=64,
            rx_auto_free=k.NONE if rx_free_delay is None else rx_free_delay,
            reverse=reverse_evaluation,
            arbiter=noc.arbiter,
            read_pointer=read_pointer_timing,
            gate_after=noc.gate_after,
            wake_cycles=noc.wake_cycles,
        )
        self._rows = 0
        self._deliveries: list[Delivery] = []

    # ----------------------------------------------------------------- properties
    @property
    def cycle(self) -> int:
        """The next cycle to simulate."""
        return int(self.state.glob[k.G_CYCLE])

    @property
    def routing_latency(self) -> int:
        return self.config.noc.routing_latency

    @property
    def lookahead(self) -> int:
        """Cycles after an injection starts during which no flit move or delivery elsewhere can change."""
        return k.min_router_cycles(int(self.state.cfg[k.C_ARBITER]), self.routing_latency)

    @property
    def rtl_lost_headers(self) -> int:
        """Headers that found no room downstream in their crossing cycle: robosoc lets them wait, the
        Hermes RTL would have lost them (docs/noc.md, "Departures from the RTL")."""
        return int(self.state.glob[k.G_RTL_LOST])

    @property
    def idle(self) -> bool:
        """No flit in the network and nothing queued or pending."""
        return bool(k.noc_idle(*self.state))

    @property
    def io_tile(self) -> tuple[int, int]:
        return self.config.io_tile

    def hops(self, src: tuple[int, int], dst: tuple[int, int]) -> int:
        """Router-to-router hops of the XY route from ``src`` to ``dst``."""
        return abs(src[0] - dst[0]) + abs(src[1] - dst[1])

    def single_packet_latency(self, hops: int, length: int) -> int:
        """Uncontended cycles from the first flit entering the source router to the last flit written
        into the destination receive memory: ``(hops + 1) * (routing_latency + 1) + length - 1``; with
        the Hermes buffer's read pointer and 2-flit buffers, where every flit after the first two
        leaves its buffer two cycles after the previous one, ``(hops + 1) * 5 + 1 + 2 * (length - 2)``
        (docs/noc.md, "The buffer's read pointer")."""
        st = self.state
        if st.cfg[k.C_READ_POINTER] and st.cfg[k.C_DEPTH] == 2:
            return (hops + 1) * (self.routing_latency + 1) + 1 + 2 * (length - 2)
        return (hops + 1) * (self.routing_latency + 1) + length - 1

    # ----------------------------------------------------------------- injection
    def inject(
        self, src: tuple[int, int], dst: tuple[int, int], payload: list[int] | tuple[int, ...], at_cycle: int
    ) -> int:
        """Queue a packet at ``src``'s NI, to be sent from ``at_cycle`` on (after earlier-ready packets).

        The packet on the wire is ``[(x << 4) | y, size, *payload]`` (plus the tag when tagging).

        Returns:
            the packet id (for :meth:`packet` and tagged deliveries).

        Raises:
            ValueError: bad tile, self-send, powered-off source or destination, too long, flit
                value out of range, or ``at_cycle`` in the past.
        """
        cfg = self.config
        src, dst = (*src,), (*dst,)  # tuples even if given lists (as tuple(), keeping the pair type)
        for name, xy in (("src", src), ("dst", dst)):
            if len(xy) != 2 or not cfg.contains(xy):
                raise ValueError(f"{name}: tile {xy} is outside the {cfg.width}x{cfg.height} mesh")
            if not cfg.is_powered(xy):
                raise ValueError(f"{name}: tile {xy} is powered off")
        if src == dst:
            raise ValueError(f"dst: packet from {src} addressed to its own tile")
        if at_cycle < self.cycle:
            raise ValueError(f"at_cycle: {at_cycle} is in the past (now {self.cycle})")
        row = self._rows
        body = list(payload)
        if self.tag_packets:
            body = [(src[0] << 4) | src[1], row >> 16, row & 0xFFFF, *body]
        flits = [(dst[0] << 4) | dst[1], len(body), *body]
        if len(flits) > cfg.noc.max_packet_flits:
            raise ValueError(f"payload: {len(flits)} flits on the wire, max {cfg.noc.max_packet_flits}")
        if len(flits) < MIN_PACKET_FLITS:
            raise ValueError(
                f"payload: packet from {src} of {len(flits)} flits; at least {MIN_PACKET_FLITS} are needed "
                "(on the Hermes RTL a packet without payload swallows the next one)"
            )
        limit = 1 << cfg.noc.flit_bits
        if any(not 0 <= f < limit for f in flits):
            raise ValueError(f"payload: flit values must be in [0, {limit})")
        self._enqueue(cfg.tile_index(src), flits, at_cycle)
        return row

    def _enqueue(self, t: int, flits: list[int], ready: int) -> None:
        """Append a queue row and link it into tile ``t``'s list, keeping it sorted by ready cycle."""
        st = self.state
        if self._rows == st.queue.shape[0]:
            grown = np.zeros((2 * st.queue.shape[0], k.Q_COLS), np.int64)
            grown[: self._rows] = st.queue
            self.state = st = st._replace(queue=grown)
        row = self._rows
        self._rows += 1
        q = st.queue
        q[row, : k.Q_FLITS] = (t, ready, len(flits), k.NONE, k.NONE, k.NONE)
        q[row, k.Q_FLITS : k.Q_FLITS + len(flits)] = flits
        head, tail = int(st.tile[t, k.T_Q_HEAD]), int(st.tile[t, k.T_Q_TAIL])
        if head == k.NONE:
            st.tile[t, k.T_Q_HEAD] = st.tile[t, k.T_Q_TAIL] = row
        elif q[tail, k.Q_READY] <= ready:
            q[tail, k.Q_NEXT] = row
            st.tile[t, k.T_Q_TAIL] = row
        elif q[head, k.Q_READY] > ready:
            q[row, k.Q_NEXT] = head
            st.tile[t, k.T_Q_HEAD] = row
        else:
            prev = head
            while q[q[prev, k.Q_NEXT], k.Q_READY] <= ready:
                prev = int(q[prev, k.Q_NEXT])
            q[row, k.Q_NEXT] = q[prev, k.Q_NEXT]
            q[prev, k.Q_NEXT] = row

    def packet(self, packet_id: int) -> PacketInfo:
        """Injection record of a packet returned by :meth:`inject`."""
        if not 0 <= packet_id < self._rows:
            raise ValueError(f"packet_id: no packet {packet_id}")
        row = self.state.queue[packet_id]
        dest = int(row[k.Q_FLITS])
        start, end = int(row[k.Q_START]), int(row[k.Q_END])
        return PacketInfo(
            src=self.config.tile_xy(int(row[k.Q_TILE])),
            dst=(dest >> 4, dest & 0xF),
            ready=int(row[k.Q_READY]),
            start=None if start < 0 else start,
            end=None if end < 0 else end,
            length=int(row[k.Q_LEN]),
        )

    # ----------------------------------------------------------------- simulation
    def run(self, until: int) -> None:
        """Simulate up to (not including) cycle ``until``; idle stretches cost no host time.

        Raises:
            NocError: the kernel reported an error (the cycle stops right after it).
        """
        st = self.state
        while True:
            status = k.noc_run(*st, until, k.BIG)
            self._drain_events()
            if status != k.STATUS_OK:
                code, t, cycle = (int(v) for v in st.glob[[k.G_STATUS, k.G_ERR_TILE, k.G_ERR_CYCLE]])
                st.glob[k.G_STATUS] = k.STATUS_OK
                raise NocError(code, self.config.tile_xy(t), cycle)
            if self.cycle >= until:
                return

    def run_until_idle(self, limit: int) -> None:
        """Run until nothing is in flight or queued (receive memories held by software do not count).

        Raises:
            RuntimeError: still busy at cycle ``limit`` (for example a deadlock or a held receive memory).
        """
        while not self.idle:
            if self.cycle >= limit:
                raise RuntimeError(f"NoC still busy at cycle {limit}")
            self.run(min(limit, self.cycle + 4096))

    def step(self) -> None:
        """Simulate exactly one cycle (no idle skipping)."""
        st = self.state
        k.noc_step(*st, self.cycle)
        self._drain_events()
        if st.glob[k.G_STATUS] != k.STATUS_OK:
            code, t, cycle = (int(v) for v in st.glob[[k.G_STATUS, k.G_ERR_TILE, k.G_ERR_CYCLE]])
            st.glob[k.G_STATUS] = k.STATUS_OK
            raise NocError(code, self.config.tile_xy(t), cycle)

    def _drain_events(self) -> None:
        st = self.state
        n = int(st.glob[k.G_NEV])
        for row in st.ev[:n]:
            length = int(row[k.EV_LEN])
            flits = tuple(int(f) for f in row[k.EV_FLITS : k.EV_FLITS + length])
            src = packet_id = None
            if self.tag_packets and length >= 2 + TAG_FLITS:
                src = (flits[2] >> 4, flits[2] & 0xF)
                packet_id = (flits[3] << 16) | flits[4]
            self._deliveries.append(
                Delivery(
                    dst=self.config.tile_xy(int(row[k.EV_TILE])),
                    cycle=int(row[k.EV_CYCLE]),
                    first_cycle=int(row[k.EV_FIRST]),
                    flits=flits,
                    src=src,
                    packet_id=packet_id,
                )
            )
        st.glob[k.G_NEV] = 0

    def stall_receive(self, tile: tuple[int, int], start: int, stop: int) -> None:
        """``tile``'s receive memory accepts no flit in cycles ``[start, stop)``, whether or not a packet is
        part-way in (a destination stalling in the middle of a packet); the router back-pressures.

        Raises:
            ValueError: bad tile, an empty or past window, or an earlier window of this tile not over yet.
        """
        self._window(tile, start, stop, k.T_RX_STALL_FROM, k.T_RX_STALL_UNTIL)

    def pause_send(self, tile: tuple[int, int], start: int, stop: int) -> None:
        """``tile``'s NI injects no flit in cycles ``[start, stop)``, even in the middle of a packet (a
        source that runs dry, which makes the buffers behind it run empty mid-packet).

        Raises:
            ValueError: as :meth:`stall_receive`.
        """
        self._window(tile, start, stop, k.T_TX_STALL_FROM, k.T_TX_STALL_UNTIL)

    def _window(self, tile: tuple[int, int], start: int, stop: int, col_from: int, col_until: int) -> None:
        cfg = self.config
        xy = (*tile,)
        if len(xy) != 2 or not cfg.contains(xy):
            raise ValueError(f"tile: {xy} is outside the {cfg.width}x{cfg.height} mesh")
        if not start < stop:
            raise ValueError(f"window: [{start}, {stop}) is empty")
        if start < self.cycle:
            raise ValueError(f"start: {start} is in the past (now {self.cycle})")
        t = cfg.tile_index(xy)
        row = self.state.tile[t]
        if row[col_until] > self.cycle:
            raise ValueError(f"tile: {xy} already has a window until {int(row[col_until])}")
        row[col_from], row[col_until] = start, stop

    def free_rx(self, tile: tuple[int, int]) -> None:
        """Software has read the receive memory of ``tile``: it accepts flits from the next cycle on."""
        k.noc_rx_free(self.state.tile, self.config.tile_index(tile))

    def rx_held(self, tile: tuple[int, int]) -> bool:
        """Whether ``tile``'s receive memory holds a complete packet not yet freed."""
        return bool(self.state.tile[self.config.tile_index(tile), k.T_RX_STATE] == k.RX_HELD)

    def deliveries(self) -> list[Delivery]:
        """Every delivery so far, ordered by cycle then destination tile index."""
        return sorted(self._deliveries, key=lambda d: (d.cycle, self.config.tile_index(d.dst)))

    # ----------------------------------------------------------------- I/O tile
    def io_send(self, dst: tuple[int, int], payload: list[int] | tuple[int, ...], at_cycle: int) -> int:
        """Inject a packet from the outside world through the I/O tile at ``at_cycle``."""
        return self.inject(self.config.io_tile, dst, payload, at_cycle)

    def io_received(self) -> list[tuple[int, tuple[int, ...]]]:
        """Packets that reached the I/O tile so far: ``(cycle of the last flit, flits)``."""
        io = tuple(self.config.io_tile)
        return [(d.cycle, d.flits) for d in self.deliveries() if d.dst == io]

    # ----------------------------------------------------------------- counters and snapshots
    def counters(self) -> PortCounters:
        """Per-router, per-port activity since the start (for router energy)."""
        st = self.state
        w, h = self.config.width, self.config.height
        cycles = int(st.glob[k.G_CYCLE] - st.glob[k.G_CYCLE0])

        def by_xy(a: np.ndarray) -> np.ndarray:
            return np.ascontiguousarray(a.reshape(h, w, *a.shape[1:]).swapaxes(0, 1))

        busy = by_xy(st.port[:, :, k.P_BUSY])
        return PortCounters(
            cycles=cycles,
            flits_in=by_xy(st.port[:, :, k.P_FLITS_IN]),
            flits_out=by_xy(st.port[:, :, k.P_FLITS_OUT]),
            busy_cycles=busy,
            idle_cycles=cycles - busy,
            router_busy_cycles=by_xy(st.tile[:, k.T_BUSY]),
            rtl_lost_headers=by_xy(st.tile[:, k.T_RTL_LOST]),
            gated_cycles=by_xy(k.gated_cycles(st.cfg, st.glob, st.tile)),
            wakeups=by_xy(st.tile[:, k.T_WAKES]),
        )

    def snapshot(self) -> tuple[k.NocState, int, list[Delivery]]:
        """Copy of the complete mesh state."""
        return k.noc_snapshot(self.state), self._rows, list(self._deliveries)

    def restore(self, snap: tuple[k.NocState, int, list[Delivery]]) -> None:
        """Return to a :meth:`snapshot`."""
        state, rows, deliveries = snap
        self.state = k.noc_snapshot(state)
        self._rows = rows
        self._deliveries = list(deliveries)
