"""auto's whole-code translation (robosoc.chip.whole_code): a second process translates a program's
whole code into the object cache and its manifest; auto then gives the program's tiles every
region at once, and the chip's state stays the interpreter's.  The second process never outlives
the process that started it, keeps what it translated when stopped, and is started once per
program across processes (a lock holding its pid)."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import robosoc.jit.tables as jit_tables
from robosoc.chip import whole_code
from robosoc.chip.mpsoc import MPSoC
from robosoc.chip.whole_code import WholeCodeTranslations, whole_code_translations
from robosoc.config.chip import ChipConfig
from robosoc.jit.engine import TranslatingCore, code_manifest_key
from robosoc.jit.manifest import read_manifest, whole_code_path, whole_code_translated
from robosoc.jit.regions import decode, translatable

pytestmark = [
    pytest.mark.usefixtures("no_records"),  # manifests, marks and locks in an empty folder
    pytest.mark.filterwarnings("ignore::robosoc.chip.single.IrqDuringMulErratum"),
]
WAIT = 600  # seconds a second process may take on a loaded host


@pytest.fixture(autouse=True)
def fresh_process_lists(monkeypatch: pytest.MonkeyPatch) -> None:
    """Nothing an earlier test translated in this process (its regions would be entered anyway)."""
    monkeypatch.setattr(jit_tables, "_TRANSLATED", {})
    monkeypatch.setattr(jit_tables, "_FRESH_TABLES", {})


def busy_program():  # type: ignore[no-untyped-def]
    from robosoc.benchmarks.chip import _build

    return _build("matrix_bench.c", True, {"BENCH_ITERATIONS": 100000, "BENCH_QUIET": None})


def loaded_chip(engine: str, tiles=((1, 0), (0, 1))) -> MPSoC:  # type: ignore[no-untyped-def]
    chip = MPSoC(ChipConfig(), engine=engine)
    program = busy_program()
    for xy in tiles:
        chip.load(xy, program)
    return chip


def state_of(chip: MPSoC) -> tuple:
    return (
        chip.cycle,
        {xy: chip.counters(xy) for xy in chip.core_tiles()},
        {xy: chip.task_counters(xy) for xy in chip.core_tiles()},
        {xy: chip.pc(xy) for xy in chip.core_tiles()},
        chip.cores.regs.copy().tolist(),
    )


def manifests() -> Path:
    return whole_code_path("x").parent


def test_translating_the_whole_code_holds_every_word_the_translator_takes() -> None:
    chip = loaded_chip("interp", tiles=((1, 0),))
    t = chip.config.tile_index((1, 0))
    core = TranslatingCore(chip.cores, t, "auto")
    made, instructions = core.translate_code()
    jt = core.tables()
    view = core._view()
    base = view.base
    takes = [w for w in range(view.code_size // 4) if translatable(decode(view.word(base + 4 * w), base + 4 * w), view)]
    assert len(takes) > 200  # the benchmark and its library
    assert all(jt.tmap[w] != 0 for w in takes)
    assert instructions >= len(takes)  # (a region may translate words an earlier one holds too)
    assert core.stats.regions == made == len(read_manifest(code_manifest_key(chip.cores, t, "auto")))
    # translated again: every region comes from the records, none is made
    again = TranslatingCore(chip.cores, t, "auto")
    jit_tables._TRANSLATED.clear()
    jit_tables._FRESH_TABLES.clear()
    assert again.translate_code() == (0, 0)
    assert again.stats.recorded == made


def test_a_second_process_translates_the_whole_code_and_auto_enters_it_at_once(monkeypatch) -> None:
    chip = loaded_chip("auto")
    t = chip.config.tile_index((1, 0))
    key = code_manifest_key(chip.cores, t, "auto")
    translations = WholeCodeTranslations()
    assert translations.start(chip.cores, t, key)
    assert translations.running() == key
    assert not translations.start(chip.cores, t, key)  # one at a time
    translations.wait(WAIT)
    assert translations.running() is None and key in translations.done
    assert whole_code_translated(key)
    records = read_manifest(key)
    assert records and int(whole_code_path(key).read_text()) == len(records)
    assert not list(manifests().glob("*.lock")) and not list(manifests().glob("*.npz"))  # nothing left behind

    # auto on a chip holding that code: both tiles get their translators at the first look, with
    # every region from the records, and translate nothing themselves
    monkeypatch.setattr(whole_code, "WHOLE_CODE_MIN_INSTRUCTIONS", 0)
    monkeypatch.setattr(whole_code, "WHOLE_CODE_MIN_SECONDS", 0.0)
    monkeypatch.setattr("robosoc.jit.policy.AUTO_WARMUP_SECONDS", 1e9)  # auto's own regions: never
    states = {}
    for engine in ("interp", "auto"):
        chip = loaded_chip(engine)
        for k in range(1, 4):
            chip.step(k * 400_000)
        states[engine] = state_of(chip)
    stats = chip._jit.stats
    assert stats is not None and stats.recorded == len(records) and stats.regions == 0
    assert all(chip._jit.translators[chip.config.tile_index(xy)] is not None for xy in ((1, 0), (0, 1)))
    assert states["auto"] == states["interp"]


def test_auto_starts_the_second_process_itself_and_takes_its_regions_mid_run(monkeypatch) -> None:
    """A tile that ran enough starts its code's translation, from the code's second chip on (the
    first only notes it: a version of a firmware flown once is not worth it); when it is done the
    tile enters the regions between two steps (its translator made meanwhile keeps its own); the
    state is the interpreter's throughout."""
    monkeypatch.setattr(whole_code, "WHOLE_CODE_MIN_INSTRUCTIONS", 1000)
    monkeypatch.setattr(whole_code, "WHOLE_CODE_MIN_SECONDS", 0.0)
    monkeypatch.setattr("robosoc.jit.policy.AUTO_WARMUP_SECONDS", 0.0)
    monkeypatch.setattr("robosoc.chip.translation.WHOLE_CODE_LOOK_SECONDS", 0.0)
    translations = whole_code_translations()
    translations.stop()  # one an earlier test's chip started (one runs at a time)
    first = loaded_chip("auto")
    first.step(300_000)
    first.step(600_000)
    assert translations.running() is None  # the code's first run: noted only
    states = {}
    for engine in ("interp", "auto"):
        chip = loaded_chip(engine)
        key = code_manifest_key(chip.cores, chip.config.tile_index((1, 0)), "auto")
        chip.step(300_000)
        chip.step(600_000)  # its look: the tiles ran enough
        ran = chip.cores.op_rows(chip.config.tile_index((1, 0))) != 0  # (what the interpreter ran by then)
        if engine == "auto":
            assert translations.running() == key
            translations.wait(WAIT)
            assert key in translations.done
        for k in range(3, 6):
            chip.step(k * 300_000)
        states[engine] = state_of(chip)
    stats = chip._jit.stats
    assert stats is not None and stats.recorded > 0
    for xy in ((1, 0), (0, 1)):
        translator = chip._jit.translators[chip.config.tile_index(xy)]
        assert translator is not None
        view, jt = translator._view(), translator.tables()
        words = np.flatnonzero(ran).tolist()  # the second process translated what the tiles had run
        assert len(words) > 50
        assert all(jt.tmap[w] != 0 for w in words if translatable(decode(view.word(view.base + 4 * w), 0), view))
    assert states["auto"] == states["interp"]


