"""The firmware's telemetry in the rows of a physics side that is not the chip's process.

The decoupled mode's physics side (:mod:`robosoc.cosim.decoupled_physics`) and the ROS physics
node (:mod:`robosoc.cosim.ros_physics`) get the chip's telemetry as entries: after the read at
the close of sample ``k``'s period, the newest value of every name the project declares
(:mod:`robosoc.host.telemetry`).  :class:`TelemetryRows` keeps them and gives each row what
lockstep's row shows: row k, the newest entry of a sample before k that has come (lockstep reads
at the close of period k-1, before row k) -- its estimate names in the flight's estimate columns,
the others as columns of their own after the flight's, in the project's order.  Entries are not
waited for here (the ``fast`` pacing of each side says when they have all come).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from robosoc.control.flight import ROW_FIELDS
from robosoc.control.host import Estimate
from robosoc.host.telemetry import ESTIMATE_NAMES, estimate_of, own_columns

__all__ = ["ESTIMATE_COLUMNS", "TelemetryRows", "estimate_columns"]

ESTIMATE_COLUMNS = [ROW_FIELDS.index(n) for n in ROW_FIELDS if n.startswith("est_")]
"""The flight row's estimate columns (``est_roll`` ... ``est_height``)."""


def estimate_columns(estimate: Estimate) -> np.ndarray:
    """The estimate columns of a flight row (:data:`ESTIMATE_COLUMNS`) of ``estimate``, as
    :func:`robosoc.control.flight.flight_row` writes them."""
    values = {f"est_{a}": v for a, v in zip(("roll", "pitch", "yaw"), estimate.euler, strict=True)}
    values.update({f"est_q{a}": v for a, v in zip("wxyz", estimate.quaternion, strict=True)})
    values["est_height"] = estimate.height
    return np.array([values[ROW_FIELDS[i]] for i in ESTIMATE_COLUMNS])


class TelemetryRows:
    """The telemetry entries of one vehicle's chip, by sample, and the values each row shows.

    Args:
        names: every telemetry name the project declares, in its order (what an entry's values are).
    """

    def __init__(self, names: Sequence[str]) -> None:
        self.names = tuple(names)
        #: the names that are columns of their own (not the estimate's), in the project's order
        self.own = own_columns(self.names)
        self._own_index = [self.names.index(n) for n in self.own]
        self._estimates = any(n in ESTIMATE_NAMES for n in self.names)
        self._pending: dict[int, tuple[float, ...]] = {}  # by sample, not yet superseded
        self._shown_k = -1
        self._shown: tuple[float, ...] | None = None  # the newest entry a row has shown
        self.received = 0  # distinct entries kept

    def arrive(self, k: int, values: Sequence[float]) -> bool:
        """Keep the entry of sample ``k`` (a repeat, or one older than a row has shown, is
        dropped); whether it has as many values as there are names (else it is refused)."""
        if len(values) != len(self.names):
            return False
        if k > self._shown_k and k not in self._pending:
            self._pending[k] = tuple(float(v) for v in values)
            self.received += 1
        return True

    def fill(self, row: np.ndarray, k: int) -> tuple[float, ...]:
        """Write row ``k``'s estimate columns (when the project publishes an estimate) from the
        newest entry of a sample before ``k``; the row's own columns' values (NaN before the first)."""
        ready = [j for j in self._pending if j < k]
        if ready:
            newest = max(ready)
            self._shown, self._shown_k = self._pending[newest], newest
            for j in ready:
                del self._pending[j]
        if self._shown is None:
            return tuple(math.nan for _ in self.own)
        if self._estimates:
            row[ESTIMATE_COLUMNS] = estimate_columns(estimate_of(dict(zip(self.names, self._shown, strict=True))))
        return tuple(self._shown[i] for i in self._own_index)
