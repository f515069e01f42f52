"""Debugging firmware on a simulated core with GDB (docs/debugging.md).

The layer has one file per concern: :mod:`~robosoc.debug.rsp` (packet framing),
:mod:`~robosoc.debug.transport` (the loopback socket), :mod:`~robosoc.debug.tdesc` (the RV32
target description), :mod:`~robosoc.debug.devices` (device registers read without side
effects), :mod:`~robosoc.debug.points` (breakpoints and watchpoints), :mod:`~robosoc.debug.target`
(one core of a SingleCoreSoC or a tile of an MPSoC) and :mod:`~robosoc.debug.gdb_server` (the
protocol and the session, driven by the simulation's run loop).
"""

from robosoc.debug.gdb_server import DebuggerKill, GdbServer
from robosoc.debug.target import ChipTarget, SingleCoreTarget, Target
from robosoc.debug.transport import Listener, ListenError

__all__ = ["ChipTarget", "DebuggerKill", "GdbServer", "ListenError", "Listener", "SingleCoreTarget", "Target"]
