"""The stub on loopback, driven packet by packet: replies, errors, fuzz, Ctrl-C, watchpoints, kill, detach.

The server runs the simulation in a thread (as ``robosoc run`` does in its main thread); the
client is raw bytes.  Whatever the client sends, the server must answer as the protocol says
(an error, the empty reply, a retransmission request) and go on; after the session the program
must have run exactly as without a debugger.
"""

from __future__ import annotations

import random
import socket
from pathlib import Path

import pytest
from typer.testing import CliRunner

from gdb_client import Background, Client, frame
from robosoc.chip.mpsoc import MPSoC
from robosoc.chip.single import SingleCoreSoC
from robosoc.cli import app
from robosoc.config.chip import ChipConfig
from robosoc.debug import ChipTarget, DebuggerKill, GdbServer, Listener, ListenError, SingleCoreTarget
from robosoc.debug.rsp import MAX_PAYLOAD, BadChecksum, Interrupt, Packet, PacketReader, escape_binary
from robosoc.debug.tdesc import target_xml
from robosoc.program.elf import load_elf

JOIN_SECONDS = 120.0  # bounded: a server that hangs fails the test instead of the suite


def single(elf: Path) -> SingleCoreSoC:
    soc = SingleCoreSoC()
    soc.load(load_elf(elf, soc.regions()))
    return soc


def serve_single(elf: Path) -> tuple[SingleCoreSoC, Client, Background]:
    soc = single(elf)
    server = GdbServer(SingleCoreTarget(soc), Listener(0))

    def run() -> object:
        with server:
            return soc.run(advance=server.advance)

    background = Background(run)
    return soc, Client(server.port), background


def serve_chip(elf: Path, xy: tuple[int, int]) -> tuple[MPSoC, Client, Background]:
    chip = MPSoC(ChipConfig())
    chip.load_all(load_elf(elf, chip.regions()))
    server = GdbServer(ChipTarget(chip, xy), Listener(0))

    def run() -> object:
        with server:
            return chip.run(advance=server.advance)

    background = Background(run)
    return chip, Client(server.port), background


def test_framing_survives_any_split_and_rejects_bad_checksums():
    wire = frame(b"m40000000,4") + b"+-\x03" + b"$g#00" + b"$abc" + frame(b"?") + b"$x#zz"
    events = []
    reader = PacketReader()
    for i in range(len(wire)):
        events += reader.feed(wire[i : i + 1])
    kinds = [type(e).__name__ for e in events]
    assert kinds == ["Packet", "Ack", "Nack", "Interrupt", "BadChecksum", "Packet", "BadChecksum"]
    assert events[0] == Packet(b"m40000000,4") and events[5] == Packet(b"?")
    assert isinstance(events[3], Interrupt) and isinstance(events[4], BadChecksum)
    assert escape_binary(b"a$#}*b") == b"a}\x04}\x03}]}\nb"


