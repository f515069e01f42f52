"""Building RISC-V ELF executables for one HF-RISCV core, with a content-keyed cache."""

import json
import os
import re
import tempfile
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path

from robosoc import output_files
from robosoc.firmware import INCLUDE_DIR, LIBC_INCLUDE_DIR, runtime_sources
from robosoc.toolchain.cache import build_key, entry_dir, file_digest, header_digests, zig_cache_dir
from robosoc.toolchain.errors import CompileError, CompilerWarning, FixedRegisterWarning, ToolchainError
from robosoc.toolchain.linker_script import (
    DEFAULT_SRAM_SIZE,
    DEFAULT_STACK_MIN,
    SRAM_BASE,
    render_linker_script,
)
from robosoc.toolchain.options import CoreBuildOptions, define_flags, normalize_opt
from robosoc.toolchain.x27_check import check_x27
from robosoc.toolchain.zig import run_zig_cc, zig_cc_command, zig_package_version

SOURCE_SUFFIXES = (".c", ".S", ".s")
ELF_NAME = "program.elf"
META_NAME = "build.json"


def resolve_sources(sources: Sequence[Path | str]) -> list[Path]:
    """Absolute source paths, checked to exist and to be C or assembly.

    Raises:
        ToolchainError: no sources, a missing file, or an unsupported suffix.
    """
    if not sources:
        raise ToolchainError("no source files given")
    resolved = []
    for src in sources:
        path = Path(src).expanduser().resolve()
        if not path.is_file():
            raise ToolchainError(f"{src}: source file not found")
        if path.suffix not in SOURCE_SUFFIXES:
            raise ToolchainError(f"{src}: unsupported source type '{path.suffix}' (expected .c, .S or .s)")
        resolved.append(path)
    return resolved


def files_named_in(message: str, sources: Sequence[Path]) -> list[Path]:
    """The sources the compiler's message mentions (all of them when it mentions none)."""
    named = [s for s in sources if re.search(re.escape(s.name) + r"[:(]", message)]
    return named or list(sources)


def build_elf(
    sources: Sequence[Path | str],
    out: Path | str | None = None,
    mul: bool = True,
    opt: str = "-O2",
    *,
    defines: Mapping[str, str | int | None] | Sequence[str] = (),
    include_dirs: Sequence[Path | str] = (),
    sram_size: int = DEFAULT_SRAM_SIZE,
    sram_base: int = SRAM_BASE,
    stack_min: int = DEFAULT_STACK_MIN,
    runtime: bool = True,
    extra_flags: Sequence[str] = (),
) -> Path:
    """Compile and link C/assembly sources into an ELF for one HF-RISCV core.

    The result is cached under the project cache (see :mod:`robosoc.toolchain.cache`), keyed on the
    contents of the sources, of the runtime and of every header in the include directories and the
    sources' folders, on the options and on the zig version: an identical second build returns the
    cached file without running the compiler.

    Args:
        sources: .c / .S / .s files of the program (``main`` included).
        out: where to copy the ELF; ``None`` returns the file inside the cache.
        mul: build for the core with the iterative multiplier (RV32I+Zmmul) or without (RV32I).
        opt: optimisation level, ``-O2`` by default (``-O0 -O1 -O2 -O3 -Os -Oz``).
        defines: preprocessor definitions, ``{"N": 3}`` or ``["N=3"]``.
        include_dirs: extra ``-I`` folders (the runtime's ``include/`` is always searched).
        sram_size / sram_base: SRAM geometry for the linker script; the stack starts at its top.
        stack_min: the link fails if code and data leave less than this for the stack.
        runtime: link the runtime (crt0, interrupt entry, print library); ``False`` for programs
            that bring their own ``_start``.
        extra_flags: further compiler flags, passed last.

    Returns:
        The ELF path (``out`` when given).

    Raises:
        CompileError: the compiler or linker failed; the message holds its diagnostics and the file.
        ToolchainError: bad options or missing sources.

    Warns:
        FixedRegisterWarning: code outside the interrupt entry writes x27 (s11).
        CompilerWarning: the compiler printed warnings.
    """
    srcs = resolve_sources(sources)
    incs = [Path(d).expanduser().resolve() for d in include_dirs]
    options = CoreBuildOptions(
        mul=mul,
        opt=normalize_opt(opt),
        defines=tuple(define_flags(defines)),
        include_dirs=tuple(str(d) for d in (*incs, INCLUDE_DIR, LIBC_INCLUDE_DIR)),
        sram_base=sram_base,
        sram_size=sram_size,
        stack_min=stack_min,
        runtime=runtime,
        extra_flags=tuple(extra_flags),
    )
    linker_script = render_linker_script(sram_base, sram_size, stack_min)
    all_sources = [*srcs, *(runtime_sources() if runtime else ())]
    key = build_key(
        {
            "kind": "core-elf",
            "zig": zig_package_version(),
            "flags": options.compiler_flags(),
            "linker_script": linker_script,
            "sources": [(str(s), file_digest(s)) for s in all_sources],
            "headers": header_digests([*incs, INCLUDE_DIR, LIBC_INCLUDE_DIR, *{s.parent for s in srcs}]),
        }
    )
    entry = entry_dir("elf", key)
    cached = entry / ELF_NAME
    if not cached.is_file():
        _compile_into(entry, all_sources, srcs, options, linker_script)
    _replay_warnings(entry / META_NAME)
    if out is None:
        return cached
    out_path = Path(out).expanduser().resolve()
    out_path.parent.mkdir(parents=True, exist_ok=True)
    output_files.write_atomic(out_path, cached.read_bytes())
    return out_path


