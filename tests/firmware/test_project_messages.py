"""Message formats a firmware project declares (issue 32): ``fields`` of a ``[[messages]]`` table
become a C struct of the generated ``robosoc_project.h``; a two-task project sends one with a value
of every field type from task to task on the chip, and what arrives is checked against the host's
own layout and values computed here; the host's offsets against the C compiler's (DWARF)."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from robosoc.config.chip import ChipConfig
from robosoc.config.packet_layout import FIELD_BYTES, MAX_PAYLOAD_BYTES
from robosoc.config.project import IO_PACKETS, PROJECT_FILE, ROBOSOC_PACKETS, TO_IO_PACKETS, load_project
from robosoc.host import images
from robosoc.host.packets import FORMATS
from robosoc.host.project_build import build_project
from robosoc.host.project_main import C_TYPES, header_text
from robosoc.program.dwarf import member_offset, type_size

TYPED = """\
[project]
name = "typed"
sources = ["tasks.c"]

[[tasks]]
name = "ping"
tile = [0, 1]
port = 1
on_message = "ping_on_message"

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
fields = [
    {name = "seq", type = "u32"},
    {name = "delta", type = "i32"},
    {name = "gain", type = "real"},
    {name = "half", type = "q16"},
    {name = "ratio", type = "f32"},
    {name = "rates", type = "real", count = 3},
    {name = "small", type = "u16"},
    {name = "tag", type = "u16"},
]

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
#include "real.h"
#include "robosoc_project.h"

/* ping: x -> a relay message with a value of every field type, set by name */
void ping_on_message(const os_msg_t *msg, void *arg)
{
    uint32_t x;
    struct robosoc_msg_relay m;
    (void)arg;
    memcpy(&x, msg->data, 4);
    m.seq = x;
    m.delta = -(int32_t)x;
    m.gain = real_add(real_from_int((int32_t)x), REAL_C(0.5));
    m.half = (int32_t)(x << 15);
    m.ratio = (float)x * 0.25f;
    for (int i = 0; i < 3; i++) {
        m.rates[i] = real_from_int((int32_t)x * (i + 1));
    }
    m.small = (uint16_t)(x + 1u);
    m.tag = 0xbeefu;
    os_send(ROBOSOC_MSG_RELAY_TILE, ROBOSOC_MSG_RELAY_PORT, &m, sizeof m);
}

