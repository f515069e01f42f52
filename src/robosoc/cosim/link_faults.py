"""Seeded fault injection on the datagrams a side sends (tests, and the decoupled mode's must-reach).

Per data datagram, with the rates of :class:`robosoc.config.link.LinkFaults`:

* garbage (own rate, independent): a datagram of 1..64 random bytes that does not start with the
  magic's first byte is sent first -- the receiver must classify it as garbage;
* then at most one of: **loss** (nothing sent), **duplication** (sent twice), **reordering** (held
  back and sent right after the next datagram that goes out whole -- if something is already
  held, the datagram goes out normally), **truncation** (only its first 0..n-1 bytes are sent).

:attr:`FaultInjector.injected` tallies what was done, in the receiver's terms: on an in-order
channel such as loopback the receiver counts exactly ``injected`` duplicates, reorderings,
truncations and garbage, and ``lost + truncated`` missing sequence numbers.  A datagram held back
when the sender stops is sent by :meth:`FaultInjector.flush` (in order then: not a reordering).
"""

from __future__ import annotations

import numpy as np

from robosoc.config.link import LinkFaults
from robosoc.cosim.datagram import MAGIC

__all__ = ["INJECTED_NAMES", "FaultInjector"]

INJECTED_NAMES = ("lost", "duplicated", "reordered", "truncated", "garbage")
GARBAGE_MAX_BYTES = 64


class FaultInjector:
    """Turns each outgoing datagram into what goes on the wire (see the module docstring)."""

    def __init__(self, faults: LinkFaults, rng: np.random.Generator) -> None:
        self.faults = faults
        self.rng = rng
        self.injected = dict.fromkeys(INJECTED_NAMES, 0)
        self._held: bytes | None = None

    def _garbage(self) -> bytes:
        size = int(self.rng.integers(1, GARBAGE_MAX_BYTES + 1))
        data = bytearray(self.rng.integers(0, 256, size, dtype=np.uint8).tobytes())
        first = int(self.rng.integers(0, 255))
        data[0] = first + (first >= MAGIC[0])  # never the magic's first byte
        return bytes(data)

    def plan(self, datagram: bytes) -> list[bytes]:
        """What to send, in order, for ``datagram``."""
        f = self.faults
        out: list[bytes] = []
        if not f.any:
            out.append(datagram)
        else:
            garbage, u = self.rng.random(2)
            if garbage < f.garbage:
                out.append(self._garbage())
                self.injected["garbage"] += 1
            whole = False
            if u < f.loss:
                self.injected["lost"] += 1
            elif u < f.loss + f.duplicate:
                out += [datagram, datagram]
                self.injected["duplicated"] += 1
                whole = True
            elif u < f.loss + f.duplicate + f.reorder and self._held is None:
                self._held = datagram
                return out
            elif f.loss + f.duplicate + f.reorder <= u < f.loss + f.duplicate + f.reorder + f.truncate:
                out.append(datagram[: int(self.rng.integers(0, len(datagram)))])
                self.injected["truncated"] += 1
            else:
                out.append(datagram)
                whole = True
            if whole and self._held is not None:
                out.append(self._held)
                self._held = None
                self.injected["reordered"] += 1
        return out

    def flush(self) -> list[bytes]:
        """The datagram still held back, if any (the sender stops)."""
        held, self._held = self._held, None
        return [held] if held is not None else []
