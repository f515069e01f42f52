"""``auto``'s second process: translating a program's whole code once, beside the run.

``auto`` interprets a tile first and translates small regions where it turns hot, paying for each
out of a share of the run (:mod:`robosoc.jit.policy`).  On the chip that does not reach ``jit``'s
speed: partial translation leaves the tile entering and leaving native code, and a tile that works
in short bursts between sleeps never looks busy enough.  So once a tile has executed
:data:`WHOLE_CODE_MIN_INSTRUCTIONS` and the chip loop has run :data:`WHOLE_CODE_MIN_SECONDS`,
on the code's second run or later (:func:`seen_before`), its program's whole code is translated
in a second process (``python -m robosoc.chip.whole_code``,
at a lower priority: on a host with a spare core the run goes on at its own speed), region by
region into the object cache and the code's manifest, then marked whole
(:func:`robosoc.jit.manifest.mark_whole_code`).  From then on, in this run and every later one,
``auto`` gives that code's tiles their translators at once and enters every region from the
records: ``jit``'s speed without ``jit``'s compile at the start.

It translates the words the run had executed first (those the interpreter decoded), then the
rest: a flight runs about half its code only after take-off, so the words executed by then are
not enough (the fixed + mul flight with only those translated flew at 0.68-0.70 s against
0.57-0.60 s with all, and 0.74-0.75 s interpreted), but the first regions made are those that
matter if it is stopped early.

At most one such process runs per simulating process, and one per program across processes
(a lock file beside the manifest, holding its pid: a sweep's workers do not translate the same
code twice).  When the process that started it ends normally it lets it finish, as ``git`` lets
its automatic garbage collection finish in the background (a few seconds; at most
:data:`RELEASED_SECONDS`): a short ``robosoc fly`` or ``robosoc bench fly`` would otherwise stop
it before it got anywhere, run after run.  After a crash (no release) it stops by itself before
its next region; Ctrl-C reaches it with its parent's process group; :meth:`WholeCodeTranslations.stop`
stops it.  Stopped, it keeps the regions done so far, and the next run goes on from there.  Its
output goes to a log beside the manifest.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import re
import subprocess
import sys
import tempfile
import time
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from robosoc.kernels.core_layout import S_CODE_SIZE, S_ERRATA, S_MEM_BASE, S_MEM_SIZE, S_MUL

if TYPE_CHECKING:
    from robosoc.chip.core_state import CoreState

#: instructions a tile executes (since its code was loaded) before its program's whole code is
#: translated: a short run (a 0.01 s flight) starts no second process
WHOLE_CODE_MIN_INSTRUCTIONS = 100_000
#: ... and the chip loop ran this many host seconds: before, no tile is looked at (a warm
#: ``robosoc fly --duration 0.01`` imports nothing of the translator and enters no region: looking
#: up and entering a program's hundred-odd regions takes about 0.1 s once per process).  Not
#: ``auto``'s warm-up of 0.2 s: the fixed + mul flight's chip loop runs about that long in all, so
#: its second process started at the flight's end and was stopped with it, flight after flight.
WHOLE_CODE_MIN_SECONDS = 0.02
#: seconds the process that was asked to stop gets before it is killed
STOP_SECONDS = 2.0
#: seconds a released second process (its parent ended normally) may go on before it stops
RELEASED_SECONDS = 120.0
#: seconds a lock without a pid yet counts as being written by the process that took it
LOCK_WRITE_SECONDS = 5.0


def _lock_path(key: str) -> Path:
    from robosoc.jit.manifest import whole_code_path

    return whole_code_path(key).with_suffix(".lock")


def _release_path(key: str) -> Path:
    """The note a process that ended normally leaves its child (its pid): finish, do not stop."""
    return _lock_path(key).with_suffix(".release")


def seen_before(key: str) -> bool:
    """Whether a chip ran the code with manifest key ``key`` before (in this process or another,
    as far as a look at its tiles); the first asking notes it.  Its whole code is translated only
    from its second run on: a firmware author flies each version of their code once or twice, and
    a translation that runs beside the only flight of a version slows it (the second host core is
    not free) for nothing."""
    path = _lock_path(key).with_suffix(".seen")
    if path.is_file():
        return True
    with contextlib.suppress(OSError):
        path.parent.mkdir(parents=True, exist_ok=True)
        path.touch()
    return False


def _alive(pid: int) -> bool:
    """Whether process ``pid`` runs (one that exited and waits to be reaped does not)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:  # a zombie (a container's first process may never reap it)
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return True
    return stat.rpartition(")")[2].split()[:1] != ["Z"]


