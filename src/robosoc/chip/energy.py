"""Energy from event counts: Σ count × coefficient, with coefficients read from a TOML file.

The default file (``energy_coefficients.toml`` beside this module) carries ORCA's published
per-instruction-class figures and, marked ``assumed``, our reasoning for what no source gives.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from robosoc.config import ConfigError
from robosoc.config.chip import ChipConfig
from robosoc.config.ranges import FLOAT_FIELDS
from robosoc.isa.table import CLASS_NAMES, CORE_STALL_KINDS
from robosoc.kernels.noc import NPORTS

INSTRUCTION_CLASSES: tuple[str, ...] = tuple(CLASS_NAMES.values())
#: The core's stall kinds (from the instruction table) and the chip's: DMA copies and sleep.
STALL_KINDS: tuple[str, ...] = (*CORE_STALL_KINDS, "dma_cycle", "sleep_cycle")
NOC_TERMS = ("buffer_active", "buffer_idle", "control_active", "control_idle", "leakage")
LEAKAGE_TERMS = ("sleep_cycle", "leakage")
"""The coefficients that are leakage per cycle (a sleeping core, a router): DVFS scales them with V
and the clock period; every other coefficient is a switching energy, scaled with V²."""


@dataclass(frozen=True)
class Coefficient:
    pj: float
    status: str
    source: str


@dataclass(frozen=True)
class EnergyModel:
    """Coefficients in pJ: per instruction of each class and per stall cycle of each kind."""

    instruction: dict[str, Coefficient]
    stall: dict[str, Coefficient]
    noc: dict[str, Coefficient]
    clock_ns: float
    path: str

    @classmethod
    def load(cls, path: str | Path | None = None) -> EnergyModel:
        """Read a coefficient file (the packaged default when ``path`` is None).

        Raises:
            ConfigError: naming the file and the missing or malformed key.
        """
        if path is None:
            ref = resources.files("robosoc.chip").joinpath("energy_coefficients.toml")
            text, where = ref.read_text(), "robosoc/chip/energy_coefficients.toml"
        else:
            where = str(path)
            try:
                text = Path(path).read_text(encoding="utf-8")
            except OSError as exc:
                raise ConfigError(where, "", f"cannot read: {exc.strerror}") from exc
            except UnicodeDecodeError as exc:
                raise ConfigError(where, "", f"not UTF-8 text (offset {exc.start}): expected a TOML file") from exc
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise ConfigError(where, "", f"invalid TOML: {exc}") from exc

        def table(section: str, keys: tuple[str, ...]) -> dict[str, Coefficient]:
            got = data.get(section)
            if not isinstance(got, dict):
                raise ConfigError(where, section, "missing table")
            out = {}
            for key in keys:
                entry = got.get(key)
                field = f"{section}.{key}"
                if not isinstance(entry, dict):
                    raise ConfigError(where, field, "missing entry")
                pj = entry.get("pj")
                if isinstance(pj, bool) or not isinstance(pj, int | float) or pj < 0:
                    raise ConfigError(where, f"{field}.pj", f"expected a non-negative number, got {pj!r}")
                try:
                    FLOAT_FIELDS["Coefficient.pj"].check("pj", pj)
                except ValueError as exc:
                    raise ConfigError(where, f"{field}.pj", str(exc).partition(": ")[2]) from None
                status = entry.get("status")
                if status not in ("published", "assumed", "measured"):
                    raise ConfigError(where, f"{field}.status", "must be 'published', 'measured' or 'assumed'")
                source = entry.get("source")
                if not isinstance(source, str) or not source.strip():
                    raise ConfigError(where, f"{field}.source", "every coefficient needs its provenance")
                out[key] = Coefficient(float(pj), status, source)
            unknown = sorted(set(got) - set(keys))
            if unknown:
                raise ConfigError(where, f"{section}.{unknown[0]}", "unknown entry")
            return out

        clock = data.get("clock_ns", 4.0)
        if isinstance(clock, bool) or not isinstance(clock, int | float) or clock <= 0:
            raise ConfigError(where, "clock_ns", "expected a positive number")
        try:
            FLOAT_FIELDS["EnergyModel.clock_ns"].check("clock_ns", clock)
        except ValueError as exc:
            raise ConfigError(where, "clock_ns", str(exc).partition(": ")[2]) from None
        return cls(
            table("instruction", INSTRUCTION_CLASSES),
            table("stall", STALL_KINDS),
            table("noc", NOC_TERMS),
            float(clock),
            where,
        )

    def at_operating_point(self, volts: float, reference_v: float, clock_ns: float) -> EnergyModel:
        """The coefficients at supply ``volts`` and clock period ``clock_ns`` (DVFS, docs/power.md), from
        theirs at ``reference_v`` and :attr:`clock_ns`: a switching energy scales with V² (C·V² per
        transition, whatever the clock), a leakage energy per cycle (:data:`LEAKAGE_TERMS`) with V
        (leakage power, to first order) times the period."""
        dynamic = (volts / reference_v) ** 2
        leakage = (volts / reference_v) * (clock_ns / self.clock_ns)
        note = f"; scaled for {volts:g} V at {clock_ns:g} ns from {reference_v:g} V at {self.clock_ns:g} ns"

        def scaled(table: dict[str, Coefficient]) -> dict[str, Coefficient]:
            return {
                key: Coefficient(c.pj * (leakage if key in LEAKAGE_TERMS else dynamic), c.status, c.source + note)
                for key, c in table.items()
            }

        return EnergyModel(scaled(self.instruction), scaled(self.stall), scaled(self.noc), clock_ns, self.path)

    def for_chip(self, chip: ChipConfig) -> EnergyModel:
        """This model at ``chip``'s DVFS operating point (itself, unscaled, when the chip lists none)."""
        period = chip.tile.clock_period_ns
        volts = chip.dvfs.voltage_at(period)
        if volts is None:
            return self
        return self.at_operating_point(volts, chip.dvfs.reference_v, period)

    def for_tile(self, chip: ChipConfig, xy: tuple[int, int]) -> EnergyModel:
        """The coefficients of tile ``xy``'s core (this model is the file's, unscaled): at the tile's own
        DVFS point when the chip lists points; without points a core on a divided clock keeps the
        chip's voltage, so its switching energies are the chip's and its leakage per (longer) core
        cycle grows with the divider (docs/power.md, "Per-tile clock")."""
        chip_model = self.for_chip(chip)
        d = chip.tile_divider(xy)
        if d == 1:
            return chip_model
        period = chip.tile_config(xy).clock_period_ns
        volts = chip.tile_volts(xy)
        if volts is not None:
            return self.at_operating_point(volts, chip.dvfs.reference_v, period)
        return chip_model.at_operating_point(1.0, 1.0, chip_model.clock_ns * d)

    def breakdown_pj(self, counts: dict[str, int]) -> dict[str, float]:
        """Energy per counter name in pJ, for counters named ``<class>`` or ``<kind>`` (see keys)."""
        out: dict[str, float] = {}
        for key, coeff in self.instruction.items():
            out[key] = counts.get(key, 0) * coeff.pj
        for key, coeff in self.stall.items():
            out[key] = counts.get(key, 0) * coeff.pj
        return out

    def total_pj(self, counts: dict[str, int]) -> float:
        """``sum(breakdown_pj(counts).values())``, the same additions in the same order, without the dict."""
        total = 0.0
        for key, coeff in self.instruction.items():
            total += counts.get(key, 0) * coeff.pj
        for key, coeff in self.stall.items():
            total += counts.get(key, 0) * coeff.pj
        return total

    def total_nj(self, counts: dict[str, int]) -> float:
        return sum(self.breakdown_pj(counts).values()) / 1000.0

    def noc_pj(self, noc: dict[str, int]) -> dict[str, float]:
        """Router energy in pJ from :meth:`robosoc.chip.mpsoc.MPSoC.noc_counters`.

        A router cycle costs leakage, its control logic (active or idle) and one term per input
        buffer (active or idle); a cycle in which a clock-gated router's clock is stopped
        (``router_gated_cycles``, absent: none) costs only its leakage, and a switched-off router's
        cycle (``router_off_cycles``, absent: none) nothing at all (docs/power.md).
        """
        c = self.noc
        gated = noc.get("router_gated_cycles", 0)
        off = noc.get("router_off_cycles", 0)
        idle_ports = noc["port_idle_cycles"] - (gated + off) * NPORTS
        return {
            "buffers": noc["port_busy_cycles"] * c["buffer_active"].pj + idle_ports * c["buffer_idle"].pj,
            "control": noc["router_busy_cycles"] * c["control_active"].pj
            + (noc["router_cycles"] - noc["router_busy_cycles"] - gated - off) * c["control_idle"].pj,
            "leakage": (noc["router_cycles"] - off) * c["leakage"].pj,
        }
