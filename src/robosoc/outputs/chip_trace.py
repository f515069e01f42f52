"""The chip's timeline as a Chrome JSON trace (``chip-trace.json``), which ui.perfetto.dev opens.

One process per tile (``tile (x,y)``), with these threads:

* ``core``: the task running (``kernel``, ``kernel (interrupt)``, ``idle``, ``estimator``, ``pid``
  ...), one slice per span between two TASK_ID stores, with ``sleep`` slices nested in them;
* ``jobs: <task>``: one slice per job from release to completion, holding ``waiting`` (release to
  start) and ``running`` (start to completion, preemptions included); jobs that overlap go to a
  second lane;
* ``NoC send`` / ``NoC receive``: a slice per packet while its flits leave the sender / from its
  first flit's arrival to the cycle the receiver sees it, joined by a flow arrow (the I/O tile has
  only these).

A flow's points are at the starts of its two slices, each written right after its slice: the
start (``s``) binds to the send slice, which encloses it, the end (``f``, ``"bp": "e"``) to the
receive slice, which encloses it too (the Trace Event Format's rules, which Perfetto follows), and
Chromium's DevTools binds a flow point only to a slice of the same thread and category that starts
at the point's very timestamp.  Points inside the slices (as before) bind in Perfetto but DevTools
draws none of them.

Timestamps are microseconds of simulated time from the chip's reset (``cycle × clock``).  The
events come from :mod:`robosoc.cosim.chip_timeline` and the job records of the replay harness.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from pathlib import Path

from robosoc import output_files
from robosoc.cosim.chip_timeline import ChipTimeline, timeline_of
from robosoc.cosim.firmware_run import FirmwareRun, ReplayResult
from robosoc.host import images
from robosoc.records import JobRecord

Tile = tuple[int, int]

THREAD_CORE = 1
THREAD_NOC_SEND = 2
THREAD_NOC_RECEIVE = 3
THREAD_JOBS = 10  # first jobs thread; lanes and tasks count up from here


def _lanes(intervals: Iterable[tuple[int, int]]) -> list[int]:
    """A lane per interval (in the given order, sorted by start) so that no two in a lane overlap."""
    ends: list[int] = []
    out = []
    for start, end in intervals:
        for lane, last in enumerate(ends):
            if last <= start:
                ends[lane] = end
                out.append(lane)
                break
        else:
            ends.append(end)
            out.append(len(ends) - 1)
    return out


def _lanes_by(items: Sequence, key, interval) -> dict[int, int]:
    """Lanes (by ``id`` of each item) per ``key`` group of ``items`` (sorted by start already)."""
    out: dict[int, int] = {}
    groups: dict[object, list] = {}
    for item in items:
        groups.setdefault(key(item), []).append(item)
    for group in groups.values():
        for item, lane in zip(group, _lanes(interval(i) for i in group), strict=True):
            out[id(item)] = lane
    return out


class _Trace:
    def __init__(self, clock_ns: float, tiles: Sequence[Tile], io_tile: Tile) -> None:
        self.clock_ns = clock_ns
        self.events: list[dict] = []
        self.pids = {xy: k + 1 for k, xy in enumerate(sorted({*tiles, io_tile}))}
        self.threads: set[tuple[int, int]] = set()
        for xy, pid in self.pids.items():
            label = f"tile ({xy[0]},{xy[1]})" + (" I/O" if xy == io_tile else "")
            self._meta("process_name", pid, 0, {"name": label})
            self._meta("process_sort_index", pid, 0, {"sort_index": pid})

    def _meta(self, name: str, pid: int, tid: int, args: dict) -> None:
        self.events.append({"name": name, "ph": "M", "pid": pid, "tid": tid, "args": args})

    def us(self, cycle: float) -> float:
        return cycle * self.clock_ns / 1000.0

    def thread(self, xy: Tile, tid: int, name: str) -> int:
        pid = self.pids[xy]
        if (pid, tid) not in self.threads:
            self.threads.add((pid, tid))
            self._meta("thread_name", pid, tid, {"name": name})
            self._meta("thread_sort_index", pid, tid, {"sort_index": tid})
        return pid

    def slice(self, xy: Tile, tid: int, thread: str, name: str, cat: str, start: float, end: float, **args) -> None:
        pid = self.thread(xy, tid, thread)
        event = {"name": name, "cat": cat, "ph": "X", "pid": pid, "tid": tid, "ts": self.us(start),
                 "dur": self.us(end) - self.us(start)}  # fmt: skip
        if args:
            event["args"] = args
        self.events.append(event)

    def flow(self, phase: str, flow_id: int, xy: Tile, tid: int, cycle: float) -> None:
        event = {"name": "packet", "cat": "noc", "ph": phase, "id": flow_id, "pid": self.pids[xy], "tid": tid,
                 "ts": self.us(cycle)}  # fmt: skip
        if phase == "f":
            event["bp"] = "e"
        self.events.append(event)


def _task_name(names: dict[tuple[Tile, int], str], xy: Tile, task: int) -> str:
    if task == images.KERNEL_TASK_ID:
        return "kernel"
    if task == images.IDLE_TASK_ID:
        return "idle"
    return names.get((xy, task), f"task {task}")


def chip_trace(
    timeline: ChipTimeline,
    jobs: Sequence[JobRecord],
    clock_ns: float,
    task_names: dict[tuple[Tile, int], str],
    metadata: dict[str, object] | None = None,
) -> dict:
    """The trace as a JSON object (``traceEvents`` plus ``otherData``).

    Args:
        timeline: what the cores and the NoC did.
        jobs: the firmware's job records (release, start, completion cycles).
        clock_ns: the chip's clock period.
        task_names: (tile, TASK_ID) → name of the application tasks (kernel and idle are known).
        metadata: more fields for ``otherData`` (firmware build, scenario ...).
    """
    trace = _Trace(clock_ns, timeline.tiles, timeline.io_tile)
    end_of = {xy: max((s.end for s in timeline.spans if s.tile == xy), default=0) for xy in timeline.tiles}
    open_sleep = {s.tile: s.start for s in timeline.sleeps if s.end is None}
    last_span = {}
    for k, span in enumerate(timeline.spans):
        last_span[span.tile] = k
    # the core: task spans, sleeps nested in them (a sleep still going runs to the end of the trace)
    for k, span in enumerate(timeline.spans):
        name = _task_name(task_names, span.tile, span.task)
        if span.interrupt:
            name += " (interrupt)"
        end = span.end
        if span.tile in open_sleep and last_span[span.tile] == k:
            end = max(end, timeline.end_cycle)
        trace.slice(span.tile, THREAD_CORE, "core", name, "task", span.start, end, task_id=span.task)
    for sleep in timeline.sleeps:
        end = sleep.end if sleep.end is not None else max(timeline.end_cycle, end_of[sleep.tile])
        trace.slice(sleep.tile, THREAD_CORE, "core", "sleep", "sleep", sleep.start, end)
    # the jobs of each task, in lanes
    tasks = list(dict.fromkeys((j.tile, j.task) for j in jobs))
    for n, (xy, task) in enumerate(tasks):
        mine = sorted((j for j in jobs if (j.tile, j.task) == (xy, task)), key=lambda j: j.release_cycle)
        lanes = _lanes((j.release_cycle, j.completion_cycle) for j in mine)
        for j, lane in zip(mine, lanes, strict=True):
            tid = THREAD_JOBS + 4 * n + lane
            thread = f"jobs: {task}" + (f" ({lane + 1})" if lane else "")
            args = {
                "job": j.job, "release_cycle": j.release_cycle, "start_cycle": j.start_cycle,
                "completion_cycle": j.completion_cycle, "response_us": trace.us(j.response_cycles),
                "exec_cycles": j.exec_cycles, "instructions": j.instructions, "deadline_met": j.deadline_met,
                "energy_pj": {k: round(v, 3) for k, v in j.energy_pj.items()},
            }  # fmt: skip
            name = f"{task} #{j.job}" + ("" if j.deadline_met else " MISSED")
            trace.slice(xy, tid, thread, name, "job", j.release_cycle, j.completion_cycle, **args)
            if j.start_cycle > j.release_cycle:
                trace.slice(xy, tid, thread, "waiting", "job", j.release_cycle, j.start_cycle)
            if j.completion_cycle > j.start_cycle:
                trace.slice(xy, tid, thread, "running", "job", j.start_cycle, j.completion_cycle)
    # NoC packets: a slice at each end (lanes where they overlap), a flow from the start of one to
    # the start of the other (each point after its slice, at the slice's own timestamp)
    sends = sorted(timeline.packets, key=lambda p: p.sent)
    send_lane = _lanes_by(sends, lambda p: p.src, lambda p: (p.sent, p.sent + p.flits))
    delivered = [p for p in sends if p.first is not None and p.visible is not None]
    delivered.sort(key=lambda p: p.first or 0)  # (first is never None here)
    receive_lane = _lanes_by(delivered, lambda p: p.dest, lambda p: (p.first, p.visible))
    for flow_id, p in enumerate(sends, start=1):
        tid = THREAD_NOC_SEND + 10 * send_lane[id(p)]
        args = {"to": f"{p.dest[0]},{p.dest[1]}", "flits": p.flits}
        name = f"packet to ({p.dest[0]},{p.dest[1]})"
        trace.slice(p.src, tid, "NoC send", name, "noc", p.sent, p.sent + p.flits, **args)
        if p.first is None or p.visible is None:
            continue
        trace.flow("s", flow_id, p.src, tid, p.sent)
        tid = THREAD_NOC_RECEIVE + 10 * receive_lane[id(p)]
        args = {"from": f"{p.src[0]},{p.src[1]}", "flits": p.flits, "latency_cycles": p.visible - p.sent}
        name = f"packet from ({p.src[0]},{p.src[1]})"
        trace.slice(p.dest, tid, "NoC receive", name, "noc", p.first, p.visible, **args)
        trace.flow("f", flow_id, p.dest, tid, p.first)
    other: dict[str, object] = {"clock_ns": clock_ns, "events_lost": timeline.lost, "end_cycle": timeline.end_cycle}
    other.update(metadata or {})
    return {"traceEvents": trace.events, "displayTimeUnit": "ns", "otherData": other}


def write_chip_trace(trace: dict, path: Path) -> None:
    """Write ``trace`` to ``path`` (under a temporary name, then renamed)."""
    with output_files.atomic_open(path, "w", encoding="utf-8") as handle:
        json.dump(trace, handle, separators=(",", ":"))


def run_trace(run: FirmwareRun, result: ReplayResult, metadata: dict[str, object] | None = None) -> dict:
    """The trace of a firmware run (replay or lockstep flight) that recorded its timeline."""
    timeline = timeline_of(run.chip, run.tiles)
    meta = {"firmware": result.firmware.label, **(metadata or {})}
    return chip_trace(timeline, result.jobs, result.clock_ns, run.names, meta)


__all__ = ["chip_trace", "run_trace", "write_chip_trace"]
