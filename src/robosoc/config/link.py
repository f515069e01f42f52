"""The decoupled mode's link: pacing, actuator hold, timeouts, redundancy and injected faults.

Frozen dataclasses checked in ``__post_init__`` (errors ``ValueError("field: reason")``), used by
``robosoc serve physics|chip`` and ``robosoc fly --decoupled`` (docs/decoupled.md)::

    pace = "realtime"        # physics side: "realtime" (wall clock) or "fast" (as fast as the chip allows)
    hold = "zoh"             # physics side: "zoh" (hold the newest command) or "linear" (ramp to it)
    peer_timeout_s = 5.0     # end when the peer has been silent this long (after first contact)
    connect_timeout_s = 300.0  # wait this long for the first contact (the chip side may be compiling)
    resend = 2               # each datagram repeats this many earlier readings / commands
    heartbeat_s = 0.02       # a side that waits for its peer repeats its newest datagram this often
    [faults]                 # injected on what a side sends (rates 0..1, seeded by the run's seed)
    loss = 0.1
    duplicate = 0.05
    reorder = 0.05
    truncate = 0.0
    garbage = 0.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

from robosoc.config.ranges import check_fields

__all__ = ["FAULT_NAMES", "HOLD_CHOICES", "PACE_CHOICES", "LinkConfig", "LinkFaults", "parse_faults"]

PACE_CHOICES = ("realtime", "fast")
HOLD_CHOICES = ("zoh", "linear")
#: Most readings or commands a datagram repeats (a datagram stays well under 1500 bytes).
MAX_RESEND = 8


def _rate(name: str, value: float) -> None:
    if not (isinstance(value, int | float) and math.isfinite(value) and 0.0 <= value <= 1.0):
        raise ValueError(f"{name}: must be a rate between 0 and 1, got {value!r}")


@dataclass(frozen=True)
class LinkFaults:
    """Faults a side injects into the data datagrams it sends (rates per datagram, 0..1).

    Each datagram gets at most one of loss, duplication, reordering (held back and sent after the
    next delivered datagram) and truncation, so their rates add up to at most 1; garbage (a
    datagram of random bytes) is sent in addition, before the datagram, with its own rate.
    """

    loss: float = 0.0
    duplicate: float = 0.0
    reorder: float = 0.0
    truncate: float = 0.0
    garbage: float = 0.0

    def __post_init__(self) -> None:
        for f in fields(self):
            _rate(f.name, getattr(self, f.name))
        exclusive = self.loss + self.duplicate + self.reorder + self.truncate
        if exclusive > 1.0 + 1e-12:
            raise ValueError(
                "loss: loss + duplicate + reorder + truncate must be at most 1 (one fault per datagram), "
                f"got {exclusive:g}"
            )
        check_fields(self)  # and every float in its range (config/ranges.py)

    @property
    def any(self) -> bool:
        return any(getattr(self, f.name) > 0 for f in fields(self))

    def as_dict(self) -> dict[str, float]:
        return {f.name: float(getattr(self, f.name)) for f in fields(self)}


FAULT_NAMES = tuple(f.name for f in fields(LinkFaults))


def parse_faults(text: str) -> LinkFaults:
    """``"loss=0.1,duplicate=0.05"`` -> :class:`LinkFaults` (names of :data:`FAULT_NAMES`).

    Raises:
        ValueError: an unknown name, a value that is not a rate, a name given twice.
    """
    values: dict[str, float] = {}
    for item in text.split(","):
        name, eq, number = item.strip().partition("=")
        name = name.strip()
        if not eq or name not in FAULT_NAMES:
            raise ValueError(
                f"expected NAME=RATE[,NAME=RATE...] with NAME one of {', '.join(FAULT_NAMES)}, got {text!r}"
            )
        if name in values:
            raise ValueError(f"{name} given twice in {text!r}")
        try:
            rate = float(number)
        except ValueError:
            raise ValueError(f"{name}: must be a rate between 0 and 1, got {number.strip()!r}") from None
        _rate(name, rate)
        values[name] = rate
    return LinkFaults(**values)


@dataclass(frozen=True)
class LinkConfig:
    """How the two sides of the decoupled mode talk and wait (see the module docstring)."""

    pace: str = "realtime"
    hold: str = "zoh"
    peer_timeout_s: float = 5.0
    connect_timeout_s: float = 300.0
    resend: int = 2
    heartbeat_s: float = 0.02
    faults: LinkFaults = field(default_factory=LinkFaults)

    def __post_init__(self) -> None:
        if self.pace not in PACE_CHOICES:
            raise ValueError(f"pace: must be one of {', '.join(PACE_CHOICES)}, got {self.pace!r}")
        if self.hold not in HOLD_CHOICES:
            raise ValueError(f"hold: must be one of {', '.join(HOLD_CHOICES)}, got {self.hold!r}")
        for name, lo, hi in (("peer_timeout_s", 0.05, 3600.0), ("connect_timeout_s", 0.05, 3600.0)):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and lo <= v <= hi):
                raise ValueError(f"{name}: must be between {lo:g} and {hi:g} s, got {v!r}")
        if not (isinstance(self.heartbeat_s, int | float) and 0.001 <= self.heartbeat_s <= 1.0):
            raise ValueError(f"heartbeat_s: must be between 0.001 and 1 s, got {self.heartbeat_s!r}")
        if self.heartbeat_s >= self.peer_timeout_s:
            raise ValueError(
                f"heartbeat_s: must be shorter than peer_timeout_s ({self.peer_timeout_s:g} s), "
                f"got {self.heartbeat_s:g}"
            )
        if isinstance(self.resend, bool) or not isinstance(self.resend, int) or not 0 <= self.resend <= MAX_RESEND:
            raise ValueError(f"resend: must be between 0 and {MAX_RESEND}, got {self.resend!r}")
        check_fields(self)  # and every float in its range (config/ranges.py)
