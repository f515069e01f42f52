"""What the motors get between actuator commands in the decoupled mode: hold or ramp.

Commands are scheduled at the physics step from which they apply (their chip time's step, or a
later one if they came late); :meth:`ActuatorHold.at` gives the PWM in force at each step, asked
for steps in increasing order.

* ``zoh``: the newest command due, held until the next (the PWM peripheral's behaviour, and
  what lockstep does);
* ``linear``: from the step a command is due, the PWM ramps linearly from the value then in force
  to the command over as many steps as separated the command from the previous one (a causal
  first-order hold, the seed's interpolation between sparse commands: smoother, about half a
  command interval later on average).  Values are rounded to whole PWM counts.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence

from robosoc.config.link import HOLD_CHOICES

__all__ = ["ActuatorHold"]

Pwm = tuple[int, int, int, int]


class ActuatorHold:
    """Scheduled commands and the PWM in force (``mode`` one of :data:`HOLD_CHOICES`)."""

    def __init__(self, mode: str, initial: Sequence[int]) -> None:
        if mode not in HOLD_CHOICES:
            raise ValueError(f"hold: must be one of {', '.join(HOLD_CHOICES)}, got {mode!r}")
        self.mode = mode
        self._due: deque[tuple[int, Pwm, int]] = deque()  # (step, command, steps since the previous one)
        self._last_step: int | None = None  # step of the newest command scheduled
        self._from = tuple(float(v) for v in initial)
        self._to = tuple(float(v) for v in initial)
        self._start = 0  # ramp: first step of the current ramp
        self._span = 1  # ramp: its length in steps
        self._asked = -1

    def schedule(self, step: int, pwm: Pwm) -> None:
        """``pwm`` applies from ``step`` (steps must not go back)."""
        if self._last_step is not None and step < self._last_step:
            raise ValueError(f"a command for step {step} after one for step {self._last_step}")
        span = step - self._last_step if self._last_step is not None else 1
        self._last_step = step
        self._due.append((step, pwm, max(1, span)))

    def at(self, step: int) -> Pwm:
        """The PWM in force at ``step`` (non-decreasing from call to call)."""
        if step < self._asked:
            raise ValueError(f"step {step} after step {self._asked}")
        self._asked = step
        while self._due and self._due[0][0] <= step:
            due, pwm, span = self._due.popleft()
            if self.mode == "zoh":
                self._from = self._to = tuple(float(v) for v in pwm)
            else:
                self._from = self._value(due - 1)  # the value in force until now
                self._to = tuple(float(v) for v in pwm)
                self._start, self._span = due, span
        value = self._value(step)
        m0, m1, m2, m3 = (min(255, max(0, round(v))) for v in value)
        return (m0, m1, m2, m3)

    def _value(self, step: int) -> tuple[float, ...]:
        if self.mode == "zoh":
            return self._to
        share = min(1.0, (step - self._start + 1) / self._span)
        return tuple(a + (b - a) * share for a, b in zip(self._from, self._to, strict=True))
