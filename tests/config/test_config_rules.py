"""Every validation rule of the configuration classes, at its boundary, with the exact message.

Each rule is checked on both sides of its limit (the limit itself accepted or rejected as the rule
says, and an infinite value, which an ``or`` in place of an ``and`` would let through), and the
message is compared whole: it is what a user reads ("``field: reason``", prefixed by the file and the
dotted path when a file is loaded).  The limits come from the docstrings and docs/scenarios.md.
"""

from __future__ import annotations

import math
from typing import Any

import pytest

from robosoc.config.chip import ChipConfig, NocConfig, TileConfig, TileOverride
from robosoc.config.ranges import FLOAT_FIELDS
from robosoc.config.scenario import (
    FlightPlan,
    GustConfig,
    HeightMove,
    ScenarioConfig,
    SensorConfig,
    SetpointStep,
    WindConfig,
    move_duration,
    steps_per_period,
)
from robosoc.config.vehicle import (
    DragConfig,
    MotorConfig,
    VehicleConfig,
    default_vehicle,
    laser_vehicle,
    vehicle_preset,
)

INF = math.inf


def rejected(cls: type, message: str, **kwargs: Any) -> None:
    with pytest.raises(ValueError) as info:
        cls(**kwargs)
    assert str(info.value) == message


# --- vehicle -------------------------------------------------------------------------------------

MOTOR_POSITIVE = ("psi", "j_m", "r_a", "alpha_m", "beta_m", "ct0s", "supply_voltage")


@pytest.mark.parametrize("name", MOTOR_POSITIVE)
def test_motor_constants_must_be_positive(name: str) -> None:
    rejected(MotorConfig, f"{name}: must be a positive number, got 0.0", **{name: 0.0})
    rejected(MotorConfig, f"{name}: must be a positive number, got inf", **{name: INF})
    low = FLOAT_FIELDS[f"MotorConfig.{name}"].lo  # positive and finite, and no smaller than this
    assert getattr(MotorConfig(**{name: low}), name) == low
    with pytest.raises(ValueError, match=rf"^{name}: must be in \[{low:g}, "):
        MotorConfig(**{name: low / 2})


@pytest.mark.parametrize("name", ["k_t", "k_m", "ct1s", "ct2s"])
def test_motor_coefficients_must_be_finite(name: str) -> None:
    rejected(MotorConfig, f"{name}: must be finite", **{name: INF})
    rejected(MotorConfig, f"{name}: must be finite", **{name: math.nan})


def test_motor_torque_coefficient_is_not_negative() -> None:
    rejected(MotorConfig, "k_t: must be >= 0, got -0.1", k_t=-0.1)
    assert MotorConfig(k_t=0.0).k_t == 0.0
    assert MotorConfig(k_m=-1.0, ct1s=-1.0, ct2s=2.0).k_m == -1.0  # signs of the others are free


@pytest.mark.parametrize("name", ["c_wxy", "c_wz", "c_mxy", "c_mz"])
def test_drag_coefficients_are_not_negative(name: str) -> None:
    rejected(DragConfig, f"{name}: must be >= 0, got -0.01", **{name: -0.01})
    rejected(DragConfig, f"{name}: must be >= 0, got inf", **{name: INF})
    assert getattr(DragConfig(**{name: 0.0}), name) == 0.0