def test_a_stopped_translation_keeps_its_regions_and_the_next_goes_on_from_there() -> None:
    chip = loaded_chip("interp", tiles=((1, 0),))
    t = chip.config.tile_index((1, 0))
    key = code_manifest_key(chip.cores, t, "auto")
    translations = WholeCodeTranslations()
    assert translations.start(chip.cores, t, key)
    deadline = time.monotonic() + WAIT
    while not read_manifest(key) and time.monotonic() < deadline:
        time.sleep(0.05)
    translations.stop()  # the process is gone, its lock with it
    assert translations.running() is None
    kept = len(read_manifest(key))
    assert kept > 0 and not whole_code_translated(key) and key not in translations.failed
    assert not list(manifests().glob("*.lock"))
    assert translations.start(chip.cores, t, key)
    translations.wait(WAIT)
    assert whole_code_translated(key) and len(read_manifest(key)) >= kept


def test_a_lock_held_by_a_live_process_is_respected_and_a_dead_ones_taken_over() -> None:
    chip = loaded_chip("interp", tiles=((1, 0),))
    t = chip.config.tile_index((1, 0))
    key = code_manifest_key(chip.cores, t, "auto")
    lock = whole_code_path(key).with_suffix(".lock")
    lock.parent.mkdir(parents=True, exist_ok=True)
    lock.write_text(f"{os.getpid()}\n")  # another process translating it (alive: this one)
    translations = WholeCodeTranslations()
    assert not translations.start(chip.cores, t, key)
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    lock.write_text(f"{gone.pid}\n")  # one that died holding it
    assert translations.start(chip.cores, t, key)
    translations.wait(WAIT)
    assert whole_code_translated(key) and not lock.exists()