def test_malformed_unknown_and_oversized_packets_get_the_protocol_answers(one_core_elf: Path):
    soc, client, background = serve_single(one_core_elf)
    reference = single(one_core_elf).run()
    program = soc.program
    assert program is not None
    work = program.address_of("work")
    assert client.ask(b"qSupported:swbreak+;hwbreak+").startswith(b"PacketSize=4000;")
    assert client.ask(b"?") == b"T05thread:1;"
    # bad checksums: a retransmission request, no reply
    for bad in (b"$g#00", b"$g#zz", b"$?#3x"):
        client.send_raw(bad)
        assert client.read_ack() == b"-"
    # a truncated packet is dropped by the next one; noise outside packets is ignored
    client.send_raw(b"$m40000000,4" + b"noise\x00\xff!" + frame(b"?"))
    assert client.read_ack() == b"+" and client.read_packet() == b"T05thread:1;"
    client.send_raw(b"garbage between packets\x7f")
    # oversized: acknowledged, then an error
    assert client.ask(b"m" + b"0" * (MAX_PAYLOAD + 10)) == b"E02"
    # unknown packets: the empty reply
    for unknown in (b"qNoSuchQuery", b"vNoSuchPacket", b"vCont?", b"!", b"Qfoo", b"z9,0,0", b"\xff\xfe"):
        assert client.ask(unknown) == b"", unknown
    # malformed arguments: E01
    for malformed in (b"m", b"mzz,4", b"m40000000", b"m1,2,3", b"M40000000,4:zz", b"M40000000,2:00", b"p99",
                      b"p", b"P1", b"P1=zz", b"P99=00000000", b"G00", b"Z0,40000000", b"Z0,zz,4",
                      b"X40000000,4:ab", b"qRcmd,zz", b"Z2,40000000,0", b"m123456789,4", b"C", b"Tzz"):  # fmt: skip
        assert client.ask(malformed) == b"E01", malformed
    assert client.ask(b"Z0,0,4") == b"E05"  # not an instruction of the loaded code
    assert client.ask(b"m0,4") == b"E03"  # no memory there
    assert client.ask(b"Me1024000,4:00000000") == b"E04"  # device registers are not written
    # what GDB needs works, in between
    xml = target_xml().encode()
    assert client.ask(b"qXfer:features:read:target.xml:0,ffff") == b"l" + xml
    first = client.ask(b"qXfer:features:read:target.xml:0,10")
    assert first == b"m" + xml[:16]
    assert client.ask(b"qXfer:features:read:other.xml:0,10").startswith(b"E")
    assert len(client.ask(b"g")) == 33 * 8
    assert client.ask(f"m{work:x},4".encode()) == program.read(work, 4).hex().encode()
    assert client.ask(b"X40000000,0:") == b"OK"  # GDB's probe for binary writes
    assert client.ask(b"qRcmd," + b"tile".hex().encode()) == b"single core\n".hex().encode()
    assert client.ask(b"D") == b"OK"
    client.close()
    result = background.join(JOIN_SECONDS)
    assert result.counters == reference.counters and result.output == reference.output


def test_random_packets_never_stop_or_hang_the_server(one_core_elf: Path):
    _, client, background = serve_single(one_core_elf)
    reference = single(one_core_elf).run()
    rng = random.Random(13)
    heads = [b"g", b"p", b"m", b"Z0,", b"z0,", b"Z1,", b"Z2,", b"Z3,", b"Z4,", b"z2,", b"q", b"qXfer:features:read:",
             b"qRcmd,", b"H", b"T", b"?", b"qSupported:", b"qThreadExtraInfo,", b"Q", b"i", b"_", b"0"]  # fmt: skip
    alphabet = b"0123456789abcdefABCDEFxyz,:;=.-+ \x00\x7f\xff\x03$#}*"
    for n in range(400):
        args = bytes(rng.choice(alphabet) for _ in range(rng.randrange(0, 40)))
        payload = (rng.choice(heads) + args).replace(b"$", b"").replace(b"#", b"")
        reply = client.ask(payload)
        assert reply == b"" or not reply.startswith(b"E") or reply[:3] in (b"E00", b"E01", b"E02", b"E03", b"E05")
        if n == 200:
            assert client.ask(b"QStartNoAckMode") == b"OK"
            client.ack_mode = False
        if n % 50 == 0:
            client.send_raw(bytes(rng.choice(b"abcxyz019\x00\xff+") for _ in range(30)))
    assert client.ask(b"?") == b"T05thread:1;"
    assert client.ask(b"D") == b"OK"
    client.close()
    result = background.join(JOIN_SECONDS)
    assert result.counters == reference.counters and result.output == reference.output


@pytest.mark.parametrize("where", ["single", "tile"])
def test_ctrl_c_watchpoint_step_and_kill(spin_elf: Path, where: str):
    if where == "single":
        machine, client, background = serve_single(spin_elf)
        program = machine.program
    else:
        machine, client, background = serve_chip(spin_elf, (1, 1))
        program = machine.programs[machine.config.tile_index((1, 1))]
    assert program is not None
    counter = program.address_of("counter")
    client.send(b"c")
    client.send_raw(b"\x03")
    assert client.read_packet() == b"T02thread:1;"
    text = bytes.fromhex(client.ask(b"qRcmd," + b"cycles".hex().encode()).decode()).decode()
    assert "cycle" in text
    pc = int.from_bytes(bytes.fromhex(client.ask(b"p20").decode()), "little")
    assert client.ask(b"s") == b"T05thread:1;"
    assert int.from_bytes(bytes.fromhex(client.ask(b"p20").decode()), "little") != pc
    # a write watchpoint stops before the store to the counter
    assert client.ask(f"Z2,{counter:x},4".encode()) == b"OK"
    assert client.ask(b"c") == f"T05thread:1;watch:{counter:x};".encode()
    pc = int.from_bytes(bytes.fromhex(client.ask(b"p20").decode()), "little")
    word = int.from_bytes(bytes.fromhex(client.ask(f"m{pc:x},4".encode()).decode()), "little")
    assert word & 0x7F == 0x23  # a store
    assert client.ask(f"z2,{counter:x},4".encode()) == b"OK"
    # a read watchpoint: the load of the counter
    assert client.ask(f"Z3,{counter:x},4".encode()) == b"OK"
    assert client.ask(b"c") == f"T05thread:1;rwatch:{counter:x};".encode()
    assert client.ask(f"z3,{counter:x},4".encode()) == b"OK"
    client.send(b"c")
    client.send_raw(b"\x03")
    assert client.read_packet() == b"T02thread:1;"
    client.send(b"k")
    background.join(JOIN_SECONDS)
    assert isinstance(background.error, DebuggerKill)
    client.close()


