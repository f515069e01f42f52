"""Every option of every command, given bad values: a usage error naming it, fast, never a traceback.

:data:`OPTIONS` describes each option (and argument) of every command; a test checks it against the
command tree, so a new option must be described here before the suite passes (docs/cli.md).  Each
option gets a fixed list of bad values for its kind (negative, zero, huge, NaN, wrong type, missing
file, folder, binary file, read-only target, a file where a folder is wanted), then hypothesis draws
more.  The base command lines are short good runs (``--max-cycles`` small, 0.01 s flights, one
benchmark run), so that a bad value let through would still end quickly -- and fail the test.
"""

from __future__ import annotations

import re
import signal
import string
from collections.abc import Iterator
from contextlib import chdir, contextmanager
from dataclasses import dataclass
from pathlib import Path

import pytest
import typer.main
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from robosoc.cli import app
from robosoc.control.flight import ROW_FIELDS

TIME_LIMIT_S = 60  # per command line; the first ones import numba, mujoco and the toolchain
HUGE = str(10**40)


class Hang(BaseException):
    """A command line ran past :data:`TIME_LIMIT_S` (a BaseException: no command may catch it)."""


@contextmanager
def time_limit(seconds: int) -> Iterator[None]:
    def expired(signum, frame):
        raise Hang(f"still running after {seconds} s")

    previous = signal.signal(signal.SIGALRM, expired)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


@dataclass(frozen=True)
class Spec:
    """One option: its kind and, for numbers, the allowed range (bad values are drawn outside it)."""

    kind: str
    lo: float | None = None
    hi: float | None = None
    choices: tuple[str, ...] = ()


