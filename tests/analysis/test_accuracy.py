"""Accuracy metrics on inputs whose answers are known by hand."""

import dataclasses
import math

import numpy as np
import pytest

from robosoc.analysis.accuracy import PwmAgreement, golden_replay, quaternion_error
from robosoc.control.flight import ROW_FIELDS
from robosoc.control.quaternion import from_euler, multiply


def _attitudes(n: int, seed: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.array([from_euler(*rng.uniform(-1.0, 1.0, 3)) for _ in range(n)])


def test_identical_series_have_no_error() -> None:
    q = _attitudes(50)
    err = quaternion_error(q, q.copy())
    assert err.samples == 50
    assert err.mean_component == 0.0 and err.max_component == 0.0
    assert err.mean_deg == pytest.approx(0.0, abs=1e-5) and err.max_deg == pytest.approx(0.0, abs=1e-5)


def test_the_sign_of_a_quaternion_does_not_count() -> None:
    q = _attitudes(20)
    err = quaternion_error(-q, q)
    assert err.mean_component == 0.0
    assert err.max_deg == pytest.approx(0.0, abs=1e-5)


def test_a_known_rotation_offset_gives_its_angle() -> None:
    q = _attitudes(30)
    offset = from_euler(0.0, 0.0, math.radians(3.0))  # 3 degrees about z, applied in the body frame
    rotated = np.array([multiply(a, offset) for a in q])
    err = quaternion_error(rotated, q)
    assert err.mean_deg == pytest.approx(3.0, abs=1e-6)
    assert err.max_deg == pytest.approx(3.0, abs=1e-6)


def test_the_seeds_terms_are_the_mean_absolute_component_difference() -> None:
    # identity against a quaternion off by 0.002 in x and 0.004 in y (not normalised: the seed's
    # metric is per component): mean |diff| = (0 + 0.002 + 0.004 + 0) / 4 = 0.0015 = 0.15 %
    a = np.array([[1.0, 0.002, 0.004, 0.0]] * 7)
    b = np.array([[1.0, 0.0, 0.0, 0.0]] * 7)
    err = quaternion_error(a, b)
    assert err.mean_component == pytest.approx(0.0015)
    assert err.mean_percent == pytest.approx(0.15)
    assert err.max_component == pytest.approx(0.004)


def test_quaternion_error_refuses_bad_shapes_and_empty_is_nan() -> None:
    with pytest.raises(ValueError, match=r"\(n, 4\)"):
        quaternion_error(np.zeros((3, 4)), np.zeros((4, 4)))
    assert math.isnan(quaternion_error(np.zeros((0, 4)), np.zeros((0, 4))).mean_deg)


def test_pwm_agreement_counts_samples_within_one_count() -> None:
    golden = np.array([[100, 100, 100, 100], [120, 120, 120, 120], [90, 90, 90, 90]])
    chip = {0: (100, 101, 99, 100), 1: (120, 123, 120, 120)}  # sample 2: no command
    agree = PwmAgreement.of(chip, golden, [0, 1, 2])
    assert agree.samples == 2
    assert agree.within_one == 0.5
    assert agree.max_diff == 3
    assert agree.mean_abs_diff == pytest.approx((0 + 1 + 1 + 0 + 0 + 3 + 0 + 0) / 8)


def test_golden_replay_is_the_host_controller_on_the_packets_values() -> None:
    from robosoc.cosim.replay import built_in_rows

    rows = built_in_rows(0.3)
    gold = golden_replay(rows)
    assert gold.quaternion.shape == (len(rows), 4)
    assert not gold.armed.any()  # the first 3 s calibrate on the ground
    # the recorded flight's own estimate columns come from the same controller on unquantised
    # samples: the golden model on the Q16.16 values stays within the quantisation's effect
    est = rows[:, [ROW_FIELDS.index(c) for c in ("est_qw", "est_qx", "est_qy", "est_qz")]]
    assert quaternion_error(gold.quaternion, est).max_deg < 0.05
    assert np.all(gold.pwm == 0)  # disarmed: motors off


def test_pwm_agreement_counts_samples_within_one_count_and_is_empty_without_commands() -> None:
    golden = np.array([[100, 100, 100, 100], [200, 200, 200, 200], [300, 300, 300, 300]], dtype=np.int64)
    chip = {0: (101, 99, 100, 100), 1: (202, 200, 200, 200), 2: (300, 300, 300, 300), 7: (0, 0, 0, 0)}
    agreement = PwmAgreement.of(chip, golden, [0, 1, 2])
    assert agreement == PwmAgreement(3, 2 / 3, 2, 4 / 12)  # sample 1 is two counts off
    empty = PwmAgreement.of({}, golden, [0, 1])
    assert (empty.samples, empty.max_diff) == (0, 0)
    assert math.isnan(empty.within_one) and math.isnan(empty.mean_abs_diff)
    assert PwmAgreement.of(chip, golden, []).samples == 0


def test_golden_replay_of_a_flight_that_takes_off_follows_the_flight_own_controller() -> None:
    """A host flight records its controller's estimate and PWM; the golden model, fed the same
    samples through the chip's Q16.16 packets, stays within the quantisation's effect of them."""
    from run_folders import host_rows

    rows = host_rows(4.5, seed=2)
    gold = golden_replay(rows)
    armed = rows[:, ROW_FIELDS.index("armed")] > 0.5
    assert armed.any() and not armed.all()
    assert np.array_equal(gold.armed, armed)
    est = rows[:, [ROW_FIELDS.index(c) for c in ("est_qw", "est_qx", "est_qy", "est_qz")]]
    assert quaternion_error(gold.quaternion, est).max_deg < 0.05
    assert np.abs(gold.height - rows[:, ROW_FIELDS.index("est_height")]).max() < 0.01
    pwm = rows[:, [ROW_FIELDS.index(f"pwm{i}") for i in range(4)]]
    assert gold.pwm.dtype == np.int64 and np.abs(gold.pwm - pwm).max() <= 3
    assert np.all(gold.pwm[~armed] == 0) and np.all(gold.pwm[armed] > 0)
    # the climb: the estimated vertical velocity is up while the height setpoint rises
    rising = np.flatnonzero(np.diff(rows[:, ROW_FIELDS.index("sp_height")]) > 0)
    assert len(rising) > 10 and np.median(gold.vertical_velocity[rising[5:]]) > 0.05
    # one row alone takes the controller's own sample period
    one = golden_replay(rows[:1])
    assert np.array_equal(one.quaternion[0], gold.quaternion[0]) and one.height[0] == gold.height[0]


def test_quaternion_error_edge_cases() -> None:
    empty = quaternion_error(np.zeros((0, 4)), np.zeros((0, 4)))
    assert empty.samples == 0
    assert all(math.isnan(v) for v in (empty.mean_component, empty.max_component, empty.mean_deg, empty.max_deg))
    for a, b in (
        (np.zeros((2, 3)), np.zeros((2, 3))),
        (np.zeros((2, 4)), np.zeros((3, 4))),
        (np.zeros(4), np.zeros(4)),
    ):
        with pytest.raises(ValueError, match="quaternion series"):
            quaternion_error(a, b)
    rng = np.random.default_rng(4)
    q = rng.normal(size=(200, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    same = quaternion_error(q, q)
    assert same.max_deg == 0.0 and same.max_component == 0.0  # no NaN from rounding past 1
    flipped = quaternion_error(-q, q)  # the same rotations
    assert flipped.max_component == 0.0 and flipped.max_deg == 0.0
    # a 90° turn about x against level, with a scaled (unnormalised) reference
    turn = quaternion_error(
        np.array([[math.cos(math.pi / 4), math.sin(math.pi / 4), 0, 0]]), np.array([[2.0, 0, 0, 0]])
    )
    assert turn.mean_deg == pytest.approx(90.0)


def test_golden_replay_follows_each_attitude_setpoint_on_its_own_axis() -> None:
    """Roll, then pitch, then yaw steps of different sizes: the golden model fed the flight's
    packets commands the motors as the flight's own controller did, axis for axis."""
    from robosoc.config.scenario import FlightPlan, ScenarioConfig, SetpointStep
    from robosoc.config.vehicle import vehicle_preset
    from robosoc.control.flight import fly
    from robosoc.control.host import HostController

    steps = (SetpointStep(1.2, "roll", 8.0), SetpointStep(1.6, "pitch", -5.0), SetpointStep(2.0, "yaw", 20.0))
    scenario = ScenarioConfig(duration_s=2.4, flight=FlightPlan(takeoff_s=0.4, climb_s=0.6, steps=steps))
    vehicle = vehicle_preset(scenario.vehicle)
    scenario = dataclasses.replace(scenario, seed=4)
    rows = fly(scenario, vehicle, HostController.for_scenario(scenario, vehicle))
    sp = rows[:, [ROW_FIELDS.index(f"sp_{a}") for a in ("roll", "pitch", "yaw")]]
    assert len(set(np.round(sp[-1], 6))) == 3  # three different attitude setpoints at the end
    gold = golden_replay(rows, scenario, vehicle)
    pwm = rows[:, [ROW_FIELDS.index(f"pwm{i}") for i in range(4)]]
    assert np.abs(gold.pwm - pwm).max() <= 3
    # each step moves the four motors apart in its own pattern: the replay sees the same steps
    late = rows[:, ROW_FIELDS.index("t")] > 1.3
    assert np.ptp(gold.pwm[late], axis=0).max() > 20


def test_parallel_quaternions_of_any_length_are_zero_degrees_apart() -> None:
    """Rounding can put the normalised dot product of parallel quaternions a hair above 1: the
    angle is still 0, never NaN; so are unnormalised integer inputs."""
    a = np.random.default_rng(1).normal(size=(1000, 4))
    b = 3.0 * a
    dot = np.abs(np.einsum("ij,ij->i", a, b)) / np.sqrt(np.einsum("ij,ij->i", a, a) * np.einsum("ij,ij->i", b, b))
    assert (dot > 1.0).any()  # the case this test is about
    err = quaternion_error(a, b)
    assert 0.0 <= err.max_deg < 1e-5 and 0.0 <= err.mean_deg < 1e-6  # not NaN: the rows above 1 count 0
    ints = quaternion_error(np.array([[2, 0, 0, 0]]), np.array([[1, 0, 0, 0]]))
    assert ints.max_deg == 0.0 and ints.max_component == 1.0