def _take_lock(key: str) -> Path | None:
    """The lock of ``key``'s whole-code translation, taken (None: a live process holds it)."""
    path = _lock_path(key)
    path.parent.mkdir(parents=True, exist_ok=True)
    for _ in range(2):
        try:
            fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            try:
                pid = int(path.read_text().strip() or "0")
                young = time.time() - path.stat().st_mtime < LOCK_WRITE_SECONDS
            except (OSError, ValueError):
                pid, young = 0, False
            if (pid > 0 and _alive(pid)) or (pid == 0 and young):  # (0: its taker writes it now)
                return None
            with contextlib.suppress(OSError):  # a process that died holding it: taken over
                path.unlink()
            continue
        with os.fdopen(fd, "w") as f:
            f.write(f"{os.getpid()}\n")
        return path
    return None


@dataclass
class _Child:
    key: str
    process: subprocess.Popen[bytes]
    lock: Path
    payload: Path


class WholeCodeTranslations:
    """The second processes this process started (at most one at a time), and what they finished."""

    def __init__(self) -> None:
        self._child: _Child | None = None
        self.done: set[str] = set()  # keys whose whole code a child of this process translated
        self.failed: set[str] = set()  # keys whose child failed (not started again in this process)
        self._registered = False

    def running(self) -> str | None:
        """The key whose code is being translated, if a child runs (a finished one is collected)."""
        child = self._child
        if child is None:
            return None
        code = child.process.poll()
        if code is None:
            return child.key
        self._collect(child, code)
        return None

    def start(self, state: CoreState, tile: int, key: str) -> bool:
        """Start translating the code of ``state``'s tile ``tile`` (manifest key ``key``) in a second
        process; False when one runs already (this process's or another's for the same code)."""
        if self.running() is not None or key in self.failed or key in self.done:
            return False
        try:
            lock = _take_lock(key)
        except OSError:  # (a cache folder it may not write: the run goes on without)
            self.failed.add(key)
            return False
        if lock is None:
            return False
        try:
            payload = self._payload(state, tile, key, lock.parent)
            log = lock.with_suffix(".log").open("wb")
            with log:
                process = subprocess.Popen(
                    [sys.executable, "-m", "robosoc.chip.whole_code", str(payload), key, str(lock)],
                    stdin=subprocess.DEVNULL,
                    stdout=log,
                    stderr=subprocess.STDOUT,
                    close_fds=True,
                )
        except OSError:
            with contextlib.suppress(OSError):
                lock.unlink()
            self.failed.add(key)
            return False
        with contextlib.suppress(OSError):  # the child holds it from now on
            lock.write_text(f"{process.pid}\n")
        self._child = _Child(key, process, lock, payload)
        if not self._registered:
            atexit.register(self.release)
            self._registered = True
        return True

    @staticmethod
    def _payload(state: CoreState, tile: int, key: str, folder: Path) -> Path:
        st = state.st[tile]
        fields = np.array([st[S_MEM_BASE], st[S_MEM_SIZE], st[S_CODE_SIZE], st[S_ERRATA], st[S_MUL]], dtype=np.int64)
        code = state.m8[tile, : int(st[S_CODE_SIZE])].copy()
        executed = np.flatnonzero(state.op_rows(tile) != 0)  # words the interpreter decoded: it ran them
        fd, name = tempfile.mkstemp(dir=folder, prefix=key[:16], suffix=".npz")
        with os.fdopen(fd, "wb") as f:
            np.savez(f, fields=fields, code=code, executed=executed, parent=os.getpid())
        return Path(name)

    def _collect(self, child: _Child, code: int) -> None:
        self._child = None
        from robosoc.jit.manifest import whole_code_translated

        if code == 0 and whole_code_translated(child.key):
            self.done.add(child.key)
        elif code > 0:  # (< 0: stopped by a signal, ours or the user's: tried again later)
            self.failed.add(child.key)
        for path in (child.payload, child.lock):
            if path == child.lock and path.is_file() and path.read_text().strip() != str(child.process.pid):
                continue  # taken over meanwhile
            with contextlib.suppress(OSError):
                path.unlink()

    def wait(self, timeout: float | None = None) -> None:
        """Wait for the child to finish (``timeout`` seconds at most: subprocess.TimeoutExpired)."""
        child = self._child
        if child is not None:
            child.process.wait(timeout)
            self._collect(child, child.process.returncode)

    def release(self) -> None:
        """At this process's normal end: let the child finish its translation (a few seconds, at
        most :data:`RELEASED_SECONDS`) rather than stop it, as ``git`` lets its automatic garbage
        collection finish in the background (after a crash, or ``os._exit``, it finds itself
        without its parent and no release, and stops; Ctrl-C reaches it with its process group)."""
        child = self._child
        if child is None or child.process.poll() is not None:
            return
        with contextlib.suppress(OSError):
            _release_path(child.key).write_text(f"{child.process.pid}\n")
        self._child = None

    def stop(self) -> None:
        """Stop the child (what it translated so far stays recorded) and wait for it."""
        child = self._child
        if child is None:
            return
        if child.process.poll() is None:
            child.process.terminate()
            try:
                child.process.wait(STOP_SECONDS)
            except subprocess.TimeoutExpired:
                child.process.kill()
                child.process.wait()
        self._collect(child, child.process.returncode)


