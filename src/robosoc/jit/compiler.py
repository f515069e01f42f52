"""Compiling region IR to native code with llvmlite, and the on-disk object cache.

A light pass pipeline (SROA, instcombine, simplifycfg, dead-store elimination) and O2 code
generation: the trade-off between compile time and speed the issue's prototype found best.  The
compiled object of a module is cached under ``$ROBOSOC_CACHE/jit/`` keyed by the IR text (which
holds the code words, the multiplier, the memory and code size and the errata mode it was written
for), the LLVM version, the host CPU and its features, and the translator's sources
(:data:`PIPELINE`); a hit skips optimisation and code generation and loads the object into the JIT.
"""

from __future__ import annotations

import hashlib
import os
import queue
import tempfile
import threading
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

import llvmlite.binding as llvm
from numba.core.compiler_lock import global_compiler_lock

from robosoc.cache import cache_root
from robosoc.kernels import kernel_digest, sources_digest

_JIT_SOURCES = sorted(Path(__file__).parent.glob("*.py"))


def pipeline_digest(sources: Iterable[Path] = _JIT_SOURCES, kernels: str | None = None) -> str:
    """Digest of what a cached object and a region record depend on besides their IR: the
    translator's ``sources`` (the IR it writes, the regions it finds, the tables and records) and
    the kernels that call the regions (``kernels``: :func:`robosoc.kernels.kernel_digest`, their
    conventions and the instruction table).  Any change there keys new objects and records.  (A
    version number bumped by hand did not: an abandoned branch had used the same number, and its
    objects, written for other conventions, crashed the chip loop of a later checkout.)"""
    return sources_digest(kernels if kernels is not None else kernel_digest(), sources)


#: The digest of this checkout's translator (:func:`pipeline_digest`), in every object's and
#: manifest's key.
PIPELINE = pipeline_digest()


@dataclass
class CompileStats:
    modules: int = 0
    cache_hits: int = 0
    reused: int = 0  # already loaded in this process
    seconds: float = 0.0  # wall time of add(): everything below plus loading into the JIT
    parse_seconds: float = 0.0
    optimise_seconds: float = 0.0
    codegen_seconds: float = 0.0
    load_seconds: float = 0.0  # into the JIT engine (linking)
    cpu_seconds: float = 0.0  # process time of add()
    compiled_seconds: float = 0.0  # wall time of the modules compiled (not from the disk cache)
    compiled_instructions: int = 0  # guest instructions in them
    background_seconds: float = 0.0  # wall time of the modules compiled in the background thread


@dataclass
class Pending:
    """A module handed to the background thread (:meth:`Compiler.compile_later`)."""

    ir_template: str
    placeholder: str
    names: list[str]
    instructions: int
    done: threading.Event = field(default_factory=threading.Event)
    addresses: list[int] = field(default_factory=list)  # of ``names``, once loaded
    hit: bool = False
    error: BaseException | None = None
    seconds: float = 0.0  # wall time in the background thread
    #: whether anybody could still use the module (None: always); a job nobody wants when the
    #: thread comes to it (its run ended, and no other core runs the code) is dropped, so that a
    #: process's later work (the next test of a suite, the processes beside it) does not share the
    #: host with a backlog nobody will run
    wanted: Callable[[], bool] | None = None
    dropped: bool = False


class _Backend:
    """What turns IR text into a native object: an LLVM context, a target machine for the host and
    the pass pipeline.  The main thread's works in the global context numba uses too (under its
    lock); the compiling thread has one of its own and needs no lock (LLVM contexts are independent
    of each other), so the main thread never waits for a module the thread is compiling."""

    def __init__(self, context: llvm.context.ContextRef | None = None) -> None:
        target = llvm.Target.from_default_triple()
        cpu, features = llvm.get_host_cpu_name(), llvm.get_host_cpu_features().flatten()
        #: what its objects depend on besides the IR (part of the cache key)
        self.host = f"llvm{llvm.llvm_version_info} {target.triple} {cpu} {features}"
        self.context = context
        self.tm = target.create_target_machine(
            cpu=cpu, features=features, opt=2, reloc="pic", codemodel="small", jit=True
        )
        self.pto = llvm.create_pipeline_tuning_options(speed_level=2)
        self.pb = llvm.create_pass_builder(self.tm, self.pto)

    def optimise(self, module: llvm.ModuleRef) -> None:
        pm = llvm.create_new_module_pass_manager()
        pm.add_always_inliner_pass()
        pm.add_sroa_pass()
        pm.add_instruction_combine_pass()
        pm.add_simplify_cfg_pass()
        pm.run(module, self.pb)

    def compile(self, ir_text: str, stats: CompileStats) -> bytes:
        """The native object of ``ir_text`` (its parse, pass and code generation times added to ``stats``)."""
        t0 = time.perf_counter()
        module = llvm.parse_assembly(ir_text, context=self.context)
        module.verify()
        t1 = time.perf_counter()
        self.optimise(module)
        t2 = time.perf_counter()
        obj = self.tm.emit_object(module)
        t3 = time.perf_counter()
        stats.parse_seconds += t1 - t0
        stats.optimise_seconds += t2 - t1
        stats.codegen_seconds += t3 - t2
        return obj


