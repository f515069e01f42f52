"""The host's reads at each period's close: a job log's new records as bytes, telemetry in one read."""

import struct

import pytest

from robosoc.config.firmware import FirmwareConfig
from robosoc.cosim.firmware_run import FirmwareRun
from robosoc.host import images
from robosoc.host.scenario_image import firmware_image
from robosoc.host.telemetry import TelemetryProbe, TelemetryReader

RECORD = struct.Struct("<BBHIIIII")  # os_job_record_t: task, flags, job, release, deadline, start, completion, exec
HEADER = struct.Struct("<IIII")  # magic, capacity, count, tick


@pytest.fixture(scope="module")
def booted() -> FirmwareRun:
    fw = FirmwareConfig()
    run = FirmwareRun(fw, firmware_image(fw))
    run.run_to(run.first_cycle)  # booted: the logs and task tables are set up
    return run


def _write_log(run: FirmwareRun, xy, count: int, records: dict[int, tuple]) -> tuple[images.JobLogReader, int]:
    """A log on tile ``xy`` that has logged ``count`` records, ``records[i]`` the i-th (in its ring slot)."""
    reader = images.JobLogReader(run.chip, xy)
    t = run.chip.config.tile_index(xy)
    magic, capacity, _, tick = HEADER.unpack(run.chip.cores.read(reader.address, HEADER.size, tile=t))
    run.chip.cores.write(reader.address, HEADER.pack(magic, capacity, count, tick), tile=t)
    for i, fields in records.items():
        run.chip.cores.write(reader.address + HEADER.size + (i % capacity) * RECORD.size, RECORD.pack(*fields), tile=t)
    return reader, capacity


def _fields(i: int) -> tuple:
    return (2 + i % 3, 1 | (i & 2), i & 0xFFFF, 1000 * i, 1000 * i + 900, 1000 * i + 5, 1000 * i + 400, 300 + i)


@pytest.mark.parametrize("seen_back, count_past", [(3, 0), (1, 7), (0, 0)])
def test_new_records_are_those_after_seen_in_order_across_the_rings_end(booted, seen_back, count_past) -> None:
    xy = booted.tiles[0]
    capacity = _write_log(booted, xy, 0, {})[1]
    count = capacity + count_past  # the ring has wrapped when count_past > 0
    seen = count - capacity + seen_back if count_past else count - seen_back
    reader, _ = _write_log(booted, xy, count, {i: _fields(i) for i in range(max(0, count - capacity), count)})
    raw, total = reader.new_records(seen)
    assert total == count
    records = images.job_record_columns(raw)
    columns = ("task", "flags", "job", "release", "deadline", "start", "completion", "exec_cycles")
    assert [tuple(int(r[c]) for c in columns) for r in records] == [_fields(i) for i in range(seen, count)]


def test_a_log_that_overwrote_unread_records_is_refused(booted) -> None:
    xy = booted.tiles[0]
    capacity = _write_log(booted, xy, 0, {})[1]
    reader, _ = _write_log(booted, xy, capacity + 5, {})
    with pytest.raises(ValueError, match="overflowed"):
        reader.new_records(4)


def test_telemetry_in_one_read_is_each_word_decoded_on_its_own(booted) -> None:
    probes = booted.image.telemetry
    assert probes
    chip = booted.chip
    t = chip.config.tile_index(probes[0].tile)
    base = probes[0].address & ~3
    # a word of every type, one of them at an odd place (read word by word then)
    words = struct.pack("<fiI", -1.25, -123456, 0xFEDCBA98)
    chip.cores.write(base, words, tile=t)
    mine = [
        TelemetryProbe(f"v{i}", probes[0].tile, base + 4 * i, code, scale, probes[0].task_id, probes[0].table)
        for i, (code, scale) in enumerate((("<f", 1.0), ("<i", 1 / 65536), ("<I", 1.0)))
    ]
    expected = {"v0": -1.25, "v1": -123456 / 65536, "v2": float(0xFEDCBA98)}
    assert not probes[0].table.job_active(chip, probes[0].tile, probes[0].task_id)  # booted, no job yet
    assert TelemetryReader(chip, mine).read() == expected
    odd = TelemetryProbe("odd", probes[0].tile, base + 2, "<I", 1.0, probes[0].task_id, probes[0].table)
    odd_value = float(struct.unpack_from("<I", words, 2)[0])
    assert TelemetryReader(chip, [*mine, odd]).read() == {**expected, "odd": odd_value}
    # the task's job becomes active (its entry's job_active byte, found by its id): nothing is read
    table = probes[0].table
    memory = chip.cores.read(table.address, table.entries * table.entry_bytes, tile=t)
    entry = next(
        i for i in range(1, table.entries) if memory[i * table.entry_bytes + table.id_offset] == probes[0].task_id
    )
    chip.cores.write(table.address + entry * table.entry_bytes + table.active_offset, b"\x01", tile=t)
    try:
        assert TelemetryReader(chip, mine).read() == {}
        assert TelemetryReader(chip, [*mine, odd]).read() == {}
    finally:
        chip.cores.write(table.address + entry * table.entry_bytes + table.active_offset, b"\x00", tile=t)


def test_the_live_view_of_jobs_is_the_results_jobs_from_any_point() -> None:
    from robosoc.cosim.replay import built_in_rows, samples_from_rows

    fw = FirmwareConfig()
    run = FirmwareRun(fw, firmware_image(fw))
    samples = samples_from_rows(built_in_rows(0.3), run.clock_ns)
    period = samples[1].cycle - samples[0].cycle
    live = []
    for k, sample in enumerate(samples):
        run.inject(sample)
        run.run_to(samples[k + 1].cycle if k + 1 < len(samples) else sample.cycle + period)
        run.close_period()
        live += run.jobs_logged(len(live))  # as the ROS chip node asks: the jobs since it last looked
    jobs = run.result().jobs
    assert len(jobs) >= 2 * (len(samples) - 2)  # both tasks ran (nearly) every sample
    assert live == [(j.task, j.release_cycle, j.completion_cycle) for j in jobs]
    assert run.jobs_logged(len(live) - 3) == live[-3:]
    # the 32-bit stamps placed on the chip's timeline: after the first sample, in their order
    cycles = [s.cycle for s in samples]
    for j in jobs:
        assert j.start_cycle >= j.release_cycle >= cycles[0] and j.completion_cycle > j.start_cycle
