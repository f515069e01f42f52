"""The stopped cores of a quantum in the order the chip handles them: a binary min-heap.

``run_chip`` handles the cores that stopped inside a quantum (before an NI access, an output
flush, an exit) in global cycle order, equal cycles in tile order.  Scanning every awake core for
the earliest stop made each stop cost O(cores): on a 16x16 chip whose cores all wake on the same
tick that was most of the host time.  The heap holds indices into the quantum's list of awake
cores (which is in tile order, so an index orders like its tile) with the cycle each was pushed
at; a core's cycle does not change while it waits in the heap, because only the core being handled
runs.  ``heap[0]`` is the earliest.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from robosoc.kernels.borrowed import UNCOUNTED

# Indices are unsigned (np.uint64): numba then indexes without the code that wraps a negative
# index around, about a third of a sift's instructions (a sleeping 16x16 chip's stops are mostly
# heap work: its 255 cores stop at the same few cycles of every tick).
_U0 = np.uint64(0)
_U1 = np.uint64(1)


@njit(cache=True, inline="always")
def _before(cyc: np.ndarray, a: np.uint64, b: np.uint64) -> bool:
    """Entry a goes before entry b: earlier cycle, then lower index."""
    return bool(cyc[a] < cyc[b] or (cyc[a] == cyc[b] and a < b))


@njit(**UNCOUNTED)
def push(heap: np.ndarray, cyc: np.ndarray, size: int, r: int, cycle: int) -> int:
    """Add index ``r`` stopped at ``cycle``; returns the new size."""
    ur = np.uint64(r)
    cyc[ur] = cycle
    i = np.uint64(size)
    while i > _U0:
        parent = (i - _U1) >> _U1
        up = np.uint64(heap[parent])
        if not _before(cyc, ur, up):
            break
        heap[i] = up
        i = parent
    heap[i] = r
    return size + 1


@njit(**UNCOUNTED)
def pop(heap: np.ndarray, cyc: np.ndarray, size: int) -> int:
    """Remove ``heap[0]`` (read it first); returns the new size."""
    size -= 1
    n = np.uint64(size)
    last = np.uint64(heap[n])
    i = _U0
    while True:
        child = (i << _U1) + _U1
        if child >= n:
            break
        c = np.uint64(heap[child])
        if child + _U1 < n:
            d = np.uint64(heap[child + _U1])
            if _before(cyc, d, c):
                child += _U1
                c = d
        if not _before(cyc, c, last):
            break
        heap[i] = c
        i = child
    heap[i] = last
    return size


__all__ = ["pop", "push"]
