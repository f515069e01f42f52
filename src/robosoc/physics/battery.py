"""A Li-Po pack by Tremblay's model (:mod:`robosoc.config.power`, docs/power.md), discharged step by step.

Per cell, with ``it`` the charge drawn so far [Ah] and ``i`` the current [A]::

    E(it) = E0 − K·Q/(Q − it) + A·exp(−B·it)        open-circuit voltage
    V     = E(it) − R·i                              terminal voltage

and the pack is ``cells`` of them in series.  State of charge ``SoC = 1 − it/Q``.  The pack is
*empty* from the first step whose terminal voltage is below the cut-off (or when nothing is
left to draw): it is then disconnected for good and delivers 0 V.
"""

from __future__ import annotations

import math

from robosoc.config.power import BatteryConfig

SECONDS_PER_HOUR = 3600.0


class Battery:
    """One pack's state: the charge drawn, and whether it has been cut off.

    Args:
        config: the pack.
    """

    __slots__ = ("_c", "cells", "config", "drawn_ah", "empty")

    def __init__(self, config: BatteryConfig) -> None:
        self.config = config
        self._c = config.tremblay()
        self.cells = config.cells
        self.drawn_ah = (1.0 - config.initial_soc) * config.capacity_ah
        self.empty = False

    @property
    def soc(self) -> float:
        """State of charge, 1 (full) .. 0."""
        return max(0.0, 1.0 - self.drawn_ah / self._c.q)

    def open_circuit_v(self) -> float:
        """The pack's open-circuit voltage at the charge drawn so far [V] (0 once empty, or -inf
        at a charge the model cannot reach: the ``K`` term diverges at Q)."""
        c = self._c
        left = c.q - self.drawn_ah
        if left <= 0.0:
            return -math.inf
        return self.cells * (c.e0 - c.k * c.q / left + c.a * math.exp(-c.b * self.drawn_ah))

    def terminal_v(self, current: float) -> float:
        """The pack's terminal voltage while it delivers ``current`` [A] (0 once empty)."""
        if self.empty:
            return 0.0
        return self.open_circuit_v() - self.cells * self._c.r * current

    def cut_off(self, current: float) -> bool:
        """Whether the pack, delivering ``current``, is below its cut-off voltage (and is now empty)."""
        if not self.empty and self.terminal_v(current) < self.config.cutoff_pack_v:
            self.empty = True
        return self.empty

    def draw(self, current: float, dt: float) -> None:
        """Deliver ``current`` [A] for ``dt`` seconds (an empty pack delivers nothing)."""
        if not self.empty:
            self.drawn_ah += current * dt / SECONDS_PER_HOUR
