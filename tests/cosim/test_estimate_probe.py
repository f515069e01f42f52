"""Telemetry: the chip's estimator state read from its tile's memory between jobs, no cycle spent."""

import math
from pathlib import Path

import numpy as np
import pytest

from robosoc.analysis.accuracy import golden_replay
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.control.flight import ROW_FIELDS
from robosoc.cosim import firmware_run
from robosoc.cosim.lockstep import fly_chip
from robosoc.cosim.replay import built_in_rows, replay
from robosoc.host.scenario_image import firmware_image
from robosoc.host.telemetry import ESTIMATE_QUATERNION
from robosoc.program.dwarf import member_offset, type_size, variable_field
from robosoc.program.elf import ElfError

WINDOW = slice(280, 330)
"""0.2 s of calibration, then 0.3 s of flight (take-off at 3 s)."""


def test_dwarf_offsets_match_the_c_layout() -> None:
    elf = firmware_image(FirmwareConfig()).elf
    # est_t starts with ekf_t: x[7], p[49], mag_reference[3] (4-byte reals), then alt_t: reference, h, v
    assert member_offset(elf, "est_t", "ekf.x") == (0, 7 * 4)
    ekf_bytes = (7 + 49 + 3) * 4
    assert member_offset(elf, "est_t", "alt")[0] == ekf_bytes
    assert member_offset(elf, "est_t", "alt.h") == (ekf_bytes + 4, 4)
    assert member_offset(elf, "est_t", "alt.v") == (ekf_bytes + 8, 4)
    with pytest.raises(ElfError, match=r"est_t\.nothing"):
        member_offset(elf, "est_t", "nothing")
    # the same through the variable that holds it, and the kernel's task table by its type
    assert variable_field(elf, "app_est", "alt.h") == (ekf_bytes + 4, 4)
    assert variable_field(elf, "app_est", "") == (0, type_size(elf, "est_t"))
    assert type_size(elf, "os_tcb") == 128  # the kernel's _Static_assert says so
    with pytest.raises(ElfError, match=r"no variable 'nowhere'"):
        variable_field(elf, "nowhere")
    with pytest.raises(ElfError, match=r"no member 'alt.x'.*ekf, alt"):
        variable_field(elf, "app_est", "alt.x")


@pytest.fixture(scope="module")
def rows() -> np.ndarray:
    return built_in_rows(3.3)[: WINDOW.stop]


@pytest.mark.parametrize(("arith", "bound_q", "bound_h"), [("float", 1e-5, 1e-5), ("fixed", 5e-4, 2e-3)])
def test_chip_estimate_follows_the_golden_ekf(rows: np.ndarray, arith: str, bound_q: float, bound_h: float) -> None:
    fw = FirmwareConfig(arith=arith)
    plain = replay(rows[WINDOW.start - 280 :], fw)  # the whole stream: the firmware calibrates first
    gold = golden_replay(rows)
    by_sample = {r.sample: r.values for r in plain.telemetry}
    ks = [k for k in range(WINDOW.start, WINDOW.stop) if k in by_sample]
    assert ks == list(range(WINDOW.start, WINDOW.stop))  # event release: every period's close
    # event release: the estimate read at the close of period k is the one after sample k
    chip_q = np.array([[by_sample[k][n] for n in ESTIMATE_QUATERNION] for k in ks])
    assert np.abs(chip_q - gold.quaternion[ks]).max() < bound_q
    heights = np.array([by_sample[k]["est_height"] for k in ks])
    assert np.abs(heights - gold.height[ks]).max() < bound_h
    assert gold.armed[ks].any() and not gold.armed[ks].all()  # the window spans the take-off


def test_the_probe_costs_no_cycle(rows: np.ndarray, monkeypatch: pytest.MonkeyPatch) -> None:
    """The same replay with the probe and without it: identical jobs and counters."""
    short = rows[:6]
    probed = replay(short, FirmwareConfig())
    calls = []
    fake = {"est_height": 0.0}
    monkeypatch.setattr(firmware_run.TelemetryReader, "read", lambda *a, **k: calls.append(a) or fake)  # reads nothing
    unprobed = replay(short, FirmwareConfig())
    assert len(calls) == len(probed.telemetry) == len(short)
    assert [r.values for r in unprobed.telemetry] == [fake] * len(calls)
    assert [(j.release_cycle, j.completion_cycle, j.exec_cycles) for j in probed.jobs] == [
        (j.release_cycle, j.completion_cycle, j.exec_cycles) for j in unprobed.jobs
    ]
    assert probed.counters == unprobed.counters and probed.cycles == unprobed.cycles


def test_lockstep_rows_carry_the_chips_estimate() -> None:
    scenario = ScenarioConfig(duration_s=0.05)
    flight = fly_chip(scenario, vehicle_preset(scenario.vehicle))
    cols = [ROW_FIELDS.index(c) for c in ("est_qw", "est_qx", "est_qy", "est_qz", "est_height")]
    est = flight.rows[:, cols]
    assert np.isnan(est[0]).all()  # nothing read before the first sample's period closed
    assert not np.isnan(est[1:]).any()
    by_sample = {r.sample: r.values for r in flight.run.telemetry}
    for k in range(1, len(flight.rows)):
        e = by_sample[k - 1]  # row k holds the newest estimate at t_k: sample k - 1's
        assert tuple(est[k, :4]) == tuple(e[n] for n in ESTIMATE_QUATERNION)
        assert est[k, 4] == e["est_height"]
    norms = [np.linalg.norm([e[n] for n in ESTIMATE_QUATERNION]) for e in by_sample.values()]
    assert all(math.isclose(n, 1.0, abs_tol=1e-3) for n in norms)


def test_the_debug_index_kept_in_a_folder_is_read_back_the_same(tmp_path: Path) -> None:
    from robosoc.program import dwarf

    elf = firmware_image(FirmwareConfig()).elf
    store = tmp_path / "dwarf"
    first = dwarf.debug_index(elf, store)
    kept = list(store.iterdir())
    assert [p.suffix for p in kept] == [".json"]  # one file, no scratch left
    dwarf._index.cache_clear()  # a later process: the kept file, not the DWARF
    again = dwarf.debug_index(elf, store)
    assert again == first and again is not first
    assert again.member_offset("est_t", "alt.h") == member_offset(elf, "est_t", "alt.h")
    assert again.variable_field("app_est", "alt.h") == variable_field(elf, "app_est", "alt.h")
    assert again.type_size("os_tcb") == 128
    kept[0].write_text("{not json")  # a damaged file is read again from the DWARF and replaced
    dwarf._index.cache_clear()
    assert dwarf.debug_index(elf, store) == first
    assert dwarf.DebugIndex.from_json(str(elf), kept[0].read_text()) == first
