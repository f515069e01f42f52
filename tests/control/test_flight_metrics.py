"""``flight_metrics`` on synthetic flights whose figures are known by construction.

Each flight is a grid of 10 ms rows (t = k/100 s, exact at the boundaries used) with every column
zero except the few samples a test marks.  The marks sit just inside and just outside each window
the metrics' docstrings define (hover span, overshoot windows, tracking spans, 90 % rise), with
distinct magnitudes, so the expected figures are sums over the marks written out in the test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from robosoc.config.scenario import FlightPlan, SetpointStep
from robosoc.control.flight import ROW_FIELDS, flight_metrics

REST = 0.2


def _rows(seconds: float, start: float = 0.0) -> np.ndarray:
    n = round((seconds - start) * 100)
    rows = np.zeros((n, len(ROW_FIELDS)))
    rows[:, 0] = (np.arange(n) + round(start * 100)) / 100
    rows[:, ROW_FIELDS.index("qw")] = 1.0
    rows[:, ROW_FIELDS.index("est_qw")] = 1.0
    return rows


def _set(rows: np.ndarray, name: str, t: float, value: float) -> None:
    k = int(np.nonzero(np.isclose(rows[:, 0], t, atol=1e-12))[0][0])
    rows[k, ROW_FIELDS.index(name)] = value


def test_hover_span_boundaries() -> None:
    # take-off climb 1.0 → 3.0 s, settled from 3.5 s; a height move 6.0 → 8.0 s, settled from 8.5 s
    plan = FlightPlan(takeoff_s=1.0, climb_s=2.0, height_m=1.0, steps=(SetpointStep(6.0, "height", 1.5),))
    assert [(m.start_s, m.end_s) for m in plan.height_moves(REST)] == [(1.0, 3.0), (6.0, 8.0)]
    rows = _rows(10.0)
    inside = {3.5: 0.3, 5.5: 0.25, 5.99: 0.1, 8.5: 0.2, 9.99: -0.05}  # hover samples
    outside = {3.49: 0.7, 6.0: 0.9, 7.0: 0.6, 8.49: 0.8, 2.0: 1.1}  # settling or moving
    for t, e in {**inside, **outside}.items():
        _set(rows, "z", t, e)  # the setpoint column is 0: z is the error
    m = flight_metrics(rows, plan, REST)
    hover_samples = 1000 - 350 - 250  # t >= 3.5, without 6.0 <= t < 8.5
    assert m.hover_rms == pytest.approx(math.sqrt(sum(e * e for e in inside.values()) / hover_samples), rel=1e-12)
    assert m.hover_max == 0.3


def test_overshoot_windows_of_climbs_and_descents() -> None:
    # moves: climb 1 → 3 s to 2.0 m; descent 3.5 → 5.5 s to 1.0 m; climb 7 → 9 s to 1.5 m.
    # windows: [1, 3.5) (cut by the next start), [3.5, 6.5), [7, 10)
    plan = FlightPlan(
        takeoff_s=1.0, climb_s=2.0, height_m=2.0,
        steps=(SetpointStep(3.5, "height", 1.0), SetpointStep(7.0, "height", 1.5)),
    )  # fmt: skip
    assert [(m.start_s, m.end_s, m.to_m) for m in plan.height_moves(REST)] == [
        (1.0, 3.0, 2.0), (3.5, 5.5, 1.0), (7.0, 9.0, 1.5)
    ]  # fmt: skip
    rows = _rows(10.5)
    rows[:, ROW_FIELDS.index("z")] = 1.5  # below the first target, above the second, at the third
    _set(rows, "z", 3.4, 2.5)  # 0.5 above the first target, in its window
    _set(rows, "z", 3.6, 2.9)  # above: not beyond a descent's target; 0.9 if the first window ran on
    _set(rows, "z", 6.0, 0.4)  # 0.6 below the descent's target
    _set(rows, "z", 6.5, 0.0)  # just after the descent's window
    _set(rows, "z", 10.0, 2.3)  # just after the last window (t < 7 + 3): 0.8 above 1.5 m
    assert flight_metrics(rows, plan, REST).overshoot == pytest.approx(0.6)
    _set(rows, "z", 9.99, 1.6)  # the last window's last sample: 0.1 above 1.5 m
    _set(rows, "z", 3.5, 0.3)  # the descent window's first sample: 0.7 below 1.0 m
    assert flight_metrics(rows, plan, REST).overshoot == pytest.approx(0.7)
    never = _rows(10.5)
    never[:, ROW_FIELDS.index("z")] = 1.2  # below both climbs' targets, above the descent's
    assert flight_metrics(never, plan, REST).overshoot == 0.0


def test_tracking_spans() -> None:
    # attitude from take-off + climb_s = 3.0 s; a roll step at 5.0 s leaves out [5.0, 5.5) for roll only
    plan = FlightPlan(takeoff_s=1.0, climb_s=2.0, steps=(SetpointStep(5.0, "roll", 10.0),))
    rows = _rows(8.0)
    roll_in = {3.0: 0.01, 4.5: 0.02, 4.99: 0.03, 5.5: 0.04}
    roll_out = {2.99: 0.5, 5.0: 0.6, 5.49: 0.7}
    for t, e in {**roll_in, **roll_out}.items():
        _set(rows, "roll", t, e)
    _set(rows, "pitch", 5.2, 0.05)  # the roll step leaves pitch alone
    _set(rows, "yaw", 7.0, 2 * math.pi + 0.01)  # wrapped: an error of 0.01 rad
    m = flight_metrics(rows, plan, REST)
    n_roll, n_all = 500 - 50, 500  # t in [3.0, 8.0), roll without [5.0, 5.5)
    assert m.tracking_rms[0] == pytest.approx(math.degrees(math.sqrt(sum(e * e for e in roll_in.values()) / n_roll)))
    assert m.tracking_rms[1] == pytest.approx(math.degrees(math.sqrt(0.05**2 / n_all)))
    assert m.tracking_rms[2] == pytest.approx(math.degrees(math.sqrt(0.01**2 / n_all)))


def _rise_plan() -> FlightPlan:
    return FlightPlan(
        takeoff_s=1.0, climb_s=2.0,
        steps=(SetpointStep(4.0, "height", 1.5), SetpointStep(5.0, "roll", 10.0), SetpointStep(6.0, "roll", -10.0),
               SetpointStep(7.0, "pitch", 20.0), SetpointStep(8.0, "yaw", 5.0)),
    )  # fmt: skip


def test_step_rise_times() -> None:
    plan = _rise_plan()
    rows = _rows(9.0)
    r10 = math.radians(10.0)
    roll, sp_roll = ROW_FIELDS.index("roll"), ROW_FIELDS.index("sp_roll")
    t = rows[:, 0]
    rows[(t >= 5.0 - 1e-9) & (t < 6.0 - 1e-9), sp_roll] = r10
    rows[t >= 6.0 - 1e-9, sp_roll] = -r10
    _set(rows, "sp_roll", 4.98, 0.05)  # an earlier setpoint: only the last one before the step counts
    # roll: 0 → 10°: 50 % at 5.10, exactly 90 % at 5.18, 95 % at 5.19, 100 % from 5.20
    for time, fraction in ((5.1, 0.5), (5.18, 0.9), (5.19, 0.95)):
        _set(rows, "roll", time, fraction * r10)
    rows[(t >= 5.2 - 1e-9) & (t < 6.0 - 1e-9), roll] = r10
    assert (rows[518, roll] - 0.0) / (r10 - 0.0) == 0.9  # the 90 % mark is exact in floating point
    # roll: 10° → −10°: 90 % of the way (to −8°) at 6.30
    rows[(t >= 6.0 - 1e-9), roll] = r10
    rows[(t >= 6.30 - 1e-9), roll] = -r10
    # pitch: 0 → 20°, already there 0.5 s before the step: rise 0
    rows[t >= 6.5 - 1e-9, ROW_FIELDS.index("pitch")] = math.radians(20.0)
    # yaw never gets there: nan
    m = flight_metrics(rows, plan, REST)
    axes = [(axis, time) for axis, time, _ in m.step_rise]
    assert axes == [("roll", 5.0), ("roll", 6.0), ("pitch", 7.0), ("yaw", 8.0)]  # the height step is skipped
    rises = [rise for _, _, rise in m.step_rise]
    assert rises[0] == pytest.approx(0.18) and rises[1] == pytest.approx(0.30) and rises[2] == 0.0
    assert math.isnan(rises[3])


def test_a_step_before_the_first_row_starts_from_zero() -> None:
    plan = _rise_plan()
    rows = _rows(9.0, start=5.0)  # the log starts at the roll step: no setpoint before it
    rows[:, ROW_FIELDS.index("roll")] = math.radians(9.5)  # 95 % of 10° from 0 at once
    rise = flight_metrics(rows, plan, REST).step_rise[0]
    assert rise == ("roll", 5.0, 0.0)


def test_armed_figures() -> None:
    plan = FlightPlan(takeoff_s=1.0, climb_s=2.0)
    rows = _rows(4.0)
    armed = rows[:, 0] >= 1.0
    rows[armed, ROW_FIELDS.index("armed")] = 1.0
    for i, value in enumerate((60, 55, 70, 80)):
        rows[armed, ROW_FIELDS.index(f"pwm{i}")] = value
    rows[~armed, ROW_FIELDS.index("pwm1")] = 0  # unarmed counts do not count
    _set(rows, "pwm2", 2.0, 51)
    half = math.radians(2.0) / 2  # the estimate tilted 2° about x at one sample
    k = 250
    rows[k, [ROW_FIELDS.index(n) for n in ("est_qw", "est_qx")]] = (math.cos(half), math.sin(half))
    rows[k, ROW_FIELDS.index("est_roll")] = math.radians(2.0)
    rows[k, ROW_FIELDS.index("est_height")] = 0.3
    _set(rows, "est_height", 0.5, 9.0)  # before arming: ignored
    m = flight_metrics(rows, plan, REST)
    n_armed = 300
    assert m.min_pwm_armed == 51
    assert m.ekf_max == pytest.approx(2.0) and m.ekf_rms == pytest.approx(2.0 / math.sqrt(n_armed))
    assert m.ekf_euler_rms == pytest.approx((2.0 / math.sqrt(n_armed), 0.0, 0.0))
    assert m.height_estimate_rms == pytest.approx(0.3 / math.sqrt(n_armed))
    never = flight_metrics(_rows(4.0), plan, REST)
    assert never.min_pwm_armed == -1 and math.isnan(never.ekf_max) and math.isnan(never.ekf_rms)
