"""The stopped cores of a quantum in the order the chip handles them: a binary min-heap.

``run_chip`` handles the cores that stopped inside a quantum (before an NI access, an output
flush, an exit) in global cycle order, equal cycles in tile order.  Scanning every awake core for
the earliest stop made each stop cost O(cores): on a 16x16 chip whose cores all wake on the same
tick that was most of the host time.  The heap holds indices into the quantum's list of awake
cores (which is in tile order, so an index orders like its tile) with the cycle each was pushed
at; a core's cycle does not change while it waits in the heap, because only the core being handled
runs.  ``heap[0]`` is the earliest.  Beside the heap a *run* holds entries in order: a stop that goes
after the run's last entry is appended there in O(1), and a pop takes the first of the run or the
heap.  The cores a quantum handles one after the other mostly stop again in that order (a sleeping
16x16 chip's 255 cores all read IRQ_CAUSE, then all store to SLEEP, at the same cycles of every
tick), so most stops never enter the heap, whose sifts were 40 % of the chip loop's own time there.
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

# ``state``: the heap's size, and the first and one past the last entry of the run (counts that
# only grow while the queue is not empty; ``run[k % len(run)]`` holds entry k)
Q_HEAP = 0
Q_HEAD = 1
Q_TAIL = 2
Q_STATE = 3


@njit(cache=True, inline="always")
def _before(cyc: np.ndarray, a: np.uint64, b: np.uint64) -> bool:
    """Entry a goes before entry b: earlier cycle, then lower index."""
    return bool(cyc[a] < cyc[b] or (cyc[a] == cyc[b] and a < b))


@njit(cache=True, inline="always")
def clear(state: np.ndarray) -> None:
    """Empty the queue."""
    state[Q_HEAP] = 0
    state[Q_HEAD] = 0
    state[Q_TAIL] = 0


@njit(cache=True, inline="always")
def size(state: np.ndarray) -> int:
    """The entries waiting."""
    return state[Q_HEAP] + state[Q_TAIL] - state[Q_HEAD]


@njit(**UNCOUNTED)
def push(heap: np.ndarray, run: np.ndarray, cyc: np.ndarray, state: np.ndarray, r: int, cycle: int) -> None:
    """Add index ``r`` stopped at ``cycle``: at the end of the run if it goes after the run's last
    entry (as the stops of cores handled in order mostly do), else into the heap."""
    ur = np.uint64(r)
    cyc[ur] = cycle
    head = state[Q_HEAD]
    tail = state[Q_TAIL]
    n = np.uint64(run.shape[0])
    if head == tail or _before(cyc, np.uint64(run[np.uint64(tail - 1) % n]), ur):
        run[np.uint64(tail) % n] = r
        state[Q_TAIL] = tail + 1
        return
    size = state[Q_HEAP]
    i = np.uint64(size)
    while i > _U0:
        parent = (i - _U1) >> _U1
        up = np.uint64(heap[parent])
        if not _before(cyc, ur, up):
            break
        heap[i] = up
        i = parent
    heap[i] = r
    state[Q_HEAP] = size + 1


@njit(**UNCOUNTED)
def pop(heap: np.ndarray, run: np.ndarray, cyc: np.ndarray, state: np.ndarray) -> np.int64:
    """Remove and return the first entry (the queue must not be empty): the run's first or the
    heap's top, whichever goes first."""
    head = state[Q_HEAD]
    tail = state[Q_TAIL]
    size = state[Q_HEAP]
    n = np.uint64(run.shape[0])
    if head != tail:
        first = np.uint64(run[np.uint64(head) % n])
        if size == 0 or _before(cyc, first, np.uint64(heap[0])):
            if head + 1 == tail:
                state[Q_HEAD] = 0
                state[Q_TAIL] = 0
            else:
                state[Q_HEAD] = head + 1
            return np.int64(first)
    top = heap[0]
    size -= 1
    state[Q_HEAP] = size
    m = np.uint64(size)
    last = np.uint64(heap[m])
    i = _U0
    while True:
        child = (i << _U1) + _U1
        if child >= m:
            break
        c = np.uint64(heap[child])
        if child + _U1 < m:
            d = np.uint64(heap[child + _U1])
            if _before(cyc, d, c):
                child += _U1
                c = d
        if not _before(cyc, c, last):
            break
        heap[i] = c
        i = child
    heap[i] = last
    return top


__all__ = ["Q_STATE", "clear", "pop", "push", "size"]
