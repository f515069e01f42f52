"""A chip step as the chip loop calls it makes, run one at a time or several chips' at once.

:meth:`robosoc.chip.mpsoc.MPSoC.step_calls` is :meth:`~robosoc.chip.mpsoc.MPSoC.step` as a
generator: it does the step's Python (pc check, translation upkeep, drains) itself and yields each
call of the compiled chip loop (:func:`robosoc.kernels.chip.run_chip`, compiled ``nogil``) as a
function of no arguments, to be sent back its status and the host seconds it took.  The chips of
several vehicles are independent between two physics steps, so :func:`run_together` runs their
loop calls on the host's cores at once, while everything else stays in the calling thread: what a
chip computes is the same whichever thread runs its loop and whatever runs beside it (a chip's
arrays are its own; the translated code's shared tables are only read by the loop).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Generator, Sequence
from concurrent.futures import ThreadPoolExecutor, wait
from typing import TypeVar

#: One call of the chip loop: runs it, returns its status (a CHIP_* reason).
ChipCall = Callable[[], int]

#: What a step's generator is sent for each call it yielded: the status and the host seconds it took.
CallResult = tuple[int, float]

T = TypeVar("T")

#: A step (or anything around one) as the loop calls it makes; its value is the step's.
StepCalls = Generator[ChipCall, CallResult, T]


def _timed(call: ChipCall) -> CallResult:
    start = time.perf_counter()
    status = call()
    return status, time.perf_counter() - start


def run_calls(calls: StepCalls[T]) -> T:
    """Run a step's loop calls one after another in this thread; the step's value."""
    try:
        call = next(calls)
        while True:
            call = calls.send(_timed(call))
    except StopIteration as done:
        return done.value


def host_cores() -> int:
    """The host cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


#: Rounds timed in each way (the calling thread alone, then on the threads) per look.
PROBE_ROUNDS = 16
#: Rounds run in the way the last look chose, before the next look.
CHOSEN_ROUNDS = 128
#: The threads are chosen when their rounds took less than this share of the wall time of the
#: rounds run alone just before.
PAYS = 0.9


class WayChooser:
    """Whether a round of several loop calls runs on the threads: a look's :data:`PROBE_ROUNDS`
    rounds alone, then as many on the threads, then :data:`CHOSEN_ROUNDS` the way that was faster
    (the threads only when they took under :data:`PAYS` of the time alone); then the next look."""

    def __init__(self) -> None:
        self._round = 0  # rounds since the last look began
        self._alone_s = 0.0  # the look's wall seconds alone, and on the threads
        self._threads_s = 0.0
        self.chosen = False  # the threads won the last look

    def on_threads(self) -> bool:
        """Whether the next round runs on the threads."""
        if self._round < PROBE_ROUNDS:
            return False
        return self._round < 2 * PROBE_ROUNDS or self.chosen

    def took(self, seconds: float) -> None:
        """The round just run (the way :meth:`on_threads` said) took ``seconds`` of wall time."""
        if self._round < PROBE_ROUNDS:
            self._alone_s += seconds
        elif self._round < 2 * PROBE_ROUNDS:
            self._threads_s += seconds
            if self._round == 2 * PROBE_ROUNDS - 1:
                self.chosen = self._threads_s < PAYS * self._alone_s
        self._round += 1
        if self._round == 2 * PROBE_ROUNDS + CHOSEN_ROUNDS:
            self._round, self._alone_s, self._threads_s = 0, 0.0, 0.0


class ChipThreads:
    """Helper threads that run the loop calls of several chips beside the calling thread.

    On a shared host the second core may be taken: a helper thread then waits for a core, or is
    preempted in a call that the calling thread waits for, and a round on the threads takes as
    long as the same calls one after the other, or longer.  So the rounds look at what the
    threads gain: a look times :data:`PROBE_ROUNDS` rounds in the calling thread alone and as
    many on the threads, and the next :data:`CHOSEN_ROUNDS` rounds run the way that was faster
    (the threads only when they took under :data:`PAYS` of the time alone).  Which thread runs
    a call changes nothing of what it computes (:class:`WayChooser`).

    Args:
        threads: how many threads run loop calls at once, the caller's included (1: the caller
            alone, no thread is started).
    """

    def __init__(self, threads: int) -> None:
        if threads < 1:
            raise ValueError(f"threads: at least 1, got {threads}")
        self.threads = threads
        self._pool = ThreadPoolExecutor(threads - 1, thread_name_prefix="robosoc-chip") if threads > 1 else None
        self.chooser = WayChooser()
        #: rounds run on the threads, and in the calling thread alone
        self.rounds = [0, 0]

    def close(self) -> None:
        """Stop the helper threads (after their calls have returned)."""
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None

    def __enter__(self) -> ChipThreads:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()

    def run_together(self, steps: Sequence[StepCalls[T]]) -> list[T]:
        """Run several chips' steps: each round takes the next loop call of every step not yet done
        and runs them on the threads at once, then sends each step its result in their order.  The
        steps' values in their order.

        A loop call's exception is thrown into its step where the call was yielded.  An exception
        of a step is raised after every step of that round was sent its result (so no chip is left
        between a loop call and its step's Python, and no loop call outlives this method); the first
        in the steps' order is raised, and every step is closed.
        """
        values: dict[int, T] = {}
        pending: list[tuple[int, ChipCall]] = []
        failure: BaseException | None = None
        for i, step in enumerate(steps):
            try:
                pending.append((i, next(step)))
            except StopIteration as done:
                values[i] = done.value
        while pending:
            results = self._run_round([call for _, call in pending])
            following: list[tuple[int, ChipCall]] = []
            for (i, _), result in zip(pending, results, strict=True):
                try:
                    if isinstance(result, BaseException):
                        following.append((i, steps[i].throw(result)))
                    else:
                        following.append((i, steps[i].send(result)))
                except StopIteration as done:
                    values[i] = done.value
                except BaseException as exc:
                    failure = failure or exc
            if failure is not None:
                for step in steps:
                    step.close()
                raise failure
            pending = following
        return [values[i] for i in range(len(steps))]

    def _run_round(self, calls: list[ChipCall]) -> list[CallResult | BaseException]:
        """Run ``calls`` on the threads at once (each taken by the first free thread), or in this
        thread alone (see the class); each one's result, or what it raised."""
        results: list[CallResult | BaseException | None] = [None] * len(calls)
        order = iter(range(len(calls)))  # shared: next() on it holds the GIL, so each index is taken once

        def work() -> None:
            for j in order:
                try:
                    results[j] = _timed(calls[j])
                except BaseException as exc:  # handed to the caller in the call's turn
                    results[j] = exc

        pool = self._pool
        on_threads = pool is not None and len(calls) > 1 and self.chooser.on_threads()
        self.rounds[0 if on_threads else 1] += 1
        start = time.perf_counter()
        if pool is not None and on_threads:
            helpers = [pool.submit(work) for _ in range(min(self.threads, len(calls)) - 1)]
            try:
                work()
            finally:
                wait(helpers)  # no loop call outlives the round, even on Ctrl-C
        else:
            work()
        if pool is not None and len(calls) > 1:
            self.chooser.took(time.perf_counter() - start)
        return [r if r is not None else RuntimeError("a chip loop call was not run") for r in results]


__all__ = ["CallResult", "ChipCall", "ChipThreads", "StepCalls", "WayChooser", "host_cores", "run_calls"]
