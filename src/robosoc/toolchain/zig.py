"""Running the ``ziglang`` PyPI package's ``zig cc`` (never a system compiler)."""

import os
import subprocess
import sys
from importlib import metadata
from pathlib import Path

from robosoc.toolchain.errors import ToolchainError


def zig_package_version() -> str:
    """Version of the installed ``ziglang`` package (part of every build-cache key)."""
    try:
        return metadata.version("ziglang")
    except metadata.PackageNotFoundError as exc:
        raise ToolchainError("the 'ziglang' package is not installed: pip install ziglang") from exc


def zig_env(zig_cache: Path) -> dict[str, str]:
    """Environment for zig with both of its caches inside the project cache folder."""
    zig_cache.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ)
    env["ZIG_GLOBAL_CACHE_DIR"] = str(zig_cache)
    env["ZIG_LOCAL_CACHE_DIR"] = str(zig_cache)
    return env


def zig_cc_command(args: list[str]) -> list[str]:
    """The full command line of ``python -m ziglang cc ARGS``."""
    return [sys.executable, "-m", "ziglang", "cc", *args]


def run_zig_cc(args: list[str], zig_cache: Path, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    """Run ``zig cc`` with the project's zig cache; returns the completed process (never raises on rc)."""
    command = zig_cc_command(args)
    try:
        return subprocess.run(command, env=zig_env(zig_cache), cwd=cwd, capture_output=True, text=True, check=False)
    except OSError as exc:
        raise ToolchainError(f"cannot run zig ({' '.join(command[:4])}): {exc}") from exc
