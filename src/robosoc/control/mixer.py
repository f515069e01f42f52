"""Motor mixing of the seed's equation 3 for the "+" layout, saturating to PWM bytes.

Inputs: total thrust u_z [N] and body torques u_α (roll, about x), u_β (pitch, about y),
u_θ (yaw, about z) [N·m].  Motors: 0 front (+x), 1 right (−y), 2 rear (−x), 3 left (+y); front
and rear spin clockwise, so speeding them up yaws the body anticlockwise (+z).  Per-motor thrust::

    f_0 = u_z/4 − u_β/(2l) + u_θ/(4k)
    f_1 = u_z/4 − u_α/(2l) − u_θ/(4k)
    f_2 = u_z/4 + u_β/(2l) + u_θ/(4k)
    f_3 = u_z/4 + u_α/(2l) − u_θ/(4k)

which inverts τ_x = (f_3 − f_1)·l, τ_y = (f_2 − f_0)·l and τ_z = k·(f_0 + f_2 − f_1 − f_3).
k [N·m/N] is the steady-state yaw torque per newton of rotor thrust at hover,
``k = k_t + k_m/(2·CT0s·ω_h)`` (the reaction torque M_e = k_t·F + k_m·ω, differentiated through
F = CT0s·ω²).

Each f_i is clamped to [0, f_max] and turned into the voltage that holds it in steady state in
still air (inverting the motor model of quadrotor.md)::

    ω = sqrt(f/CT0s);  M_e = k_t·f + k_m·ω;  I = M_e/Psi;  U = (I²·R_A + I·Psi·ω)/(alpha_m + I·beta_m)

and then into a byte ``pwm = round(U·255/V_s)`` clamped to 0..255.  (At 3.62 N this gives
121.2 → 121, the hover command.)
"""

from __future__ import annotations

import math

import numpy as np

from robosoc.config.vehicle import MotorConfig


def thrust_to_voltage(motor: MotorConfig, force: float) -> float:
    """Voltage [V] that holds a rotor at thrust ``force`` [N] in steady state (0 for no thrust)."""
    if force <= 0.0:
        return 0.0
    omega = math.sqrt(force / motor.ct0s)
    current = (motor.k_t * force + motor.k_m * omega) / motor.psi
    if current <= 0.0:
        return 0.0
    return (current * current * motor.r_a + current * motor.psi * omega) / (motor.alpha_m + current * motor.beta_m)


def yaw_coefficient(motor: MotorConfig, hover_force: float) -> float:
    """k: steady-state yaw reaction torque per newton of thrust around ``hover_force`` [N·m/N]."""
    omega = math.sqrt(hover_force / motor.ct0s)
    return motor.k_t + motor.k_m / (2.0 * motor.ct0s * omega)


class Mixer:
    """Equation 3 for the "+" layout, from thrust and torques to four PWM bytes."""

    def __init__(self, motor: MotorConfig, arm_length: float, hover_force: float) -> None:
        self.motor = motor
        self.arm = arm_length
        self.yaw_k = yaw_coefficient(motor, hover_force)
        self.max_force = _max_force(motor)

    def forces(self, u_z: float, u_roll: float, u_pitch: float, u_yaw: float) -> np.ndarray:
        """Per-motor thrust [N] before saturation."""
        base = u_z / 4.0
        roll = u_roll / (2.0 * self.arm)
        pitch = u_pitch / (2.0 * self.arm)
        yaw = u_yaw / (4.0 * self.yaw_k)
        return np.array([base - pitch + yaw, base - roll - yaw, base + pitch + yaw, base + roll - yaw])

    def pwm(self, u_z: float, u_roll: float, u_pitch: float, u_yaw: float) -> np.ndarray:
        """Four PWM bytes (uint8) for thrust ``u_z`` [N] and torques [N·m]."""
        out = np.empty(4, dtype=np.uint8)
        scale = 255.0 / self.motor.supply_voltage
        for i, force in enumerate(self.forces(u_z, u_roll, u_pitch, u_yaw)):
            clamped = min(self.max_force, max(0.0, float(force)))
            out[i] = min(255, max(0, round(thrust_to_voltage(self.motor, clamped) * scale)))
        return out


def _max_force(motor: MotorConfig) -> float:
    """Thrust at full supply voltage in steady state (bisection on thrust_to_voltage)."""
    lo, hi = 0.0, 100.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if thrust_to_voltage(motor, mid) < motor.supply_voltage:
            lo = mid
        else:
            hi = mid
    return lo
