"""The stepping API: a :class:`World` of one or more :class:`Quadrotor` s on MuJoCo.

Typical use::

    world = World([default_vehicle()], SensorConfig(), WindConfig())
    quad = world.quadrotors[0]
    world.reset(seed=1)
    while world.time < 10.0:
        sample = quad.sensors()            # latest sample (carries its timestamp)
        quad.apply_pwm(controller(sample)) # held until the next call
        world.advance(sample.time + world.sensor_period)

Every physics step (1 ms) each vehicle's motors advance (explicit Euler), the propulsion and drag
wrenches are computed in the body frame at the body origin, moved to the centre of mass
(τ_com = τ_origin − c × F) and rotated into the world frame, because MuJoCo's ``xfrc_applied``
is a world-frame wrench at the body's CoM.  Then ``mj_step`` integrates.  Sensors are sampled
at the end of every sensor period; the wind is updated every ``wind.update_s``.

One seed drives everything: ``np.random.SeedSequence(seed)`` spawns one stream for the wind and
one per vehicle (in vehicle order) for its sensors, then (with the position sensor on) one per
vehicle for its position fixes: children spawned later leave the earlier ones unchanged.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import mujoco
import numpy as np

from robosoc.config.scenario import PHYSICS_DT_S, SensorConfig, WindConfig
from robosoc.config.vehicle import VehicleConfig
from robosoc.physics.drag import Drag
from robosoc.physics.mjcf import body_name, world_xml
from robosoc.physics.power import PowerSystem
from robosoc.physics.propulsion import Propulsion
from robosoc.physics.sensors import PositionFixModel, SensorModel, SensorSample, Truth
from robosoc.physics.wind import Wind


class Quadrotor:
    """One vehicle in a :class:`World`: its motors, drag, sensors and MuJoCo addresses."""

    def __init__(self, world: World, config: VehicleConfig, sensors: SensorConfig) -> None:
        self.world = world
        self.config = config
        self.name = config.name
        model = world.model
        self.body_id = model.body(body_name(config)).id
        joint = model.joint(f"{config.name}/root")
        self._qpos = int(joint.qposadr[0])
        self._dof = int(joint.dofadr[0])
        self.propulsion = Propulsion(config.motor, config.arm_length, world.dt)
        self.power: PowerSystem | None = PowerSystem(config.power, world.dt) if config.power.battery_on else None
        """The pack and the power budget of a battery flight (None: constant supply, no budget kept)."""
        self.drag = Drag(config.drag)
        self.sensor_model = SensorModel(sensors, world.dt)
        self.position_model = PositionFixModel(sensors) if sensors.position.enabled else None
        self._com = tuple(float(c) for c in config.com)
        self._has_com_offset = any(c != 0.0 for c in self._com)
        self._sample: SensorSample | None = None
        self.pwm: tuple[int, int, int, int] = (0, 0, 0, 0)

    # ----------------------------------------------------------------- public API
    def apply_pwm(self, pwm: Sequence[int]) -> None:
        """Command four PWM bytes (motor 0 front, 1 right, 2 rear, 3 left), held until changed.

        Raises:
            ValueError: not four integers in 0..255.
        """
        self.propulsion.set_pwm(pwm)
        m0, m1, m2, m3 = (int(v) for v in pwm)  # four: set_pwm checked them
        self.pwm = (m0, m1, m2, m3)

    def sensors(self) -> SensorSample:
        """The latest sensor sample (taken at the last sensor tick, ``sample.time``)."""
        assert self._sample is not None, "reset the world first"
        return self._sample

    def truth(self) -> Truth:
        """Ground-truth pose and twist now (no noise)."""
        data = self.world.data
        a, d = self._qpos, self._dof
        return Truth(
            time=self.world.time,
            position=data.qpos[a : a + 3].copy(),
            quaternion=data.qpos[a + 3 : a + 7].copy(),
            velocity=data.qvel[d : d + 3].copy(),
            angular_velocity=data.qvel[d + 3 : d + 6].copy(),
        )

    @property
    def rotor_speeds(self) -> np.ndarray:
        """Rotor speeds ω [rad/s] of motors 0..3."""
        return np.array(self.propulsion.omega)

    # ----------------------------------------------------------------- internals
    def _reset(self, rng: np.random.Generator, position_rng: np.random.Generator | None = None) -> None:
        self.propulsion.reset()
        if self.power is not None:
            self.power = PowerSystem(self.config.power, self.world.dt)
        self.pwm = (0, 0, 0, 0)
        truth = self.truth()
        self.sensor_model.reset(rng, truth.velocity, truth.quaternion)
        if self.position_model is not None:
            self.position_model.reset(position_rng if position_rng is not None else np.random.default_rng(0))
        self._take_sample(0.0, window=0.0)

    def _take_sample(self, time: float, window: float) -> None:
        data = self.world.data
        a, d = self._qpos, self._dof
        velocity = data.qvel[d : d + 3].tolist()
        self._sample = self.sensor_model.sample(
            time, float(data.qpos[a + 2]), data.qpos[a + 3 : a + 7].tolist(), velocity, window
        )
        if self.position_model is not None:
            fix = self.position_model.sample(time, data.qpos[a : a + 3].tolist(), velocity)
            self._sample = dataclasses.replace(self._sample, position_fix=fix)

    def _apply_wrench(
        self, qpos: list[float], qvel: list[float], xfrc: np.ndarray, wind: tuple[float, float, float]
    ) -> None:
        """Advance the motors one step and write this step's world-frame wrench at the CoM."""
        a, d = self._qpos, self._dof
        # R(q), inlined (this runs every step): row-major body→world.
        w, x, y, z = qpos[a + 3 : a + 7]
        r00 = 1.0 - 2.0 * (y * y + z * z)
        r01 = 2.0 * (x * y - w * z)
        r02 = 2.0 * (x * z + w * y)
        r10 = 2.0 * (x * y + w * z)
        r11 = 1.0 - 2.0 * (x * x + z * z)
        r12 = 2.0 * (y * z - w * x)
        r20 = 2.0 * (x * z - w * y)
        r21 = 2.0 * (y * z + w * x)
        r22 = 1.0 - 2.0 * (x * x + y * y)
        vx, vy, vz, p, q, r = qvel[d : d + 6]
        # Rotor inflow uses the body-frame velocity (w = third row of Rᵀ·v).
        w_body = r02 * vx + r12 * vy + r22 * vz
        power = self.power
        if power is None:
            fz, tx, ty, tz = self.propulsion.step(w_body, p, q)
        else:  # a battery flight: the motors run on the pack's terminal voltage (physics/power.py)
            volts = power.supply_v()
            self.propulsion.set_supply(volts)
            fz, tx, ty, tz = self.propulsion.step(w_body, p, q)
            power.consume(self.propulsion.electrical_power(), volts)
        # Drag uses the air-relative velocity in the body frame: Rᵀ·(v − wind).
        ax, ay, az = vx - wind[0], vy - wind[1], vz - wind[2]
        dfx, dfy, dfz, dtx, dty, dtz = self.drag.wrench(
            r00 * ax + r10 * ay + r20 * az,
            r01 * ax + r11 * ay + r21 * az,
            r02 * ax + r12 * ay + r22 * az,
            p,
            q,
            r,
        )
        fx, fy, fz = dfx, dfy, dfz + fz
        tx, ty, tz = tx + dtx, ty + dty, tz + dtz
        if self._has_com_offset:
            # The wrench acts at the origin; at the CoM c it is (F, τ − c × F).
            cx, cy, cz = self._com
            tx -= cy * fz - cz * fy
            ty -= cz * fx - cx * fz
            tz -= cx * fy - cy * fx
        xfrc[self.body_id] = (
            r00 * fx + r01 * fy + r02 * fz,
            r10 * fx + r11 * fy + r12 * fz,
            r20 * fx + r21 * fy + r22 * fz,
            r00 * tx + r01 * ty + r02 * tz,
            r10 * tx + r11 * ty + r12 * tz,
            r20 * tx + r21 * ty + r22 * tz,
        )