VEHICLE_REJECTED = [
    ({"name": ""}, "name: must be a non-empty identifier (letters, digits, _ or -), got ''"),
    ({"name": "a b"}, "name: must be a non-empty identifier (letters, digits, _ or -), got 'a b'"),
    ({"name": "a.b"}, "name: must be a non-empty identifier (letters, digits, _ or -), got 'a.b'"),
    ({"mass": 0.0}, "mass: must be positive, got 0.0"),
    ({"mass": INF}, "mass: must be positive, got inf"),
    ({"inertia": (0.01, 0.01, 0.0)}, "inertia: all three principal moments must be positive, got (0.01, 0.01, 0.0)"),
    ({"inertia": (INF, INF, INF)}, "inertia: all three principal moments must be positive, got (inf, inf, inf)"),
    ({"inertia": (0.01, 0.01, 0.03)}, "inertia: violates the triangle inequality of a rigid body: (0.01, 0.01, 0.03)"),
    ({"inertia": (0.03, 0.01, 0.01)}, "inertia: violates the triangle inequality of a rigid body: (0.03, 0.01, 0.01)"),
    ({"inertia": (0.01, 0.03, 0.01)}, "inertia: violates the triangle inequality of a rigid body: (0.01, 0.03, 0.01)"),
    ({"com": (0.0, 0.0, 0.2)}, "com: must lie within 0.2 m of the body origin, got (0.0, 0.0, 0.2)"),
    ({"com": (-0.2, 0.0, 0.0)}, "com: must lie within 0.2 m of the body origin, got (-0.2, 0.0, 0.0)"),
    ({"com": (0.0, INF, 0.0)}, "com: must lie within 0.2 m of the body origin, got (0.0, inf, 0.0)"),
    ({"arm_length": 0.049}, "arm_length: must be in [0.05, 2] m, got 0.049"),
    ({"arm_length": 2.5}, "arm_length: must be in [0.05, 2] m, got 2.5"),
    ({"arm_length": INF}, "arm_length: must be in [0.05, 2] m, got inf"),
    ({"skid_half_length": 0.0}, "skid_half_length: must be positive, got 0.0"),
    ({"skid_offset_y": INF}, "skid_offset_y: must be positive, got inf"),
    ({"skid_radius": 0.0}, "skid_radius: must be positive, got 0.0"),
    ({"skid_bottom_z": 0.0}, "skid_bottom_z: must be below the body origin (negative), got 0.0"),
    ({"skid_bottom_z": -INF}, "skid_bottom_z: must be below the body origin (negative), got -inf"),
    ({"skid_bottom_z": -0.01, "skid_radius": 0.005}, "skid_radius: the skid must fit below the body origin"),
    ({"body_half_extents": (0.1, 0.1, 0.0)}, "body_half_extents: must be positive, got (0.1, 0.1, 0.0)"),
    ({"body_half_extents": (INF, 0.1, 0.1)}, "body_half_extents: must be positive, got (inf, 0.1, 0.1)"),
    ({"spawn_position": (0.0, INF, 0.3)}, "spawn_position: must be finite"),
    ({"spawn_position": (0.0, 0.0, 0.18)},
     "spawn_position: z = 0.18 puts the skids below the ground (skid_bottom_z = -0.1825)"),
    ({"spawn_yaw_deg": INF}, "spawn_yaw_deg: must be finite"),
    ({"idle_pwm": 255}, "idle_pwm: must be a PWM count in [0, 254], got 255"),
    ({"idle_pwm": -1}, "idle_pwm: must be a PWM count in [0, 254], got -1"),
    ({"idle_pwm": 50.0}, "idle_pwm: must be a PWM count in [0, 254], got 50.0"),
]  # fmt: skip


@pytest.mark.parametrize(("kwargs", "message"), VEHICLE_REJECTED)
def test_vehicle_rules(kwargs: dict[str, Any], message: str) -> None:
    rejected(VehicleConfig, message, **kwargs)


VEHICLE_ACCEPTED = [
    {"name": "my_quad-2"},
    {"mass": 0.5},
    {"inertia": (0.01, 0.01, 0.02)},  # the triangle inequality holds with equality, each way
    {"inertia": (0.02, 0.01, 0.01)},
    {"inertia": (0.01, 0.02, 0.01)},
    {"com": (0.0, 0.0, -0.19)},
    {"arm_length": 0.05},
    {"arm_length": 2.0},
    {"skid_bottom_z": -0.011, "skid_radius": 0.005, "spawn_position": (0.0, 0.0, 0.011)},
    {"spawn_position": (0.0, 0.0, 0.1825)},  # resting exactly on the ground
    {"idle_pwm": 0},
    {"idle_pwm": 254},
]


