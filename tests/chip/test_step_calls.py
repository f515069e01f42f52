"""Running several chips' loop calls at once (robosoc.chip.step_calls): every step is driven to its
end in its own order, its value returned in the steps' order; a failing step's exception comes after
the round's other steps were sent their results, and a failing call is thrown into its step."""

from __future__ import annotations

import threading

import pytest

from robosoc.chip.step_calls import CHOSEN_ROUNDS, PROBE_ROUNDS, ChipThreads, StepCalls, WayChooser, run_calls


def counting(name: str, calls: int, log: list[tuple[str, int]], fail_at: int | None = None) -> StepCalls[str]:
    """A step of ``calls`` loop calls; call i returns status i; each result is logged as it arrives."""
    for i in range(calls):
        status, seconds = yield (lambda i=i: i)
        assert seconds >= 0.0
        log.append((name, status))
        if fail_at == i:
            raise RuntimeError(f"{name} failed at {i}")
    return f"{name} done after {calls}"


@pytest.mark.parametrize("threads", [1, 2, 4])
def test_every_step_runs_its_calls_in_order_and_returns_its_value(threads: int) -> None:
    log: list[tuple[str, int]] = []
    with ChipThreads(threads) as pool:
        values = pool.run_together([counting("a", 3, log), counting("b", 0, log), counting("c", 1, log)])
    assert values == ["a done after 3", "b done after 0", "c done after 1"]
    assert [s for n, s in log if n == "a"] == [0, 1, 2]
    assert [s for n, s in log if n == "c"] == [0]
    # rounds: every step not yet done is sent its result before any takes its next call
    assert log[:2] == [("a", 0), ("c", 0)]


def test_the_calls_of_a_round_run_on_several_threads_at_once() -> None:
    barrier = threading.Barrier(3, timeout=10)  # passes only if three calls wait at the same time

    def step() -> StepCalls[int]:
        for _ in range(PROBE_ROUNDS):  # a look's rounds alone come first
            yield lambda: 0
        status, _ = yield lambda: barrier.wait() * 0 + 7
        return status

    with ChipThreads(3) as pool:
        assert pool.run_together([step(), step(), step()]) == [7, 7, 7]
        assert pool.rounds == [1, PROBE_ROUNDS]


def test_the_first_failing_step_is_raised_after_the_round_is_done() -> None:
    log: list[tuple[str, int]] = []
    with ChipThreads(2) as pool, pytest.raises(RuntimeError, match="b failed at 0"):
        pool.run_together([counting("a", 2, log), counting("b", 2, log, fail_at=0), counting("c", 2, log, fail_at=0)])
    assert log == [("a", 0), ("b", 0), ("c", 0)]  # every step got the round's result; no later round


def test_a_failing_call_is_thrown_into_its_step() -> None:
    seen: list[str] = []

    def step() -> StepCalls[str]:
        try:
            yield lambda: 1 // 0
        except ZeroDivisionError:
            seen.append("thrown")
            raise
        return "never"

    with ChipThreads(2) as pool, pytest.raises(ZeroDivisionError):
        pool.run_together([step()])
    assert seen == ["thrown"]


def test_run_calls_sends_each_call_its_status() -> None:
    log: list[tuple[str, int]] = []
    assert run_calls(counting("x", 4, log)) == "x done after 4"
    assert log == [("x", 0), ("x", 1), ("x", 2), ("x", 3)]


def test_no_threads_is_refused() -> None:
    with pytest.raises(ValueError, match="threads: at least 1, got 0"):
        ChipThreads(0)


def test_each_look_times_rounds_alone_then_on_the_threads_and_takes_the_faster_way() -> None:
    for threads_s, chosen in ((0.89, True), (0.91, False)):  # a round alone takes 1 s
        chooser = WayChooser()
        ways = []
        for _ in range(2 * (2 * PROBE_ROUNDS + CHOSEN_ROUNDS)):  # two looks
            ways.append(chooser.on_threads())
            chooser.took(threads_s if ways[-1] else 1.0)
        look = [False] * PROBE_ROUNDS + [True] * PROBE_ROUNDS + [chosen] * CHOSEN_ROUNDS
        assert ways == look + look, threads_s