class World:
    """A MuJoCo world with one or more quadrotors, shared wind, and a sensor clock.

    Args:
        vehicles: vehicle configs (distinct names).
        sensors: sensor rate and noise, shared by all vehicles.
        wind: the wind field.

    Raises:
        ValueError: duplicate vehicle names.
    """

    def __init__(
        self,
        vehicles: Sequence[VehicleConfig],
        sensors: SensorConfig | None = None,
        wind: WindConfig | None = None,
    ) -> None:
        self.sensor_config = sensors or SensorConfig()
        self.wind_config = wind or WindConfig()
        self.xml = world_xml(vehicles)
        self.model = mujoco.MjModel.from_xml_string(self.xml)
        self.data = mujoco.MjData(self.model)
        self.dt = float(self.model.opt.timestep)
        if not math.isclose(self.dt, PHYSICS_DT_S):
            raise AssertionError("the model's timestep must be the physics step")
        self.sensor_steps = self.sensor_config.period_steps
        self.sensor_period = self.sensor_steps * self.dt
        self.wind = Wind(self.wind_config, self.dt)
        self._wind_steps = self.wind_config.update_steps
        self.quadrotors = [Quadrotor(self, v, self.sensor_config) for v in vehicles]
        self.steps = 0
        self.seed: int | None = None

    @property
    def time(self) -> float:
        """Simulated time [s] (an integer number of steps times dt, so no drift)."""
        return self.steps * self.dt

    def quadrotor(self, name: str) -> Quadrotor:
        """The vehicle called ``name``.

        Raises:
            KeyError: no such vehicle.
        """
        for quad in self.quadrotors:
            if quad.name == name:
                return quad
        raise KeyError(f"no vehicle named {name!r} (have: {', '.join(q.name for q in self.quadrotors)})")

    def reset(self, seed: int = 0) -> None:
        """Put every vehicle back at its spawn pose with motors stopped, and reseed all noise."""
        self.seed = seed
        mujoco.mj_resetData(self.model, self.data)
        mujoco.mj_forward(self.model, self.data)
        self.steps = 0
        n = len(self.quadrotors)
        position = self.sensor_config.position.enabled
        streams = np.random.SeedSequence(seed).spawn(1 + (2 * n if position else n))
        self.wind.reset(np.random.default_rng(streams[0]))
        for i, quad in enumerate(self.quadrotors):
            fixes = np.random.default_rng(streams[1 + n + i]) if position else None
            quad._reset(np.random.default_rng(streams[1 + i]), fixes)

    def step(self) -> None:
        """Advance one physics step (1 ms)."""
        data = self.data
        qpos = data.qpos.tolist()
        qvel = data.qvel.tolist()
        xfrc = data.xfrc_applied
        wind = self.wind.velocity
        for quad in self.quadrotors:
            quad._apply_wrench(qpos, qvel, xfrc, wind)
        mujoco.mj_step(self.model, data)
        self.steps += 1
        steps = self.steps
        if steps % self._wind_steps == 0:
            self.wind.update(steps * self.dt)
        if steps % self.sensor_steps == 0:
            t = steps * self.dt
            for quad in self.quadrotors:
                quad._take_sample(t, self.sensor_period)

    def advance(self, until: float) -> None:
        """Step until simulated time reaches ``until`` [s] (rounded to the nearest whole step)."""
        target = round(until / self.dt)
        step = self.step
        for _ in range(target - self.steps):
            step()
