"""The energy model: provenance on every coefficient, sums by hand, bad files named."""

import json
import tomllib
from importlib import resources

import pytest

from robosoc.chip.energy import INSTRUCTION_CLASSES, STALL_KINDS, EnergyModel
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


# --- every rule of a coefficient file, with the exact message ----------------------------------------


def _default_data() -> dict:
    return tomllib.loads(resources.files("robosoc.chip").joinpath("energy_coefficients.toml").read_text())


def _dump(data: dict) -> str:
    """TOML text of a coefficient-file-shaped dict (top-level scalars, then section.key tables)."""

    def value(v: object) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        return json.dumps(v) if isinstance(v, str) else repr(v)

    lines = [f"{k} = {value(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for section, entries in data.items():
        if isinstance(entries, dict):
            for key, entry in entries.items():
                lines.append(f"[{section}.{key}]")
                lines += [f"{k} = {value(v)}" for k, v in entry.items()]
    return "\n".join(lines) + "\n"


def _load_edited(tmp_path, edit) -> EnergyModel:
    data = _default_data()
    edit(data)
    path = tmp_path / "coefficients.toml"
    path.write_text(_dump(data))
    return EnergyModel.load(path)


def test_the_dumped_default_file_loads_to_the_default_model(tmp_path):
    assert _load_edited(tmp_path, lambda d: None).instruction == EnergyModel.load().instruction


def _set(section: str, key: str, field: str, v: object):
    def edit(d: dict) -> None:
        d[section][key][field] = v

    return edit


def _drop(section: str, key: str | None = None, field: str | None = None):
    def edit(d: dict) -> None:
        if key is None:
            del d[section]
        elif field is None:
            del d[section][key]
        else:
            del d[section][key][field]

    return edit


def _add_unknown(d: dict) -> None:
    d["stall"]["zz_cycle"] = {"pj": 1.0, "status": "assumed", "source": "x"}
    d["stall"]["aa_cycle"] = {"pj": 1.0, "status": "assumed", "source": "x"}


STATUS_RULE = "must be 'published', 'measured' or 'assumed'"
BAD_FILES = [
    (_drop("noc"), "noc", "missing table"),
    (_drop("instruction"), "instruction", "missing table"),
    (_drop("stall", "sleep_cycle"), "stall.sleep_cycle", "missing entry"),
    (_drop("instruction", "mul", "pj"), "instruction.mul.pj", "expected a non-negative number, got None"),
    (_set("instruction", "mul", "pj", -0.5), "instruction.mul.pj", "expected a non-negative number, got -0.5"),
    (_set("stall", "mul_cycle", "pj", "10"), "stall.mul_cycle.pj", "expected a non-negative number, got '10'"),
    (_set("noc", "leakage", "pj", True), "noc.leakage.pj", "expected a non-negative number, got True"),
    (_drop("noc", "leakage", "status"), "noc.leakage.status", STATUS_RULE),
    (_set("noc", "leakage", "status", "Published"), "noc.leakage.status", STATUS_RULE),
    (_drop("stall", "dma_cycle", "source"), "stall.dma_cycle.source", "every coefficient needs its provenance"),
    (_set("stall", "dma_cycle", "source", "  "), "stall.dma_cycle.source", "every coefficient needs its provenance"),
    (_add_unknown, "stall.aa_cycle", "unknown entry"),
    (lambda d: d.update(clock_ns=0), "clock_ns", "expected a positive number"),
    (lambda d: d.update(clock_ns=-4.0), "clock_ns", "expected a positive number"),
    (lambda d: d.update(clock_ns=True), "clock_ns", "expected a positive number"),
    (lambda d: d.update(clock_ns="4"), "clock_ns", "expected a positive number"),
]  # fmt: skip


@pytest.mark.parametrize(("edit", "field", "reason"), BAD_FILES)
def test_each_bad_coefficient_names_file_field_and_reason(tmp_path, edit, field, reason):
    with pytest.raises(ConfigError) as info:
        _load_edited(tmp_path, edit)
    path = str(tmp_path / "coefficients.toml")
    assert (info.value.where, info.value.field, info.value.reason) == (path, field, reason)
    assert str(info.value) == f"{path}: {field}: {reason}"


def test_unreadable_and_invalid_files_name_the_file(tmp_path):
    missing = tmp_path / "nope.toml"
    with pytest.raises(ConfigError) as info:
        EnergyModel.load(missing)
    assert (info.value.where, info.value.field) == (str(missing), "")
    assert info.value.reason == "cannot read: No such file or directory"
    broken = tmp_path / "broken.toml"
    broken.write_text("clock_ns = [")
    with pytest.raises(ConfigError) as info:
        EnergyModel.load(broken)
    assert (info.value.where, info.value.field) == (str(broken), "")
    assert info.value.reason.startswith("invalid TOML: ")
    latin = tmp_path / "latin.toml"
    latin.write_bytes(b"clock_ns = 4.0\n# caf\xe9\n")
    with pytest.raises(ConfigError) as info:
        EnergyModel.load(latin)
    assert (info.value.where, info.value.field) == (str(latin), "")
    assert info.value.reason == "not UTF-8 text (offset 20): expected a TOML file"


def test_edge_values_that_are_accepted(tmp_path):
    def edit(d: dict) -> None:
        d["instruction"]["mul"]["pj"] = 0  # zero and integers are fine
        d["stall"]["mul_cycle"]["pj"] = 12
        d["stall"]["mul_cycle"]["status"] = "measured"
        d["clock_ns"] = 0.5

    m = _load_edited(tmp_path, edit)
    assert m.instruction["mul"].pj == 0.0
    assert m.stall["mul_cycle"].pj == 12.0 and isinstance(m.stall["mul_cycle"].pj, float)
    assert m.stall["mul_cycle"].status == "measured" and m.clock_ns == 0.5
    assert m.path == str(tmp_path / "coefficients.toml")
    defaulted = _load_edited(tmp_path, lambda d: d.pop("clock_ns"))
    assert defaulted.clock_ns == 4.0
    assert EnergyModel.load().clock_ns == 4.0 and EnergyModel.load().path == "robosoc/chip/energy_coefficients.toml"


def test_noc_energy_terms_by_hand():
    m = EnergyModel.load()
    counts = {"router_cycles": 100, "router_busy_cycles": 30, "port_busy_cycles": 40, "port_idle_cycles": 460}
    assert m.noc_pj(counts) == pytest.approx(
        {
            "buffers": 40 * 3.102 + 460 * 1.459,
            "control": 30 * 10.621 + 70 * 2.303,
            "leakage": 100 * 0.892,
        }
    )


def test_breakdown_names_every_class_and_stall_kind_and_ignores_other_counters():
    m = EnergyModel.load()
    counts = {"add": 2, "sleep_cycle": 10, "dma_cycle": 3, "cycles": 1000, "instructions": 2}
    breakdown = m.breakdown_pj(counts)
    assert set(breakdown) == set(INSTRUCTION_CLASSES) | set(STALL_KINDS)
    assert breakdown["add"] == 2 * 23.58 and breakdown["sleep_cycle"] == 10 * 0.9 and breakdown["dma_cycle"] == 3 * 14.4
    assert sum(v for k, v in breakdown.items() if k not in ("add", "sleep_cycle", "dma_cycle")) == 0
    assert m.total_nj(counts) == pytest.approx((2 * 23.58 + 9.0 + 3 * 14.4) / 1000)


def test_total_is_the_breakdowns_sum_bit_for_bit():
    # the flight's job records add the breakdown in this order; total_pj must give the same float
    import random

    model = EnergyModel.load()
    keys = [*model.instruction, *model.stall, "cycles", "instructions"]
    rng = random.Random(3)
    for _ in range(5000):
        counts = {k: rng.randrange(0, 10 ** rng.randrange(1, 12)) for k in keys if rng.random() < 0.8}
        assert model.total_pj(counts) == sum(model.breakdown_pj(counts).values())
    assert model.total_pj({}) == 0.0