# (command, option or argument metavar) -> Spec
OPTIONS: dict[tuple[str, str], Spec] = {
    ("run", "PROGRAMS"): Spec("in_file"),
    ("run", "--mul"): Spec("flag"),
    ("run", "--max-cycles"): Spec("int", 1, 2**62),
    ("run", "--stats"): Spec("out_file"),
    ("run", "--energy"): Spec("in_file"),
    ("run", "--sram-size"): Spec("sram"),
    ("run", "--mesh"): Spec("mesh"),
    ("run", "--chip"): Spec("in_file"),
    ("run", "--off"): Spec("tile"),
    ("run", "--trace"): Spec("int", 0, 2**62),
    ("run", "--profile"): Spec("int", 0, 2**61),
    ("run", "--errata"): Spec("choice", choices=("spec", "rtl")),
    ("run", "--exit-code"): Spec("choice", choices=("status", "program")),
    ("run", "--engine"): Spec("choice", choices=("interp", "jit", "auto")),
    ("run", "--gdb"): Spec("int", 0, 65535),  # 0: any free port (never tried: it would wait for GDB)
    ("run", "--tile"): Spec("tile"),
    ("cc", "FILES"): Spec("in_file"),
    ("cc", "--output"): Spec("out_file"),
    ("cc", "--mul"): Spec("flag"),
    ("cc", "--opt"): Spec("choice", choices=tuple(f"{p}{o}" for p in ("", "O", "-O") for o in "0123sz")),
    ("cc", "--define"): Spec("define"),
    ("cc", "--include"): Spec("in_dir"),
    ("cc", "--sram-size"): Spec("sram"),
    ("cc", "--no-runtime"): Spec("flag"),
    ("fly", "--controller"): Spec("choice", choices=("host", "chip")),
    ("fly", "--arith"): Spec("choice", choices=("float", "fixed")),
    ("fly", "--fixed-mul"): Spec("choice", choices=("shift-add", "muldi3")),
    ("fly", "--engine"): Spec("choice", choices=("interp", "jit", "auto")),
    ("fly", "--mul"): Spec("flag"),
    ("fly", "SCENARIO"): Spec("in_file"),
    ("fly", "--duration"): Spec("float", 0.01, 3600.0),  # at least one sensor period of 10 ms
    ("fly", "--seconds"): Spec("float", 0.01, 3600.0),  # the hidden alias of --duration
    ("fly", "--vehicles"): Spec("int", 1, 16),
    ("fly", "--seed"): Spec("int", 0, 2**63 - 1),
    ("fly", "--scenario"): Spec("in_file"),
    ("fly", "--vehicle"): Spec("choice", choices=("default", "laser")),
    ("fly", "--out"): Spec("out_dir"),
    ("fly", "--supply"): Spec("choice", choices=("constant", "battery")),
    ("fly", "--noc-gating"): Spec("flag"),
    ("bench sweep", "--points"): Spec("int", 1, 256),
    ("bench sweep", "--seconds"): Spec("float", 0.01, 60.0),
    ("bench sweep", "--workers"): Spec("int", 1, 256),
    ("sweep", "FILE"): Spec("in_file"),
    ("sweep", "--workers"): Spec("int", 1, 256),
    ("sweep", "--dask"): Spec("dask"),
    ("sweep", "--out"): Spec("out_dir"),
    ("sweep", "--retry-failed"): Spec("flag"),
    ("fly", "--no-out"): Spec("flag"),
    ("fly", "--video"): Spec("out_any"),
    ("bench fly", "--arith"): Spec("choice", choices=("float", "fixed")),
    ("bench fly", "--mul"): Spec("flag"),
    ("bench fly", "--duration"): Spec("float", 0.01, 3600.0),
    ("bench fly", "--breakdown"): Spec("flag"),
    ("bench fly", "--vehicles"): Spec("int", 1, 16),
    ("bench fly", "--engine"): Spec("choice", choices=("interp", "jit", "auto")),
    ("bench fly", "--runs"): Spec("int", 1, 100),
    ("scenario show", "FILE"): Spec("in_file"),
    ("fly", "--foxglove"): Spec("int", 0, 65535),
    ("fly", "--foxglove-keep"): Spec("flag"),  # 0: any free port (never tried: it would serve a flight)
    ("fly", "--decoupled"): Spec("flag"),
    ("fly", "--pace"): Spec("choice", choices=("realtime", "fast")),
    ("fly", "--hold"): Spec("choice", choices=("zoh", "linear")),
    ("fly", "--faults"): Spec("faults"),
    ("fly", "--resend"): Spec("int", 0, 8),
    ("fly", "--peer-timeout"): Spec("float", 0.05, 3600.0),
    ("fly", "--bind"): Spec("address"),
    ("serve physics", "--duration"): Spec("float", 0.01, 3600.0),
    ("serve physics", "--seconds"): Spec("float", 0.01, 3600.0),  # the hidden alias of --duration
    ("serve physics", "--seed"): Spec("int", 0, 2**63 - 1),
    ("serve physics", "--scenario"): Spec("in_file"),
    ("serve physics", "SCENARIO"): Spec("in_file"),
    ("serve physics", "--vehicle"): Spec("choice", choices=("default", "laser")),
    ("serve physics", "--out"): Spec("out_dir"),
    ("serve physics", "--no-out"): Spec("flag"),
    ("serve physics", "--bind"): Spec("address"),
    ("serve physics", "--ros"): Spec("flag"),
    ("serve physics", "--vehicles"): Spec("int", 1, 16),
    ("serve physics", "--start-delay"): Spec("float", 0.0, 600.0),
    ("serve chip", "--ros"): Spec("flag"),
    ("serve chip", "--ns"): Spec("namespace"),
    ("serve physics", "--pace"): Spec("choice", choices=("realtime", "fast")),
    ("serve physics", "--hold"): Spec("choice", choices=("zoh", "linear")),
    ("serve physics", "--faults"): Spec("faults"),
    ("serve physics", "--resend"): Spec("int", 0, 8),
    ("serve physics", "--peer-timeout"): Spec("float", 0.05, 3600.0),
    ("serve physics", "--connect-timeout"): Spec("float", 0.05, 3600.0),
    ("serve chip", "--duration"): Spec("float", 0.01, 3600.0),
    ("serve chip", "--seconds"): Spec("float", 0.01, 3600.0),  # the hidden alias of --duration
    ("serve chip", "--seed"): Spec("int", 0, 2**63 - 1),
    ("serve chip", "--scenario"): Spec("in_file"),
    ("serve chip", "SCENARIO"): Spec("in_file"),
    ("serve chip", "--vehicle"): Spec("choice", choices=("default", "laser")),
    ("serve chip", "--arith"): Spec("choice", choices=("float", "fixed")),
    ("serve chip", "--mul"): Spec("flag"),
    ("serve chip", "--fixed-mul"): Spec("choice", choices=("shift-add", "muldi3")),
    ("serve chip", "--peer"): Spec("address"),
    ("serve chip", "--bind"): Spec("address"),
    ("serve chip", "--out"): Spec("out_dir"),
    ("serve chip", "--no-out"): Spec("flag"),
    ("serve chip", "--faults"): Spec("faults"),
    ("serve chip", "--resend"): Spec("int", 0, 8),
    ("serve chip", "--peer-timeout"): Spec("float", 0.05, 3600.0),
    ("serve chip", "--connect-timeout"): Spec("float", 0.05, 3600.0),
    ("bench core", "--runs"): Spec("int", 1, 1000),
    ("bench core", "--mul"): Spec("flag"),
    ("bench core", "--engine"): Spec("choice", choices=("interp", "jit", "auto")),
    ("bench chip", "--engine"): Spec("choice", choices=("interp", "jit", "auto")),
    ("bench core", "--compare"): Spec("flag"),
    ("bench physics", "--seconds"): Spec("float", 0.001, 3600.0),
    ("bench physics", "--runs"): Spec("int", 1, 1000),
    ("bench noc", "--size"): Spec("mesh"),
    ("bench noc", "--cycles"): Spec("int", 1, 1_000_000),
    ("bench noc", "--plot"): Spec("out_file"),
    ("bench noc", "--seed"): Spec("int", 0, 2**63 - 1),
    ("bench noc", "--arbiter"): Spec("choice", choices=("hermes", "per-output", "both")),
    ("bench noc", "--rates"): Spec("rates"),
    ("bench noc", "--packet-flits"): Spec("int", 5, 64),
    ("bench noc", "--depth"): Spec("int", 2, 256),
    ("bench noc", "--rx-hold"): Spec("int", 0, 10_000),
    ("bench noc", "--compare-read-pointer"): Spec("flag"),
    ("bench noc", "--gating"): Spec("choice", choices=("off", "on", "both")),
    ("bench chip", "--runs"): Spec("int", 1, 1000),
    ("bench chip", "--cycles"): Spec("int", 1, 10**10),
    ("bench chip", "--ticks"): Spec("int", 1, 100_000),
    ("bench chip", "--noc"): Spec("flag"),
    ("firmware build", "--arith"): Spec("choice", choices=("float", "fixed")),
    ("firmware build", "--mul"): Spec("flag"),
    ("firmware build", "--fixed-mul"): Spec("choice", choices=("shift-add", "muldi3")),
    ("firmware build", "--config"): Spec("in_file"),
    ("firmware build", "--output"): Spec("out_file"),
    ("firmware size", "ELF"): Spec("in_file"),
    ("firmware size", "--arith"): Spec("choice", choices=("float", "fixed")),
    ("firmware size", "--mul"): Spec("flag"),
    ("firmware size", "--fixed-mul"): Spec("choice", choices=("shift-add", "muldi3")),
    ("firmware size", "--config"): Spec("in_file"),
    ("firmware size", "--top"): Spec("int", 1, 10_000),
    ("firmware replay", "LOG"): Spec("in_file"),
    ("firmware replay", "--arith"): Spec("choice", choices=("float", "fixed")),
    ("firmware replay", "--mul"): Spec("flag"),
    ("firmware replay", "--fixed-mul"): Spec("choice", choices=("shift-add", "muldi3")),
    ("firmware replay", "--config"): Spec("in_file"),
    ("firmware replay", "--seconds"): Spec("float", 0.02, 600.0),
    ("firmware replay", "--seed"): Spec("int", 0, 2**63 - 1),
    ("firmware replay", "--out"): Spec("out_dir"),
    ("report", "RUN_DIR"): Spec("in_dir"),
    ("report", "--out"): Spec("out_file"),
    ("report", "--mcap"): Spec("flag"),
    ("profile", "RUN_DIR"): Spec("in_dir"),
    ("profile", "--top"): Spec("int", 1, 1000),
    ("fly", "--profile"): Spec("flag"),
    ("table", "--iterations"): Spec("int", 1, 10_000),
    ("table", "--release"): Spec("choice", choices=("event", "periodic", "both")),
    ("table", "--closed-loop"): Spec("flag"),
    ("table", "--seed"): Spec("int", 0, 2**63 - 1),
    ("table", "--workers"): Spec("int", 1, 64),
    ("table", "--out"): Spec("out_dir"),
    ("table", "--firmware"): Spec("in_dir"),
    ("table", "--fixed-mul"): Spec("choice", choices=("shift-add", "muldi3")),
    ("table", "SCENARIO"): Spec("in_file"),
    ("table", "--scenario"): Spec("in_file"),
    ("fly", "--firmware"): Spec("in_dir"),
    ("serve chip", "--firmware"): Spec("in_dir"),
    ("serve physics", "--firmware"): Spec("in_dir"),
    ("scenario show", "--firmware"): Spec("in_dir"),
    ("firmware build", "--firmware"): Spec("in_dir"),
    ("firmware size", "--firmware"): Spec("in_dir"),
    ("firmware replay", "--firmware"): Spec("in_dir"),
    ("new", "DIR"): Spec("out_dir"),
    ("new", "--template"): Spec("choice", choices=("blank", "position", "quadrotor")),
}

