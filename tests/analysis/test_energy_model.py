"""The energy model: provenance on every coefficient, sums by hand, bad files named."""

import pytest

from robosoc.analysis.energy import INSTRUCTION_CLASSES, STALL_KINDS, EnergyModel
from robosoc.config import ConfigError


def test_default_coefficients_are_orca_values_with_provenance():
    m = EnergyModel.load()
    # platform.md §5: pJ per instruction at 4 ns
    published = {"jump": 18.56, "branch": 31.70, "memory": 43.15, "add": 23.58, "logic": 20.70, "other": 19.76}
    for name, pj in published.items():
        assert m.instruction[name].pj == pj and m.instruction[name].status == "published"
    for name in ("mul", "system"):
        assert m.instruction[name].status == "assumed" and "no published figure" in m.instruction[name].source
    for kind in STALL_KINDS:
        assert m.stall[kind].source
    assert set(m.instruction) == set(INSTRUCTION_CLASSES)


def test_energy_is_the_sum_of_count_times_coefficient():
    m = EnergyModel.load()
    counts = {"add": 10, "memory": 3, "branch": 2, "mul": 1, "mul_cycle": 20}
    want = 10 * 23.58 + 3 * 43.15 + 2 * 31.70 + 1 * m.instruction["mul"].pj + 20 * m.stall["mul_cycle"].pj
    assert m.total_nj(counts) == pytest.approx(want / 1000)


def test_bad_files_name_file_and_key(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[instruction.add]\npj = -1\nstatus = "published"\nsource = "x"\n')
    with pytest.raises(ConfigError, match=r"bad\.toml: instruction"):
        EnergyModel.load(bad)
    bad.write_text("clock_ns = [")
    with pytest.raises(ConfigError, match="invalid TOML"):
        EnergyModel.load(bad)
    with pytest.raises(ConfigError, match="cannot read"):
        EnergyModel.load(tmp_path / "nope.toml")


def test_router_energy_matches_the_published_per_cycle_figures():
    m = EnergyModel.load()
    idle = {"router_cycles": 1, "router_busy_cycles": 0, "port_busy_cycles": 0, "port_idle_cycles": 5}
    assert sum(m.noc_pj(idle).values()) == pytest.approx(10.49, abs=0.01)  # platform.md: ~10.5 pJ
    # one flit sitting in one input buffer of a router for a cycle: ~10 pJ more (platform.md §5)
    busy = {"router_cycles": 1, "router_busy_cycles": 1, "port_busy_cycles": 1, "port_idle_cycles": 4}
    assert sum(m.noc_pj(busy).values()) - sum(m.noc_pj(idle).values()) == pytest.approx(9.96, abs=0.01)


def _single_cycle_classes() -> set[str]:
    """Classes every instruction of which costs one cycle (from the instruction table's timing)."""
    from robosoc.isa.table import CLASS_NAMES, INSTRUCTIONS, Timing

    out = set()
    for cls, name in CLASS_NAMES.items():
        rows = [row for row in INSTRUCTIONS if row.cls == cls and not row.unsupported]
        if rows and all(row.timing == Timing.SINGLE for row in rows):
            out.add(name)
    return out


def test_every_assumed_coefficient_follows_the_reasoning_of_its_note():
    """Each ``assumed`` figure is tied to what its note says it equals; a change to either side (the
    number or the figure it is derived from) that breaks the reasoning fails here.  Rounded figures
    (10.0 for 9.88, 14.4 for 14.38, 0.9 for 0.892) are within 2 %."""
    m = EnergyModel.load()
    ins, stall, noc = m.instruction, m.stall, m.noc
    assert _single_cycle_classes() == {"add", "logic", "other"}  # LUI/AUIPC share 'jump' with JAL/JALR
    cheapest = min(ins[name].pj for name in _single_cycle_classes())
    memory = ins["memory"].pj
    derived = {  # key: (value by the note's reasoning, words of the note that state it)
        ("instruction", "mul"): (ins["add"].pj, "costed like an add"),
        ("instruction", "system"): (ins["jump"].pj, "costed as the jump class"),
        ("stall", "mul_cycle"): (cheapest / 2, f"half of the cheapest single-cycle instruction ({cheapest} pJ)"),
        ("stall", "entry_cycle"): (stall["mul_cycle"].pj, "costed like a multiplier stall cycle"),
        ("stall", "dma_cycle"): (memory / 3, f"one cycle of a load/store ({memory} pJ over its 3 cycles)"),
        ("stall", "sleep_cycle"): (noc["leakage"].pj, "equal to the router leakage per cycle"),
    }  # fmt: skip
    tables = {"instruction": ins, "stall": stall, "noc": noc}
    assumed = {(t, k) for t, table in tables.items() for k, c in table.items() if c.status == "assumed"}
    assert assumed == set(derived)  # a new assumed figure needs its rule here
    for (table, key), (value, words) in derived.items():
        coefficient = tables[table][key]
        assert words in coefficient.source, (table, key)
        assert coefficient.pj == pytest.approx(value, rel=0.02), (table, key, value)
    # the sleep figure's note also names the router leakage in µW: 223.08 µW x 4 ns
    assert noc["leakage"].pj == pytest.approx(223.08e-6 * m.clock_ns * 1e-9 * 1e12, abs=5e-4)
    # the stalls that ORCA's per-instruction energies already include cost nothing
    for kind in ("branch_cycle", "memory_cycle"):
        assert stall[kind].pj == 0.0 and stall[kind].status == "published"
