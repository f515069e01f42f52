"""The command line's helpers called directly: option parsing, error messages, files, consoles.

Each expectation is written from docs/cli.md's rules (the option named as typed, the exit codes of
cli/exit_codes.py), not read back from the code.
"""

from __future__ import annotations

import dataclasses
import io
from pathlib import Path

import click
import pytest
import typer
from rich.console import Console

from robosoc.cli import cc, console, errors, exit_codes, files, gdb_option, options, run, sweep
from robosoc.cli.errors import CliError

# --- options.py ------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "min_tiles", "expected"),
    [("2x3", 2, (2, 3)), ("16X16", 2, (16, 16)), ("1x2", 2, (1, 2)), ("1x1", 1, (1, 1)), ("16x1", 16, (16, 1))],
)
def test_parse_mesh_accepts_sides_1_to_16(text: str, min_tiles: int, expected: tuple[int, int]) -> None:
    assert options.parse_mesh("--mesh", text, min_tiles) == expected


@pytest.mark.parametrize(
    ("text", "reason"),
    [
        ("2by2", "expected WxH such as 2x2, got '2by2'"),
        ("2x2x2", "expected WxH such as 2x2, got '2x2x2'"),
        ("0x2", "width must be between 1 and 16 tiles, got '0x2'"),
        ("17x2", "width must be between 1 and 16 tiles, got '17x2'"),
        ("2x0", "height must be between 1 and 16 tiles, got '2x0'"),
        ("2x17", "height must be between 1 and 16 tiles, got '2x17'"),
        ("1x1", "a mesh needs at least 2 tiles, got '1x1'"),
    ],
)
def test_parse_mesh_names_the_option_and_the_rule(text: str, reason: str) -> None:
    with pytest.raises(CliError) as caught:
        options.parse_mesh("--size", text)
    assert caught.value.message == f"--size: {reason}"
    assert caught.value.code == exit_codes.USAGE


def test_parse_mesh_counts_tiles_against_min_tiles() -> None:
    with pytest.raises(CliError, match="at least 7 tiles, got '2x3'"):
        options.parse_mesh("--mesh", "2x3", min_tiles=7)
    assert options.parse_mesh("--mesh", "2x3", min_tiles=6) == (2, 3)


def test_parse_tile() -> None:
    assert options.parse_tile("--off", "1,0") == (1, 0)
    assert options.parse_tile("--off", "0,0") == (0, 0)
    for text in ("1", "1,2,3", "a,b", ""):
        with pytest.raises(CliError) as caught:
            options.parse_tile("--off", text)
        assert caught.value.message == f"--off: expected X,Y such as 1,1, got {text!r}"
    for text in ("-1,0", "0,-1"):
        with pytest.raises(CliError) as caught:
            options.parse_tile("--off", text)
        assert caught.value.message == f"--off: coordinates must be >= 0, got {text!r}"


def test_parse_floats() -> None:
    assert options.parse_floats("--rates", "0.5,1", 0.0, 1.0, lo_open=True) == (0.5, 1.0)
    assert options.parse_floats("--rates", "0", 0.0, 1.0) == (0.0,)  # closed at lo without lo_open
    with pytest.raises(CliError) as caught:
        options.parse_floats("--rates", "0,0.5", 0.0, 1.0, lo_open=True)
    assert caught.value.message == "--rates: must be in (0, 1], got 0 (in '0,0.5')"
    with pytest.raises(CliError) as caught:
        options.parse_floats("--rates", "0.1,x", 0.0, 1.0)
    assert caught.value.message == "--rates: expected numbers separated by commas, got '0.1,x'"


def test_exclusive_names_every_option_given() -> None:
    options.exclusive(out=True, no_out=False)
    options.exclusive(out=False, no_out=False)
    with pytest.raises(CliError) as caught:
        options.exclusive(out=True, no_out=True)
    assert caught.value.message == "--out: cannot be combined with --no-out"
    with pytest.raises(CliError) as caught:
        options.exclusive(a=True, **{"--b-c": True}, d_e=True)
    assert caught.value.message == "--a: cannot be combined with --b-c or --d-e"
    with pytest.raises(CliError) as caught:  # an argument keeps its metavar (it used to read --LOG)
        options.exclusive(LOG=True, **{"--seconds": True})
    assert caught.value.message == "LOG: cannot be combined with --seconds"


