"""Motor mixing of the seed's equation 3 for the "+" layout, with desaturation, to PWM counts.

Inputs: total thrust u_z [N] and body torques u_α (roll, about x), u_β (pitch, about y),
u_θ (yaw, about z) [N·m].  Motors: 0 front (+x), 1 right (−y), 2 rear (−x), 3 left (+y); front
and rear spin clockwise, so speeding them up yaws the body anticlockwise (+z).  Per-motor thrust
(equation 3) is the collective share plus the attitude differences r, p, y::

    r = u_α/(2l),  p = u_β/(2l),  y = u_θ/(4k)
    f_0 = u_z/4 − p + y
    f_1 = u_z/4 − r − y
    f_2 = u_z/4 + p + y
    f_3 = u_z/4 + r − y

which inverts τ_x = (f_3 − f_1)·l, τ_y = (f_2 − f_0)·l and τ_z = k·(f_0 + f_2 − f_1 − f_3).
k [N·m/N] is the steady-state yaw torque per newton of rotor thrust at hover,
``k = k_t + k_m/(2·CT0s·ω_h)`` (the reaction torque M_e = k_t·F + k_m·ω, differentiated through
F = CT0s·ω²).

**Limits.**  Every motor stays within [f_min, f_max]: f_min is the steady-state thrust at the
vehicle's ``idle_pwm`` (the in-flight minimum; 1.67 N at 50 counts), f_max the thrust at full
supply voltage (9.57 N).  Both are computed once at start (:func:`voltage_to_thrust`); the
firmware takes them as constants.

**Desaturation** (attitude before collective thrust, roll/pitch before yaw).  With S = f_max −
f_min the room of one motor, the spread max − min of the four differences is
``max(2·max(|r|, |p|), |r| + |p| + 2·|y|)`` for this layout, so:

1. if 2·max(|r|, |p|) > S, roll/pitch alone do not fit: r and p are scaled by
   S/(2·max(|r|, |p|)) (same signs, same ratio, so the torque keeps its direction) and y = 0;
2. otherwise y is clamped to ±(S − |r| − |p|)/2 (same sign, smaller if need be);
3. the collective share u_z/4 is clamped to [f_min − min(d_i), f_max − max(d_i)] over the four
   differences d_i: collective thrust gives way, at the top as at the bottom, and every motor
   ends up in [f_min, f_max] with the whole (remaining) torque.

Without saturation the forces are equation 3 exactly.

**PWM.**  Each force is turned into the voltage that holds it in steady state in still air
(inverting the motor model of quadrotor.md, :func:`thrust_to_voltage`)::

    ω = sqrt(f/CT0s);  M_e = k_t·f + k_m·ω;  I = M_e/Psi;  U = (I²·R_A + I·Psi·ω)/(alpha_m + I·beta_m)

and into a count by the one conversion :func:`pwm_counts`, ``floor(U·255/V_s + 0.5)`` (round
half up), finally clamped to [idle_pwm, 255].  At 3.62 N this gives 121.2 → 121, the hover
command.
"""

from __future__ import annotations

import math

from robosoc.config.vehicle import MotorConfig
from robosoc.physics.propulsion import PWM_MAX

Forces = tuple[float, float, float, float]
Pwm = tuple[int, int, int, int]


def thrust_to_voltage(motor: MotorConfig, force: float) -> float:
    """Voltage [V] that holds a rotor at thrust ``force`` [N] in steady state (0 for no thrust)."""
    if force <= 0.0:
        return 0.0
    omega = math.sqrt(force / motor.ct0s)
    current = (motor.k_t * force + motor.k_m * omega) / motor.psi
    if current <= 0.0:
        return 0.0
    return (current * current * motor.r_a + current * motor.psi * omega) / (motor.alpha_m + current * motor.beta_m)


def voltage_to_thrust(motor: MotorConfig, voltage: float) -> float:
    """Steady-state thrust [N] in still air at ``voltage`` [V]: :func:`thrust_to_voltage` inverted
    by bisection (it rises monotonically).  Computed once at start, not per sample."""
    lo, hi = 0.0, 100.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if thrust_to_voltage(motor, mid) < voltage:
            lo = mid
        else:
            hi = mid
    return lo


def pwm_counts(motor: MotorConfig, voltage: float) -> int:
    """The PWM count for ``voltage`` [V]: floor(U·255/V_s + 0.5), clamped to 0..255."""
    counts = math.floor(voltage * PWM_MAX / motor.supply_voltage + 0.5)
    return min(PWM_MAX, max(0, counts))


def yaw_coefficient(motor: MotorConfig, hover_force: float) -> float:
    """k: steady-state yaw reaction torque per newton of thrust around ``hover_force`` [N·m/N]."""
    omega = math.sqrt(hover_force / motor.ct0s)
    return motor.k_t + motor.k_m / (2.0 * motor.ct0s * omega)


class Mixer:
    """Equation 3 for the "+" layout with desaturation, from thrust and torques to four PWM counts."""

    def __init__(self, motor: MotorConfig, arm_length: float, hover_force: float, idle_pwm: int) -> None:
        self.motor = motor
        self.arm = arm_length
        self.idle_pwm = idle_pwm
        self.yaw_k = yaw_coefficient(motor, hover_force)
        self.min_force = voltage_to_thrust(motor, idle_pwm * motor.supply_voltage / PWM_MAX)
        self.max_force = voltage_to_thrust(motor, motor.supply_voltage)

    def equation_3(self, u_z: float, u_roll: float, u_pitch: float, u_yaw: float) -> Forces:
        """Per-motor thrust [N] of equation 3, without limits."""
        base = u_z / 4.0
        r = u_roll / (2.0 * self.arm)
        p = u_pitch / (2.0 * self.arm)
        y = u_yaw / (4.0 * self.yaw_k)
        return (base - p + y, base - r - y, base + p + y, base + r - y)

    def forces(self, u_z: float, u_roll: float, u_pitch: float, u_yaw: float) -> Forces:
        """Per-motor thrust [N] after desaturation: each in [min_force, max_force]."""
        room = self.max_force - self.min_force
        r = u_roll / (2.0 * self.arm)
        p = u_pitch / (2.0 * self.arm)
        y = u_yaw / (4.0 * self.yaw_k)
        widest = max(abs(r), abs(p))
        if 2.0 * widest > room:
            # 1. Roll/pitch alone overflow: scale both (direction kept), no yaw.
            scale = room / (2.0 * widest)
            r *= scale
            p *= scale
            y = 0.0
        else:
            # 2. Yaw gets the room roll/pitch leave.
            yaw_room = 0.5 * (room - abs(r) - abs(p))
            y = min(yaw_room, max(-yaw_room, y))
        d0, d1, d2, d3 = -p + y, -r - y, p + y, r - y
        # 3. The collective share gives way.
        lowest = min(d0, d1, d2, d3)
        highest = max(d0, d1, d2, d3)
        base = min(self.max_force - highest, max(self.min_force - lowest, u_z / 4.0))
        return (base + d0, base + d1, base + d2, base + d3)

    def pwm(self, u_z: float, u_roll: float, u_pitch: float, u_yaw: float) -> Pwm:
        """Four PWM counts in [idle_pwm, 255] for thrust ``u_z`` [N] and torques [N·m]."""
        f0, f1, f2, f3 = self.forces(u_z, u_roll, u_pitch, u_yaw)
        return (self._count(f0), self._count(f1), self._count(f2), self._count(f3))

    def _count(self, force: float) -> int:
        counts = pwm_counts(self.motor, thrust_to_voltage(self.motor, force))
        return min(PWM_MAX, max(self.idle_pwm, counts))
