"""The packet formats: one source (robosoc.host.packets), the C header generated from it and
up to date, C and Python agreeing on every field, and every packet fitting a NoC packet with room
for the messaging header."""

from pathlib import Path

import pytest

from robosoc.config.packet_layout import MAX_PACKET_FLITS
from robosoc.host import packets
from robosoc.host.packets import ESTIMATE, FORMATS, POSITION, PWM, SENSOR, from_flits, to_flits
from robosoc.toolchain import build_elf, compile_native, run_native

single = pytest.importorskip("robosoc.chip.single")

PACKET_CHECK = Path(__file__).resolve().parent / "packet_check.c"


def test_header_is_generated_from_the_python_definitions() -> None:
    assert packets.HEADER_PATH.read_text() == packets.c_header()
    assert packets.main(["--check"]) == 0


def test_every_packet_fits_one_noc_packet_with_the_messaging_header() -> None:
    for fmt in FORMATS:
        assert fmt.size % 4 == 0
        assert packets.NOC_HEADER_FLITS + packets.MESSAGE_HEADER_FLITS + fmt.flits <= MAX_PACKET_FLITS
        assert [f.name for f in fmt.fields[:2]] == ["kind", "flags"]
    assert len({fmt.kind for fmt in FORMATS}) == len(FORMATS)


def test_pack_unpack_round_trip() -> None:
    values = {"flags": 1, "seq": 42, "time_us": 420000, "dt_us": 10000, "gyro": (0.5, -0.25, 1e-3)}
    data = SENSOR.pack(values)
    assert len(data) == SENSOR.size
    back = SENSOR.unpack(from_flits(to_flits(data)))
    assert back["seq"] == 42 and back["kind"] == SENSOR.kind
    assert back["gyro"] == (0.5, -0.25, round(1e-3 * 65536) / 65536)
    assert back["mag"] == (0.0, 0.0, 0.0)


def test_bad_values_and_packets_are_errors() -> None:
    with pytest.raises(ValueError, match=r"outside the Q16\.16 range"):
        SENSOR.pack({"baro_altitude": 40000.0})
    with pytest.raises(ValueError, match="unknown fields"):
        PWM.pack({"speed": 3})
    with pytest.raises(ValueError, match="expected 4"):
        PWM.pack({"pwm": (1, 2, 3)})
    with pytest.raises(ValueError, match="not a u16"):
        PWM.pack({"pwm": (1, 2, 3, 70000)})
    with pytest.raises(ValueError, match="kind"):
        PWM.unpack(ESTIMATE.pack({})[: PWM.size])
    with pytest.raises(ValueError, match="bytes, expected"):
        PWM.unpack(b"\0\0")


def _value(field: int, element: int) -> float:
    v = (field + 1) * 1.25 + element / 4
    return -v if element & 1 else v


def _expected() -> dict[str, dict[str, object]]:
    def vec(field: int, n: int) -> tuple[float, ...]:
        return tuple(_value(field, i) for i in range(n))

    return {
        "sensor": {
            "kind": SENSOR.kind,
            "flags": 1,
            "seq": 123456789,
            "time_us": 4000000000,
            "dt_us": 10000,
            "gyro": vec(0, 3),
            "accel": vec(1, 3),
            "mag": vec(2, 3),
            "baro_altitude": _value(3, 0),
            "setpoint": vec(4, 4),
            "height_feedforward": vec(5, 2),
        },
        "estimate": {
            "kind": ESTIMATE.kind,
            "flags": 1,
            "seq": 7,
            "time_us": 70000,
            "dt_us": 10000,
            "quaternion": vec(0, 4),
            "rate": vec(1, 3),
            "height": _value(2, 0),
            "vertical_velocity": _value(3, 0),
            "setpoint": vec(4, 4),
            "height_feedforward": vec(5, 2),
        },
        "pwm": {"kind": PWM.kind, "flags": 0, "seq": 65537, "pwm": (100, 150, 200, 250)},
        "position": {
            "kind": POSITION.kind,
            "flags": 1,
            "seq": 99,
            "time_us": 990000,
            "fix_time_us": 980000,
            "fix_number": 49,
            "position": vec(0, 3),
            "velocity": vec(1, 3),
            "setpoint": vec(2, 3),
            "setpoint_velocity": vec(3, 3),
            "setpoint_accel": vec(4, 3),
        },
    }


def _check_output(text: str) -> None:
    formats = {fmt.name: fmt for fmt in FORMATS}
    seen = set()
    for line in text.splitlines():
        name, *flits = line.split()
        fmt = formats[name]
        assert len(flits) == fmt.flits
        assert fmt.unpack(from_flits([int(f, 16) for f in flits])) == _expected()[name]
        seen.add(name)
    assert seen == set(formats)


@pytest.mark.parametrize("mul", [True, False], ids=["mul", "no-mul"])
def test_c_structs_decode_in_python_on_core(mul: bool) -> None:
    result = single.run_elf(build_elf([PACKET_CHECK], mul=mul), mul=mul, max_cycles=50_000_000)
    assert result.exit_code == 0
    _check_output(result.output.decode())


def test_c_structs_decode_in_python_host() -> None:
    code, out = run_native(compile_native([PACKET_CHECK]))
    assert code == 0
    _check_output(out.decode())


def test_docs_show_the_formats_as_defined() -> None:
    docs = Path(__file__).resolve().parents[2] / "docs" / "firmware-libraries.md"
    text = docs.read_text()
    start = text.index("<!-- packets:begin -->\n") + len("<!-- packets:begin -->\n")
    assert text[start : text.index("<!-- packets:end -->")] == packets.markdown_tables()