@pytest.mark.parametrize("kwargs", VEHICLE_ACCEPTED)
def test_vehicle_edges_that_are_accepted(kwargs: dict[str, Any]) -> None:
    vehicle = VehicleConfig(**kwargs)
    for name, value in kwargs.items():
        assert getattr(vehicle, name) == value


def test_vehicle_presets() -> None:
    a = default_vehicle("a", (1.0, 2.0, 3.0))
    assert (a.name, a.variant, a.spawn_position, a.mass) == ("a", "default", (1.0, 2.0, 3.0), 1.478)
    b = laser_vehicle("b")
    assert (b.name, b.variant, b.mass, b.spawn_position) == ("b", "laser", 1.748, (0.0, 0.0, 0.3))
    assert b.inertia == (0.013931, 0.013957, 0.021988) and b.com == (0.0, 0.0, -0.015)
    assert laser_vehicle(spawn_position=(0.0, 0.0, 1.0)).spawn_position == (0.0, 0.0, 1.0)
    assert vehicle_preset("laser", name="x") == laser_vehicle("x")
    assert vehicle_preset("default", name="y") == default_vehicle("y")
    with pytest.raises(ValueError) as info:
        vehicle_preset("hexa")
    assert str(info.value) == "variant: unknown vehicle 'hexa' (known: default, laser)"


# --- scenario ------------------------------------------------------------------------------------

STEP_RULE = "1 ms physics steps"
RATES = "(use 1000, 500, 250, 200, 100, 50, ... Hz)"


def test_steps_per_period() -> None:
    assert steps_per_period(1000.0) == 1 and steps_per_period(100.0) == 10 and steps_per_period(0.5) == 2000
    for bad in (0.0, -100.0, INF, math.nan, 300.0, 2000.0):
        assert steps_per_period(bad) is None, bad
    assert steps_per_period(50.0, dt_s=0.002) == 10


def test_sensor_rules() -> None:
    rejected(SensorConfig, f"rate_hz: 300.0 Hz is not a whole number of {STEP_RULE} {RATES}",
             rate_hz=300.0)  # fmt: skip
    rejected(SensorConfig, f"rate_hz: 0.0 Hz is not a whole number of {STEP_RULE} {RATES}",
             rate_hz=0.0)  # fmt: skip
    assert SensorConfig(rate_hz=1000.0).period_steps == 1 and SensorConfig(rate_hz=0.5).period_steps == 2000
    for name in ("accel_sigma", "gyro_sigma"):
        rejected(SensorConfig, f"{name}: must be >= 0, got (0.1, -0.1, 0.1)", **{name: (0.1, -0.1, 0.1)})
        rejected(SensorConfig, f"{name}: must be >= 0, got (inf, 0.0, 0.0)", **{name: (INF, 0.0, 0.0)})
        assert getattr(SensorConfig(**{name: (0.0, 0.0, 0.0)}), name) == (0.0, 0.0, 0.0)
    for name in ("accel_bias", "gyro_bias", "mag_sigma", "mag_bias", "baro_sigma", "baro_bias"):
        rejected(SensorConfig, f"{name}: must be >= 0, got -1.0", **{name: -1.0})
        rejected(SensorConfig, f"{name}: must be >= 0, got inf", **{name: INF})
        assert getattr(SensorConfig(**{name: 0.0}), name) == 0.0
    rejected(SensorConfig, "bias_tau_s: must be positive, got 0.0", bias_tau_s=0.0)
    rejected(SensorConfig, "bias_tau_s: must be positive, got inf", bias_tau_s=INF)
    assert SensorConfig(bias_tau_s=0.5).bias_tau_s == 0.5


