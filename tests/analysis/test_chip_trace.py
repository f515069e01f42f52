"""The chip trace: Chrome JSON trace events that Perfetto loads, equal to what the chip did.

The recorder's task spans and sleeps are checked against the chip's own per-task accounting (an
independent path: counters snapshotted at every TASK_ID store), the trace's job slices against the
kernel's job records, and every event against the trace-event format's rules (JSON schema for the
fields of each phase, nesting of slices on a thread, flow ids paired start to end).
"""

from __future__ import annotations

import json
from collections import Counter, defaultdict
from pathlib import Path

import jsonschema
import pytest

from headless_chromium import BROWSER, devtools_flows
from robosoc.cosim.chip_timeline import timeline_of
from robosoc.host import images
from robosoc.outputs.chip_trace import run_trace, write_chip_trace
from run_folders import ChipReplay

needs_chromium = pytest.mark.skipif(BROWSER is None, reason="chromium is not installed (.ci/run installs it)")

_NUMBER = {"type": "number"}
_ID = {"type": "integer", "minimum": 0}
_BASE = {"name": {"type": "string", "minLength": 1}, "pid": _ID, "tid": _ID}
EVENT_SCHEMA = {
    "oneOf": [
        {"type": "object", "required": ["name", "ph", "pid", "tid", "args"],
         "properties": {**_BASE, "ph": {"const": "M"}, "args": {"type": "object", "minProperties": 1}}},
        {"type": "object", "required": ["name", "cat", "ph", "pid", "tid", "ts", "dur"],
         "properties": {**_BASE, "ph": {"const": "X"}, "cat": {"type": "string"}, "ts": {**_NUMBER, "minimum": 0},
                        "dur": {**_NUMBER, "minimum": 0}, "args": {"type": "object"}}},
        {"type": "object", "required": ["name", "cat", "ph", "id", "pid", "tid", "ts"],
         "properties": {**_BASE, "ph": {"const": "s"}, "cat": {"type": "string"}, "id": _ID, "ts": _NUMBER}},
        {"type": "object", "required": ["name", "cat", "ph", "id", "pid", "tid", "ts", "bp"],
         "properties": {**_BASE, "ph": {"const": "f"}, "cat": {"type": "string"}, "id": _ID, "ts": _NUMBER,
                        "bp": {"const": "e"}}},
    ]
}  # fmt: skip
TRACE_SCHEMA = {
    "type": "object",
    "required": ["traceEvents"],
    "properties": {"traceEvents": {"type": "array", "items": EVENT_SCHEMA}, "displayTimeUnit": {"enum": ["ms", "ns"]}},
}


@pytest.fixture(scope="module")
def trace(chip_flight: ChipReplay, tmp_path_factory) -> dict:
    path = tmp_path_factory.mktemp("trace") / "chip-trace.json"
    write_chip_trace(run_trace(chip_flight.run, chip_flight.result, {"scenario": "default"}), path)
    return json.loads(path.read_text())


def test_every_event_has_the_fields_of_its_phase(trace: dict) -> None:
    jsonschema.validate(trace, TRACE_SCHEMA)
    phases = Counter(e["ph"] for e in trace["traceEvents"])
    assert phases["X"] > 0 and phases["s"] == phases["f"] > 0
    assert trace["otherData"]["events_lost"] == 0


def _slices(trace: dict) -> dict[tuple[int, int], list[dict]]:
    out: dict[tuple[int, int], list[dict]] = defaultdict(list)
    for e in trace["traceEvents"]:
        if e["ph"] == "X":
            out[(e["pid"], e["tid"])].append(e)
    return out


def test_slices_nest_on_every_thread(trace: dict) -> None:
    eps = 1e-6  # us: the float rounding of cycle * clock / 1000
    for thread, slices in _slices(trace).items():
        stack: list[float] = []
        for e in sorted(slices, key=lambda e: (e["ts"], -e["dur"])):
            while stack and stack[-1] <= e["ts"] + eps:
                stack.pop()
            end = e["ts"] + e["dur"]
            assert not stack or end <= stack[-1] + eps, (thread, e)
            stack.append(end)


