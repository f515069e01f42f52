"""One GDB at a time (issue 34, item 8): a second GDB connecting while one is attached is answered with
an error packet that says why and disconnected, instead of waiting in the listener's backlog forever;
the first session goes on.  And the run's summary leaves out the host MIPS figure under GDB (it said
"host nan MIPS" after a session)."""

from __future__ import annotations

import socket
from pathlib import Path

from gdb_client import Background, Client, frame
from robosoc.chip.single import SingleCoreSoC
from robosoc.cli.run import cpi_text, host_speed
from robosoc.debug import GdbServer, Listener, SingleCoreTarget
from robosoc.debug.gdb_server import SECOND_GDB_REPLY
from robosoc.program.elf import load_elf

JOIN_SECONDS = 120.0


def test_a_second_gdb_is_refused_with_a_message_and_the_first_goes_on(one_core_elf: Path) -> None:
    soc = SingleCoreSoC()
    soc.load(load_elf(one_core_elf, soc.regions()))
    logged: list[str] = []
    server = GdbServer(SingleCoreTarget(soc), Listener(0), log=logged.append)

    def run() -> object:
        with server:
            return soc.run(advance=server.advance)

    background = Background(run)
    first = Client(server.port)
    assert first.ask(b"?") == b"T05thread:1;"

    second = socket.create_connection(("127.0.0.1", server.port), timeout=30)
    second.sendall(b"+" + frame(b"qSupported:swbreak+"))
    answer = b""
    while chunk := second.recv(4096):  # the server closes the connection after its answer
        answer += chunk
    second.close()
    assert answer == b"+" + frame(SECOND_GDB_REPLY)
    assert SECOND_GDB_REPLY.startswith(b"E.") and b"one GDB at a time" in SECOND_GDB_REPLY

    assert first.ask(b"?") == b"T05thread:1;"  # the first session did not notice
    first.send(b"D")
    assert first.read_packet() == b"OK"
    result = background.join(JOIN_SECONDS)
    first.close()
    assert result.output.startswith(b"start\n")  # the program ran to its end
    assert any(line.startswith("refused a second GDB connection from 127.0.0.1:") for line in logged), logged


def test_the_summary_leaves_out_the_host_speed_when_it_says_nothing() -> None:
    assert host_speed(2_000_000, 0.5, debugged=False) == ", host 4 MIPS"
    assert host_speed(2_000_000, 0.5, debugged=True) == ""  # the session's time, halts included
    assert host_speed(2_000_000, 0.0, debugged=False) == ""  # not measured: no "nan MIPS"
    assert cpi_text(34, 21) == "CPI 1.619" and cpi_text(3, 0) == "CPI n/a"  # killed before an instruction
