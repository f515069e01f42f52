"""The estimate probe: the chip's estimator state read from its tile's memory, no cycle spent."""

import math

import numpy as np
import pytest

from robosoc.analysis.accuracy import golden_replay
from robosoc.config.firmware import FirmwareConfig
from robosoc.config.scenario import ScenarioConfig
from robosoc.config.vehicle import vehicle_preset
from robosoc.control.flight import ROW_FIELDS
from robosoc.cosim.lockstep import fly_chip
from robosoc.cosim.replay import built_in_rows, replay
from robosoc.host import flight_app
from robosoc.program.dwarf import member_offset
from robosoc.program.elf import ElfError

WINDOW = slice(280, 330)
"""0.2 s of calibration, then 0.3 s of flight (take-off at 3 s)."""


def test_dwarf_offsets_match_the_c_layout() -> None:
    elf = flight_app.build(FirmwareConfig())
    # est_t starts with ekf_t: x[7], p[49], mag_reference[3] (4-byte reals), then alt_t: reference, h, v
    assert member_offset(elf, "est_t", "ekf.x") == (0, 7 * 4)
    ekf_bytes = (7 + 49 + 3) * 4
    assert member_offset(elf, "est_t", "alt")[0] == ekf_bytes
    assert member_offset(elf, "est_t", "alt.h") == (ekf_bytes + 4, 4)
    assert member_offset(elf, "est_t", "alt.v") == (ekf_bytes + 8, 4)
    with pytest.raises(ElfError, match=r"est_t\.nothing"):
        member_offset(elf, "est_t", "nothing")


@pytest.fixture(scope="module")
def rows() -> np.ndarray:
    return built_in_rows(3.3)[: WINDOW.stop]


@pytest.mark.parametrize(("arith", "bound_q", "bound_h"), [("float", 1e-5, 1e-5), ("fixed", 5e-4, 2e-3)])
def test_chip_estimate_follows_the_golden_ekf(rows: np.ndarray, arith: str, bound_q: float, bound_h: float) -> None:
    fw = FirmwareConfig(arith=arith)
    plain = replay(rows[WINDOW.start - 280 :], fw)  # the whole stream: the firmware calibrates first
    gold = golden_replay(rows)
    by_sample = {e.sample: e for e in plain.estimates}
    ks = [k for k in range(WINDOW.start, WINDOW.stop) if k in by_sample]
    assert ks == list(range(WINDOW.start, WINDOW.stop))  # event release: every period's close
    chip_q = np.array([by_sample[k].quaternion for k in ks])
    assert np.abs(chip_q - gold.quaternion[ks]).max() < bound_q
    heights = np.array([by_sample[k].height for k in ks])
    assert np.abs(heights - gold.height[ks]).max() < bound_h
    # event release: the estimate read at the close of period k is the one after sample k
    assert all(by_sample[k].jobs == k + 1 for k in ks)
    assert gold.armed[ks].any() and not gold.armed[ks].all()  # the window spans the take-off


def test_the_probe_costs_no_cycle(rows: np.ndarray, monkeypatch: pytest.MonkeyPatch) -> None:
    """The same replay with the probe and without it: identical jobs and counters."""
    short = rows[:6]
    probed = replay(short, FirmwareConfig())
    calls = []
    fake = flight_app.ChipEstimate(0, 10**9, (1.0, 0.0, 0.0, 0.0), 0.0, 0.0)
    # the flight's reader, made once per run, reads nothing
    monkeypatch.setattr(flight_app.EstimateReader, "read", lambda self, *a, **k: calls.append(a) or fake)
    unprobed = replay(short, FirmwareConfig())
    assert len(calls) == len(probed.estimates) == len(short) and unprobed.estimates == [fake] * len(calls)
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
    by_sample = {e.sample: e for e in flight.run.estimates}
    for k in range(1, len(flight.rows)):
        e = by_sample[k - 1]  # row k holds the newest estimate at t_k: sample k - 1's
        assert tuple(est[k, :4]) == pytest.approx(e.quaternion, abs=0)
        assert est[k, 4] == e.height
    assert all(math.isclose(np.linalg.norm(e.quaternion), 1.0, abs_tol=1e-3) for e in by_sample.values())