PATH = "\0"  # "\0dir": one of the bad_paths fixture's paths
BINARY = "\x01"  # "\x01<hex>": a file with these bytes
NO_DIGITS = string.ascii_letters + string.punctuation + " "

BAD_VALUES: dict[str, list[str]] = {
    "int": ["-5", "0", HUGE, "nan", "inf", "abc", "1.5", ""],
    "float": ["-1", "0", "1e308", "nan", "inf", "-inf", "abc", ""],
    "namespace": ["", "/1uav", "/uav 1", "//", "/a-b", "uav1/../x"],
    "sram": ["-4", "0", "4098", str(2**40), "nan", "abc"],
    "choice": ["", "nope", "-1", "nan", HUGE],
    "mesh": ["", "0x0", "1x1", "-2x2", "99999x99999", "nan", "2x", "2x2x2"],
    "tile": ["", "a,b", "-1,0", "99,99", "nan", "0,0", "1"],
    "rates": ["", "0", "-0.1", "2", "nan", "inf", "a", "0.1,,0.2"],
    "dask": ["", "nowhere", "tcp://", "tcp://host:0", "host:99999", "ftp://host:80", ":8786"],
    "define": ["", "-x", "A B=1", "=1", "1X", "A-B"],
    "flag": ["=1"],
    "address": ["", "nohost", "127.0.0.1:99999", "127.0.0.1:abc", ":5600", "::1:5600", "a b:5600"],
    "faults": [
        "",
        "loss",
        "loss=2",
        "loss=-0.1",
        "loss=nan",
        "nope=0.1",
        "loss=0.6,duplicate=0.6",
        "loss=0.1,loss=0.2",
    ],
    "in_file": ["\0missing", "\0dir", "\0binary", "\0under_file"],
    "in_dir": ["\0missing", "\0file"],
    "out_file": ["\0dir", "\0read_only", "\0under_file"],
    "out_dir": ["\0file", "\0read_only", "\0under_file"],
    "out_any": ["\0dir", "\0file", "\0read_only", "\0under_file"],
}


