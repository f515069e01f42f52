"""The Perfetto trace of a hand-made timeline, event for event: processes and threads named and
ordered, task spans with interrupts and a sleep still going at the end, jobs in lanes, packets at
both ends joined by flows (clock 4 ns: a cycle is 0.004 µs)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from robosoc import output_files
from robosoc.cosim.chip_timeline import ChipTimeline, Packet, Sleep, TaskSpan
from robosoc.host.images import IDLE_TASK_ID, KERNEL_TASK_ID
from robosoc.outputs import chip_trace as chip_trace_module
from robosoc.outputs.chip_trace import chip_trace, write_chip_trace
from robosoc.records import JobRecord

A, B, IO = (1, 0), (0, 1), (0, 0)
US = 0.004  # µs per cycle at 4 ns


def _job(task: str, tile, n: int, release: int, start: int, done: int, met: bool = True) -> JobRecord:
    return JobRecord(task, tile, n, release, start, done, done - start, met, 50 + n, {"task": 1.23456}, False)


def _timeline() -> ChipTimeline:
    spans = [
        TaskSpan(A, KERNEL_TASK_ID, 0, 100),
        TaskSpan(A, 2, 100, 400),
        TaskSpan(A, KERNEL_TASK_ID, 400, 450, interrupt=True),
        TaskSpan(B, IDLE_TASK_ID, 0, 300),
        TaskSpan(A, 7, 450, 500),  # a task without a name
        TaskSpan(B, KERNEL_TASK_ID, 300, 350),  # B's last span: B sleeps from 320 to the end
    ]
    sleeps = [Sleep(A, 150, 200), Sleep(B, 320, None)]
    packets = [
        Packet(IO, A, 10, 8, 30, 45),  # delivered: both ends and a flow
        Packet(IO, A, 12, 6, 50, 70),  # sent while the first still leaves: a second send lane
        Packet(A, B, 14, 4, 40, 48),  # overlaps both: lanes are per sender and per receiver
        Packet(A, B, 460, 4, None, None),  # not delivered yet: the sender's slice only
        Packet(A, B, 470, 2, 480, None),  # arrived, not yet seen by the receiver: the same
    ]
    return ChipTimeline([A, B], IO, spans, sleeps, packets, lost=2, end_cycle=1000)


@pytest.fixture(scope="module")
def trace() -> dict:
    jobs = [
        _job("estimator", A, 0, 100, 110, 300),
        _job("estimator", A, 1, 200, 300, 420, met=False),  # released before job 0 completed: lane 2
        _job("estimator", A, 2, 420, 420, 440),  # back in lane 1, no wait
        _job("pid", B, 0, 50, 60, 60),  # completed at its start: no running slice
    ]
    return chip_trace(_timeline(), jobs, 4.0, {(A, 2): "estimator", (B, 3): "pid"}, {"firmware": "fixed+mul"})


def _by(trace: dict, **match) -> list[dict]:
    return [e for e in trace["traceEvents"] if all(e.get(k) == v for k, v in match.items())]


def test_every_tile_is_a_process_named_and_sorted_and_the_io_tile_says_so(trace: dict) -> None:
    # pids by sorted tile: (0,0) -> 1, (0,1) -> 2, (1,0) -> 3
    assert trace["traceEvents"][:6] == [
        {"name": "process_name", "ph": "M", "pid": 1, "tid": 0, "args": {"name": "tile (0,0) I/O"}},
        {"name": "process_sort_index", "ph": "M", "pid": 1, "tid": 0, "args": {"sort_index": 1}},
        {"name": "process_name", "ph": "M", "pid": 2, "tid": 0, "args": {"name": "tile (0,1)"}},
        {"name": "process_sort_index", "ph": "M", "pid": 2, "tid": 0, "args": {"sort_index": 2}},
        {"name": "process_name", "ph": "M", "pid": 3, "tid": 0, "args": {"name": "tile (1,0)"}},
        {"name": "process_sort_index", "ph": "M", "pid": 3, "tid": 0, "args": {"sort_index": 3}},
    ]
    assert trace["displayTimeUnit"] == "ns"
    assert trace["otherData"] == {"clock_ns": 4.0, "events_lost": 2, "end_cycle": 1000, "firmware": "fixed+mul"}


def test_each_thread_is_named_once_with_its_sort_index(trace: dict) -> None:
    names = {(e["pid"], e["tid"]): e["args"]["name"] for e in _by(trace, name="thread_name")}
    assert names == {
        (3, 1): "core",
        (2, 1): "core",
        (3, 10): "jobs: estimator",
        (3, 11): "jobs: estimator (2)",
        (2, 14): "jobs: pid",
        (1, 2): "NoC send",
        (1, 12): "NoC send",
        (3, 3): "NoC receive",
        (3, 2): "NoC send",
        (2, 3): "NoC receive",
    }
    assert len(_by(trace, name="thread_name")) == len(names)
    order = {(e["pid"], e["tid"]): e["args"]["sort_index"] for e in _by(trace, name="thread_sort_index")}
    assert order == {key: key[1] for key in names}


def test_core_slices_name_their_task_and_a_sleep_still_going_runs_to_the_end(trace: dict) -> None:
    core = [(e["pid"], e["name"], e["cat"], e["ts"], e["dur"], e.get("args")) for e in _by(trace, tid=1, ph="X")]
    assert core == [
        (3, "kernel", "task", 0.0, pytest.approx(100 * US), {"task_id": KERNEL_TASK_ID}),
        (3, "estimator", "task", pytest.approx(100 * US), pytest.approx(300 * US), {"task_id": 2}),
        (3, "kernel (interrupt)", "task", pytest.approx(400 * US), pytest.approx(50 * US), {"task_id": 0}),
        (2, "idle", "task", 0.0, pytest.approx(300 * US), {"task_id": IDLE_TASK_ID}),
        (3, "task 7", "task", pytest.approx(450 * US), pytest.approx(50 * US), {"task_id": 7}),
        # B's last span holds its sleep, which lasts to the end of the recording
        (2, "kernel", "task", pytest.approx(300 * US), pytest.approx(700 * US), {"task_id": 0}),
        (3, "sleep", "sleep", pytest.approx(150 * US), pytest.approx(50 * US), None),
        (2, "sleep", "sleep", pytest.approx(320 * US), pytest.approx(680 * US), None),
    ]


def test_jobs_go_to_lanes_and_hold_their_waiting_and_running_parts(trace: dict) -> None:
    jobs = [(e["pid"], e["tid"], e["name"], e["ts"], e["dur"]) for e in _by(trace, cat="job")]
    assert jobs == [
        (3, 10, "estimator #0", pytest.approx(100 * US), pytest.approx(200 * US)),
        (3, 10, "waiting", pytest.approx(100 * US), pytest.approx(10 * US)),
        (3, 10, "running", pytest.approx(110 * US), pytest.approx(190 * US)),
        (3, 11, "estimator #1 MISSED", pytest.approx(200 * US), pytest.approx(220 * US)),
        (3, 11, "waiting", pytest.approx(200 * US), pytest.approx(100 * US)),
        (3, 11, "running", pytest.approx(300 * US), pytest.approx(120 * US)),
        (3, 10, "estimator #2", pytest.approx(420 * US), pytest.approx(20 * US)),
        (3, 10, "running", pytest.approx(420 * US), pytest.approx(20 * US)),
        (2, 14, "pid #0", pytest.approx(50 * US), pytest.approx(10 * US)),
        (2, 14, "waiting", pytest.approx(50 * US), pytest.approx(10 * US)),
    ]
    first = _by(trace, name="estimator #0")[0]["args"]
    assert first == {
        "job": 0, "release_cycle": 100, "start_cycle": 110, "completion_cycle": 300,
        "response_us": pytest.approx(200 * US), "exec_cycles": 190, "instructions": 50, "deadline_met": True,
        "energy_pj": {"task": 1.235},
    }  # fmt: skip
    assert _by(trace, name="estimator #1 MISSED")[0]["args"]["deadline_met"] is False


def test_packets_have_a_slice_at_each_end_and_a_flow_between(trace: dict) -> None:
    noc = [(e["pid"], e["tid"], e["name"], e["ts"], e["dur"], e["args"]) for e in _by(trace, cat="noc", ph="X")]
    assert noc == [
        (1, 2, "packet to (1,0)", pytest.approx(10 * US), pytest.approx(8 * US), {"to": "1,0", "flits": 8}),
        (3, 3, "packet from (0,0)", pytest.approx(30 * US), pytest.approx(15 * US),
         {"from": "0,0", "flits": 8, "latency_cycles": 35}),
        (1, 12, "packet to (1,0)", pytest.approx(12 * US), pytest.approx(6 * US), {"to": "1,0", "flits": 6}),
        (3, 3, "packet from (0,0)", pytest.approx(50 * US), pytest.approx(20 * US),
         {"from": "0,0", "flits": 6, "latency_cycles": 58}),
        (3, 2, "packet to (0,1)", pytest.approx(14 * US), pytest.approx(4 * US), {"to": "0,1", "flits": 4}),
        (2, 3, "packet from (1,0)", pytest.approx(40 * US), pytest.approx(8 * US),
         {"from": "1,0", "flits": 4, "latency_cycles": 34}),
        (3, 2, "packet to (0,1)", pytest.approx(460 * US), pytest.approx(4 * US), {"to": "0,1", "flits": 4}),
        (3, 2, "packet to (0,1)", pytest.approx(470 * US), pytest.approx(2 * US), {"to": "0,1", "flits": 2}),
    ]  # fmt: skip
    flows = [{k: v for k, v in e.items() if k != "ts"} for e in trace["traceEvents"] if e["ph"] in "sf"]
    assert flows == [
        {"name": "packet", "cat": "noc", "ph": "s", "id": 1, "pid": 1, "tid": 2},
        {"name": "packet", "cat": "noc", "ph": "f", "id": 1, "pid": 3, "tid": 3, "bp": "e"},
        {"name": "packet", "cat": "noc", "ph": "s", "id": 2, "pid": 1, "tid": 12},
        {"name": "packet", "cat": "noc", "ph": "f", "id": 2, "pid": 3, "tid": 3, "bp": "e"},
        {"name": "packet", "cat": "noc", "ph": "s", "id": 3, "pid": 3, "tid": 2},
        {"name": "packet", "cat": "noc", "ph": "f", "id": 3, "pid": 2, "tid": 3, "bp": "e"},
    ]
    times = [e["ts"] for e in trace["traceEvents"] if e["ph"] in "sf"]
    # each point at the start of its packet's slice, exactly (DevTools binds by equal timestamps)
    assert times == [10 * US, 30 * US, 12 * US, 50 * US, 14 * US, 40 * US]
    slices = _by(trace, cat="noc", ph="X")
    assert times == [slices[k]["ts"] for k in (0, 1, 2, 3, 4, 5)]


def test_lanes_reuse_a_lane_once_it_is_free() -> None:
    lanes = chip_trace_module._lanes
    assert lanes([(0, 10), (10, 20), (5, 15), (12, 30), (20, 25)]) == [0, 0, 1, 2, 0]
    assert lanes([]) == []
    assert lanes([(0, 5), (1, 2), (2, 3), (3, 9)]) == [0, 1, 1, 1]


def test_a_trace_file_is_compact_json_and_an_interrupted_write_leaves_no_partial_file(
    trace: dict, tmp_path: Path, monkeypatch
) -> None:
    path = tmp_path / "chip-trace.json"
    write_chip_trace(trace, path)
    text = path.read_text(encoding="utf-8")
    assert text == json.dumps(trace, separators=(",", ":"))  # compact: traces get large
    assert sorted(p.name for p in tmp_path.iterdir()) == ["chip-trace.json"]

    def interrupted(src, dst):
        raise KeyboardInterrupt

    monkeypatch.setattr(output_files.os, "replace", interrupted)  # the one writer of outputs
    with pytest.raises(KeyboardInterrupt):
        write_chip_trace({"traceEvents": []}, path)
    assert json.loads(path.read_text(encoding="utf-8")) == trace  # the last whole file stays
    assert sorted(p.name for p in tmp_path.iterdir()) == ["chip-trace.json"]


def test_sleeps_past_the_chips_cycle_and_tiles_that_only_slept() -> None:
    """A tile's own cycle can run ahead of the chip's (a long quantum): a sleep still going lasts to
    the later of the two.  A tile whose recording holds only a sleep still gets its core thread.  Two
    packets reaching one tile at overlapping times take two receive lanes."""
    c = (1, 1)
    timeline = ChipTimeline(
        [A, B, c],
        IO,
        spans=[TaskSpan(A, KERNEL_TASK_ID, 0, 500), TaskSpan(B, KERNEL_TASK_ID, 0, 350)],
        sleeps=[Sleep(B, 320, None), Sleep(c, 100, None)],
        packets=[Packet(IO, B, 0, 4, 10, 40), Packet(A, B, 2, 4, 20, 30)],
        end_cycle=300,
    )
    trace = chip_trace(timeline, [], 4.0, {})
    sleeps = {e["pid"]: (e["ts"], e["dur"]) for e in _by(trace, name="sleep", ph="X")}
    pid = {xy: k + 1 for k, xy in enumerate(sorted({A, B, c, IO}))}
    assert sleeps[pid[B]] == (pytest.approx(320 * US), pytest.approx(30 * US))  # to B's own 350, not 300
    assert sleeps[pid[c]] == (pytest.approx(100 * US), pytest.approx(200 * US))  # no span: to the chip's cycle
    names = {(e["pid"], e["tid"]): e["args"]["name"] for e in _by(trace, name="thread_name")}
    assert names[(pid[c], 1)] == "core"
    receive = [(e["tid"], e["name"]) for e in _by(trace, cat="noc", ph="X") if e["pid"] == pid[B]]
    assert receive == [(3, "packet from (0,0)"), (13, "packet from (1,0)")]
    assert names[(pid[B], 13)] == "NoC receive"