def test_gust_rules() -> None:
    rejected(GustConfig, "start_s: must be >= 0, got -1.0", start_s=-1.0)
    rejected(GustConfig, "start_s: must be >= 0, got inf", start_s=INF)
    assert GustConfig(start_s=0.0).start_s == 0.0 and GustConfig(start_s=0.5).start_s == 0.5
    rejected(GustConfig, "duration_s: must be positive, got 0.0", duration_s=0.0, rise_s=0.0)
    rejected(GustConfig, "duration_s: must be positive, got inf", duration_s=INF)
    rejected(GustConfig, "rise_s: must be >= 0 and at most half of duration_s, got 0.6", duration_s=1.0, rise_s=0.6)
    rejected(GustConfig, "rise_s: must be >= 0 and at most half of duration_s, got -0.1", rise_s=-0.1)
    rejected(GustConfig, "rise_s: must be >= 0 and at most half of duration_s, got inf", rise_s=INF)
    assert GustConfig(duration_s=1.0, rise_s=0.5).rise_s == 0.5 and GustConfig(rise_s=0.0).rise_s == 0.0
    assert GustConfig(duration_s=0.01, rise_s=0.0).duration_s == 0.01
    rejected(GustConfig, "velocity: components must be within ±30 m/s, got (30.5, 0.0, 0.0)", velocity=(30.5, 0.0, 0.0))
    rejected(GustConfig, "velocity: components must be within ±30 m/s, got (0.0, -INF, 0.0)".replace("-INF", "-inf"),
             velocity=(0.0, -INF, 0.0))  # fmt: skip
    assert GustConfig(velocity=(30.0, -30.0, 0.0)).velocity == (30.0, -30.0, 0.0)


def test_wind_rules() -> None:
    rejected(
        WindConfig, "constant: components must be within ±30 m/s, got (0.0, 0.0, -30.5)", constant=(0.0, 0.0, -30.5)
    )
    rejected(WindConfig, "constant: components must be within ±30 m/s, got (inf, 0.0, 0.0)", constant=(INF, 0.0, 0.0))
    assert WindConfig(constant=(-30.0, 30.0, 0.0)).constant == (-30.0, 30.0, 0.0)
    rejected(WindConfig, "gust_sigma: must be in [0, 10] m/s, got 10.5", gust_sigma=10.5)
    rejected(WindConfig, "gust_sigma: must be in [0, 10] m/s, got -0.1", gust_sigma=-0.1)
    rejected(WindConfig, "gust_sigma: must be in [0, 10] m/s, got inf", gust_sigma=INF)
    assert WindConfig(gust_sigma=10.0).gust_sigma == 10.0
    rejected(WindConfig, "gust_tau_s: must be positive, got 0.0", gust_tau_s=0.0)
    rejected(WindConfig, "gust_tau_s: must be positive, got inf", gust_tau_s=INF)
    assert WindConfig(gust_tau_s=0.5).gust_tau_s == 0.5
    for bad in (0.0015, 0.0001, 0.0, -0.01):
        rejected(WindConfig, f"update_s: must be a whole number of {STEP_RULE}, got {bad}", update_s=bad)
    assert WindConfig(update_s=0.001).update_steps == 1 and WindConfig(update_s=0.002).update_steps == 2
    assert WindConfig().update_steps == 10 and WindConfig(update_s=0.5).update_steps == 500


