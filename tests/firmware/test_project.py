"""Firmware projects (issue 32): the project file checked as data, its generated ``main`` and header,
and a two-task project built and run on the chip: each task on its tile, messages from the I/O tile
through both tasks and back, results computed on the host independently."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from robosoc.config.chip import ChipConfig
from robosoc.config.project import PROJECT_FILE, FirmwareProject, load_project
from robosoc.config.validate import ConfigError
from robosoc.host import images
from robosoc.host.project_build import build_project
from robosoc.host.project_main import TASK_REFUSED_EXIT, header_text, main_source, task_ids

PINGPONG = """\
[project]
name = "pingpong"
sources = ["tasks.c"]
defines = ["SCALE=3"]

[[tasks]]
name = "ping"
tile = [0, 1]
port = 1
on_message = "ping_on_message"
init = "ping_init"

[[tasks]]
name = "pong"
tile = [1, 0]
port = 2
on_message = "pong_on_message"

[[messages]]
name = "request"
port = 1
source = "io"
destination = "ping"

[[messages]]
name = "relay"
port = 2
source = "ping"
destination = "pong"

[[messages]]
name = "answer"
port = 3
source = "pong"
destination = "io"
"""

TASKS_C = r"""
#include <stdint.h>
#include <string.h>
#include "os.h"
#include "robosoc_project.h"

static uint32_t ping_offset;

void ping_init(void) { ping_offset = 1000u; }

/* ping: x -> x * SCALE + 1000, on to pong */
void ping_on_message(const os_msg_t *msg, void *arg)
{
    (void)arg;
    uint32_t x;
    memcpy(&x, msg->data, 4);
    x = x * SCALE + ping_offset;
    os_send(ROBOSOC_MSG_RELAY_TILE, ROBOSOC_MSG_RELAY_PORT, &x, 4);
}

/* pong: y -> (y, y ^ 0xffff) back to the I/O tile */
void pong_on_message(const os_msg_t *msg, void *arg)
{
    (void)arg;
    uint32_t out[2];
    memcpy(&out[0], msg->data, 4);
    out[1] = out[0] ^ 0xffffu;
    os_send(ROBOSOC_MSG_ANSWER_TILE, ROBOSOC_MSG_ANSWER_PORT, out, sizeof out);
}
"""


POND = 'on_message = "pong_on_message"'
LAST = 'destination = "ping"'  # the end of the first message: a table added after it
REF = '\n\n[[reference]]\ntask = "pong"\nbuild = "fixed+mul"\nresponse_ms = 1.0\nenergy_nj = 2.0'
TEL = '\n\n[[telemetry]]\nname = "count"\ntask = "pong"\nvalue = "pongs"\ntype = "u32"'


_U32 = '{name = "a", type = "u32"}'
_FIELDS = f"fields = [{_U32}]"
_FULL = '{name = "a", type = "real", count = 29}'  # 116 bytes: a whole NoC packet's payload


def _relay(fields: str, before: str = "") -> tuple[str, str]:
    """A change declaring the relay message's (ping -> pong) ``fields``."""
    return ('destination = "pong"', f'destination = "pong"\n{before}fields = [{fields}]')


def _after_last(table: str, old: str = "", new: str = "") -> tuple[str, str]:
    """A change adding ``table`` (with ``old`` replaced by ``new`` in it) after the first message."""
    return (LAST, LAST + (table.replace(old, new) if old else table))


def write_project(folder: Path, text: str = PINGPONG, c_text: str = TASKS_C) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / PROJECT_FILE).write_text(text)
    (folder / "tasks.c").write_text(c_text)
    return folder


@pytest.fixture
def pingpong(tmp_path: Path) -> FirmwareProject:
    return load_project(write_project(tmp_path / "pingpong"))


def test_the_project_file_is_read_as_data(pingpong: FirmwareProject) -> None:
    assert pingpong.task_names == ("ping", "pong")
    assert pingpong.tiles() == [(0, 1), (1, 0)]
    assert [m.name for m in pingpong.inputs()] == ["request"] and [m.name for m in pingpong.outputs()] == ["answer"]
    assert pingpong.project.arith == ("float", "fixed") and pingpong.project.multiplier == (True, False)
    assert task_ids(pingpong, (0, 1)) == {"ping": 2} and task_ids(pingpong, (1, 0)) == {"pong": 2}
    assert task_ids(pingpong, (1, 0), {"ping": (1, 0)}) == {"ping": 2, "pong": 3}  # file order on a shared tile