def base_command(command: str, option: str, elves: dict[str, Path], tmp: Path) -> list[str]:
    """A short good command line for ``command``, without ``option`` where the base would set it."""
    if command == "run":
        return ["run", *([] if option == "PROGRAMS" else [str(elves["ok"])]), "--max-cycles", "100000"]
    if command == "cc":
        source = tmp / "ok.c"
        source.write_text("int main(void) { return 0; }\n")
        return [
            "cc",
            *([] if option == "FILES" else [str(source)]),
            *([] if option == "--output" else ["-o", str(tmp / "ok.elf")]),
        ]
    if command == "report":
        if option == "RUN_DIR":
            return ["report"]
        run = tmp / "run"
        run.mkdir(exist_ok=True)
        (run / "flight.csv").write_text(",".join(ROW_FIELDS) + "\n" + ",".join(["0.0"] * len(ROW_FIELDS)) + "\n")
        return ["report", str(run)]
    if command == "profile":
        if option == "RUN_DIR":
            return ["profile"]
        run = tmp / "run"  # a bad value let through would fly these 0.01 s again
        run.mkdir(exist_ok=True)
        (run / "scenario.toml").write_text("duration_s = 0.01\n")
        (run / "summary.json").write_text("{}\n")
        return ["profile", str(run)]
    if command == "sweep":
        sweep = tmp / "ok-sweep.toml"
        sweep.write_text("[base]\nduration_s = 0.01\n[grid]\nduration_s = [0.01]\n")
        return ["sweep", *([] if option == "FILE" else [str(sweep)]), "--workers", "1"]
    if command == "fly":
        length = [] if option in ("--duration", "--seconds") else ["--duration", "0.01"]
        return ["fly", *length, *([] if option in ("--out", "--no-out") else ["--no-out"])]
    if command == "bench fly":
        runs = [] if option == "--runs" else ["--runs", "1"]
        return ["bench", "fly", *([] if option == "--duration" else ["--duration", "0.01"]), "--arith", "fixed", *runs]
    if command.startswith("serve "):  # a bad value let through would wait 0.5 s for the peer and exit with 5
        base = {"--seconds": "0.01", "--connect-timeout": "0.5", "--bind": "127.0.0.1:0"}
        if command == "serve chip":
            base["--peer"] = "127.0.0.1:9"
        args = command.split() + [w for name, v in base.items() if name != option for w in (name, v)]
        return args + ([] if option in ("--out", "--no-out") else ["--no-out"])
    return {
        "bench core": ["bench", "core", "--runs", "1"],
        "bench physics": ["bench", "physics", "--seconds", "0.01", "--runs", "1"],
        "bench sweep": ["bench", "sweep", "--points", "1", "--seconds", "0.01", "--workers", "1"],
        "bench noc": ["bench", "noc", "--size", "2x2", "--cycles", "10", "--rates", "0.1", "--arbiter", "hermes"],
        "bench chip": ["bench", "chip", "--runs", "1", "--cycles", "10", "--ticks", "1", "--no-noc"],
        "firmware build": ["firmware", "build"],
        "new": ["new", *([] if option == "DIR" else [str(tmp / "new-project")])],
        "scenario show": ["scenario", "show"],
        "firmware size": ["firmware", "size"],
        "firmware replay": ["firmware", "replay", *([] if option in ("LOG", "--seconds") else ["--seconds", "0.02"])],
        "table": ["table", *([] if option == "--iterations" else ["--iterations", "1"]), "--workers", "1"]
        if option != "--workers"
        else ["table", "--iterations", "1"],
    }[command]