def test_setpoint_step_rules() -> None:
    rejected(SetpointStep, "time_s: must be >= 0, got -1.0", time_s=-1.0, axis="roll", value=0.0)
    rejected(SetpointStep, "time_s: must be >= 0, got inf", time_s=INF, axis="roll", value=0.0)
    assert SetpointStep(0.0, "roll", 0.0).time_s == 0.0 and SetpointStep(0.5, "roll", 0.0).time_s == 0.5
    for value in (0.29, 5.1, INF):
        rejected(
            SetpointStep, f"value: height must be in [0.3, 5] m, got {value}", time_s=1.0, axis="height", value=value
        )
    assert SetpointStep(1.0, "height", 0.3).value == 0.3 and SetpointStep(1.0, "height", 5.0).value == 5.0
    for axis in ("roll", "pitch", "yaw"):
        rejected(SetpointStep, f"value: {axis} must be within ±45 degrees, got 45.5", time_s=1.0, axis=axis, value=45.5)
        rejected(SetpointStep, f"value: {axis} must be within ±45 degrees, got -inf", time_s=1.0, axis=axis, value=-INF)
        assert SetpointStep(1.0, axis, 45.0).value == 45.0 and SetpointStep(1.0, axis, -45.0).value == -45.0
    # an attitude step is not held to the height range, nor a height step to the angle range
    assert SetpointStep(1.0, "roll", 0.0).value == 0.0 and SetpointStep(1.0, "height", 4.0).value == 4.0


def test_move_duration_by_hand() -> None:
    # by speed: π·|Δ|/(2·rate); by acceleration: π·sqrt(|Δ|/(2·3)); at least shortest_s
    assert move_duration(4.0, 0.0, 2.0, 1.0) == pytest.approx(math.pi * 4.0 / 4.0)  # speed, up
    assert move_duration(-4.0, 0.0, 2.0, 1.0) == pytest.approx(math.pi * 4.0 / 2.0)  # speed, down: the descent rate
    assert move_duration(0.5, 0.0, 10.0, 10.0) == pytest.approx(math.pi * math.sqrt(0.5 / 6.0))  # acceleration
    assert move_duration(0.5, 3.0, 10.0, 10.0) == 3.0
    assert move_duration(0.0, 0.0, 2.0, 1.0) == 0.0
    assert move_duration(0.8, 0.0, 0.5, 10.0) == pytest.approx(math.pi * 0.8 / 1.0)  # a small climb uses the climb rate


def test_flight_plan_rules() -> None:
    rejected(
        FlightPlan, "takeoff_s: must be >= 0.1 s (the controller calibrates before take-off), got 0.09", takeoff_s=0.09
    )
    rejected(
        FlightPlan, "takeoff_s: must be >= 0.1 s (the controller calibrates before take-off), got inf", takeoff_s=INF
    )
    assert FlightPlan(takeoff_s=0.1).takeoff_s == 0.1 and FlightPlan(takeoff_s=0.5).takeoff_s == 0.5
    for bad in (0.29, 5.5, INF):
        rejected(FlightPlan, f"height_m: must be in [0.3, 5] m, got {bad}", height_m=bad)
    assert FlightPlan(height_m=0.3).height_m == 0.3 and FlightPlan(height_m=5.0).height_m == 5.0
    rejected(FlightPlan, "climb_s: must be >= 0, got -0.5", climb_s=-0.5)
    rejected(FlightPlan, "climb_s: must be >= 0, got inf", climb_s=INF)
    assert FlightPlan(climb_s=0.0).climb_s == 0.0 and FlightPlan(climb_s=0.5).climb_s == 0.5
    for name in ("climb_rate_mps", "descent_rate_mps"):
        for bad in (0.09, 10.5, INF):
            rejected(FlightPlan, f"{name}: must be in [0.1, 10] m/s, got {bad}", **{name: bad})
        assert getattr(FlightPlan(**{name: 0.1}), name) == 0.1 and getattr(FlightPlan(**{name: 10.0}), name) == 10.0
    early = (SetpointStep(4.4, "roll", 5.0),)
    rejected(FlightPlan, "steps[0].time_s: must not come before take-off + climb_s (4.5 s), got 4.4", steps=early)
    ok = (SetpointStep(4.5, "roll", 5.0), SetpointStep(1.0, "height", 2.0))  # at the limit; height steps are free here
    assert FlightPlan(steps=ok).steps == ok
    rejected(FlightPlan, "steps[1].time_s: must not come before take-off + climb_s (2.5 s), got 2.0",
             takeoff_s=2.0, climb_s=0.5,
             steps=(SetpointStep(3.0, "yaw", 1.0), SetpointStep(2.0, "pitch", 1.0)))  # fmt: skip


