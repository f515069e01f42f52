"""Thousands of ``-D`` (issue 34, item 8): zig cc cannot preprocess an assembly source once its command
line passes about 32 KB and prints its usage, which robosoc cc showed as a "compile error".  The defines
then go to a generated header; a refusal of the command line by zig is named as such."""

from __future__ import annotations

from pathlib import Path

from typer.testing import CliRunner

from robosoc.cli import app, exit_codes
from robosoc.toolchain.build import MAX_DEFINE_CHARS, defines_to_header

runner = CliRunner()


def test_few_defines_stay_on_the_command_line(tmp_path: Path) -> None:
    args = ["-O2", "-DN=1", "-DFLAG", "a.c"]
    assert defines_to_header(args, tmp_path / "defines.h") == args
    assert not (tmp_path / "defines.h").exists()


def test_many_defines_go_to_a_header_with_the_same_meaning(tmp_path: Path) -> None:
    many = [f"-DSYM_{i}={i}" for i in range(MAX_DEFINE_CHARS // 10)]
    args = ["-O2", *many, "-DFLAG", '-DSTR="a b"', "-DEMPTY=", "a.c", "-o", "a.elf"]
    header = tmp_path / "defines.h"
    out = defines_to_header(args, header)
    assert out == ["-include", str(header), "-O2", "a.c", "-o", "a.elf"]
    text = header.read_text().splitlines()
    assert text[0] == "#define SYM_0 0" and '#define STR "a b"' in text
    assert "#define FLAG 1" in text and "#define EMPTY " in text
    with_newline = [*args[:-3], "-DBAD=a\nb", *args[-3:]]  # cannot be a #define line: left as it was
    assert defines_to_header(with_newline, header) == with_newline


def test_cc_with_thousands_of_defines_compiles_and_they_hold(tmp_path: Path) -> None:
    source = tmp_path / "d.c"
    source.write_text("int main(void) { return SYM_2999 - 2999 + LAST; }\n")
    elf = tmp_path / "d.elf"
    defines = [arg for i in range(3000) for arg in ("-D", f"SYM_{i}={i}")]
    result = runner.invoke(app, ["cc", str(source), "-o", str(elf), *defines, "-D", "LAST=7"])
    assert result.exit_code == 0, result.output
    assert "Usage: zig" not in result.output
    result = runner.invoke(app, ["run", str(elf)])
    assert result.exit_code == exit_codes.PROGRAM_FAILED and "exit code 7" in result.output, result.output