def command_line(command: str, option: str, value: str, elves, bad_paths, tmp: Path) -> list[str]:
    if value.startswith(PATH):
        value = str(bad_paths[value[1:]])
    args = base_command(command, option, elves, tmp)
    if not option.startswith("-"):
        return [*args, value]
    if OPTIONS[(command, option)].kind == "flag":
        return [*args, option + value]
    return [*args, option, value]


def check_refused(args: list[str], option: str) -> None:
    with time_limit(TIME_LIMIT_S):
        result = CliRunner().invoke(app, args)
    output = result.output
    assert "Traceback" not in output, (args, output)
    assert result.exit_code == 2, (args, result.exit_code, output)
    first = output.strip().splitlines()[0] if output.strip() else ""
    assert first.startswith("robosoc"), (args, output)
    name = option if option.startswith("-") else Path(args[-1]).name
    assert name in output, (args, output)


def walk(command, path: tuple[str, ...] = ()) -> Iterator[tuple[str, str]]:
    subcommands = getattr(command, "commands", None)
    if subcommands:
        for name, sub in subcommands.items():
            yield from walk(sub, (*path, name))
        return
    for param in command.params:
        if param.name == "help":
            continue
        if param.param_type_name == "argument":
            yield " ".join(path), param.metavar or param.name.upper()
        else:
            yield " ".join(path), next(o for o in [*param.opts, *param.secondary_opts] if o.startswith("--"))


def test_every_option_of_every_command_is_described() -> None:
    found = set(walk(typer.main.get_command(app)))
    assert found - set(OPTIONS) == set(), "describe the new options in OPTIONS (and see docs/cli.md)"
    assert set(OPTIONS) - found == set(), "options described here that no command has"


CASES = [
    (command, option, value)
    for (command, option), spec in OPTIONS.items()
    for value in BAD_VALUES[spec.kind]
    if not (spec.kind in ("int", "float") and spec.lo == 0 and value == "0")
]