def test_stop_replies_name_the_breakpoint_or_watchpoint_kind(one_core_elf: Path):
    soc, client, background = serve_single(one_core_elf)
    reference = single(one_core_elf).run()
    program = soc.program
    assert program is not None
    work, main, counter = (program.address_of(name) for name in ("work", "main", "counter"))
    assert client.ask(b"qSupported:swbreak+;hwbreak+").startswith(b"PacketSize=")
    assert client.ask(f"Z1,{main:x},4".encode()) == b"OK"
    assert client.ask(b"c") == b"T05thread:1;hwbreak:;"
    assert client.ask(f"z1,{main:x},4".encode()) == b"OK"
    assert client.ask(f"Z0,{work:x},4".encode()) == b"OK"
    assert client.ask(b"c") == b"T05thread:1;swbreak:;"
    assert client.ask(b"p20") == work.to_bytes(4, "little").hex().encode()
    assert client.ask(f"z0,{work:x},4".encode()) == b"OK"
    assert client.ask(f"Z4,{counter:x},4".encode()) == b"OK"
    assert client.ask(b"c") == f"T05thread:1;awatch:{counter:x};".encode()
    assert client.ask(f"z4,{counter:x},4".encode()) == b"OK"
    assert client.ask(b"c") == b"W07"  # the program's exit code; the stub detaches
    result = background.join(JOIN_SECONDS)
    client.close()
    assert result.counters == reference.counters and result.output == reference.output


def test_gdb_going_away_lets_the_program_finish(one_core_elf: Path):
    soc, client, background = serve_single(one_core_elf)
    reference = single(one_core_elf).run()
    program = soc.program
    assert program is not None
    assert client.ask(f"Z0,{program.address_of('work'):x},4".encode()) == b"OK"
    assert client.ask(b"c") == b"T05thread:1;"
    client.close()  # no detach: the stub takes its marks away and lets the program run
    result = background.join(JOIN_SECONDS)
    assert result.counters == reference.counters and result.output == reference.output


def test_a_port_in_use_is_a_clear_error(one_core_elf: Path):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        port = busy.getsockname()[1]
        with pytest.raises(ListenError, match="already in use"):
            Listener(port)
        result = CliRunner().invoke(app, ["run", str(one_core_elf), "--gdb", str(port)])
    assert result.exit_code == 2
    assert f"port {port} on 127.0.0.1 is already in use" in result.stderr
    assert "--gdb" in result.stderr


def test_gdb_options_that_do_not_fit_are_usage_errors(one_core_elf: Path):
    runner = CliRunner()
    result = runner.invoke(app, ["run", str(one_core_elf), "--tile", "1,0"])
    assert result.exit_code == 2 and "goes with --gdb" in result.stderr
    result = runner.invoke(app, ["run", str(one_core_elf), "--gdb", "0", "--tile", "1,0"])
    assert result.exit_code == 2 and "needs the MPSoC" in result.stderr
    result = runner.invoke(app, ["run", str(one_core_elf), "--gdb", "0", "--trace", "5"])
    assert result.exit_code == 2 and "--trace" in result.stderr
    result = runner.invoke(app, ["run", str(one_core_elf), "--mesh", "2x2", "--gdb", "0", "--tile", "0,0"])
    assert result.exit_code == 2 and "has no core to debug" in result.stderr
    result = runner.invoke(app, ["run", str(one_core_elf), "--gdb", "70000"])
    assert result.exit_code == 2 and "--gdb: must be between 0 and 65535, got 70000" in result.stderr