def starting_script(end: str) -> str:
    """A process that starts a translation of the matrix benchmark's code, prints the second
    process's pid and ends with ``end``."""
    return (
        "import os, sys\n"
        "from robosoc.chip.mpsoc import MPSoC\n"
        "from robosoc.chip.whole_code import whole_code_translations\n"
        "from robosoc.config.chip import ChipConfig\n"
        "from robosoc.jit.engine import code_manifest_key\n"
        "from robosoc.benchmarks.chip import _build\n"
        "chip = MPSoC(ChipConfig(), engine='interp')\n"
        "chip.load((1, 0), _build('matrix_bench.c', True, {'BENCH_ITERATIONS': 100000, 'BENCH_QUIET': None}))\n"
        "key = code_manifest_key(chip.cores, 1, 'auto')\n"
        "assert whole_code_translations().start(chip.cores, 1, key)\n"
        "print(whole_code_translations()._child.process.pid, key, flush=True)\n"
        f"{end}\n"
    )


def gone_within(pid: int, seconds: float) -> bool:
    deadline = time.monotonic() + seconds
    while whole_code._alive(pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    return not whole_code._alive(pid)


def test_the_second_process_stops_when_the_process_that_started_it_dies() -> None:
    """A crash (no exit handlers) leaves no process behind: the second process sees it has lost its
    parent between two regions without a release and stops, keeping what it did."""
    done = subprocess.run(
        [sys.executable, "-c", starting_script("os._exit(0)")], capture_output=True, text=True, timeout=WAIT, check=True
    )
    pid, key = done.stdout.split()
    assert gone_within(int(pid), WAIT)
    assert not whole_code_translated(key)  # (the benchmark's code takes a few seconds)
    assert "without releasing it" in whole_code_path(key).with_suffix(".log").read_text()


def test_a_process_that_ends_normally_lets_the_second_process_finish() -> None:
    done = subprocess.run(
        [sys.executable, "-c", starting_script("sys.exit(0)")], capture_output=True, text=True, timeout=WAIT, check=True
    )
    pid, key = done.stdout.split()
    assert gone_within(int(pid), WAIT)
    assert whole_code_translated(key)
    assert not list(manifests().glob("*.lock")) and not list(manifests().glob("*.release"))


def test_the_second_process_refuses_a_payload_that_is_not_the_keys_code(tmp_path: Path) -> None:
    chip = loaded_chip("interp", tiles=((1, 0),))
    t = chip.config.tile_index((1, 0))
    payload = WholeCodeTranslations._payload(chip.cores, t, "0" * 64, tmp_path)
    assert whole_code.main([str(payload), "0" * 64]) == 1
    assert not whole_code_translated("0" * 64)
    assert whole_code.main(["only-one-argument"]) == 2
    assert whole_code.main([str(payload), "../../elsewhere"]) == 2  # not a manifest key: no path built from it
    for bad in (tmp_path / "missing.npz", tmp_path / "garbage.npz", tmp_path, Path("/dev/null")):
        if bad.name == "garbage.npz":
            bad.write_text("not a payload\n")
        assert whole_code.main([str(bad), "0" * 64]) == 1  # a message, not a traceback


def test_a_lock_being_written_is_respected_and_a_cache_it_cannot_write_starts_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    chip = loaded_chip("interp", tiles=((1, 0),))
    t = chip.config.tile_index((1, 0))
    key = code_manifest_key(chip.cores, t, "auto")
    lock = whole_code_path(key).with_suffix(".lock")
    lock.parent.mkdir(parents=True, exist_ok=True)
    lock.write_text("")  # just taken: its pid comes next
    assert not WholeCodeTranslations().start(chip.cores, t, key)
    assert lock.exists()

    blocked = tmp_path / "blocked"
    blocked.mkdir()
    (blocked / "jit").write_text("a file where the translator's folder would be\n")
    monkeypatch.setenv("ROBOSOC_CACHE", str(blocked))
    translations = WholeCodeTranslations()
    assert not translations.start(chip.cores, t, key)  # no exception: the run goes on interpreting
    assert key in translations.failed and translations.running() is None
