"""Compiling the same C for the host with ``zig cc`` (native target), to compare results.

The host build links the print library's host variant (``hf_putchar`` → ``putchar``) and uses the
same arithmetic-relevant flags as the core build (no FMA contraction), so a program that avoids
undefined behaviour prints the same bytes on the host and on the simulated core.
"""

import os
import shutil
import subprocess
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path

from robosoc import output_files
from robosoc.firmware import INCLUDE_DIR, host_sources
from robosoc.toolchain.build import files_named_in, resolve_sources
from robosoc.toolchain.cache import build_key, entry_dir, file_digest, header_digests, zig_cache_dir
from robosoc.toolchain.errors import CompileError, ToolchainError
from robosoc.toolchain.options import COMMON_FLAGS, define_flags, normalize_opt
from robosoc.toolchain.zig import run_zig_cc, zig_cc_command, zig_package_version

EXE_NAME = "program"


def compile_native(
    sources: Sequence[Path | str],
    out: Path | str | None = None,
    opt: str = "-O2",
    *,
    defines: Mapping[str, str | int | None] | Sequence[str] = (),
    include_dirs: Sequence[Path | str] = (),
    print_library: bool = True,
) -> Path:
    """Compile C sources into a host executable (cached like :func:`~robosoc.toolchain.build.build_elf`).

    Args:
        sources: .c files of the program.
        out: where to copy the executable; ``None`` returns the file inside the cache.
        opt: optimisation level.
        defines: preprocessor definitions.
        include_dirs: extra ``-I`` folders (the runtime's ``include/`` is always searched).
        print_library: link ``lib/hf_print.c`` (host variant).

    Returns:
        The executable's path.

    Raises:
        CompileError: the compiler failed (message and file).
    """
    srcs = resolve_sources(sources)
    incs = [Path(d).expanduser().resolve() for d in include_dirs]
    all_sources = [*srcs, *(host_sources() if print_library else ())]
    flags = [
        normalize_opt(opt),
        *COMMON_FLAGS,
        *define_flags(defines),
        *(f"-I{d}" for d in (*incs, INCLUDE_DIR)),
    ]
    key = build_key(
        {
            "kind": "native",
            "zig": zig_package_version(),
            "flags": flags,
            "sources": [(str(s), file_digest(s)) for s in all_sources],
            "headers": header_digests([*incs, INCLUDE_DIR, *{s.parent for s in srcs}]),
        }
    )
    entry = entry_dir("native", key)
    exe = entry / EXE_NAME
    if not exe.is_file():
        entry.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(prefix=".build-", dir=entry.parent) as scratch_name:
            scratch = Path(scratch_name)
            args = [*flags, *map(str, all_sources), "-o", str(scratch / EXE_NAME)]
            proc = run_zig_cc(args, zig_cache_dir(), cwd=scratch)
            if proc.returncode != 0 or not (scratch / EXE_NAME).is_file():
                message = proc.stderr or proc.stdout or f"zig cc exited with status {proc.returncode}"
                raise CompileError(files_named_in(message, srcs), message, zig_cc_command(args))
            try:
                os.replace(scratch, entry)
            except OSError:
                if not exe.is_file():
                    raise
            else:
                scratch.mkdir()
    if out is None:
        return exe
    out_path = Path(out).expanduser().resolve()
    out_path.parent.mkdir(parents=True, exist_ok=True)
    output_files.check_regular(out_path)  # a device, FIFO or socket is neither replaced nor opened
    shutil.copy2(exe, out_path)
    return out_path


def run_native(exe: Path, timeout: float = 60.0) -> tuple[int, bytes]:
    """Run a host executable; returns (exit code, stdout bytes).

    Raises:
        ToolchainError: it could not start or ran past ``timeout`` seconds.
    """
    try:
        proc = subprocess.run([str(exe)], capture_output=True, timeout=timeout, check=False)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise ToolchainError(f"{exe}: host run failed: {exc}") from exc
    return proc.returncode, proc.stdout
