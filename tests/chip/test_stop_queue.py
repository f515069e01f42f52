"""The chip loop's stop queue (kernels/stop_queue.py): stopped cores come out in (cycle, index)
order, whichever of its two parts (the run of entries pushed in order, the heap) holds them."""

from __future__ import annotations

import random

import numpy as np
import pytest

from robosoc.kernels import stop_queue


def _queue(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    state = np.zeros(stop_queue.Q_STATE, dtype=np.int64)
    stop_queue.clear(state)
    return np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64), state


@pytest.mark.parametrize("seed", range(12))
def test_the_stops_come_out_in_cycle_then_index_order(seed: int) -> None:
    """Random pushes and pops, as the chip loop makes them (each index waits at most once; an index
    popped comes back later, at a later cycle or, some of the time, an earlier one than others
    waiting), against a reference that sorts what waits by (cycle, index).  Cycles repeat often,
    as on a chip whose cores wake on one tick, and the queue stays full for long stretches, so the
    run's slots wrap around many times."""
    rng = random.Random(seed)
    n = rng.choice([1, 2, 3, 7, 16, 255])
    heap, run, cyc, state = _queue(n)
    waiting: dict[int, int] = {}
    out: list[int] = []
    want: list[int] = []
    now = 0
    for r in range(n):  # the quantum's first stops, in index order (the fill)
        c = now + rng.choice([0, 0, 0, 5, rng.randrange(50)])
        stop_queue.push(heap, run, cyc, state, r, c)
        waiting[r] = c
    for _ in range(40 * n + 50):
        assert stop_queue.size(state) == len(waiting)
        if waiting and (rng.random() < 0.6 or len(waiting) == n):
            first = min(waiting, key=lambda r: (waiting[r], r))
            want.append(first)
            got = stop_queue.pop(heap, run, cyc, state)
            out.append(int(got))
            now = waiting.pop(first)
        else:
            r = rng.choice([r for r in range(n) if r not in waiting])
            c = now + rng.choice([0, 0, 1, 17, 40, rng.randrange(200)]) - rng.choice([0, 0, 0, 30])
            stop_queue.push(heap, run, cyc, state, r, c)
            waiting[r] = c
        assert out == want
    while waiting:
        first = min(waiting, key=lambda r: (waiting[r], r))
        assert stop_queue.pop(heap, run, cyc, state) == first
        waiting.pop(first)
    assert stop_queue.size(state) == 0


def test_stops_pushed_in_order_never_enter_the_heap() -> None:
    """A core handled after another and stopping again no earlier goes to the end of the run: the
    heap stays empty, so a pop costs no sift (a sleeping chip's stops)."""
    n = 8
    heap, run, cyc, state = _queue(n)
    for r in range(n):
        stop_queue.push(heap, run, cyc, state, r, 100)
    for tick in range(5):
        for r in range(n):
            assert stop_queue.pop(heap, run, cyc, state) == r
            stop_queue.push(heap, run, cyc, state, r, 200 + 100 * tick)
            assert state[stop_queue.Q_HEAP] == 0
    assert stop_queue.size(state) == n  # (the run wrapped around its n slots five times)
    # a stop before the run's last entry goes into the heap, and comes out first
    assert stop_queue.pop(heap, run, cyc, state) == 0
    stop_queue.push(heap, run, cyc, state, 0, 50)
    assert state[stop_queue.Q_HEAP] == 1
    assert [stop_queue.pop(heap, run, cyc, state) for _ in range(n)] == [0, 1, 2, 3, 4, 5, 6, 7]