def test_height_moves_in_time_order_whatever_the_list_order() -> None:
    plan = FlightPlan(
        takeoff_s=3.0, height_m=1.0, climb_s=1.5,
        steps=(SetpointStep(9.0, "height", 2.0), SetpointStep(5.0, "roll", 1.0), SetpointStep(6.0, "height", 1.5)),
    )  # fmt: skip
    moves = plan.height_moves(0.2)
    assert moves == (
        HeightMove(3.0, 1.5, 0.2, 1.0),
        HeightMove(6.0, 1.5, 1.0, 1.5),
        HeightMove(9.0, 1.5, 1.5, 2.0),
    )
    assert moves[1].end_s == 7.5
    scenario = ScenarioConfig(flight=plan)  # the later step in the list comes first in time: accepted
    assert scenario.flight.height_moves(0.1825)[2].from_m == 1.5


def test_scenario_rules() -> None:
    for bad in (0.0, 3600.5, INF):
        rejected(ScenarioConfig, f"duration_s: must be in (0, 3600] s, got {bad}", duration_s=bad)
    assert ScenarioConfig(duration_s=3600.0).duration_s == 3600.0 and ScenarioConfig(duration_s=0.5).duration_s == 0.5
    rejected(ScenarioConfig, "vehicle: unknown vehicle 'blimp' (known: default, laser)", vehicle="blimp")
    rejected(ScenarioConfig, f"duration_s: must be a whole number of {STEP_RULE}, got 1.0005", duration_s=1.0005)
    assert ScenarioConfig(duration_s=1.001).duration_s == 1.001
    # a height step before the previous height move ended: the climb ends at 3 + 1.5 s
    rejected(ScenarioConfig,
             "flight.steps[1].time_s: a height step must not come before the previous height move ends "
             "(4.5 s), got 4.4",
             flight=FlightPlan(steps=(SetpointStep(5.0, "roll", 1.0), SetpointStep(4.4, "height", 2.0))))  # fmt: skip
    at_end = ScenarioConfig(flight=FlightPlan(steps=(SetpointStep(4.5, "height", 2.0),)))
    assert at_end.flight.steps[0].time_s == 4.5
    # the laser vehicle's rest height decides its climb too (same duration here: 1.5 s minimum)
    assert (
        ScenarioConfig(vehicle="laser", flight=FlightPlan(steps=(SetpointStep(4.5, "height", 2.0),))).vehicle == "laser"
    )


# --- chip ------------------------------------------------------------------------------------------


def test_tile_rules() -> None:
    for bad in (4095, 4098, (1 << 30) + 4):
        rejected(
            TileConfig, f"sram_bytes: must be a multiple of 4 between 4096 and 2**30 bytes, got {bad}", sram_bytes=bad
        )
    assert TileConfig(sram_bytes=4096).sram_bytes == 4096 and TileConfig(sram_bytes=1 << 30).sram_bytes == 1 << 30
    rejected(TileConfig, "clock_period_ns: must be in [0.5, 1000] ns, got 0", clock_period_ns=0.0)
    rejected(TileConfig, "clock_period_ns: must be in [0.5, 1000] ns, got 1e-09", clock_period_ns=1e-9)
    rejected(TileConfig, "clock_period_ns: must be a finite number, got inf", clock_period_ns=math.inf)
    assert TileConfig(clock_period_ns=0.5).clock_period_ns == 0.5
    rejected(TileOverride, "x: must be >= 0, got -1", x=-1, y=0)
    rejected(TileOverride, "y: must be >= 0, got -2", x=0, y=-2)
    rejected(
        TileOverride,
        "sram_bytes: must be a multiple of 4 between 4096 and 2**30 bytes, got 100",
        x=0,
        y=0,
        sram_bytes=100,
    )
    rejected(TileOverride, "clock_period_ns: must be in [0.5, 1000] ns, got -1", x=0, y=0, clock_period_ns=-1.0)
    assert TileOverride(0, 0, clock_period_ns=0.5).clock_period_ns == 0.5