_TRANSLATIONS = WholeCodeTranslations()


def whole_code_translations() -> WholeCodeTranslations:
    """This process's second processes."""
    return _TRANSLATIONS


def translate_whole_code(payload: Path, key: str, lock: Path | None = None) -> int:
    """The second process: translate the code in ``payload`` (its build's state fields, code bytes
    and the words a run executed, those first) whose manifest key is ``key``; 0 when done or
    stopped (its parent gone without a release, or released too long ago), 1 when the payload does
    not give ``key``.  At the end it removes ``lock`` if it still holds this process's pid, and the
    release note."""
    try:
        return _translate(payload, key)
    finally:
        mine = str(os.getpid())
        for path in (lock, _release_path(key)):
            with contextlib.suppress(OSError):
                if path is not None and path.read_text().strip() == mine:
                    path.unlink()


def _translate(payload: Path, key: str) -> int:
    from robosoc.chip.core_state import CoreState
    from robosoc.jit.engine import TranslatingCore, code_manifest_key
    from robosoc.jit.manifest import mark_whole_code, read_manifest

    try:
        with np.load(payload) as data:
            base, mem_size, code_size, errata, mul = (int(v) for v in data["fields"])
            code = data["code"]
            executed = data["executed"].astype(np.int64)
            parent = int(data["parent"])
        state = CoreState.new(mul=bool(mul), sram_size=mem_size, base=base, errata=errata, code_size=code_size)
        state.m8[0, :code_size] = code
    except (OSError, EOFError, ValueError, KeyError, TypeError, IndexError, zipfile.BadZipFile) as exc:
        print(f"whole_code: cannot read the payload {payload}: {exc}", file=sys.stderr)
        return 1
    with contextlib.suppress(OSError):  # read: not left behind if this process is stopped
        payload.unlink()
    if code_manifest_key(state, 0, "auto") != key:
        print(f"whole_code: {payload} does not hold the code of manifest {key}", file=sys.stderr)
        return 1
    stop = _StopRule(key, parent)
    words = np.arange(code_size // 4)
    executed = executed[(executed >= 0) & (executed < len(words))]
    words = np.concatenate([executed, words])  # what the run executed first
    made, instructions = TranslatingCore(state, 0, "auto").translate_code(stop, words)
    if stop():
        print(f"whole_code: stopped after {made} regions ({stop.why})", file=sys.stderr)
        return 0
    mark_whole_code(key, len(read_manifest(key)))
    print(f"whole_code: {made} regions, {instructions} instructions translated", file=sys.stderr)
    return 0


class _StopRule:
    """Whether the second process stops before its next region: its parent is gone without
    releasing it, or released it more than :data:`RELEASED_SECONDS` ago."""

    def __init__(self, key: str, parent: int) -> None:
        self.parent = parent  # (not this process's parent when it starts: that one may have ended already)
        self.release = _release_path(key)
        self.released_at: float | None = None
        self.why = ""

    def __call__(self) -> bool:
        if os.getppid() == self.parent:
            return False
        if self.released_at is None:
            try:
                released = self.release.read_text().strip() == str(os.getpid())
            except OSError:
                released = False
            if not released:
                self.why = "its parent ended without releasing it"
                return True
            self.released_at = time.monotonic()
        if time.monotonic() - self.released_at > RELEASED_SECONDS:
            self.why = f"released more than {RELEASED_SECONDS:g} s ago"
            return True
        return False


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) not in (2, 3):
        print("usage: python -m robosoc.chip.whole_code PAYLOAD KEY [LOCK]", file=sys.stderr)
        return 2
    if re.fullmatch(r"[0-9a-f]{64}", args[1]) is None:
        print(f"whole_code: KEY must be a manifest key (64 hex digits), got {args[1]!r}", file=sys.stderr)
        return 2
    with contextlib.suppress(OSError):
        os.nice(10)  # background work: the run it serves goes first
    try:
        return translate_whole_code(Path(args[0]), args[1], Path(args[2]) if len(args) == 3 else None)
    except KeyboardInterrupt:  # Ctrl-C reaches the whole process group: the regions done stay
        return 130


if __name__ == "__main__":
    sys.exit(main())