class Compiler:
    """One MCJIT engine that native regions are added to; addresses stay valid for its lifetime.

    Compiling and loading in the main thread run under numba's global compiler lock (llvmlite
    shares its global LLVM context with numba); :meth:`compile_later` compiles in a second thread,
    in an LLVM context of its own (llvmlite's calls release the GIL, so on a machine with a spare
    core the simulation goes on meanwhile).
    """

    def __init__(self, cache: bool = True) -> None:
        llvm.initialize_native_target()
        llvm.initialize_native_asmprinter()
        self.main = _Backend()
        self.engine = llvm.create_mcjit_compiler(llvm.parse_assembly(""), self.main.tm)
        self.cache_dir = cache_root() / "jit" if cache else None
        self.env = f"{self.main.host} pipeline {PIPELINE}"
        self.stats = CompileStats()
        self.loaded: dict[str, int] = {}
        self.stems: set[str] = set()  # modules loaded into the engine
        self._jobs: queue.Queue[Pending] = queue.Queue()
        self._worker: threading.Thread | None = None
        self._load_lock = threading.Lock()  # loading into the engine: one thread at a time

    def key(self, ir_text: str) -> str:
        return hashlib.sha256((self.env + "\n" + ir_text).encode()).hexdigest()

    def object_code(self, ir_text: str, backend: _Backend | None = None, key: str | None = None) -> tuple[bytes, bool]:
        """The native object of an IR module, from the cache when there: (bytes, was cached).

        Compiled by ``backend`` (the compiling thread's), else by the main thread's under numba's lock.
        ``key``: the cache key (:meth:`key` of the text, or of the template the text was made from).
        """
        path = self._path(key if key is not None else self.key(ir_text))
        if path is not None and path.is_file():
            return path.read_bytes(), True
        if backend is not None:
            obj = backend.compile(ir_text, self.stats)
        else:
            with global_compiler_lock:
                obj = self.main.compile(ir_text, self.stats)
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
            with os.fdopen(fd, "wb") as f:
                f.write(obj)
            Path(tmp).replace(path)  # readers see a whole object or none
        return obj, False

    @staticmethod
    def _stem(key: str) -> str:
        """The functions' stem in a module whose template has cache key ``key``."""
        return "r" + key[:32]

    def _path(self, key: str) -> Path | None:
        if self.cache_dir is None:
            return None
        return self.cache_dir / key[:2] / f"{key}.o"

    def add(self, ir_template: str, placeholder: str, names: list[str], instructions: int = 0) -> list[int]:
        """Compile (or load) a module and return the native address of each function in ``names``.

        Functions are named in ``ir_template`` with ``placeholder`` as the stem; the real stem is
        derived from the cache key, so a region translated again (another run, or after
        self-modifying code) reuses the code already loaded.
        """
        start, cpu = time.perf_counter(), time.process_time()
        key = self.key(ir_template)  # hashed once: the stem and the object's file both come from it
        stem = self._stem(key)
        real = [n.replace(placeholder, stem) for n in names]
        if stem not in self.stems:
            obj, hit = self.object_code(ir_template.replace(placeholder, stem), key=key)
            if not self._load(stem, real, obj, hit, time.perf_counter() - start, instructions):
                self.stats.reused += 1  # the compiling thread loaded it meanwhile
        else:
            self.stats.reused += 1
        self.stats.seconds += time.perf_counter() - start
        self.stats.cpu_seconds += time.process_time() - cpu
        return [self.loaded[n] for n in real]

    def add_cached(self, key: str, placeholder: str, names: list[str]) -> list[int] | None:
        """The native addresses of ``names`` in the module whose template has cache key ``key``
        (:meth:`key`), loaded already or loaded now from the object cache; None when its object is
        in neither (a region recorded by an earlier run is then translated afresh)."""
        start, cpu = time.perf_counter(), time.process_time()
        stem = self._stem(key)
        real = [n.replace(placeholder, stem) for n in names]
        if stem in self.stems:
            self.stats.reused += 1
        else:
            path = self._path(key)
            try:
                obj = path.read_bytes() if path is not None else None
            except OSError:
                obj = None
            if obj is None:
                return None
            if not self._load(stem, real, obj, True, time.perf_counter() - start, 0):
                self.stats.reused += 1
        self.stats.seconds += time.perf_counter() - start
        self.stats.cpu_seconds += time.process_time() - cpu
        return [self.loaded[n] for n in real]

    def _load(self, stem: str, real: list[str], obj: bytes, hit: bool, seconds: float, instructions: int) -> bool:
        """Load a module's object into the engine and count it (``seconds`` to get the object);
        whether it was loaded (False: loaded already, by the other thread)."""
        t0 = time.perf_counter()
        with self._load_lock, global_compiler_lock:
            if stem in self.stems:
                return False
            self.engine.add_object_file(llvm.ObjectFileRef.from_data(obj))
            self.engine.finalize_object()
            for n in real:
                address = self.engine.get_function_address(n)
                if not address:
                    raise RuntimeError(f"translated function {n} not found after loading its object")
                self.loaded[n] = address
            self.stems.add(stem)
        load = time.perf_counter() - t0
        self.stats.load_seconds += load
        self.stats.cache_hits += int(hit)
        if not hit:
            self.stats.compiled_seconds += seconds + load
            self.stats.compiled_instructions += instructions
        self.stats.modules += 1
        return True

    def ready(self, ir_template: str) -> bool:
        """Whether :meth:`add` would cost no compiling (loaded in this process, or in the disk cache)."""
        key = self.key(ir_template)
        if self._stem(key) in self.stems:
            return True
        path = self._path(key)
        return path is not None and path.is_file()

    def compile_later(
        self,
        ir_template: str,
        placeholder: str,
        names: list[str],
        instructions: int = 0,
        wanted: Callable[[], bool] | None = None,
    ) -> Pending:
        """Compile and load a module in the background thread; :meth:`finish` gives its functions'
        addresses once ``done`` is set.

        The thread loads the object into the engine itself: llvmlite makes every LLVM call under
        one process-wide lock, so a load in the main thread would wait for whatever module the
        thread is generating code for (7 ms a region, measured); the main thread then makes no LLVM
        call at all for a region compiled in the background.
        """
        job = Pending(ir_template, placeholder, names, instructions, wanted=wanted)
        self._jobs.put(job)
        if self._worker is None:
            self._worker = threading.Thread(target=self._work, name="robosoc-jit-compile", daemon=True)
            self._worker.start()
        return job

    def _work(self) -> None:
        backend = _Backend(llvm.create_context())
        while True:
            job = self._jobs.get()
            if job.wanted is not None and not job.wanted():
                job.dropped = True
                job.done.set()
                continue
            start = time.perf_counter()
            try:
                key = self.key(job.ir_template)
                stem = self._stem(key)
                obj, job.hit = self.object_code(job.ir_template.replace(job.placeholder, stem), backend, key)
                real = [n.replace(job.placeholder, stem) for n in job.names]
                job.seconds = time.perf_counter() - start
                if self._load(stem, real, obj, job.hit, job.seconds, job.instructions) and not job.hit:
                    self.stats.background_seconds += job.seconds
                job.addresses = [self.loaded[n] for n in real]
            except BaseException as exc:  # handed to the main thread by finish()
                job.error = exc
            job.done.set()

    def finish(self, job: Pending) -> list[int]:
        """The addresses of the functions of a module :meth:`compile_later` loaded (``job.done`` set)."""
        if job.error is not None:
            raise job.error
        return job.addresses


_SHARED: Compiler | None = None


def shared_compiler() -> Compiler:
    """The process's compiler (one JIT engine: regions compiled once are reused by every core and run)."""
    global _SHARED
    if _SHARED is None:
        _SHARED = Compiler()
    return _SHARED