def test_the_generated_main_creates_each_task_on_its_tile(pingpong: FirmwareProject) -> None:
    main = main_source(pingpong)
    assert "if (tile == ROBOSOC_TASK_PING_TILE) { /* ping */" in main
    assert (
        "        ping_init();\n        robosoc_created(os_task_event(ping_on_message, 0, 1u, 10u, 2048u), 0u);" in main
    )
    assert "robosoc_created(os_task_event(pong_on_message, 0, 2u, 10u, 2048u), 1u);" in main
    assert "void pong_init" not in main  # no init declared for a task without one
    header = header_text(pingpong, {"pong": (1, 1)})
    assert "#define ROBOSOC_TASK_PING_TILE OS_TILE(0, 1)" in header
    assert "#define ROBOSOC_TASK_PONG_TILE OS_TILE(1, 1)" in header
    assert "#define ROBOSOC_MSG_RELAY_TILE ROBOSOC_TASK_PONG_TILE" in header
    assert "#define ROBOSOC_MSG_ANSWER_TILE (os_io_tile())\n#define ROBOSOC_MSG_ANSWER_PORT 3u" in header


def _run(project: FirmwareProject, values: list[int], mapping=None, arith="fixed", multiplier=True) -> list[tuple]:
    from robosoc.chip.mpsoc import MPSoC
    from robosoc.program.elf import load_elf

    elf = build_project(project, arith=arith, multiplier=multiplier, mapping=mapping)
    chip = MPSoC(ChipConfig(width=2, height=2, io_tile=(0, 0)))
    program = load_elf(elf, chip.regions())
    tiles = sorted({tuple((mapping or {}).get(t.name, t.tile)) for t in project.tasks})
    for xy in tiles:
        chip.load(xy, program)
    ping_tile = tuple((mapping or {}).get("ping", (0, 1)))
    cycle = 200_000
    for k, x in enumerate(values):
        for payload in images.message_packets(struct.pack("<I", x), 1, src_tile=0, src_port=1, seq=k):
            chip.inject(ping_tile, payload, cycle + k * 50_000)
    chip.step(cycle + len(values) * 50_000 + 100_000)
    answers = [struct.unpack("<II", m.data) for m in images.reassemble(chip.received()) if m.port == 3]
    logs = {xy: images.read_job_log(chip, xy).records for xy in tiles}
    return answers, logs


@pytest.mark.parametrize(("arith", "multiplier"), [("fixed", True), ("float", False)])
def test_a_two_task_project_runs_on_the_chip(pingpong: FirmwareProject, arith: str, multiplier: bool) -> None:
    values = [0, 7, 123456]
    answers, logs = _run(pingpong, values, arith=arith, multiplier=multiplier)
    expected = [(x * 3 + 1000, (x * 3 + 1000) ^ 0xFFFF) for x in values]  # SCALE=3 from the project's defines
    assert answers == expected
    assert [r.task for r in logs[(0, 1)]] == [2, 2, 2] and [r.task for r in logs[(1, 0)]] == [2, 2, 2]
    assert all(r.met and r.event for rs in logs.values() for r in rs)


def test_a_mapping_moves_a_task_and_the_messages_follow(pingpong: FirmwareProject) -> None:
    answers, logs = _run(pingpong, [5], mapping={"pong": (1, 1)})
    assert answers == [(1015, 1015 ^ 0xFFFF)]
    assert [r.task for r in logs[(1, 1)]] == [2] and (1, 0) not in logs


def test_a_build_the_project_does_not_support_is_named(tmp_path: Path) -> None:
    project = load_project(
        write_project(tmp_path / "p", PINGPONG.replace('defines = ["SCALE=3"]', 'arith = ["fixed"]'))
    )
    with pytest.raises(ValueError, match=r"^arith: the project 'pingpong' supports fixed, not 'float'"):
        build_project(project, arith="float")


def test_a_refused_task_ends_the_program_with_its_index(tmp_path: Path) -> None:
    """Two tasks of 1 MiB stack each on one tile of 2 MiB SRAM: the kernel has no memory for the
    second, and ``main`` ends the program with the refused task's index."""
    big = PINGPONG.replace("on_message = ", "stack_bytes = 1048576\non_message = ")
    project = load_project(write_project(tmp_path / "p", big))
    from robosoc.chip.mpsoc import MPSoC
    from robosoc.program.elf import load_elf

    chip = MPSoC(ChipConfig(width=2, height=2, io_tile=(0, 0)))
    chip.load((0, 1), load_elf(build_project(project, mapping={"pong": (0, 1)}), chip.regions()))
    chip.step(300_000)
    assert chip.state((0, 1)) == "exited" and chip.exit_code((0, 1)) == TASK_REFUSED_EXIT + 1