@dataclasses.dataclass(frozen=True)
class _Two:
    duration_s: float = 1.0
    seed: int = 0
    tiles: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        if self.duration_s <= 0:
            raise ValueError(f"duration_s: must be > 0, got {self.duration_s}")
        if self.seed > 10 and self.duration_s > 5:
            raise ValueError("duration_s: at most 5 s with a seed above 10")
        if any(t < 0 for t in self.tiles):
            raise ValueError("tiles[1]: must be >= 0")
        if self.seed == 7:
            raise ValueError("seven is not a seed")


def test_override_names_the_option_that_set_the_field() -> None:
    config = options.override(_Two(), {"--seconds": ("duration_s", 2.0), "--seed": ("seed", 3)})
    assert config == _Two(2.0, 3)
    with pytest.raises(CliError) as caught:
        options.override(_Two(), {"--seconds": ("duration_s", -1.0)})
    assert caught.value.message == "--seconds: must be > 0, got -1.0"
    with pytest.raises(CliError) as caught:  # --seed broke a rule on duration_s, which --seconds set
        options.override(_Two(), {"--seconds": ("duration_s", 6.0), "--seed": ("seed", 11)}, ["a.toml"])
    assert caught.value.message == "--seconds: at most 5 s with a seed above 10 (with a.toml)"
    with pytest.raises(CliError) as caught:  # a field no option set: the option that was applied
        options.override(_Two(duration_s=6.0), {"--seed": ("seed", 11)}, ["a.toml", "b.toml"])
    assert caught.value.message == "--seed: duration_s: at most 5 s with a seed above 10 (with a.toml, b.toml)"
    with pytest.raises(CliError) as caught:  # an element of a tuple field
        options.override(_Two(), {"--off": ("tiles", (1, -1))})
    assert caught.value.message == "--off: must be >= 0"
    with pytest.raises(CliError) as caught:  # a message naming no field
        options.override(_Two(), {"--seed": ("seed", 7)})
    assert caught.value.message == "--seed: seven is not a seed"
    with pytest.raises(CliError) as caught:  # an unknown field is the option's fault too
        options.override(_Two(), {"--nope": ("nope", 1)})
    assert caught.value.message.startswith("--nope: ")


def _param(*opts: str, name: str = "value") -> click.Option:
    return click.Option(list(opts), type=str) if opts else click.Argument([name])


def _ctx(resilient: bool = False) -> click.Context:
    return click.Context(click.Command("x"), resilient_parsing=resilient)


def test_callbacks_name_the_long_option_and_keep_lists() -> None:
    check = options.int_range(1, 10, "cycles")
    assert check(_ctx(), _param("-n", "--count"), 3) == 3
    assert check(_ctx(), _param("-n", "--count"), [1, 10]) == [1, 10]
    assert check(_ctx(), _param("-n", "--count"), (2,)) == (2,)
    assert check(_ctx(), _param("-n", "--count"), None) is None
    assert check(_ctx(resilient=True), _param("-n", "--count"), 99) == 99  # completion: no check
    with pytest.raises(CliError) as caught:
        check(_ctx(), _param("-n", "--count"), 11)
    assert caught.value.message == "--count: must be between 1 and 10 cycles, got 11"
    with pytest.raises(CliError, match=r"^-n: "):
        check(_ctx(), _param("-n"), 0)
    with pytest.raises(CliError, match=r"^value: "):
        check(_ctx(), _param(), [5, 0])
    assert options.option_name(_param("-o", "--out")) == "--out"


def test_choice_pattern_and_ranges() -> None:
    pick = options.choice("-O2", "-Os", normalize=cc._opt_level)
    assert pick(_ctx(), _param("--opt"), "2") == "-O2"
    assert pick(_ctx(), _param("--opt"), "Os") == "-Os"
    with pytest.raises(CliError) as caught:
        pick(_ctx(), _param("--opt"), "O4")
    assert caught.value.message == "--opt: must be one of -O2, -Os, got 'O4'"
    plain_choice = options.choice("a", "b")
    assert plain_choice(_ctx(), _param("--x"), "b") == "b"
    with pytest.raises(CliError, match=r"^--x: must be one of a, b, got 'B'$"):
        plain_choice(_ctx(), _param("--x"), "B")
    name = options.pattern(r"[A-Z]+", "capitals")
    assert name(_ctx(), _param("--d"), "AB") == "AB"
    with pytest.raises(CliError) as caught:
        name(_ctx(), _param("--d"), "AB\nC")  # the whole text must match, newlines included
    assert caught.value.message == "--d: expected capitals, got 'AB\\nC'"
    define = options.pattern(r"[A-Z]+(=.*)?", "NAME or NAME=VALUE")
    assert define(_ctx(), _param("-D"), "A=1\n2") == "A=1\n2"  # a value may span lines
    half_open = options.float_range(0.0, 1.0, lo_open=True, unit="s")
    assert half_open(_ctx(), _param("--t"), 1.0) == 1.0
    with pytest.raises(CliError, match=r"^--t: must be in \(0, 1\] s, got 0"):
        half_open(_ctx(), _param("--t"), 0.0)
    assert options.seed()(_ctx(), _param("--seed"), 2**63 - 1) == 2**63 - 1
    assert options.sram_bytes()(_ctx(), _param("--sram-size"), 4096) == 4096
    with pytest.raises(CliError, match=r"^--sram-size: "):
        options.sram_bytes()(_ctx(), _param("--sram-size"), 4098)