def _bound_by_the_format(point: dict, slices: list[dict]) -> dict | None:
    """The slice a flow point binds to by the Trace Event Format's rules (which Perfetto follows): a
    start (``s``), or an end with ``"bp": "e"``, to the innermost slice of its thread enclosing its
    timestamp; another end to the next slice of its thread starting at or after it."""
    if point["ph"] == "s" or point.get("bp") == "e":
        enclosing = [e for e in slices if e["ts"] <= point["ts"] < e["ts"] + e["dur"]]
        return max(enclosing, key=lambda e: e["ts"], default=None)
    later = [e for e in slices if e["ts"] >= point["ts"]]
    return min(later, key=lambda e: e["ts"], default=None)


def _bound_by_devtools(point: dict, slices: list[dict]) -> dict | None:
    """The slice DevTools binds it to (front_end/models/trace/handlers/FlowsHandler.ts): the first
    event of the same thread and category whose timestamp equals the point's."""
    return next((e for e in slices if e["ts"] == point["ts"] and e["cat"] == point["cat"]), None)


def _packet_slices(trace: dict) -> dict[int, tuple[dict, dict]]:
    """Per flow id, the send and receive slices of its packet (flows are numbered in the order of
    the send slices, each flow point written right after its slice)."""
    out: dict[int, tuple[dict, dict]] = {}
    events = trace["traceEvents"]
    for k, e in enumerate(events):
        if e["ph"] == "f":
            start = next(s for s in events[:k] if s["ph"] == "s" and s["id"] == e["id"])
            send = events[events.index(start) - 1]
            out[e["id"]] = (send, events[k - 1])
    return out


def test_flows_bind_to_the_slices_of_their_packet_by_the_format_and_by_devtools(trace: dict) -> None:
    starts = {e["id"]: e for e in trace["traceEvents"] if e["ph"] == "s"}
    ends = {e["id"]: e for e in trace["traceEvents"] if e["ph"] == "f"}
    assert len(starts) == sum(e["ph"] == "s" for e in trace["traceEvents"])  # ids unique
    assert set(starts) == set(ends)
    slices = _slices(trace)
    packets = _packet_slices(trace)
    assert set(packets) == set(starts)
    tiles = {  # pid → "x,y" from the process names ("tile (1,0)", "tile (0,0) I/O")
        e["pid"]: e["args"]["name"].split("(")[1].split(")")[0]
        for e in trace["traceEvents"]
        if e["name"] == "process_name"
    }
    for flow_id, (send, receive) in packets.items():
        # the slices written just before the points are one packet's: leaving the tile it came from,
        # reaching the tile it went to
        assert send["cat"] == receive["cat"] == "noc" and send["ph"] == receive["ph"] == "X"
        assert tiles[send["pid"]] == receive["args"]["from"] and tiles[receive["pid"]] == send["args"]["to"]
        assert send["args"]["flits"] == receive["args"]["flits"]
        assert send["ts"] <= receive["ts"] and send["dur"] > 0 and receive["dur"] > 0
        for point, mine in ((starts[flow_id], send), (ends[flow_id], receive)):
            assert (point["pid"], point["tid"]) == (mine["pid"], mine["tid"])
            thread = slices[(point["pid"], point["tid"])]
            assert _bound_by_the_format(point, thread) is mine, point
            assert _bound_by_devtools(point, thread) is mine, point


@needs_chromium
def test_devtools_trace_model_reports_every_flow(trace: dict, tmp_path: Path) -> None:
    """Chromium's DevTools, given the trace, reports one flow per packet joining its two slices."""
    flows = devtools_flows(trace["traceEvents"], tmp_path)
    packets = _packet_slices(trace)
    assert len(packets) > 50
    shown = sorted(tuple((e["name"], e["ts"], e["pid"], e["tid"], e["ph"]) for e in flow) for flow in flows)
    expected = sorted(tuple((e["name"], e["ts"], e["pid"], e["tid"], "X") for e in pair) for pair in packets.values())
    assert shown == expected


