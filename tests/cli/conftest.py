"""Small programs and input files shared by the command-line tests."""

import os
from pathlib import Path

import pytest

from robosoc.toolchain import build_elf

PROGRAMS = {
    "ok": "int main(void) { return 0; }\n",
    "three": '#include "hf_print.h"\nint main(void) { hf_puts("three\\n"); return 3; }\n',
    "word": "int main(void) { return (int)0xd114ce5a; }\n",
    "page": "int main(void) { return 0x100; }\n",
    "loop": 'int main(void) { for (;;) { __asm__ volatile(""); } }\n',
    "fault": "int main(void) { *(volatile int *)0x10 = 1; return 0; }\n",
    "mulhsu": (
        "int main(void) { volatile int a = -3; volatile unsigned b = 5; int hi;\n"
        '  __asm__ volatile("mulhsu %0, %1, %2" : "=r"(hi) : "r"(a), "r"(b)); return hi == -1 ? 0 : 1; }\n'
    ),
}


@pytest.fixture(scope="session")
def elves(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """ELF files by name: ok (exit 0), three (prints, exit 3), word (exit 0xd114ce5a), page (exit 0x100),
    loop (never exits), fault (an unmapped store), mulhsu (hits the MULHSU erratum, exit 0)."""
    folder = tmp_path_factory.mktemp("elves")
    out = {}
    for name, source in PROGRAMS.items():
        src = folder / f"{name}.c"
        src.write_text(source)
        out[name] = build_elf([src], mul=True)
    return out


@pytest.fixture(scope="session")
def bad_paths(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Paths that no command can use: missing, a folder, a binary file, a file in the way, read-only."""
    folder = tmp_path_factory.mktemp("bad")
    binary = folder / "binary.toml"
    binary.write_bytes(bytes(range(256)) * 4)
    a_file = folder / "a-file"
    a_file.write_text("not a folder\n")
    a_dir = folder / "a-dir.mp4"  # a folder whose name looks like a file
    a_dir.mkdir()
    return {
        "missing": folder / "missing" / "nothing.toml",
        "dir": a_dir,
        "binary": binary,
        "file": a_file,
        "under_file": a_file / "inside.json",
        "read_only": read_only_dir(folder) / "out.json",
    }


def read_only_dir(folder: Path) -> Path:
    """A folder no file can be created in, for this user (root ignores permission bits: /sys then)."""
    if os.geteuid() != 0:
        ro = folder / "read-only"
        ro.mkdir(exist_ok=True)
        ro.chmod(0o555)
        return ro
    sys_dir = Path("/sys")
    probe = sys_dir / "robosoc-probe"
    try:
        probe.mkdir()
    except OSError:
        return sys_dir
    probe.rmdir()
    pytest.skip("no read-only place for root here")