#: Most characters of ``-D`` options given to zig on its command line: past about 32 KB, zig cc
#: cannot preprocess an assembly (.S) source (it prints its usage).  More go to a generated header.
MAX_DEFINE_CHARS = 16_000
DEFINES_HEADER = "defines.h"


def defines_to_header(args: list[str], header: Path) -> list[str]:
    """``args``, or, when their ``-D`` options are longer than :data:`MAX_DEFINE_CHARS`, ``args``
    without them and with ``-include header``, a header that defines the same names (``-DN=V`` is
    ``#define N V``, ``-DN`` is ``#define N 1``)."""
    defines = [a for a in args if a.startswith("-D") and len(a) > 2]
    if sum(len(a) + 1 for a in defines) <= MAX_DEFINE_CHARS or any("\n" in a or "\r" in a for a in defines):
        return args
    lines = []
    for flag in defines:
        name, eq, value = flag[2:].partition("=")
        lines.append(f"#define {name} {value if eq else '1'}\n")
    header.write_text("".join(lines), encoding="utf-8")
    moved = set(defines)
    return ["-include", str(header), *(a for a in args if a not in moved)]


def _compile_into(
    entry: Path, all_sources: list[Path], user_sources: list[Path], options: CoreBuildOptions, ld: str
) -> None:
    """Run the compiler in a scratch folder and move the ELF and its metadata into ``entry``."""
    entry.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix=".build-", dir=entry.parent) as scratch_name:
        scratch = Path(scratch_name)
        (scratch / "link.ld").write_text(ld)
        elf = scratch / ELF_NAME
        script = str(scratch / "link.ld")
        args = [*options.compiler_flags(), "-T", script, *map(str, all_sources), "-o", str(elf)]
        args = defines_to_header(args, scratch / DEFINES_HEADER)
        proc = run_zig_cc(args, zig_cache_dir(), cwd=scratch)
        if proc.returncode != 0 or not elf.is_file():
            message = proc.stderr or proc.stdout or f"zig cc exited with status {proc.returncode}"
            if message.startswith("info: Usage: zig"):  # zig's answer to a command line it cannot pass on
                chars = sum(len(a) + 1 for a in args)
                message = (
                    f"zig cc refused its command line ({len(args)} arguments, {chars} characters) and printed its "
                    "usage; fewer or shorter -D/-I options may help"
                )
            raise CompileError(files_named_in(message, user_sources), message, zig_cc_command(args))
        meta = {
            "command": zig_cc_command(args),
            "compiler_warnings": proc.stderr.strip(),
            "x27_warnings": check_x27(elf, ", ".join(s.name for s in user_sources)),
        }
        (scratch / META_NAME).write_text(json.dumps(meta, indent=1))
        try:
            os.replace(scratch, entry)  # atomic publish; a concurrent identical build may win
        except OSError:
            if not (entry / ELF_NAME).is_file():
                raise
        else:
            # TemporaryDirectory must find something to remove
            scratch.mkdir()


def _replay_warnings(meta_path: Path) -> None:
    """Issue the warnings recorded at build time again, so a cache hit reports what a build did."""
    try:
        meta = json.loads(meta_path.read_text())
    except (OSError, ValueError):
        return
    if meta.get("compiler_warnings"):
        warnings.warn(meta["compiler_warnings"], CompilerWarning, stacklevel=3)
    for text in meta.get("x27_warnings", []):
        warnings.warn(text, FixedRegisterWarning, stacklevel=3)