@pytest.mark.parametrize(
    ("text", "expected"), [("2", "-O2"), ("O3", "-O3"), ("-Os", "-Os"), ("z", "-Oz"), ("-O9", "-O9"), ("2s", "2s")]
)
def test_opt_level_spellings(text: str, expected: str) -> None:
    assert cc._opt_level(text) == expected


# --- errors.py -------------------------------------------------------------------------------------


def test_run_guarded_maps_each_outcome_to_its_exit_code(capsys: pytest.CaptureFixture[str]) -> None:
    def raising(exc: BaseException):
        def main() -> object:
            raise exc

        return main

    assert errors.run_guarded(lambda: None) == exit_codes.OK
    assert errors.run_guarded(lambda: 7) == 7
    assert errors.run_guarded(lambda: True) == exit_codes.OK  # a bool is not an exit code
    assert errors.run_guarded(raising(CliError("--x: bad", code=exit_codes.PEER_LOST)), "robosoc t") == 5
    assert capsys.readouterr().err == "robosoc t: --x: bad\n"
    assert errors.run_guarded(raising(SystemExit(None))) == exit_codes.OK
    assert errors.run_guarded(raising(SystemExit(4))) == 4
    assert errors.run_guarded(raising(SystemExit("text"))) == exit_codes.USAGE
    assert errors.run_guarded(raising(KeyboardInterrupt()), "robosoc t") == exit_codes.INTERRUPTED
    assert capsys.readouterr().err == "robosoc t: interrupted\n"
    assert errors.run_guarded(raising(click.exceptions.Abort()), "robosoc t") == exit_codes.INTERRUPTED
    assert capsys.readouterr().err == "robosoc t: interrupted\n"
    assert errors.run_guarded(raising(ValueError("boom")), "robosoc t") == exit_codes.INTERNAL_ERROR
    err = capsys.readouterr().err
    assert "Traceback" in err and "ValueError: boom" in err
    assert err.endswith(f"robosoc t: internal error: {errors.REPORT}\n")
    broken = OSError(32, "Broken pipe")  # EPIPE as a plain OSError
    assert errors.run_guarded(raising(broken)) == exit_codes.BROKEN_PIPE
    assert errors.run_guarded(raising(OSError(2, "No such file"))) == exit_codes.INTERNAL_ERROR
    capsys.readouterr()


def test_click_errors_read_like_the_option_rules(capsys: pytest.CaptureFixture[str]) -> None:
    cmd = click.Command("noc", params=[click.Option(["-s", "--size"]), click.Argument(["file"])])
    ctx = click.Context(cmd, info_name="noc", parent=click.Context(click.Group("robosoc"), info_name="robosoc"))

    def bad(exc: BaseException):
        def main() -> object:
            raise exc

        return main

    param = cmd.params[0]
    code = errors.run_guarded(bad(click.BadParameter("Not A Size", ctx=ctx, param=param)))
    assert code == exit_codes.USAGE
    assert capsys.readouterr().err == "robosoc noc: --size: not A Size\n(see 'robosoc noc --help')\n"
    errors.run_guarded(bad(click.BadParameter("PWM is refused", ctx=ctx, param=param)))
    assert capsys.readouterr().err.startswith("robosoc noc: --size: PWM is refused\n")  # an acronym keeps its case
    errors.run_guarded(bad(click.MissingParameter(ctx=ctx, param=cmd.params[1])))
    assert capsys.readouterr().err.startswith("robosoc noc: missing argument FILE\n")
    errors.run_guarded(bad(click.MissingParameter(ctx=ctx, param=param)))
    assert capsys.readouterr().err.startswith("robosoc noc: missing option -s\n")
    errors.run_guarded(bad(click.BadParameter("Wrong", ctx=ctx, param=cmd.params[1])))
    assert capsys.readouterr().err.startswith("robosoc noc: FILE: wrong\n")
    errors.run_guarded(bad(click.UsageError("Got Two", ctx=None)))
    assert capsys.readouterr().err == "robosoc: got Two\n(see 'robosoc --help')\n"