@pytest.mark.parametrize(
    ("command", "option", "value"), CASES, ids=[f"{c}|{o}|{v.replace(PATH, '@')}" for c, o, v in CASES]
)
def test_bad_value_is_refused(command, option, value, elves, bad_paths, tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    check_refused(command_line(command, option, value, elves, bad_paths, tmp_path), option)


def _number_text(spec: Spec) -> st.SearchStrategy[str]:
    """Numbers outside the spec's range, as text."""
    lo, hi = spec.lo, spec.hi
    if spec.kind == "int":
        below = st.integers(max_value=int(lo) - 1).map(str)
        above = st.integers(min_value=int(hi) + 1, max_value=10**40).map(str)
        fractional = st.floats(allow_nan=False, allow_infinity=False).filter(lambda v: v != int(v)).map(repr)
        return st.one_of(below, above, fractional)
    below = st.floats(max_value=lo, exclude_max=True, allow_nan=False, allow_infinity=False).map(repr)
    above = st.floats(min_value=hi, exclude_min=True, allow_nan=False, allow_infinity=False).map(repr)
    return st.one_of(below, above)


def bad_text(spec: Spec) -> st.SearchStrategy[str]:
    words = st.text(alphabet=NO_DIGITS, max_size=12)
    special = st.sampled_from(["nan", "-nan", "inf", "-inf", "NaN", "1e999", HUGE, "-" + HUGE, "0x10", ""])
    if spec.kind in ("int", "float"):
        return st.one_of(_number_text(spec), words, special)
    if spec.kind == "choice":
        return st.one_of(words, special, st.integers().map(str)).filter(lambda v: v not in spec.choices)
    if spec.kind == "sram":
        return st.one_of(
            st.integers(max_value=4095).map(str),
            st.integers(min_value=2**30 + 1, max_value=10**30).map(str),
            st.integers(min_value=1024, max_value=2**28).map(lambda v: str(4 * v + 2)),
            words,
            special,
        )
    if spec.kind == "mesh":
        side = st.one_of(st.integers(max_value=0), st.integers(min_value=17, max_value=10**9))
        return st.one_of(words, special, st.tuples(side, st.integers(1, 16)).map(lambda t: f"{t[0]}x{t[1]}"))
    if spec.kind == "tile":
        far = st.integers(min_value=2, max_value=10**9)
        return st.one_of(words, special, st.tuples(far, far).map(lambda t: f"{t[0]},{t[1]}"))
    if spec.kind == "rates":
        out = st.one_of(st.floats(max_value=0.0), st.floats(min_value=1.0, exclude_min=True)).map(repr)
        return st.one_of(words, special, st.lists(out, min_size=1, max_size=3).map(",".join))
    if spec.kind == "define":  # anything but NAME[=VALUE] with NAME a C identifier ("_", "_1=" are)
        return st.one_of(
            st.sampled_from(["", "-x", "A B", "=1", "-DX"]),
            st.text(alphabet=string.digits + string.punctuation + " ", min_size=1, max_size=6).filter(
                lambda v: re.fullmatch(r"[A-Za-z_]\w*(=.*)?", v) is None
            ),
        )
    if spec.kind == "flag":
        return st.sampled_from(["=1", "=yes", "=", "=nan"])
    if spec.kind == "dask":  # anything but 'local' or scheme://host:port with a port in 1..65535
        far = st.integers(min_value=65536, max_value=10**12)
        return st.one_of(words.filter(lambda v: v != "local"), special, far.map(lambda p: f"tcp://host:{p}"))
    if spec.kind == "namespace":
        return st.sampled_from(BAD_VALUES["namespace"])
    if spec.kind == "address":
        far = st.integers(min_value=65536, max_value=10**12).map(lambda p: f"127.0.0.1:{p}")
        return st.one_of(words, special, far)
    if spec.kind == "faults":
        rate = st.one_of(st.floats(max_value=0.0, exclude_max=True), st.floats(min_value=1.0, exclude_min=True))
        return st.one_of(words, special, rate.map(lambda r: f"loss={r!r}"))
    # files: a bad path, or a binary file (not UTF-8; for ELF files: with or without the ELF magic)
    paths = st.sampled_from(BAD_VALUES[spec.kind])
    if spec.kind != "in_file":
        return paths
    junk = st.binary(max_size=200).map(lambda b: b + b"\xff\xfe\x00")
    elf_like = st.binary(min_size=0, max_size=120).map(lambda b: b"\x7fELF\x01\x01\x01" + b + b"\xff")
    return st.one_of(paths, st.one_of(junk, elf_like).map(lambda b: BINARY + b.hex()))


@st.composite
def bad_case(draw) -> tuple[str, str, str]:
    (command, option), spec = draw(st.sampled_from(sorted(OPTIONS.items())))
    return command, option, draw(bad_text(spec))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(case=bad_case())
def test_generated_bad_values_are_refused(case, elves, bad_paths, tmp_path_factory) -> None:
    command, option, value = case
    tmp = tmp_path_factory.mktemp("fuzz")
    if value.startswith(BINARY):
        path = tmp / ("input" + (".c" if command == "cc" else ".toml"))
        path.write_bytes(bytes.fromhex(value[1:]))
        value = str(path)
    with chdir(tmp):
        check_refused(command_line(command, option, value, elves, bad_paths, tmp), option)