def test_job_slices_equal_the_job_records(trace: dict, chip_flight: ChipReplay) -> None:
    result = chip_flight.result
    us = result.clock_ns / 1000
    jobs = {(e["name"].split(" #")[0], e["args"]["job"]): e for e in trace["traceEvents"]
            if e["ph"] == "X" and e["cat"] == "job" and "args" in e}  # fmt: skip
    assert len(jobs) == len(result.jobs) > 0
    for j in result.jobs:
        e = jobs[(j.task, j.job)]
        assert e["ts"] == pytest.approx(j.release_cycle * us, abs=1e-6)
        assert e["dur"] == pytest.approx(j.response_cycles * us, abs=1e-6)
        assert e["args"]["start_cycle"] == j.start_cycle and e["args"]["exec_cycles"] == j.exec_cycles


def test_task_spans_and_sleeps_equal_the_chips_accounting(chip_flight: ChipReplay) -> None:
    run = chip_flight.run
    timeline = timeline_of(run.chip, run.tiles)
    assert timeline.lost == 0
    for xy in run.tiles:
        cycles: Counter[int] = Counter()
        for span in timeline.spans:
            if span.tile == xy:
                cycles[span.task] += span.end - span.start
        accounted = {task: c["cycles"] for task, c in run.chip.task_counters(xy).items()}
        assert dict(cycles) == accounted
        slept = sum(s.end - s.start for s in timeline.sleeps if s.tile == xy and s.end is not None)
        assert slept == run.chip.counters(xy)["sleep_cycle"] > 0
        # a sleep lies inside the idle task's span that stored to SLEEP, and ends before the next span
        idle = [s for s in timeline.spans if s.tile == xy and s.task == images.IDLE_TASK_ID]
        for sleep in (s for s in timeline.sleeps if s.tile == xy and s.end is not None):
            assert any(span.start <= sleep.start and sleep.end <= span.end for span in idle), sleep
    interrupts = sum(s.interrupt for s in timeline.spans)
    kernel_entries = sum(s.task == images.KERNEL_TASK_ID for s in timeline.spans)
    assert 0 < interrupts < kernel_entries  # kernel calls from tasks are not interrupts


def test_packets_are_the_messages_the_host_exchanged(chip_flight: ChipReplay) -> None:
    run, result = chip_flight.run, chip_flight.result
    timeline = timeline_of(run.chip, run.tiles)
    io = timeline.io_tile
    injected = sum(
        len(images.io_packets(s.payload, run.image.sensor[1], run.chip_config.io_tile, s.seq)) for s in result.samples
    )
    assert sum(p.src == io for p in timeline.packets) == injected
    assert sum(p.dest == io and p.visible is not None for p in timeline.packets) == len(result.commands)
    for p in timeline.packets:
        assert p.visible is not None and p.sent < p.first < p.visible  # every packet arrived, in order
    pwm_arrivals = sorted(p.visible - 1 for p in timeline.packets if p.dest == io)
    assert pwm_arrivals == sorted(c.cycle for c in result.commands)  # the last flit's cycle


def test_a_chip_that_does_not_record_is_refused(chip_flight: ChipReplay) -> None:
    from robosoc.chip.mpsoc import MPSoC

    with pytest.raises(ValueError, match="record_timeline"):
        timeline_of(MPSoC(chip_flight.run.chip_config))


def test_trace_file_is_written_whole(trace: dict, tmp_path: Path) -> None:
    path = tmp_path / "chip-trace.json"
    write_chip_trace(trace, path)
    assert json.loads(path.read_text()) == trace
    assert not list(tmp_path.glob("*.partial"))


def test_the_trace_shows_the_application_tiles_and_the_io_tile_only(trace: dict, chip_flight: ChipReplay) -> None:
    run = chip_flight.run
    io = run.chip.config.io_tile
    expected = {f"tile ({x},{y})" for x, y in run.tiles} | {f"tile ({io[0]},{io[1]}) I/O"}
    names = {e["args"]["name"] for e in trace["traceEvents"] if e["name"] == "process_name"}
    assert names == expected
    assert trace["otherData"]["firmware"] == chip_flight.result.firmware.label