/* pong: the relay message's bytes as they arrived, then its fields read by name as 32-bit words */
void pong_on_message(const os_msg_t *msg, void *arg)
{
    robosoc_msg_relay_t m;
    uint32_t named[10];
    uint8_t out[ROBOSOC_MSG_RELAY_BYTES + sizeof named];
    (void)arg;
    if (msg->len != ROBOSOC_MSG_RELAY_BYTES) {
        return;
    }
    memcpy(&m, msg->data, sizeof m);
    named[0] = m.seq;
    named[1] = (uint32_t)m.delta;
    named[2] = (uint32_t)real_to_fix16(m.gain);
    named[3] = (uint32_t)m.half;
    named[4] = (uint32_t)(m.ratio * 4.0f);
    named[5] = m.small;
    named[6] = m.tag;
    for (int i = 0; i < 3; i++) {
        named[7 + i] = (uint32_t)real_to_fix16(m.rates[i]);
    }
    memcpy(out, msg->data, ROBOSOC_MSG_RELAY_BYTES);
    memcpy(out + ROBOSOC_MSG_RELAY_BYTES, named, sizeof named);
    os_send(ROBOSOC_MSG_ANSWER_TILE, ROBOSOC_MSG_ANSWER_PORT, out, sizeof out);
}
"""


def _project(tmp_path: Path, text: str = TYPED):
    folder = tmp_path / "typed"
    folder.mkdir(parents=True, exist_ok=True)
    (folder / PROJECT_FILE).write_text(text)
    (folder / "tasks.c").write_text(TASKS_C)
    return load_project(folder)


def test_the_project_knows_robosocs_packets_by_the_hosts_names() -> None:
    assert tuple(fmt.name for fmt in FORMATS) == ROBOSOC_PACKETS
    assert set(IO_PACKETS) | set(TO_IO_PACKETS) <= set(ROBOSOC_PACKETS)
    assert set(C_TYPES) == set(FIELD_BYTES)
    assert MAX_PAYLOAD_BYTES == 116  # 64 flits - 2 NoC header - 4 message header = 58 flits of 2 bytes


def test_declared_fields_are_laid_out_without_padding_by_hand(tmp_path: Path) -> None:
    relay = _project(tmp_path).messages[1]
    # seq 0, delta 4, gain 8, half 12, ratio 16, rates 20..31, small 32, tag 34: 36 bytes
    assert relay.offsets == (0, 4, 8, 12, 16, 20, 32, 34) and relay.size == 36


def test_the_header_declares_each_messages_type_and_size(tmp_path: Path) -> None:
    header = header_text(_project(tmp_path))
    assert "struct robosoc_msg_relay {\n    uint32_t seq;\n    int32_t delta;\n    real_t gain;\n" in header
    assert "    int32_t half; /* Q16.16 */\n    float ratio;\n    real_t rates[3];\n    uint16_t small;\n" in header
    assert "typedef struct robosoc_msg_relay robosoc_msg_relay_t;\n#define ROBOSOC_MSG_RELAY_BYTES 36u" in header
    assert '_Static_assert(offsetof(struct robosoc_msg_relay, tag) == 34, "relay.tag offset");' in header
    assert '#include "real.h"' in header
    # the I/O tile's messages are robosoc's packets: the sensor packet in, the PWM packet out
    sensor = next(fmt for fmt in FORMATS if fmt.name == "sensor")
    request = "typedef struct robosoc_sensor_packet robosoc_msg_request_t;\n"
    request += f"#define ROBOSOC_MSG_REQUEST_BYTES {sensor.size}u"
    assert request in header
    assert "typedef struct robosoc_pwm_packet robosoc_msg_answer_t;" in header
    start = TYPED.index("fields = [")
    between = TYPED[:start] + 'packet = "estimate"\n' + TYPED[TYPED.index("]\n", start) + 2 :]
    assert "typedef struct robosoc_estimate_packet robosoc_msg_relay_t;" in header_text(_project(tmp_path, between))


def _expected(x: int, arith: str) -> tuple[tuple, tuple]:
    """The relay message's fields as the host decodes them, and pong's words, for input ``x``."""
    real = (lambda v: round(v * 65536)) if arith == "fixed" else float
    fields = (x, -x, real(x + 0.5), x << 15, x * 0.25, tuple(real(x * k) for k in (1, 2, 3)), x + 1, 0xBEEF)
    words = (x, -x & 0xFFFFFFFF, (2 * x + 1) << 15, x << 15, x, x + 1, 0xBEEF, x << 16, (2 * x) << 16, (3 * x) << 16)
    return fields, words


@pytest.mark.parametrize(("arith", "multiplier"), [("fixed", True), ("float", False)])
def test_a_declared_struct_travels_from_task_to_task(tmp_path: Path, arith: str, multiplier: bool) -> None:
    from robosoc.chip.mpsoc import MPSoC
    from robosoc.program.elf import load_elf

    project = _project(tmp_path)
    relay = project.messages[1]
    elf = build_project(project, arith=arith, multiplier=multiplier)  # the header's static asserts hold
    # the C compiler's layout (DWARF) is the host's
    assert type_size(elf, "robosoc_msg_relay") == relay.size == type_size(elf, "robosoc_msg_relay_t")
    for f, offset in zip(relay.fields, relay.offsets, strict=True):
        assert member_offset(elf, "robosoc_msg_relay", f.name) == (offset, FIELD_BYTES[f.type] * f.count), f.name

    chip = MPSoC(ChipConfig(width=2, height=2, io_tile=(0, 0)))
    program = load_elf(elf, chip.regions())
    for xy in project.tiles():
        chip.load(xy, program)
    values = [0, 7, 1234]
    for k, x in enumerate(values):
        for payload in images.message_packets(struct.pack("<I", x), 1, src_tile=0, src_port=1, seq=k):
            chip.inject((0, 1), payload, 200_000 + k * 50_000)
    chip.step(200_000 + len(values) * 50_000 + 100_000)
    answers = [m.data for m in images.reassemble(chip.received()) if m.port == 3]
    assert len(answers) == len(values)
    code = {"u16": "H", "u32": "I", "i32": "i", "q16": "i", "f32": "f", "real": "i" if arith == "fixed" else "f"}
    for x, data in zip(values, answers, strict=True):
        raw, named = data[: relay.size], struct.unpack("<10I", data[relay.size :])
        decoded = []
        for f, offset in zip(relay.fields, relay.offsets, strict=True):  # the host's offsets
            items = struct.unpack_from(f"<{f.count}{code[f.type]}", raw, offset)
            decoded.append(items[0] if f.count == 1 else items)
        fields, words = _expected(x, arith)
        assert tuple(decoded) == fields
        assert named == words


def test_a_message_may_fill_one_noc_packet_and_no_more() -> None:
    from robosoc.config.project import MessageSpec
    from robosoc.config.validate import ConfigError, from_mapping

    def message(*fields: dict) -> MessageSpec:
        return from_mapping(MessageSpec, {"name": "m", "port": 2, "source": "a", "destination": "b", "fields": fields})

    assert message({"name": "v", "type": "real", "count": 29}).size == MAX_PAYLOAD_BYTES
    assert message({"name": "v", "type": "u16", "count": 58}).size == MAX_PAYLOAD_BYTES
    with pytest.raises(ConfigError, match=r"^fields: 118 bytes, more than the 116"):
        message({"name": "v", "type": "u16", "count": 58}, {"name": "w", "type": "u16"})