@pytest.mark.parametrize(
    ("change", "key", "reason"),
    [
        (('name = "pong"', 'name = "ping"'), "tasks[1].name", "'ping' is also tasks[0]"),
        (('name = "pong"', 'name = "int"'), "tasks[1].name", "must be a C identifier"),
        (("tile = [1, 0]", "tile = [1]"), "tasks[1].tile", "expected 2 values, got 1"),
        (("tile = [1, 0]", 'tile = "1,0"'), "tasks[1].tile", "expected a list"),
        (("port = 2\n", "port = 0\n"), "tasks[1].port", "must be between 1 and 255"),
        ((POND, 'on_message = "pong on message"'), "tasks[1].on_message", "C identifier"),
        (
            ('on_message = "pong_on_message"', 'on_message = "pong_on_message"\ncolour = 1'),
            "tasks[1].colour",
            "unknown",
        ),
        (
            ('on_message = "pong_on_message"', 'on_message = "pong_on_message"\nperiod_ticks = 5'),
            "tasks[1].period_ticks",
            "only for periodic release",
        ),
        (('destination = "pong"', 'destination = "pang"'), "messages[1].destination", "no task 'pang'"),
        (('destination = "pong"', 'destination = "pong"\npacket = "gps"'), "messages[1].packet", "between tasks one"),
        (('destination = "io"', 'destination = "io"\npacket = "sensor"'), "messages[2].packet", "takes 'pwm', got"),
        (('destination = "io"', 'destination = "io"\n' + _FIELDS), "messages[2].fields", "takes 'pwm' packets only"),
        ((LAST, LAST + "\n" + _FIELDS), "messages[0].fields", "what the I/O tile sends"),
        (_relay('{name = "a", type = "u64"}'), "messages[1].fields[0].type", "'u16', 'u32', 'i32', 'q16', 'f32'"),
        (_relay('{name = "a", type = 3}'), "messages[1].fields[0].type", "expected a string"),
        (_relay('{name = "int", type = "u32"}'), "messages[1].fields[0].name", "must be a C identifier"),
        (_relay('{name = "a b", type = "u32"}'), "messages[1].fields[0].name", "must be a C identifier"),
        (_relay('{name = "a", type = "u32", count = 0}'), "messages[1].fields[0].count", "between 1 and 58, got 0"),
        (_relay('{name = "a", type = "u16", count = 59}'), "messages[1].fields[0].count", "between 1 and 58"),
        (_relay('{name = "a", type = "u32", count = 2.0}'), "messages[1].fields[0].count", "expected an integer"),
        (_relay('{name = "a", type = "u32", unit = "m"}'), "messages[1].fields[0].unit", "unknown field"),
        (_relay('{type = "u32"}'), "messages[1].fields[0].name", "missing required field"),
        (_relay('"a"'), "messages[1].fields[0]", "expected a table"),
        (('source = "ping"', 'source = "ping"\nfields = "a"'), "messages[1].fields", "expected a list"),
        (_relay(_U32 + "," + _U32), "messages[1].fields[1].name", "'a' is also fields[0]"),
        (_relay('{name = "a", type = "u16"}, {name = "b", type = "real"}'), "messages[1].fields[1]", "'b' (real)"),
        (_relay('{name = "a", type = "u32"}, {name = "b", type = "u16"}'), "messages[1].fields", "padded at its end"),
        (_relay(_FULL + ', {name = "b", type = "u32"}'), "messages[1].fields", "120 bytes, more than the 116"),
        (_relay(_U32, 'packet = "estimate"\n'), "messages[1].fields", "not both"),
        (
            ('destination = "ping"', 'destination = "ping"\npacket = "gps"'),
            "messages[0].packet",
            "'sensor', 'position'",
        ),
        (('sources = ["tasks.c"]', 'sources = ["tasks.c", "missing.c"]'), "project.sources[1]", "no such file"),
        (('sources = ["tasks.c"]', 'sources = ["tasks.h"]'), "project.sources[0]", "expected a .c, .S or .s file"),
        (('sources = ["tasks.c"]', 'sources = "tasks.c"'), "project.sources", "expected a list"),
        (('defines = ["SCALE=3"]', 'defines = ["3SCALE"]'), "project.defines[0]", "expected NAME or NAME=VALUE"),
        (('name = "pingpong"', 'name = "pingpong"\nbuilds = 4'), "project.builds", "unknown field"),
        (('[[tasks]]\nname = "pong"', '[[task]]\nname = "pong"'), "task", "unknown field"),
        ((POND, POND + '\nlabel = "' + "x" * 25 + '"'), "tasks[1].label", "at most 24"),
        (_after_last(REF, "fixed+mul", "fixed"), "reference[0].build", "one of"),
        (_after_last(REF, "1.0", "nan"), "reference[0].response_ms", "nan"),
        (_after_last(REF, "2.0", "-2.0"), "reference[0].energy_nj", "nJ"),
        (_after_last(REF, '"pong"', '"pang"'), "reference[0].task", "no task 'pang'"),
        (_after_last(REF + REF), "reference[1]", "is also reference[0]"),
        (_after_last(TEL, '"u32"', '"u64"'), "telemetry[0].type", "'u32'"),
        (_after_last(TEL, '"pongs"', '"pongs[x]"'), "telemetry[0].value", "[index]"),
        (_after_last(TEL, '"pong"', '"pang"'), "telemetry[0].task", "no task 'pang'"),
        (_after_last(TEL + TEL), "telemetry[1].name", "is also telemetry[0]"),
    ],
)
def test_a_wrong_project_file_names_the_file_and_key(
    tmp_path: Path, change: tuple[str, str], key: str, reason: str
) -> None:
    text = PINGPONG.replace(*change, 1)
    assert text != PINGPONG
    folder = write_project(tmp_path / "p", text)
    with pytest.raises(ConfigError) as caught:
        load_project(folder)
    assert caught.value.where == str(folder / PROJECT_FILE)
    assert caught.value.field == key and reason in caught.value.reason, caught.value


