"""What a receiver counts about one direction of the link, from sequence numbers and rejections.

Data datagrams are numbered 0, 1, 2 ... by their sender.  The receiver keeps the numbers it has
seen and the highest one:

* a number seen before is a **duplicate** (dropped);
* a number below the highest, not seen before, arrived **late** (reordered; kept);
* **lost** is how many numbers up to the highest (or up to the sender's count in its bye, which
  also catches losses at the end) never arrived intact -- a truncated datagram's number is among
  them, since its header cannot be trusted;
* rejected datagrams count as **truncated** or **garbage** (:class:`robosoc.cosim.datagram.Rejection`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from robosoc.cosim.datagram import Rejection

__all__ = ["COUNTER_NAMES", "Arrival", "ReceiveCounts"]

COUNTER_NAMES = ("sent", "received", "lost", "duplicated", "reordered", "truncated", "garbage")


class Arrival:
    NEW = "new"
    LATE = "late"
    DUPLICATE = "duplicate"


@dataclass
class ReceiveCounts:
    """One direction, as its receiver sees it (``sent`` is filled in from the sender's side)."""

    received: int = 0
    duplicated: int = 0
    reordered: int = 0
    truncated: int = 0
    garbage: int = 0
    highest: int = -1
    announced: int = 0  # data datagrams the sender says it sent (its bye), 0 until then
    rejected: dict[str, int] = field(default_factory=dict)
    _seen: set[int] = field(default_factory=set, repr=False)

    def arrive(self, seq: int) -> tuple[str, int]:
        """Count data datagram ``seq``: its :class:`Arrival` and how many numbers it skipped."""
        if seq in self._seen:
            self.duplicated += 1
            return Arrival.DUPLICATE, 0
        self._seen.add(seq)
        self.received += 1
        if seq < self.highest:
            self.reordered += 1
            return Arrival.LATE, 0
        gap = seq - self.highest - 1
        self.highest = seq
        return Arrival.NEW, gap

    def reject(self, reason: Rejection) -> None:
        setattr(self, reason.counter, getattr(self, reason.counter) + 1)
        self.rejected[reason.value] = self.rejected.get(reason.value, 0) + 1

    @property
    def lost(self) -> int:
        return max(self.highest + 1, self.announced) - self.received

    def as_dict(self) -> dict[str, object]:
        """The counters of :data:`COUNTER_NAMES` but ``sent`` (the sender's), and the rejections by class."""
        return {
            "received": self.received,
            "lost": self.lost,
            "duplicated": self.duplicated,
            "reordered": self.reordered,
            "truncated": self.truncated,
            "garbage": self.garbage,
            "rejected": dict(sorted(self.rejected.items())),
        }
