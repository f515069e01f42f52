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
