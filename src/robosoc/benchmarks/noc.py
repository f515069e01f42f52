"""NoC alone under uniform random traffic: host speed (flits per second) and latency against injection rate.

Every tile of a ``width`` × ``height`` mesh (default 8×8) generates, in each of ``cycles`` cycles, a
packet of ``packet_flits`` flits with probability ``rate / packet_flits`` (``rate`` = offered flits per
cycle per tile), addressed to a uniformly drawn other tile. The network is then run until every packet
has been delivered. Latency is counted from the cycle the packet was generated (source queueing
included) to the cycle its last flit reached the receive memory; the network latency starts when its
first flit entered the source router.

Both router models run on the same traffic: ``hermes`` (the RTL's single switch controller per router)
and ``per-output`` (one arbiter per output port) with the same per-hop timing (routing latency 4, i.e.
5 cycles per uncontended router), so the difference is the arbitration alone. With
``compare_read_pointer`` the Hermes model also runs without its buffer's read-pointer timing
(``hermes-before``: the model before issue 38, docs/noc.md "The buffer's read pointer"), on the same
traffic, which shows what the tail-credit rule and the bubble change under load. ``rx_hold`` makes every
receiver hold its memory that many cycles after each packet (as in the RTL measurement of platform.md §4).
Each model runs
with the routers' clocks always on and with clock gating (``noc.clock_gating``, the default
``gate_after_cycles`` and ``wake_cycles``; docs/noc.md): the routers' energy over the run (the packaged
energy model) and what the wake-ups add to the mean latency are printed side by side.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from rich import box
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from robosoc.chip.energy import EnergyModel
from robosoc.chip.noc import Mesh
from robosoc.config.chip import ARBITERS, HERMES_ROUTING_LATENCY, ChipConfig, NocConfig
from robosoc.config.ranges import MAX_CYCLES, check_float, check_int, check_seed
from robosoc.output_files import save_figure

__all__ = ["NocBenchmarkRow", "run_noc_benchmark"]

DEFAULT_RATES = (0.02, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35)


@dataclass(frozen=True)
class NocBenchmarkRow:
    """Figures for one router model at one injection rate.

    Attributes:
        arbiter: the router model (``config.chip.ARBITERS``).
        read_pointer: Hermes with its buffer's read-pointer timing (False: ``hermes-before``; always
            False for per-output routers, which never have it).
        rate: offered load, flits per cycle per tile.
        packets: packets generated (and delivered).
        flits: flits delivered.
        accepted: delivered flits per cycle per tile over the whole run (generation plus drain).
        latency: mean cycles from generation to the last flit in the receive memory.
        network_latency: mean cycles from the first flit entering the source router to the last flit
            in the receive memory.
        sim_cycles: cycles simulated.
        host_seconds: host time of the simulation (kernel plus event collection).
        rtl_lost_headers: headers that found no room in their crossing cycle (the RTL would have lost
            them: its timing is only comparable where this is 0).
        moved: ``hermes-before`` rows: packets whose start or arrival cycle differs from the ``hermes``
            run on the same traffic (None for other rows).
        gating: the routers were clock-gated.
        noc_uj: the routers' energy over the run (generation plus drain) [µJ].
        wakeups: routers woken from a stopped clock.
    """

    arbiter: str
    read_pointer: bool
    rate: float
    packets: int
    flits: int
    accepted: float
    latency: float
    network_latency: float
    sim_cycles: int
    host_seconds: float
    rtl_lost_headers: int = 0
    moved: int | None = None
    gating: bool = False
    noc_uj: float = 0.0
    wakeups: int = 0

    @property
    def model(self) -> str:
        """The router model as printed: ``hermes``, ``hermes-before``, ``per-output``, ``+gating`` if gated."""
        name = "hermes-before" if self.arbiter == "hermes" and not self.read_pointer else self.arbiter
        return f"{name}+gating" if self.gating else name

    @property
    def flits_per_second(self) -> float:
        return self.flits / self.host_seconds if self.host_seconds > 0 else 0.0


def _traffic(
    mesh: Mesh, rate: float, cycles: int, packet_flits: int | tuple[int, int], rng: np.random.Generator
) -> int:
    """Queue the random packets (lengths fixed, or uniform in an inclusive range); returns how many."""
    cfg = mesh.config
    n = cfg.n_tiles
    lo, hi = (packet_flits, packet_flits) if isinstance(packet_flits, int) else packet_flits
    arrivals = np.argwhere(rng.random((cycles, n)) < 2 * rate / (lo + hi))  # rows of (cycle, tile)
    dests = rng.integers(n - 1, size=len(arrivals))
    lengths = [lo] * len(arrivals) if lo == hi else rng.integers(lo, hi + 1, size=len(arrivals)).tolist()
    for (cycle, t), d, length in zip(arrivals.tolist(), dests.tolist(), lengths, strict=True):
        d = d if d < t else d + 1
        payload = [0] * (length - 2 - 3)  # the mesh adds the 3-flit tag
        mesh.inject(cfg.tile_xy(t), cfg.tile_xy(d), payload, at_cycle=cycle)
    return len(arrivals)


def run_noc_benchmark(
    width: int = 8,
    height: int = 8,
    rates: tuple[float, ...] = DEFAULT_RATES,
    cycles: int = 10_000,
    packet_flits: int | tuple[int, int] = 16,
    buffer_depth: int = 16,
    routing_latency: int = HERMES_ROUTING_LATENCY,
    seed: int = 1,
    plot_path: str | Path | None = None,
    console: Console | None = None,
    arbiters: tuple[str, ...] = ARBITERS,
    compare_read_pointer: bool = False,
    rx_hold: int = 0,
    gating: tuple[bool, ...] = (False, True),
) -> list[NocBenchmarkRow]:
    """Run the NoC alone under uniform random traffic at each rate, for each router model, and print a table.

    Args:
        width, height: mesh size.
        rates: offered loads in flits per cycle per tile.
        cycles: cycles during which traffic is generated (the run continues until all is delivered).
        packet_flits: flits per packet on the wire (at least 5: header and the 3-flit tag), or an inclusive
            range ``(lo, hi)`` from which each packet's length is drawn uniformly.
        buffer_depth: flits per input buffer (default: the platform's 16).
        routing_latency: of the per-output model (the Hermes model's is fixed at 4).
        seed: traffic seed (the same traffic for every model).
        arbiters: router models to run.
        compare_read_pointer: also run the Hermes model without its buffer's read-pointer timing
            (``hermes-before``), for the before/after curves.
        rx_hold: cycles every receive memory stays held after a delivery (0: freed the next cycle).
        gating: each model without (False) and/or with (True) clock-gated routers.
        plot_path: if given, a PNG of latency against offered load is written there.
        console: where to print (default: a new rich console).

    Returns:
        one :class:`NocBenchmarkRow` per rate. The last printed line is ``noc: <median> Mflits/s``.
    """
    lengths = (packet_flits, packet_flits) if isinstance(packet_flits, int) else packet_flits
    for value in lengths:
        check_int("packet_flits", value, 5, 64)
    if lengths[0] > lengths[1]:
        raise ValueError(f"packet_flits: the range {lengths[0]}-{lengths[1]} is empty")
    flits_text = str(lengths[0]) if lengths[0] == lengths[1] else f"{lengths[0]}-{lengths[1]}"
    check_int("cycles", cycles, 1, MAX_CYCLES, "cycles")
    check_seed("seed", seed)
    check_int("rx_hold", rx_hold, 0, 10_000)
    for rate in rates:
        check_float("rates", rate, 0.0, 1.0, lo_open=True)
    for arbiter in arbiters:
        if arbiter not in ARBITERS:
            raise ValueError(f"arbiter: must be one of {', '.join(ARBITERS)}, got {arbiter!r}")
    console = console or Console(width=max(Console().width, 100))  # the table needs ~90 columns
    chips = {
        (arbiter, gated): ChipConfig(
            width=width,
            height=height,
            noc=NocConfig(
                buffer_depth=buffer_depth,
                arbiter=arbiter,
                routing_latency=HERMES_ROUTING_LATENCY if arbiter == "hermes" else routing_latency,
                clock_gating=gated,
            ),
        )
        for arbiter in arbiters
        for gated in dict.fromkeys(gating)
        if arbiter in ARBITERS  # all are (checked above): narrows the name to an Arbiter
    }
    models = [(arbiter, gated, cfg, True) for (arbiter, gated), cfg in chips.items()]
    if compare_read_pointer and ("hermes", False) in chips:
        models.insert(1, ("hermes", False, chips[("hermes", False)], False))
    energy = EnergyModel.load()

    warm = Mesh(next(iter(chips.values())))  # JIT compile (or load from cache) outside the timings
    warm.inject((0, 0), (width - 1, height - 1), [1, 2, 3], at_cycle=0)
    warm.run_until_idle(limit=10_000)

    rows: list[NocBenchmarkRow] = []
    timing: dict[float, dict[int, tuple[int, int]]] = {}  # hermes, per rate: packet -> (start, arrival)
    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total} packets"),
        TimeElapsedColumn(),
    )
    with Progress(*columns, console=console, transient=True) as progress:
        for (arbiter, gated, cfg, read_pointer), rate in ((model, rate) for model in models for rate in rates):
            rng = np.random.default_rng(seed)
            mesh = Mesh(
                cfg, tag_packets=True, event_capacity=8192, rx_free_delay=rx_hold, read_pointer_timing=read_pointer
            )
            n_packets = _traffic(mesh, rate, cycles, packet_flits, rng)
            model = arbiter if read_pointer or arbiter != "hermes" else "hermes-before"
            label = f"{model}+gating" if gated else model
            task = progress.add_task(f"{width}x{height} {label} rate {rate:.3f}", total=n_packets)
            host = 0.0
            chunk = max(1000, cycles // 20)
            while not mesh.idle:
                start = time.perf_counter()
                mesh.run(mesh.cycle + chunk)
                host += time.perf_counter() - start
                progress.update(task, completed=len(mesh._deliveries))
                if mesh.cycle > 1000 * cycles + 100_000:
                    raise RuntimeError(f"rate {rate}: traffic not drained after {mesh.cycle} cycles")
            progress.remove_task(task)
            deliveries = mesh.deliveries()
            latency_cycles: list[int] = []
            network_cycles: list[int] = []
            times: dict[int, tuple[int, int]] = {}
            for d in deliveries:
                assert d.packet_id is not None  # the mesh tags its packets
                packet = mesh.packet(d.packet_id)
                assert packet.start is not None  # delivered, so it entered the network
                latency_cycles.append(d.cycle - packet.ready)
                network_cycles.append(d.cycle - packet.start)
                times[d.packet_id] = (packet.start, d.cycle)
            moved = None
            if arbiter == "hermes" and read_pointer and not gated:
                timing[rate] = times
            elif arbiter == "hermes" and not gated and rate in timing:
                moved = sum(times[p] != timing[rate].get(p) for p in times)
            latency = np.array(latency_cycles, dtype=np.float64)
            network = np.array(network_cycles, dtype=np.float64)
            last = max((d.cycle for d in deliveries), default=0) + 1
            flits = sum(d.length for d in deliveries)
            counters = mesh.counters()
            rows.append(
                NocBenchmarkRow(
                    arbiter=arbiter,
                    read_pointer=read_pointer and arbiter == "hermes",
                    rate=rate,
                    packets=len(deliveries),
                    flits=flits,
                    accepted=flits / (last * cfg.n_tiles) if deliveries else 0.0,
                    latency=float(latency.mean()) if deliveries else 0.0,
                    network_latency=float(network.mean()) if deliveries else 0.0,
                    sim_cycles=last,
                    host_seconds=host,
                    rtl_lost_headers=mesh.rtl_lost_headers,
                    moved=moved,
                    gating=gated,
                    noc_uj=sum(energy.noc_pj(counters.energy_counts()).values()) / 1e6,
                    wakeups=int(counters.wakeups.sum()),
                )
            )

    table = Table(
        title=f"NoC {width}x{height}, uniform random, {flits_text}-flit packets, depth {buffer_depth}"
        + (f", receivers hold {rx_hold} cycles" if rx_hold else "")
        + f"; hermes: the RTL's switch controller and buffer (hermes-before: without the buffer's read-pointer "
        f"timing), per-output: routing latency {routing_latency}",
        box=box.SIMPLE_HEAD,
        pad_edge=False,
        caption="load and accept: flits/cycle/tile; lat: mean cycles from generation (net: from the first "
        "flit entering the source router) to the last flit in the receive memory; lost: headers the RTL "
        "would have lost (no room in their crossing cycle: robosoc lets them wait); moved: packets whose start "
        "or arrival cycle differs from the hermes row's; +gating: routers idle for gate_after_cycles stop their "
        "clock (Δlat: mean latency change against the same router ungated, wakes: wake-ups); µJ: the routers' "
        "energy over the run",
    )
    headers = (
        "router", "load", "accept", "pkts", "lat", "net", "lost", "moved", "Δlat", "wakes", "µJ", "cycles",
        "host s", "Mflit/s",
    )  # fmt: skip
    for name in headers:
        table.add_column(name, justify="right", no_wrap=True)
    plain = {(r.arbiter, r.rate): r for r in rows if not r.gating and (r.read_pointer or r.arbiter != "hermes")}
    for r in rows:
        base = plain.get((r.arbiter, r.rate)) if r.gating else None
        table.add_row(
            r.model,
            f"{r.rate:.3f}",
            f"{r.accepted:.3f}",
            str(r.packets),
            f"{r.latency:.2f}",
            f"{r.network_latency:.2f}",
            str(r.rtl_lost_headers),
            "" if r.moved is None else str(r.moved),
            f"{r.latency - base.latency:+.1f}" if base is not None else "",
            str(r.wakeups) if r.gating else "",
            f"{r.noc_uj:.2f}" + (f" ({r.noc_uj / base.noc_uj - 1:+.0%})" if base is not None and base.noc_uj else ""),
            str(r.sim_cycles),
            f"{r.host_seconds:.3f}",
            f"{r.flits_per_second / 1e6:.2f}",
        )
    console.print(table)
    if plot_path is not None:
        _plot(rows, Path(plot_path), f"NoC {width}x{height} uniform random ({flits_text}-flit packets)")
        console.print(f"plot written to {plot_path}")
    median = float(np.median([r.flits_per_second for r in rows])) if rows else 0.0
    console.print(f"noc: {median / 1e6:.2f} Mflits/s")
    return rows


def _plot(rows: list[NocBenchmarkRow], path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for model in dict.fromkeys(r.model for r in rows):
        mine = [r for r in rows if r.model == model]
        rate = [r.rate for r in mine]
        ax.plot(rate, [r.latency for r in mine], "o-", label=f"{model}: generation to delivery")
        ax.plot(rate, [r.network_latency for r in mine], "s--", label=f"{model}: in the network")
    ax.set_xlabel("offered load (flits / cycle / tile)")
    ax.set_ylabel("average packet latency (cycles)")
    ax.set_yscale("log")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    save_figure(fig, path, dpi=120)
    plt.close(fig)
