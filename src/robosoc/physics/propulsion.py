"""The hector quadrotor's propulsion: four DC motors with rotors, explicit Euler every physics step.

Per motor i (quadrotor.md)::

    U_i  = pwm_i · V_s / 255                        zero-order hold between commands
    v1   = [w − l·q, w − l·p, w + l·q, w + l·p]     axial inflow at each rotor (body u, v, w, p, q, r)
    F_i  = CT0s·ω_i² + CT1s·v1_i·ω_i + CT2s·v1_i²   thrust
    T    = (U_i·beta_m − Psi·ω_i) / (2·R_A)
    I_i  = T + sqrt(T² + U_i·alpha_m/R_A)           motor current
    M_e  = Psi·I_i                                  electrical torque
    ω_i ← ω_i + dt/J_M · (M_e − k_t·F_i − k_m·ω_i)

Body wrench at the body origin: force (0, 0, ΣF); torque ((F3 − F1)·l, (F2 − F0)·l,
M_e0 + M_e2 − M_e1 − M_e3).  Motor 0 front (+x), 1 right (−y), 2 rear (−x), 3 left (+y).

The hot path works on Python floats: for four values, scalar arithmetic is several times cheaper
than numpy calls (each of which costs about a microsecond of dispatch).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from robosoc.config.vehicle import MotorConfig

PWM_MAX = 255
"""PWM commands are bytes."""


class Propulsion:
    """State and dynamics of the four motors of one vehicle."""

    __slots__ = (
        "_a_r",
        "_alpha_over_r",
        "_beta",
        "_ct0",
        "_ct1",
        "_ct2",
        "_dt_over_j",
        "_inv_2r",
        "_k_m",
        "_k_t",
        "_psi",
        "arm",
        "forces",
        "motor",
        "omega",
        "pwm",
        "torques",
        "voltages",
    )

    def __init__(self, motor: MotorConfig, arm_length: float, dt: float) -> None:
        self.motor = motor
        self.arm = arm_length
        self._psi = motor.psi
        self._beta = motor.beta_m
        self._inv_2r = 1.0 / (2.0 * motor.r_a)
        self._alpha_over_r = motor.alpha_m / motor.r_a
        self._a_r = motor.r_a
        self._ct0 = motor.ct0s
        self._ct1 = motor.ct1s
        self._ct2 = motor.ct2s
        self._k_t = motor.k_t
        self._k_m = motor.k_m
        self._dt_over_j = dt / motor.j_m
        self.omega = [0.0, 0.0, 0.0, 0.0]
        self.pwm = (0, 0, 0, 0)
        self.voltages = [0.0, 0.0, 0.0, 0.0]
        self.forces = [0.0, 0.0, 0.0, 0.0]
        self.torques = [0.0, 0.0, 0.0, 0.0]

    def reset(self, omega: Sequence[float] = (0.0, 0.0, 0.0, 0.0)) -> None:
        """Set the rotor speeds [rad/s] and zero the input voltages."""
        self.omega = [float(w) for w in omega]
        self.pwm = (0, 0, 0, 0)
        self.voltages = [0.0, 0.0, 0.0, 0.0]
        self.forces = [0.0, 0.0, 0.0, 0.0]
        self.torques = [0.0, 0.0, 0.0, 0.0]

    def set_pwm(self, pwm: Sequence[int]) -> None:
        """Latch four PWM bytes (held until the next call).

        Raises:
            ValueError: not four integers in 0..255.
        """
        if len(pwm) != 4:
            raise ValueError(f"pwm: expected 4 values, got {len(pwm)}")
        volts = []
        for i, value in enumerate(pwm):
            byte = int(value)
            if byte != value or not 0 <= byte <= PWM_MAX:
                raise ValueError(f"pwm[{i}]: must be an integer in 0..255, got {value!r}")
            volts.append(byte * self.motor.supply_voltage / PWM_MAX)
        self.voltages = volts
        b0, b1, b2, b3 = (int(v) for v in pwm)
        self.pwm = (b0, b1, b2, b3)

    def set_supply(self, volts: float) -> None:
        """Run the latched PWM on a supply of ``volts`` (a battery's terminal voltage) instead of
        ``motor.supply_voltage``: each motor gets ``pwm/255`` of it (an ideal ESC)."""
        self.voltages = [byte * volts / PWM_MAX for byte in self.pwm]

    def electrical_power(self) -> float:
        """The motors' electrical power in the last step [W]: ``Σ U_i·I_i``, with ``I_i = M_e,i/Psi``."""
        u0, u1, u2, u3 = self.voltages
        m0, m1, m2, m3 = self.torques
        return (u0 * m0 + u1 * m1 + u2 * m2 + u3 * m3) / self._psi

    def step(self, w: float, p: float, q: float) -> tuple[float, float, float, float]:
        """Advance the motors one step; return the body wrench (Fz, τx, τy, τz) at the origin.

        Args:
            w: body-frame vertical velocity [m/s] (axial inflow).
            p: body roll rate [rad/s].
            q: body pitch rate [rad/s].

        The thrust and torque returned are those of the speeds at the start of the step (explicit
        Euler), matching the original plugin.
        """
        arm = self.arm
        lq = arm * q
        lp = arm * p
        o0, o1, o2, o3 = self.omega
        u0, u1, u2, u3 = self.voltages
        psi = self._psi
        beta = self._beta
        inv_2r = self._inv_2r
        alpha_r = self._alpha_over_r
        ct0 = self._ct0
        ct1 = self._ct1
        ct2 = self._ct2
        k_t = self._k_t
        k_m = self._k_m
        dt_j = self._dt_over_j
        sqrt = math.sqrt
        # Unrolled over the four motors (a loop with indexing costs about a third more here).
        v = w - lq
        f0 = (ct0 * o0 + ct1 * v) * o0 + ct2 * v * v
        t = (u0 * beta - psi * o0) * inv_2r
        m0 = psi * (t + sqrt(t * t + u0 * alpha_r))
        v = w - lp
        f1 = (ct0 * o1 + ct1 * v) * o1 + ct2 * v * v
        t = (u1 * beta - psi * o1) * inv_2r
        m1 = psi * (t + sqrt(t * t + u1 * alpha_r))
        v = w + lq
        f2 = (ct0 * o2 + ct1 * v) * o2 + ct2 * v * v
        t = (u2 * beta - psi * o2) * inv_2r
        m2 = psi * (t + sqrt(t * t + u2 * alpha_r))
        v = w + lp
        f3 = (ct0 * o3 + ct1 * v) * o3 + ct2 * v * v
        t = (u3 * beta - psi * o3) * inv_2r
        m3 = psi * (t + sqrt(t * t + u3 * alpha_r))
        self.omega = [
            o0 + dt_j * (m0 - k_t * f0 - k_m * o0),
            o1 + dt_j * (m1 - k_t * f1 - k_m * o1),
            o2 + dt_j * (m2 - k_t * f2 - k_m * o2),
            o3 + dt_j * (m3 - k_t * f3 - k_m * o3),
        ]
        self.forces = [f0, f1, f2, f3]
        self.torques = [m0, m1, m2, m3]
        return (f0 + f1 + f2 + f3, (f3 - f1) * arm, (f2 - f0) * arm, m0 + m2 - m1 - m3)


def steady_state(
    motor: MotorConfig, pwm: float, inflow: float = 0.0, supply_v: float | None = None
) -> tuple[float, float, float]:
    """Equilibrium of one motor at a constant (possibly fractional) PWM: (ω, thrust, M_e).

    Solves dω/dt = 0 by bisection on ω (the net torque falls monotonically with ω above the
    idle equilibrium).  ``supply_v``: the supply voltage (default ``motor.supply_voltage``).
    Used by tests, documentation and the checks before a flight; not on the hot path.
    """
    u = pwm * (motor.supply_voltage if supply_v is None else supply_v) / PWM_MAX

    def net(om: float) -> float:
        force = motor.ct0s * om * om + motor.ct1s * inflow * om + motor.ct2s * inflow * inflow
        t = (u * motor.beta_m - motor.psi * om) / (2 * motor.r_a)
        torque = motor.psi * (t + math.sqrt(t * t + u * motor.alpha_m / motor.r_a))
        return torque - motor.k_t * force - motor.k_m * om

    lo, hi = 1e-6, 1e5
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if net(mid) > 0:
            lo = mid
        else:
            hi = mid
    om = 0.5 * (lo + hi)
    force = motor.ct0s * om * om + motor.ct1s * inflow * om + motor.ct2s * inflow * inflow
    t = (u * motor.beta_m - motor.psi * om) / (2 * motor.r_a)
    torque = motor.psi * (t + math.sqrt(t * t + u * motor.alpha_m / motor.r_a))
    return om, force, torque


def hover_pwm(motor: MotorConfig, mass: float, gravity: float) -> float:
    """Fractional PWM at which four motors at rest in still air carry ``mass`` (bisection)."""
    lo, hi = 0.0, float(PWM_MAX)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if 4.0 * steady_state(motor, mid)[1] < mass * gravity:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)
