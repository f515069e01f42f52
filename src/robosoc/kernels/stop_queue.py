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


@njit(cache=True, inline="always")
def _before(cyc: np.ndarray, a: int, b: int) -> bool:
    """Entry a goes before entry b: earlier cycle, then lower index."""
    return cyc[a] < cyc[b] or (cyc[a] == cyc[b] and a < b)


@njit(**UNCOUNTED)
def push(heap: np.ndarray, cyc: np.ndarray, size: int, r: int, cycle: int) -> int:
    """Add index ``r`` stopped at ``cycle``; returns the new size."""
    cyc[r] = cycle
    i = size
    while i > 0:
        parent = (i - 1) >> 1
        if not _before(cyc, r, heap[parent]):
            break
        heap[i] = heap[parent]
        i = parent
    heap[i] = r
    return size + 1


@njit(**UNCOUNTED)
def pop(heap: np.ndarray, cyc: np.ndarray, size: int) -> int:
    """Remove ``heap[0]`` (read it first); returns the new size."""
    size -= 1
    last = heap[size]
    i = 0
    while True:
        child = 2 * i + 1
        if child >= size:
            break
        if child + 1 < size and _before(cyc, heap[child + 1], heap[child]):
            child += 1
        if not _before(cyc, heap[child], last):
            break
        heap[i] = heap[child]
        i = child
    heap[i] = last
    return size


__all__ = ["pop", "push"]