def test_a_message_on_another_port_of_its_task_waits_there_unless_that_port_releases_another_task(
    tmp_path: Path,
) -> None:
    """A second input of a task (the position example's fix): a message on a port of the task's tile
    that no task there is released by is kept for the task to read; on another task's port, refused."""
    mailbox = PINGPONG.replace('destination = "ping"', 'destination = "ping"\n\n[[messages]]\nname = "extra"\n'
                               'port = 5\nsource = "io"\ndestination = "pong"\npacket = "position"', 1)  # fmt: skip
    project = load_project(write_project(tmp_path / "a", mailbox))
    assert [(m.name, m.io_packet) for m in project.inputs()] == [("request", "sensor"), ("extra", "position")]
    assert "#define ROBOSOC_MSG_EXTRA_TILE ROBOSOC_TASK_PONG_TILE\n#define ROBOSOC_MSG_EXTRA_PORT 5u" in header_text(
        project
    )
    taken = mailbox.replace("port = 5\n", "port = 4\n").replace(
        "[[messages]]",
        '[[tasks]]\nname = "pang"\ntile = [1, 0]\nport = 4\non_message = "pong_on_message"\n\n[[messages]]',
        1,
    )
    with pytest.raises(ConfigError) as caught:
        load_project(write_project(tmp_path / "b", taken))
    assert caught.value.field == "messages[1].port"
    assert "port 4 of tile [1, 0] releases task 'pang', not 'pong'" in caught.value.reason


def test_two_tasks_on_one_port_of_one_tile_are_refused(tmp_path: Path) -> None:
    text = PINGPONG.replace("tile = [1, 0]\nport = 2", "tile = [0, 1]\nport = 1")
    with pytest.raises(ConfigError, match=r"tasks\[1\]\.port: port 1 of tile \[0, 1\] is taken by task 'ping'"):
        load_project(write_project(tmp_path / "p", text))


def test_a_missing_project_file_and_a_project_without_tasks(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="file not found"):
        load_project(tmp_path)
    (tmp_path / PROJECT_FILE).write_text('[project]\nname = "empty"\nsources = ["a.c"]\n')
    with pytest.raises(ConfigError, match="tasks: a project needs at least one task"):
        load_project(tmp_path)


@pytest.mark.parametrize(
    ("tile", "reason"),
    [((2, 0), "outside the 2x2 mesh"), ((0, 0), "is the I/O tile"), ((1, 1), "powered off")],
)
def test_a_task_on_a_tile_without_a_core_is_refused(pingpong: FirmwareProject, tile, reason: str) -> None:
    import dataclasses

    project = dataclasses.replace(
        pingpong, tasks=(pingpong.tasks[0], dataclasses.replace(pingpong.tasks[1], tile=tile))
    )
    with pytest.raises(ValueError, match=rf"^tasks\[1\]\.tile: \[{tile[0]}, {tile[1]}\] \(pong\) .*{reason}"):
        project.check_chip(ChipConfig(width=2, height=2, io_tile=(0, 0), powered_off=((1, 1),)))