def test_noc_rules() -> None:
    for bad in (1, 257):
        rejected(NocConfig, f"buffer_depth: must be between 2 and 256 flits, got {bad}", buffer_depth=bad)
    assert NocConfig(buffer_depth=2).buffer_depth == 2 and NocConfig(buffer_depth=256).buffer_depth == 256
    rejected(NocConfig, "flit_bits: must be 16 (ORCA) or 32, got 33", flit_bits=33)
    assert NocConfig(flit_bits=32).flit_bits == 32
    for bad in (2, 65):
        rejected(
            NocConfig, f"max_packet_flits: must be between 3 and 64 (the NI memories), got {bad}", max_packet_flits=bad
        )
    assert NocConfig(max_packet_flits=3).max_packet_flits == 3 and NocConfig(max_packet_flits=64).max_packet_flits == 64
    rejected(NocConfig, "arbiter: must be one of 'hermes', 'per-output', got 'xy'", arbiter="xy")
    for bad in (-1, 65):
        rejected(
            NocConfig,
            f"routing_latency: must be between 0 and 64 cycles, got {bad}",
            arbiter="per-output",
            routing_latency=bad,
        )
    assert NocConfig(arbiter="per-output", routing_latency=64).routing_latency == 64
    rejected(NocConfig, "routing_latency: the Hermes switch controller fixes it at 4 (5 cycles per router), got 3; "
                        'use arbiter = "per-output" to vary it',
             routing_latency=3)  # fmt: skip


def test_chip_rules() -> None:
    rejected(ChipConfig, "errata: must be one of 'spec', 'rtl', got 'none'", errata="none")
    for name in ("width", "height"):
        rejected(ChipConfig, f"{name}: must be between 1 and 16, got 17", **{name: 17})
        rejected(ChipConfig, f"{name}: must be between 1 and 16, got 0", **{name: 0})
    assert ChipConfig(width=16, height=16).n_tiles == 256
    rejected(ChipConfig, "width: a mesh needs at least 2 tiles", width=1, height=1)
    assert ChipConfig(width=1, height=2).n_tiles == 2 and ChipConfig(width=3, height=1).n_tiles == 3
    rejected(ChipConfig, "io_tile: (2, 0) is outside the 2x2 mesh", io_tile=(2, 0))
    rejected(ChipConfig, "powered_off[1]: (0, 2) is outside the 2x2 mesh", powered_off=((1, 1), (0, 2)))
    rejected(ChipConfig, "powered_off[1]: (1, 1) is listed twice", powered_off=((1, 1), (1, 1)))
    rejected(ChipConfig, "powered_off[0]: (0, 0) is the I/O tile", powered_off=((0, 0),))
    rejected(ChipConfig, "tiles[0]: (3, 0) is outside the 3x1 mesh", width=3, height=1, tiles=(TileOverride(3, 0),))
    rejected(ChipConfig, "tiles[1]: (1, 0) is overridden twice", tiles=(TileOverride(1, 0), TileOverride(1, 0)))
    chip = ChipConfig(width=3, height=2)
    assert [chip.contains(xy) for xy in ((2, 1), (3, 1), (2, 2), (-1, 0), (0, -1))] == [
        True,
        False,
        False,
        False,
        False,
    ]
    assert chip.tile_index((2, 1)) == 5 and chip.tile_xy(5) == (2, 1)
    with pytest.raises(ValueError) as info:
        chip.tile_index((0, 2))
    assert str(info.value) == "tile (0, 2) is outside the 3x2 mesh"
