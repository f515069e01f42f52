"""Scripted sessions of Debian's gdb-multiarch against ``robosoc run --gdb``, on one core and on a 2x2 mesh.

Each session breaks in a function, reads registers, a global and memory, steps ten instructions,
watches a variable and continues to the exit; the program's output and every counter and cycle
of the run (the ``--stats`` file: all tiles and the network on the MPSoC) must equal a run
without GDB.  Skipped without gdb-multiarch, except on CI (CI=true), where .ci/run installs it.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import time
from pathlib import Path

from gdb_client import gdb_multiarch
from robosoc.chip.single import SingleCoreSoC
from robosoc.kernels.core_layout import RUN_BREAK
from robosoc.program.elf import load_elf

SECONDS = 300  # generous bounds that only keep a broken server from hanging the suite
STEPS = 10


def robosoc_run(*args: str) -> list[str]:
    return [sys.executable, "-m", "robosoc", "run", *args]


def plain_run(tmp_path: Path, args: list[str]) -> tuple[subprocess.CompletedProcess[str], dict]:
    stats = tmp_path / "plain.json"
    proc = subprocess.run(robosoc_run(*args, "--stats", str(stats)), capture_output=True, text=True, timeout=SECONDS)
    return proc, json.loads(stats.read_text())


def gdb_session(tmp_path: Path, elf: Path, args: list[str], commands: list[str]) -> tuple[int, str, str, dict, str]:
    """Run ``robosoc run ARGS --gdb 0`` and a batch gdb-multiarch on it: (exit, stdout, stderr, stats, gdb output)."""
    gdb = gdb_multiarch()
    stats = tmp_path / "gdb.json"
    out, err = tmp_path / "out.txt", tmp_path / "err.txt"
    with out.open("w") as stdout, err.open("w") as stderr:
        proc = subprocess.Popen(robosoc_run(*args, "--gdb", "0", "--stats", str(stats)), stdout=stdout, stderr=stderr)
    try:
        deadline = time.monotonic() + SECONDS
        while not (found := re.search(r"waiting for GDB on 127\.0\.0\.1:(\d+)", err.read_text())):
            assert proc.poll() is None, f"robosoc ended before listening:\n{err.read_text()}"
            assert time.monotonic() < deadline, "robosoc did not start listening"
            time.sleep(0.1)
        port = found.group(1)
        script = ["set pagination off", "set confirm off", f"target remote 127.0.0.1:{port}", *commands]
        argv = [gdb, "-nx", "-batch", str(elf)] + [a for c in script for a in ("-ex", c)]
        session = subprocess.run(argv, capture_output=True, text=True, timeout=SECONDS)
        code = proc.wait(timeout=SECONDS)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    return code, out.read_text(), err.read_text(), json.loads(stats.read_text()), session.stdout + session.stderr


def session_commands(function: str) -> list[str]:
    return [
        f"break {function}",
        "continue",
        "info registers",
        "print total",
        "x/4wx &counter",
        *["stepi"] * STEPS,
        "info registers pc",
        "monitor cycles",
        "monitor task",
        "monitor tile",
        "delete",
        "watch counter",
        "continue",
        "delete",
        "continue",
    ]


def test_a_gdb_session_on_one_core(tmp_path: Path, one_core_elf: Path):
    args = [str(one_core_elf), "--exit-code", "program"]  # the program's own code, as with GDB
    plain, plain_stats = plain_run(tmp_path, args)
    code, stdout, stderr, stats, gdb = gdb_session(tmp_path, one_core_elf, args, session_commands("work"))
    assert "Breakpoint 1, work (n=" in gdb, gdb
    assert re.search(r"^ra +0x4", gdb, re.M) and re.search(r"^sp +0x40", gdb, re.M) and re.search(r"^t6 ", gdb, re.M)
    assert "$1 = 5" in gdb
    assert re.search(r"<counter>:\s+0x00000000\s+0x[0-9a-f]{8}\s+0x[0-9a-f]{8}\s+0x[0-9a-f]{8}", gdb)
    assert "Hardware watchpoint 2: counter" in gdb and "Old value = 0" in gdb and "New value = 135" in gdb, gdb
    assert "[Inferior 1 (Remote target) exited with code 07]" in gdb
    assert "single core" in gdb and "no task ids" in gdb
    # ten stepi from the breakpoint end where ten instructions of the core end, in the same cycle
    where = int(re.findall(r"Breakpoint 1 at (0x[0-9a-f]+)", gdb)[0], 16)
    pc, cycle = replay_steps(one_core_elf, where, STEPS)
    assert re.search(rf"^pc +0x{pc:x}\b", gdb, re.M), gdb
    assert f"cycle {cycle} (the next instruction executes in it)" in gdb
    # the run itself: as without GDB
    assert code == plain.returncode == 7
    assert stdout == plain.stdout == "start\ntotal 498\n"
    assert stats == plain_stats
    summary = r"robosoc: (\d+) cycles, (\d+) instructions"
    assert re.findall(summary, stderr) == re.findall(summary, plain.stderr) != []


def replay_steps(elf: Path, breakpoint: int, steps: int) -> tuple[int, int]:
    """pc and cycle after ``steps`` instructions from the first arrival at ``breakpoint`` (no debugger)."""
    soc = SingleCoreSoC()
    soc.load(load_elf(elf, soc.regions()))
    soc.set_breakpoint(breakpoint)
    assert soc.step_until(10**9) == RUN_BREAK
    soc.set_breakpoint(breakpoint, on=False)
    for _ in range(steps):
        soc.step_until(soc.cycle + 1)
    return soc.state.pc, soc.cycle


def test_a_gdb_session_on_a_tile_of_a_2x2_mesh(tmp_path: Path, mesh_elf: Path):
    args = [str(mesh_elf), "--mesh", "2x2"]
    plain, plain_stats = plain_run(tmp_path, args)
    commands = session_commands("next_value")
    code, stdout, stderr, stats, gdb = gdb_session(tmp_path, mesh_elf, [*args, "--tile", "1,0"], commands)
    assert "Breakpoint 1, next_value (v=" in gdb, gdb
    assert re.search(r"^pc +0x4", gdb, re.M) and re.search(r"^ra +0x4", gdb, re.M)
    assert "$1 = 5" in gdb
    assert re.search(r"<counter>:\s+0x[0-9a-f]{8}", gdb)
    assert re.search(r"tile \(1,0\) running at cycle \d+; chip time \d+", gdb)
    assert "task 0" in gdb and "tile (1,0) of the 2x2 mesh" in gdb
    watch = re.search(r"Hardware watchpoint 2: counter\s+Old value = (\d+)\s+New value = (\d+)", gdb)
    assert watch and watch.group(1) != watch.group(2), gdb
    assert "[Inferior 1 (Remote target) exited normally]" in gdb
    # tile (1,0) was stopped, stepped and watched; the other tiles and the network never noticed
    assert code == plain.returncode == 0
    assert stdout == plain.stdout and "[0,1] tile 1 value" in stdout and "[1,1] alone" in stdout
    assert stats == plain_stats
    assert stats["tiles"]["1,1"]["counters"]["cycles"] == plain_stats["tiles"]["1,1"]["counters"]["cycles"]
    assert re.findall(r"chip (\d+) cycles", stderr) == re.findall(r"chip (\d+) cycles", plain.stderr) != []


def test_a_gdb_session_through_interrupts_and_sleep(tmp_path: Path, traffic_elf: Path):
    # the traffic program receives in its interrupt handler and sleeps while it waits: stops in
    # the handler, steps and a watchpoint on a variable the handler writes
    args = [str(traffic_elf), "--mesh", "2x2"]
    plain, plain_stats = plain_run(tmp_path, args)
    commands = ["break irq_handler", "continue", "continue", *["stepi"] * 5, "finish", "delete",
                "watch got", "continue", "delete", "continue"]  # fmt: skip
    code, stdout, _, stats, gdb = gdb_session(tmp_path, traffic_elf, [*args, "--tile", "1,1"], commands)
    assert gdb.count("Breakpoint 1, irq_handler (cause=2)") == 2, gdb
    assert re.search(r"Hardware watchpoint 2: got\s+Old value = (\d+)\s+New value = (\d+)", gdb), gdb
    assert "[Inferior 1 (Remote target) exited normally]" in gdb
    assert code == plain.returncode == 0
    assert stdout == plain.stdout
    assert stats == plain_stats
    assert stats["tiles"]["1,1"]["counters"]["sleep_cycle"] > 0