def test_command_path_and_print_error(capsys: pytest.CaptureFixture[str]) -> None:
    root = click.Context(click.Group("anything"), info_name="python -m robosoc")
    sub = click.Context(click.Group("bench"), info_name="bench", parent=root)
    leaf = click.Context(click.Command("noc"), info_name="noc", parent=sub)
    assert errors.command_path(leaf) == "robosoc bench noc"
    assert errors.command_path(None) == "robosoc"
    errors.print_error("robosoc x", "[bold]y[/bold]")
    assert capsys.readouterr().err == "robosoc x: [bold]y[/bold]\n"


# --- console.py --------------------------------------------------------------------------------------


def test_consoles_off_a_terminal_do_not_wrap(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("COLUMNS", raising=False)
    out = console.make_console()
    assert out.width == console.PIPE_WIDTH and out.soft_wrap and not out.is_terminal
    assert console.make_console(min_width=300).width == 300
    assert console.make_console(stderr=True).stderr
    assert not console.make_console().stderr
    monkeypatch.setenv("COLUMNS", "120")
    assert console.make_console().width == 120
    monkeypatch.setenv("COLUMNS", "0")
    assert console.make_console().width == console.PIPE_WIDTH
    monkeypatch.setenv("COLUMNS", "wide")
    assert console.make_console().width == console.PIPE_WIDTH


def test_plain_and_note_print_brackets_as_written() -> None:
    buffer = io.StringIO()
    out = Console(file=buffer, width=200, color_system="standard", force_terminal=True, highlight=False)
    console.plain(out, "pip install 'robosoc[video]'")
    console.note(out, "[bold]x")
    text = buffer.getvalue()
    assert "pip install 'robosoc[video]'" in text and "[bold]x" in text
    assert "\x1b[33m[bold]x" in text  # the note in yellow


# --- files.py ----------------------------------------------------------------------------------------


def test_input_files_and_folders(tmp_path: Path) -> None:
    good = tmp_path / "a.toml"
    good.write_text("x = 1\n")
    assert files.input_file(good, "--scenario") == good
    assert files.read_toml(good, "--scenario") == {"x": 1}
    with pytest.raises(CliError) as caught:
        files.input_file(tmp_path, "--scenario", "TOML file")
    assert caught.value.message == f"--scenario: {tmp_path}: is a folder, expected a TOML file"
    with pytest.raises(CliError) as caught:
        files.input_file(tmp_path, None, "ELF file")
    assert caught.value.message == f"{tmp_path}: is a folder, expected an ELF file"
    with pytest.raises(CliError) as caught:
        files.input_file(tmp_path / "none.toml", "--scenario")
    assert caught.value.message == f"--scenario: {tmp_path / 'none.toml'}: file not found"
    with pytest.raises(CliError) as caught:
        files.input_dir(good, "--include")
    assert caught.value.message == f"--include: {good}: is a file, expected a folder"
    with pytest.raises(CliError) as caught:
        files.input_dir(tmp_path / "none", "--include")
    assert caught.value.message == f"--include: {tmp_path / 'none'}: folder not found"
    assert files.input_dir(tmp_path, "--include") == tmp_path
    bad = tmp_path / "bad.toml"
    bad.write_text("x = = 1\n")
    with pytest.raises(CliError, match=rf"^--chip: {bad}: invalid TOML: "):
        files.read_toml(bad, "--chip")
    latin = tmp_path / "latin.txt"
    latin.write_bytes(b"ab\xe9")
    with pytest.raises(CliError) as caught:
        files.read_text(latin, None)
    assert caught.value.message == f"{latin}: not UTF-8 text (byte 0xe9 at offset 2): expected a text file"


def test_outputs_are_checked_and_leave_nothing_behind(tmp_path: Path) -> None:
    target = tmp_path / "new" / "stats.json"
    assert files.output_file(target, "--stats") == target
    assert target.parent.is_dir() and not target.exists()  # the check leaves no file behind
    kept = tmp_path / "kept.json"
    kept.write_text("old")
    assert files.output_file(kept, "--stats") == kept and kept.read_text() == "old"
    assert files.output_file(tmp_path / "p.PNG", "--plot", suffixes=(".png", ".pdf"))
    with pytest.raises(CliError) as caught:
        files.output_file(tmp_path / "p.jpeg", "--plot", suffixes=(".png", ".pdf"))
    assert caught.value.message == f"--plot: {tmp_path / 'p.jpeg'}: must end in .png or .pdf"
    with pytest.raises(CliError) as caught:
        files.output_file(kept, "--stats", inputs=[tmp_path / "other", kept])
    assert caught.value.message == f"--stats: {kept}: is also an input of this command: it would be overwritten"
    with pytest.raises(CliError) as caught:
        files.output_file("", "--stats")
    assert caught.value.message == "--stats: : is a folder, expected a file name"
    with pytest.raises(CliError) as caught:
        files.output_file(kept / "x.json", None)
    assert caught.value.message == f"{kept / 'x.json'}: cannot create folder {kept}: a file is in the way"
    folder = tmp_path / "made" / "deep"
    assert files.output_dir(folder, "--out") == folder and folder.is_dir() and list(folder.iterdir()) == []
    with pytest.raises(CliError) as caught:
        files.output_dir(kept, "--out")
    assert caught.value.message == f"--out: {kept}: is a file, expected a folder"
    with pytest.raises(CliError) as caught:
        files.output_dir(folder, "--out", inputs=[folder])
    assert caught.value.message == f"--out: {folder}: is also an input of this command"


# --- run.py and sweep.py: exit words, summaries, scheduler addresses ------------------------------------


def test_exit_status_of_run() -> None:
    status, program = exit_codes.EXIT_CODE_STATUS, exit_codes.EXIT_CODE_PROGRAM
    assert run.exit_status(0, status) == exit_codes.OK
    assert run.exit_status(1, status) == exit_codes.PROGRAM_FAILED
    assert run.exit_status(0x100, status) == exit_codes.PROGRAM_FAILED
    assert run.exit_status(0x1FF, program) == 0xFF
    assert run.exit_status(0x100, program) == 0
    assert run._exit_note(0x100, program) == (
        "the program's exit code 256 (0x00000100) reads as 0 modulo 256; use --exit-code status"
    )
    assert run._exit_note(0x100, status) is None
    assert run._exit_note(0, program) is None
    assert run._exit_note(0x101, program) is None
    assert run._code_text(255) == "255"
    assert run._code_text(256) == "256 (0x00000100)"
    assert run._errata_summary({"mulhsu": 2, "div": 0, "sra": 1}) == ", RTL errata: mulhsu 2, sra 1"
    assert run._errata_summary({"mulhsu": 0}) == ""


@pytest.mark.parametrize(
    ("text", "address"),
    [
        ("local", "local"),
        ("host:8786", "tcp://host:8786"),
        ("tls://10.0.0.1:1", "tls://10.0.0.1:1"),
        ("ws://h:65535", "ws://h:65535"),
        ("wss://h:80", "wss://h:80"),
        ("inproc://h:9", "inproc://h:9"),
        ("tcp://[::1]:8786", "tcp://[::1]:8786"),  # the port after the last colon
    ],
)
def test_dask_addresses(text: str, address: str) -> None:
    assert sweep._dask_address(text) == address


@pytest.mark.parametrize(
    ("text", "reason"),
    [
        ("ftp://h:80", "expected 'local' or a scheduler address such as tcp://host:8786, got 'ftp://h:80'"),
        ("h", "expected 'local' or a scheduler address such as tcp://host:8786, got 'h'"),
        (":8786", "expected 'local' or a scheduler address such as tcp://host:8786, got ':8786'"),
        ("h:", "expected 'local' or a scheduler address such as tcp://host:8786, got 'h:'"),
        ("h:0", "port must be 1..65535, got 0"),
        ("h:65536", "port must be 1..65535, got 65536"),
    ],
)
def test_bad_dask_addresses(text: str, reason: str) -> None:
    with pytest.raises(ValueError) as caught:
        sweep._dask_address(text)
    assert str(caught.value) == reason
    with pytest.raises(CliError) as refused:
        sweep._check_dask(_ctx(), _param("--dask"), text)
    assert refused.value.message == f"--dask: {reason}"
    assert sweep._check_dask(_ctx(), _param("--dask"), None) is None


def test_cli_errors_are_usage_errors_by_default() -> None:
    assert CliError("x").code == exit_codes.USAGE
    assert options.fail("--a", "b").message == "--a: b"


# --- link_options.py and link_report.py: the decoupled mode's options and endings ------------------------


def test_link_options_name_the_option() -> None:
    from robosoc.cli import link_options
    from robosoc.config.link import LinkConfig
    from robosoc.cosim.link import Address

    peer = link_options.address_option(any_port=False)
    bind = link_options.address_option(any_port=True)
    assert peer(_ctx(), _param("--peer"), "127.0.0.1:9") == Address("127.0.0.1", 9)
    assert bind(_ctx(), _param("--bind"), "127.0.0.1:0") == Address("127.0.0.1", 0)
    assert peer(_ctx(), _param("--peer"), None) is None
    assert peer(_ctx(resilient=True), _param("--peer"), "nonsense") is None
    with pytest.raises(CliError) as caught:
        peer(_ctx(), _param("--peer"), "127.0.0.1:0")
    assert caught.value.message == "--peer: the port must be between 1 and 65535, got '127.0.0.1:0'"
    faults = link_options._faults(_ctx(), _param("--faults"), "loss=0.25")
    assert faults is not None and faults.as_dict()["loss"] == 0.25
    assert link_options._faults(_ctx(), _param("--faults"), None) is None
    assert link_options._faults(_ctx(resilient=True), _param("--faults"), "loss=9") is None
    with pytest.raises(CliError, match=r"^--faults: "):
        link_options._faults(_ctx(), _param("--faults"), "loss=2")
    config = link_options.link_config("fast", "linear", faults, 3, 0.5, 9.0)
    assert (config.pace, config.hold, config.resend, config.peer_timeout_s, config.connect_timeout_s) == (
        "fast",
        "linear",
        3,
        0.5,
        9.0,
    )
    assert config.faults == faults and link_options.link_config().faults.any is False
    assert link_options.link_config() == LinkConfig()  # the defaults are the configuration's own
    for kwargs, message in (
        ({"peer_timeout": 0.01}, "--peer-timeout: must be between 0.05 and 3600 s, got 0.01"),
        ({"connect_timeout": 4000.0}, "--connect-timeout: must be between 0.05 and 3600 s, got 4000.0"),
        ({"pace": "slow"}, "--pace: must be one of realtime, fast, got 'slow'"),
        ({"pace": "a: b"}, "--pace: must be one of realtime, fast, got 'a: b'"),  # a colon in the value
        ({"resend": 99}, "--resend: must be between 0 and 8, got 99"),
    ):
        with pytest.raises(CliError) as caught:
            link_options.link_config(**kwargs)
        assert caught.value.message == message


def test_end_of_side_exit_codes() -> None:
    from robosoc.cli.link_report import end_of_side
    from robosoc.cosim.decoupled_physics import Ended

    assert end_of_side(Ended.DONE, "", "out") is None
    for ended, code in (
        (Ended.INTERRUPTED, exit_codes.INTERRUPTED),
        (Ended.PEER_LOST, exit_codes.PEER_LOST),
        (Ended.PEER_ENDED, exit_codes.PEER_LOST),
        (Ended.MISMATCH, exit_codes.USAGE),
    ):
        with pytest.raises(CliError) as caught:
            end_of_side(ended, "the chip went quiet", "runs/x")
        assert caught.value.code == code
        first = "interrupted" if ended == Ended.INTERRUPTED else "the chip went quiet"
        assert caught.value.message == f"{first}; what was done is in runs/x"
        with pytest.raises(CliError) as caught:
            end_of_side(ended, "the chip went quiet", "")
        assert caught.value.message == first


def test_link_counts_table() -> None:
    from robosoc.cli.link_report import print_link_counts
    from robosoc.cosim.link_counters import COUNTER_NAMES

    buffer = io.StringIO()
    out = Console(file=buffer, width=200)
    counts = dict(zip(COUNTER_NAMES, range(1, len(COUNTER_NAMES) + 1), strict=True))
    print_link_counts(
        out,
        {
            "to chip": {"sent": 9, "injected": {"lost": 2, "garbage": 1}},
            "from chip": counts,
        },
    )
    lines = buffer.getvalue().splitlines()
    assert lines[0].rstrip() == "datagrams"  # the title on the left, the table without padding at its edge
    assert lines[1].startswith("direction") and lines[2].startswith("to chip")
    # the figures end under their headings (right-aligned), the injected faults too
    for k, name in enumerate(COUNTER_NAMES):
        end = lines[1].index(name) + len(name)
        assert lines[3][:end].rstrip().endswith(str(k + 1)) and lines[3][end : end + 1] in (" ", ""), name
    assert lines[2].rstrip().endswith("2/0/0/0/1") and len(lines[2].rstrip()) == len(lines[1].rstrip())
    assert lines[1].split() == ["direction", *COUNTER_NAMES, "injected", "(lost/dupl/reor/trun/garb)"]
    assert lines[2].split() == ["to", "chip", "9", *["-"] * (len(COUNTER_NAMES) - 1), "2/0/0/0/1"]
    assert lines[3].split() == ["from", "chip", *[str(v) for v in counts.values()], "-"]


# --- closed pipes: rich's exit 1 and Python's final flush -----------------------------------------------


def test_a_closed_pipe_under_rich_is_141_and_stdout_goes_quiet(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import os
    import sys

    first = (tmp_path / "stdout.txt").open("w")
    monkeypatch.setattr(sys, "stdout", first)
    assert errors._stdout_identity() == (os.fstat(first.fileno()).st_dev, os.fstat(first.fileno()).st_ino)
    null = open(os.devnull, "w")  # noqa: SIM115  (closed at the end)

    def rich_exit() -> object:  # what rich does on a closed pipe: stdout to /dev/null, exit 1
        sys.stdout = null
        raise SystemExit(1)

    assert errors.run_guarded(rich_exit) == exit_codes.BROKEN_PIPE
    assert errors._rich_closed_pipe(None) is False  # stdout is /dev/null now, but nothing says it changed
    monkeypatch.setattr(sys, "stdout", first)
    assert errors.run_guarded(lambda: (_ for _ in ()).throw(SystemExit(1))) == exit_codes.INTERNAL_ERROR
    assert errors._rich_closed_pipe(None) is False
    # a closed pipe seen by Python: stdout's descriptor now writes nowhere
    assert errors.run_guarded(lambda: (_ for _ in ()).throw(BrokenPipeError())) == exit_codes.BROKEN_PIPE
    os.write(first.fileno(), b"lost\n")
    assert (tmp_path / "stdout.txt").read_text() == ""
    second = (tmp_path / "second.txt").open("w")
    monkeypatch.setattr(sys, "stdout", second)
    out = console._Console(file=io.StringIO())
    with pytest.raises(BrokenPipeError):
        out.on_broken_pipe()
    assert out.quiet
    os.write(second.fileno(), b"lost\n")
    assert (tmp_path / "second.txt").read_text() == ""
    monkeypatch.setattr(sys, "stdout", io.StringIO())  # no descriptor at all: nothing to silence, no error
    assert errors._stdout_identity() is None
    errors._silence_stdout()
    for handle in (first, second, null):
        handle.close()


def test_consoles_on_a_terminal_wrap_at_its_width_but_not_below_min_width(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TTY_COMPATIBLE", "1")  # rich: treat the output as a terminal
    monkeypatch.setenv("COLUMNS", "60")
    wide = console.make_console(min_width=100)
    assert wide.is_terminal and wide.width == 100 and not wide.soft_wrap
    narrow = console.make_console(min_width=40)
    assert narrow.is_terminal and narrow.width == 60
    assert console.make_console(stderr=True, min_width=100).stderr


def test_os_error_reasons_and_articles() -> None:
    assert files._reason(OSError(13, "Permission denied")) == "permission denied"
    assert files._reason(OSError("no strerror here")) == "no strerror here"
    assert files._article("ELF file") == "an ELF file" and files._article("TOML file") == "a TOML file"
    assert files._article("x-ray") == "a x-ray"


# --- gdb_option.py and files.load_program ------------------------------------------------------------


@pytest.mark.parametrize(
    ("gdb", "tile", "one_core", "trace", "profile", "message"),
    [
        (None, "0,1", False, 0, 0, "--tile X,Y picks the tile to debug: it goes with --gdb PORT"),
        (1234, "0,1", True, 0, 0, "--tile X,Y needs the MPSoC (--mesh WxH or --chip FILE)"),
        (1234, None, False, 100, 0, "--gdb cannot be combined with --trace or --profile"),
        (1234, None, True, 0, 10, "--gdb cannot be combined with --trace or --profile"),
    ],
)
def test_gdb_option_combinations_that_cannot_work_are_usage_errors(
    gdb: int | None, tile: str | None, one_core: bool, trace: int, profile: int, message: str,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    with pytest.raises(typer.Exit) as caught:
        gdb_option.check_gdb_options(gdb, tile, one_core, trace, profile)
    assert caught.value.exit_code == exit_codes.USAGE
    assert capsys.readouterr().err == f"robosoc run: {message}\n"


@pytest.mark.parametrize(("gdb", "tile", "one_core"), [(None, None, True), (1234, None, True), (0, "1,0", False)])
def test_gdb_option_combinations_that_work_pass(gdb: int | None, tile: str | None, one_core: bool) -> None:
    gdb_option.check_gdb_options(gdb, tile, one_core, 0, 0)


@pytest.fixture(scope="module")
def small_elf(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from robosoc.toolchain import build_elf

    src = tmp_path_factory.mktemp("prog") / "tiny.c"
    src.write_text("int main(void) { return 7; }\n")
    return build_elf([src], mul=True)


def test_load_program_places_segments_in_the_regions_or_names_the_one_that_does_not_fit(small_elf: Path) -> None:
    from robosoc.chip.core_state import SRAM_BASE
    from robosoc.program.elf import Region

    program = files.load_program(small_elf)  # no regions: any address
    first = min(addr for addr, _ in program.segments)
    assert first == SRAM_BASE and program.entry == SRAM_BASE
    assert files.load_program(small_elf, None, [Region(SRAM_BASE, 1 << 20, "sram")]).entry == program.entry
    tiny = [Region(SRAM_BASE, 16, "sram")]  # 16 bytes: the code does not fit
    with pytest.raises(CliError) as caught:
        files.load_program(small_elf, None, tiny)
    assert caught.value.message.startswith(f"{small_elf}: segment 0 at 0x{SRAM_BASE:08x}-")
    assert caught.value.message.endswith(
        f"is outside the allowed memory (sram 0x{SRAM_BASE:08x}-0x{SRAM_BASE + 15:08x})"
    )
    with pytest.raises(CliError) as caught:
        files.load_program(small_elf, "--program", tiny)
    assert caught.value.message.startswith(f"--program: {small_elf}: segment 0 ")


def test_load_program_errors_name_the_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    text = tmp_path / "notes.txt"
    text.write_text("not an executable\n")
    with pytest.raises(CliError, match=rf"^{text}: "):
        files.load_program(text)
    with pytest.raises(CliError) as caught:
        files.load_program(tmp_path / "none.elf", "--program")
    assert caught.value.message == f"--program: {tmp_path / 'none.elf'}: file not found"
    with pytest.raises(CliError) as caught:
        files.load_program(tmp_path, None)
    assert caught.value.message == f"{tmp_path}: is a folder, expected an ELF file"

    def parser_trips(path: object, regions: object = None) -> None:
        raise IndexError("index out of range")

    monkeypatch.setattr("robosoc.program.elf.load_elf", parser_trips)
    with pytest.raises(CliError) as caught:
        files.load_program(text, "--program")
    assert caught.value.message == f"--program: {text}: malformed ELF file (IndexError: index out of range)"
    with pytest.raises(CliError) as caught:
        files.load_program(text)
    assert caught.value.message == f"{text}: malformed ELF file (IndexError: index out of range)"


def test_without_a_null_device_to_compare_rich_is_not_taken_for_a_closed_pipe(monkeypatch: pytest.MonkeyPatch) -> None:
    import os
    import sys

    null = open(os.devnull, "w")  # noqa: SIM115  (closed at the end)
    real_stat = os.stat
    try:
        monkeypatch.setattr(sys, "stdout", null)  # stdout changed to the null device ...
        assert errors._rich_closed_pipe((-1, -1)) is True

        def no_null(path, *args, **kwargs):  # type: ignore[no-untyped-def]
            if path == os.devnull:
                raise PermissionError(path)
            return real_stat(path, *args, **kwargs)

        monkeypatch.setattr(errors.os, "stat", no_null)  # ... but it cannot be told from any other file
        assert errors._rich_closed_pipe((-1, -1)) is False
    finally:
        monkeypatch.undo()
        null.close()
