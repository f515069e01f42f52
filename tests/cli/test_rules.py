"""One test per rule of docs/cli.md: option names in messages, outputs checked before work, exit
codes, the library checking the same ranges, output that survives a pipe, warnings kept inside."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import warnings
from pathlib import Path

import pytest
import typer.main
from typer.testing import CliRunner

from robosoc.cli import app, exit_codes

runner = CliRunner()


def invoke(*args: object):
    return runner.invoke(app, [str(a) for a in args])


def lines(result) -> list[str]:
    return result.output.splitlines()


# --- option names in messages, the configuration validator's style ------------------------------


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["fly", "--seed", "-1"], "robosoc fly: --seed: must be between 0 and 2**63-1, got -1"),
        (
            ["fly", "--seconds", "0.0015", "--no-out"],
            "robosoc fly: --seconds: must be a whole number of 1 ms physics steps, got 0.0015",
        ),
        (
            ["fly", "--seconds", "0.005", "--no-out"],
            "robosoc fly: --seconds: a flight lasts at least one sensor period (0.01 s at 100 Hz), got 0.005 s",
        ),
        (["fly", "--out", "x", "--no-out"], "robosoc fly: --out: cannot be combined with --no-out"),
        (
            ["bench", "chip", "--cycles", "-5"],
            "robosoc bench chip: --cycles: must be between 1 and 10**10 cycles, got -5",
        ),
        (
            ["bench", "physics", "--seconds", "nan"],
            "robosoc bench physics: --seconds: must be a finite number, got nan",
        ),
        (["bench", "noc", "--rates", "0.1,2"], "robosoc bench noc: --rates: must be in (0, 1], got 2 (in '0.1,2')"),
        (["bench", "core", "--runs", "0"], "robosoc bench core: --runs: must be between 1 and 1000, got 0"),
    ],
)
def test_errors_name_the_option_as_typed(args: list[str], message: str) -> None:
    result = invoke(*args)
    assert result.exit_code == exit_codes.USAGE
    assert message in lines(result)
    assert "duration_s" not in result.output and "Traceback" not in result.output


def test_run_errors_name_options_and_files(elves: dict[str, Path], bad_paths: dict[str, Path]) -> None:
    ok, loop = elves["ok"], elves["loop"]
    cases = {
        ("--max-cycles", "-5"): "robosoc run: --max-cycles: must be between 1 and 2**62 cycles, got -5",
        ("--max-cycles", str(10**30)): f"robosoc run: --max-cycles: must be between 1 and 2**62 cycles, got {10**30}",
        ("--sram-size", str(0xA000_0000)): "robosoc run: --sram-size: must be between 4096 and 2**30 bytes, "
        "got 2684354560",
        ("--off", "5,5"): "robosoc run: --off: (5, 5) is outside the 2x2 mesh",
        ("--off", "1,0", "--off", "0,1", "--off", "1,1"): "robosoc run: --off: no core tile left to run on the 2x2 "
        "mesh (I/O tile (0, 0), powered off: [(1, 0), (0, 1), (1, 1)])",
        ("--errata", "hardware"): "robosoc run: --errata: must be one of spec, rtl, got 'hardware'",
        ("--chip", str(bad_paths["dir"])): f"robosoc run: --chip: {bad_paths['dir']}: is a folder, expected a "
        "TOML file",
    }
    for extra, message in cases.items():
        result = invoke("run", loop, *extra)
        assert result.exit_code == exit_codes.USAGE, (extra, result.output)
        assert message in lines(result), (extra, result.output)
    result = invoke("run", bad_paths["binary"])
    assert result.exit_code == 2 and f"robosoc run: {bad_paths['binary']}: not an ELF file" in result.output
    result = invoke("run", ok, "--stats", bad_paths["under_file"])
    assert (
        result.exit_code == 2 and "robosoc run: --stats:" in result.output and "a file is in the way" in result.output
    )


def test_fly_refuses_bad_files_before_flying(bad_paths: dict[str, Path]) -> None:
    for args, reason in [
        (["--scenario", bad_paths["dir"]], "is a folder, expected a TOML file"),
        (["--scenario", bad_paths["binary"]], "not UTF-8 text (byte 0x80 at offset 128): expected a TOML file"),
        (["--scenario", bad_paths["missing"]], "no such file or folder"),
        (["--out", bad_paths["file"]], "is a file, expected a folder"),
    ]:
        result = invoke("fly", "--seconds", "0.01", *args)
        assert result.exit_code == 2, result.output
        assert f"robosoc fly: {args[0]}: {args[1]}: {reason}" in lines(result)
        assert "flying scenario" not in result.output


def test_usage_errors_from_the_parser_use_the_same_style() -> None:
    assert (
        "robosoc run: --max-cycles: input should be a valid integer"
        in invoke("run", "x.elf", "--max-cycles", "abc").output
    )
    result = invoke("run")
    assert result.exit_code == 2 and "robosoc run: missing argument PROGRAMS" in lines(result)
    result = invoke("cc", "x.c")
    assert result.exit_code == 2 and "robosoc cc: missing option --output" in lines(result)
    result = invoke("bench", "noc", "--nope")
    assert result.exit_code == 2 and "robosoc bench noc: no such option: --nope" in lines(result)


# --- output paths are checked before any long work --------------------------------------------


def _forbid(monkeypatch: pytest.MonkeyPatch, target: str) -> None:
    def called(*args, **kwargs):
        raise AssertionError(f"{target} ran although an output path is bad")

    monkeypatch.setattr(target, called)


def test_output_paths_are_checked_before_the_work(
    elves: dict[str, Path], bad_paths: dict[str, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    src = tmp_path / "ok.c"
    src.write_text("int main(void) { return 0; }\n")
    for target in (
        "robosoc.chip.single.SingleCoreSoC.run",
        "robosoc.chip.mpsoc.MPSoC.run",
        "robosoc.toolchain.build_elf",
        "robosoc.control.flight.fly",
        "robosoc.benchmarks.noc.run_noc_benchmark",
    ):
        _forbid(monkeypatch, target)
    read_only = bad_paths["read_only"]
    cases = [
        (["run", elves["loop"], "--stats", read_only], "--stats"),
        (["run", elves["loop"], "--mesh", "2x2", "--stats", bad_paths["dir"]], "--stats"),
        (["run", elves["ok"], "--stats", elves["ok"]], "--stats"),  # would overwrite the program
        (["cc", src, "-o", bad_paths["dir"]], "--output"),
        (["cc", src, "-o", src], "--output"),
        (["fly", "--out", read_only.parent / "flights"], "--out"),
        (["fly", "--no-out", "--video", bad_paths["under_file"].with_suffix(".mp4")], "--video"),
        (["bench", "noc", "--plot", read_only.with_suffix(".png")], "--plot"),
        (["bench", "noc", "--plot", tmp_path / "latency.jpeg"], "--plot"),
    ]
    for args, option in cases:
        result = invoke(*args)
        assert result.exit_code == exit_codes.USAGE, (args, result.output)
        assert result.output.startswith(f"robosoc {args[0]}") and f" {option}: " in result.output, result.output


def test_missing_output_folders_are_created(elves: dict[str, Path], tmp_path: Path) -> None:
    stats = tmp_path / "new" / "deeper" / "stats.json"
    result = invoke("run", elves["ok"], "--stats", stats)
    assert result.exit_code == 0, result.output
    assert json.loads(stats.read_text())["exit_code"] == 0
    assert not list(stats.parent.glob("*.partial"))


# --- exit codes -----------------------------------------------------------------------------------


def test_run_exit_codes(elves: dict[str, Path], tmp_path: Path) -> None:
    def code(*args: object) -> int:
        return invoke("run", *args).exit_code

    assert code(elves["ok"]) == exit_codes.OK
    result = invoke("run", elves["three"])
    assert result.exit_code == exit_codes.PROGRAM_FAILED and "; exit code 3" in result.output
    assert code(elves["three"], "--exit-code", "program") == 3
    for mode in ("status", "program"):  # a simulator stop is 3 in both modes
        budget = invoke("run", elves["loop"], "--max-cycles", "1000", "--exit-code", mode)
        assert budget.exit_code == exit_codes.SIMULATOR_STOP and "cycle budget of 1000 cycles" in budget.output
        fault = invoke("run", elves["fault"], "--exit-code", mode)
        assert fault.exit_code == exit_codes.SIMULATOR_STOP and "0x00000010" in fault.output
    assert code(elves["word"]) == exit_codes.PROGRAM_FAILED
    assert code(elves["word"], "--exit-code", "program") == 0x5A
    page = invoke("run", elves["page"], "--exit-code", "program")
    assert page.exit_code == 0 and "reads as 0 modulo 256; use --exit-code status" in page.output
    assert code(elves["page"]) == exit_codes.PROGRAM_FAILED
    stats = tmp_path / "chip.json"
    assert code(elves["word"], "--mesh", "2x2", "--stats", stats) == exit_codes.PROGRAM_FAILED
    assert set(json.loads(stats.read_text())["exit_codes"].values()) == {0xD114CE5A}
    assert code(elves["ok"], "--mesh", "2x2") == exit_codes.OK
    assert code(elves["loop"], "--mesh", "2x2", "--max-cycles", "2000") == exit_codes.SIMULATOR_STOP


def test_exit_codes_of_the_real_process(elves: dict[str, Path]) -> None:
    def run(*args: object) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, "-m", "robosoc", *map(str, args)], capture_output=True, text=True, timeout=120
        )

    assert run("run", elves["loop"], "--max-cycles", "100").returncode == exit_codes.SIMULATOR_STOP
    proc = run("fly", "--seed", "-1")
    assert proc.returncode == exit_codes.USAGE and proc.stdout == ""
    assert proc.stderr == "robosoc fly: --seed: must be between 0 and 2**63-1, got -1\n"


@pytest.mark.parametrize(
    ("raised", "code", "text"),
    [
        (lambda: RuntimeError("boom"), exit_codes.INTERNAL_ERROR, "robosoc bench core: internal error: this is a bug"),
        (KeyboardInterrupt, exit_codes.INTERRUPTED, "robosoc bench core: interrupted"),
        (BrokenPipeError, exit_codes.BROKEN_PIPE, ""),
    ],
)
def test_internal_errors_interrupts_and_closed_pipes(monkeypatch, raised, code, text) -> None:
    def bench(**kwargs):
        raise raised()  # a fresh exception each run: the command marks the one it saw with its name

    monkeypatch.setattr("robosoc.benchmarks.core.run_core_benchmark", bench)
    result = invoke("bench", "core")
    assert result.exit_code == code
    assert text in result.output
    assert ("Traceback" in result.output) == (code == exit_codes.INTERNAL_ERROR)
    if code == exit_codes.INTERNAL_ERROR:
        assert "RuntimeError: boom" in result.output and "please report it" in result.output


def test_an_interrupted_run_prints_its_summary(elves: dict[str, Path], monkeypatch: pytest.MonkeyPatch) -> None:
    def interrupted(self, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("robosoc.chip.single.SingleCoreSoC.run", interrupted)
    result = invoke("run", elves["ok"])
    assert result.exit_code == exit_codes.INTERRUPTED
    assert "robosoc: 3 cycles, 0 instructions" in result.output and "robosoc run: interrupted" in result.output


def _commands(command, path=()):
    subcommands = getattr(command, "commands", None)
    if not subcommands:
        yield path
    for name, sub in (subcommands or {}).items():
        yield from _commands(sub, (*path, name))


def test_help_documents_the_exit_codes() -> None:
    for path in _commands(typer.main.get_command(app)):
        text = " ".join(invoke(*path, "--help").output.split())
        assert "Exit codes: 0" in text and "2 usage or input error" in text and "130 interrupted" in text, path
    text = " ".join(invoke("run", "--help").output.split())
    assert "3 the simulator stopped the program" in text and "4 the program exited with a non-zero code" in text


# --- the library checks the same ranges -----------------------------------------------------------


def test_library_functions_check_their_arguments(elves: dict[str, Path]) -> None:
    from robosoc.benchmarks.chip import run_chip_benchmark
    from robosoc.benchmarks.core import run_core_benchmark
    from robosoc.benchmarks.noc import run_noc_benchmark
    from robosoc.benchmarks.physics import run_physics_benchmark
    from robosoc.chip.mpsoc import MPSoC
    from robosoc.chip.single import SingleCoreSoC, run_elf
    from robosoc.config.chip import ChipConfig
    from robosoc.config.scenario import ScenarioConfig
    from robosoc.program.elf import load_elf

    soc = SingleCoreSoC()
    soc.load(load_elf(elves["loop"], soc.regions()))
    with pytest.raises(ValueError, match=r"^max_cycles: must be between 1 and 2\*\*62 cycles, got -5$"):
        soc.run(max_cycles=-5)
    with pytest.raises(ValueError, match="max_cycles: must be between"):
        soc.run(max_cycles=2**70)
    with pytest.raises(ValueError, match="chunk: must be between"):
        soc.run(max_cycles=100, chunk=0)
    with pytest.raises(ValueError, match="max_cycles: expected an integer"):
        soc.run(max_cycles=True)
    with pytest.raises(ValueError, match="sram_size: must be between 4 and 2684354560 bytes"):
        SingleCoreSoC(sram_size=0xA000_0000 + 4)  # would reach the devices at 0xe0000000
    with pytest.raises(ValueError, match="max_cycles: must be between"):
        MPSoC(ChipConfig()).run(max_cycles=0)
    with pytest.raises(ValueError, match="seconds: must be a finite number"):
        run_physics_benchmark(math.nan, 1)
    with pytest.raises(ValueError, match="cycles: must be between"):
        run_chip_benchmark(cycles=-5)
    with pytest.raises(ValueError, match="runs: must be >= 1"):
        run_core_benchmark(runs=0)
    with pytest.raises(ValueError, match="rates: must be a finite number"):
        run_noc_benchmark(rates=(math.nan,))
    with pytest.raises(ValueError, match=r"rates: must be in \(0, 1\]"):
        run_noc_benchmark(rates=(2.0,))
    with pytest.raises(ValueError, match="seed: must be between 0"):
        ScenarioConfig(seed=-1)
    assert run_elf(elves["word"]).exit_code == 0xD114CE5A  # the exit word, unsigned
    chip = MPSoC(ChipConfig())
    chip.load_all(load_elf(elves["word"], chip.regions()))
    assert set(chip.run().exit_codes.values()) == {0xD114CE5A}


def test_library_config_readers_name_bad_files(bad_paths: dict[str, Path]) -> None:
    from robosoc.chip.energy import EnergyModel
    from robosoc.config import ConfigError, load_toml
    from robosoc.config.scenario import ScenarioConfig

    with pytest.raises(ConfigError, match="is a folder"):
        load_toml(ScenarioConfig, bad_paths["dir"])
    with pytest.raises(ConfigError, match="not UTF-8"):
        load_toml(ScenarioConfig, bad_paths["binary"])
    with pytest.raises(ConfigError, match="not UTF-8"):
        EnergyModel.load(bad_paths["binary"])


# --- output that survives a pipe, brackets printed as written ------------------------------------


def test_piped_output_keeps_long_paths_and_brackets(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from robosoc.physics import render

    def no_backend():
        raise render.RenderUnavailable("no OpenGL here; MP4 needs pip install 'robosoc[video]'")

    monkeypatch.setattr(render, "find_backend", no_backend)
    out = tmp_path / ("a folder name long enough that an 80-column console would wrap it " * 2).strip() / "run[1]"
    result = invoke("fly", "--seconds", "0.02", "--out", out, "--video", tmp_path / "flight.mp4")
    assert result.exit_code == 0, result.output
    files = "scenario.toml, flight.csv, summary.json, flight.png, flight.mcap, jobs.csv, chip-trace.json, report.html"
    assert f"run folder: {out} ({files})" in lines(result)
    assert "no video: no OpenGL here; MP4 needs pip install 'robosoc[video]'" in lines(result)
    assert any(line.startswith("flying scenario default for 0.02 s") and line.endswith("Hz") for line in lines(result))


def test_error_messages_print_brackets_literally(elves: dict[str, Path]) -> None:
    result = invoke("run", elves["ok"], "--off", "[1],[bold]")
    assert "robosoc run: --off: expected X,Y such as 1,1, got '[1],[bold]'" in lines(result)


# --- warnings stay inside the command ---------------------------------------------------------------


def test_run_reports_errata_itself_and_leaves_warning_filters_alone(elves: dict[str, Path]) -> None:
    before = list(warnings.filters)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        single = invoke("run", elves["mulhsu"])
        chip = invoke("run", elves["mulhsu"], "--mesh", "2x2")
    assert single.exit_code == chip.exit_code == 0, single.output + chip.output
    assert "RTL errata: mulhsu 1" in single.output and "MULHSU executed 1 times" in chip.output
    assert [w for w in caught if "MULHSU" in str(w.message)] == []
    assert warnings.filters == before
