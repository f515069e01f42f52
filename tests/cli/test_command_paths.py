"""Each command's own paths, run in-process over tiny programs and flights of a few samples.

What a command must do is read from docs/cli.md and the command's help: the exit codes of
cli/exit_codes.py, messages that name the option (or argument) as typed, and the files it writes,
read back with their own readers (json, csv, the mcap library, PNG's signature).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from robosoc.cli import app, exit_codes

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def invoke(*args: object):
    return CliRunner().invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def hello(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A program that prints "hi" then "a" and "b" (no newline after b) and exits with 5."""
    folder = tmp_path_factory.mktemp("hello")
    source = folder / "hello.c"
    source.write_text('#include "hf_print.h"\nint main(void) { hf_puts("hi\\na\\nb"); return 5; }\n')
    result = invoke("cc", source, "-o", folder / "hello.elf")
    assert result.exit_code == 0, result.output
    return folder / "hello.elf"


@pytest.fixture(scope="module")
def host_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The run folder of a 0.05 s flight of the host controller."""
    out = tmp_path_factory.mktemp("runs") / "host"
    result = invoke("fly", "--controller", "host", "--seconds", "0.05", "--out", out)
    assert result.exit_code == 0, result.output
    return out


# --- robosoc cc -----------------------------------------------------------------------------------


def test_cc_passes_defines_includes_and_level_to_the_compiler(tmp_path: Path) -> None:
    include = tmp_path / "inc"
    include.mkdir()
    (include / "value.h").write_text("#define VALUE 30\n")
    source = tmp_path / "sum.c"
    source.write_text('#include "value.h"\nint main(void) { return VALUE + RET; }\n')
    elf = tmp_path / "out" / "sum.elf"
    result = invoke("cc", source, "-o", elf, "-D", "RET=7", "-I", include, "-O", "s", "--no-mul")
    assert result.exit_code == 0, result.output
    assert result.stdout.strip() == str(elf) and elf.read_bytes()[:4] == b"\x7fELF"
    ran = invoke("run", elf, "--no-mul", "--exit-code", "program")
    assert ran.exit_code == 37, ran.output
    broken = tmp_path / "broken.c"
    broken.write_text("int main(void) { return missing; }\n")
    result = invoke("cc", broken, "-o", tmp_path / "b.elf")
    assert result.exit_code == exit_codes.USAGE and "missing" in result.output and "Traceback" not in result.output
    text = tmp_path / "notes.txt"
    text.write_text("int x;\n")
    result = invoke("cc", text, "-o", tmp_path / "t.elf")
    assert result.exit_code == exit_codes.USAGE
    assert f"robosoc cc: {text}: unsupported source type '.txt' (expected .c, .S or .s)" in result.output
    result = invoke("cc", source, "-o", tmp_path / "x.elf", "-I", tmp_path / "nowhere")
    assert result.exit_code == exit_codes.USAGE
    assert f"robosoc cc: --include: {tmp_path / 'nowhere'}: folder not found" in result.output


# --- robosoc run: trace, profile, the MPSoC's options --------------------------------------------------


def test_run_trace_stops_at_the_cycle_budget(hello: Path) -> None:
    full = invoke("run", hello, "--trace", "3")
    assert full.exit_code == exit_codes.PROGRAM_FAILED, full.output  # exit code 5 with --exit-code status
    trace = full.stderr.splitlines()
    assert trace[0].split()[:4] == ["cycle", "pc", "word", "instruction"]
    cycles = [int(line.split()[0]) for line in trace[1:4]]
    assert cycles == [3, 4, 5] and not re.match(r"\s*\d+\s+[0-9a-f]{8}\s", trace[4])
    assert full.stdout == "hi\na\nb"
    budget = invoke("run", hello, "--trace", "10", "--max-cycles", "5")
    assert budget.exit_code == exit_codes.SIMULATOR_STOP, budget.output
    traced = [line for line in budget.stderr.splitlines()[1:] if re.match(r"\s*\d+\s+[0-9a-f]{8}\s", line)]
    assert [int(line.split()[0]) for line in traced] == [3, 4]  # the instruction ending at cycle 5 is the last


def test_run_trace_of_one_instruction_and_none_by_default(hello: Path) -> None:
    one = invoke("run", hello, "--trace", "1")
    lines = one.stderr.splitlines()
    assert lines[0].split()[:4] == ["cycle", "pc", "word", "instruction"]
    assert int(lines[1].split()[0]) == 3 and not re.match(r"\s*\d+\s+[0-9a-f]{8}\s", lines[2])
    plain = invoke("run", hello)
    assert plain.stderr.startswith("robosoc: ") and plain.stderr.count("\n") == 1  # the summary line alone


def test_run_profile_of_every_cycle(hello: Path, tmp_path: Path) -> None:
    stats = tmp_path / "p1.json"
    assert invoke("run", hello, "--profile", "1", "--stats", stats).exit_code == exit_codes.PROGRAM_FAILED
    assert sum(json.loads(stats.read_text())["profile"].values()) == pytest.approx(1.0)


def test_run_profile_shares_go_to_stderr_and_stats(hello: Path, tmp_path: Path) -> None:
    stats = tmp_path / "p.json"
    result = invoke("run", hello, "--profile", "20", "--stats", stats, "--errata", "rtl", "--no-mul")
    assert result.exit_code == exit_codes.PROGRAM_FAILED, result.output
    record = json.loads(stats.read_text())
    assert set(record["profile"]) >= {"main", "_start"} and sum(record["profile"].values()) == pytest.approx(1.0)
    assert (record["exit_code"], record["mul"], record["errata_mode"], record["error"]) == (5, False, "rtl", None)
    assert record["program"] == str(hello) and record["warnings"] == []
    assert re.search(r"^\s+\d+\.\d%\s+\d+\s+main$", result.stderr, re.MULTILINE), result.stderr
    plain = tmp_path / "plain.json"
    assert invoke("run", hello, "--stats", plain).exit_code == exit_codes.PROGRAM_FAILED
    assert json.loads(plain.read_text())["profile"] is None


def test_run_on_a_chip_file_prefixes_each_tile_line(hello: Path, tmp_path: Path) -> None:
    chip = tmp_path / "chip.toml"
    chip.write_text('width = 3\nheight = 1\nerrata = "rtl"\n')
    stats = tmp_path / "chip.json"
    result = invoke("run", hello, "--chip", chip, "--stats", stats)
    assert result.exit_code == exit_codes.PROGRAM_FAILED, result.output
    for tile in ("1,0", "2,0"):  # the last line has no newline: printed whole at the end
        assert [line for line in result.stdout.splitlines() if line.startswith(f"[{tile}]")] == [
            f"[{tile}] hi",
            f"[{tile}] a",
            f"[{tile}] b",
        ]
    record = json.loads(stats.read_text())
    assert record["mesh"] == [3, 1] and record["errata_mode"] == "rtl" and record["error"] is None
    assert record["exit_codes"] == {"1,0": 5, "2,0": 5} and record["programs"] == [str(hello)]
    assert "robosoc: tile (1, 0): exited with exit code 5," in result.stderr
    spec = tmp_path / "spec.json"
    assert invoke("run", hello, "--chip", chip, "--errata", "spec", "--stats", spec).exit_code == 4
    assert json.loads(spec.read_text())["errata_mode"] == "spec"  # the option given wins over the file
    two = invoke("run", hello, hello, "--chip", chip, "--exit-code", "program")
    assert two.exit_code == 5, two.output


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--sram-size", "8192"], "--sram-size: has no effect with --chip: set tile.sram_bytes in {chip}"),
        (["--no-mul"], "--mul/--no-mul: has no effect with --chip: set tile.multiplier in {chip}"),
        (["--mul"], "--mul/--no-mul: has no effect with --chip: set tile.multiplier in {chip}"),
        (["--mesh", "2x2"], "--mesh: cannot be combined with --chip"),
        (["--profile", "10"], "--profile: works on one core (without --mesh/--chip/--off)"),
        (["--trace", "10"], "--trace: works on one core (without --mesh/--chip/--off)"),
        (
            ["PROGRAM", "PROGRAM", "PROGRAM"],
            "3 programs for 2 core tiles [(1, 0), (2, 0)]: give one program, or one per tile",
        ),
    ],
)
def test_run_refuses_what_the_chip_cannot_take(hello: Path, tmp_path: Path, extra: list[str], message: str) -> None:
    chip = tmp_path / "chip.toml"
    chip.write_text("width = 3\nheight = 1\n")
    args = [hello if a == "PROGRAM" else a for a in extra]
    result = invoke("run", *([] if "PROGRAM" in extra else [hello]), *args, "--chip", chip)
    assert result.exit_code == exit_codes.USAGE, result.output
    assert result.stderr.splitlines() == [f"robosoc run: {message.format(chip=chip)}"]


def test_the_chip_file_engine_runs_the_mesh_and_the_option_overrides_it(hello: Path, tmp_path: Path) -> None:
    chip = tmp_path / "chip.toml"
    chip.write_text('width = 3\nheight = 1\nengine = "jit"\n')
    runs = [invoke("run", hello, "--chip", chip), invoke("run", hello, "--chip", chip, "--engine", "interp")]
    assert (runs[0].exit_code, runs[0].stdout) == (runs[1].exit_code, runs[1].stdout) and runs[0].stdout
    chip.write_text('width = 3\nheight = 1\nengine = "fast"\n')
    result = invoke("run", hello, "--chip", chip)
    assert result.exit_code == exit_codes.USAGE
    assert "engine: must be one of 'interp', 'jit', 'auto', got 'fast'" in result.stderr and str(chip) in result.stderr


def test_run_several_programs_need_the_mpsoc_and_engines_run_without_gdb(hello: Path) -> None:
    result = invoke("run", hello, hello)
    assert result.exit_code == exit_codes.USAGE
    assert result.stderr.splitlines() == ["robosoc run: several programs need --mesh WxH or --chip FILE"]
    result = invoke("run", hello, "--engine", "auto", "--gdb", "0")
    assert result.exit_code == exit_codes.USAGE
    assert "robosoc run: --engine: auto runs without --gdb (the debugger uses the interpreter)" in result.stderr
    result = invoke("run", hello, "--off", "1,1", "--trace", "1")
    assert result.exit_code == exit_codes.USAGE and "robosoc run: --trace: works on one core" in result.stderr
    result = invoke("run", hello, "--off", "1,0", "--off", "0,1", "--off", "1,1")
    assert result.exit_code == exit_codes.USAGE and "robosoc run: --off: no core tile left" in result.stderr


def test_run_with_a_chip_without_core_tiles_names_the_file(hello: Path, tmp_path: Path) -> None:
    chip = tmp_path / "io-only.toml"
    chip.write_text("width = 2\nheight = 1\npowered_off = [[1, 0]]\n")
    result = invoke("run", hello, "--chip", chip)
    assert result.exit_code == exit_codes.USAGE, result.output
    assert result.stderr.startswith("robosoc run: --chip: no core tile left to run on the 2x1 mesh")


# --- robosoc serve: a side whose peer never answers ends with 5 and keeps its files ----------------


def test_serve_physics_without_a_chip(tmp_path: Path) -> None:
    out = tmp_path / "physics"
    args = ["serve", "physics", "--seconds", "0.01", "--connect-timeout", "0.05", "--bind", "127.0.0.1:0"]
    result = invoke(*args, "--pace", "fast", "--hold", "linear", "--out", out)
    assert result.exit_code == exit_codes.PEER_LOST, result.output
    assert re.search(r"pace fast, hold linear; listening on 127\.0\.0\.1:\d+$", result.stdout, re.MULTILINE)
    assert result.stderr == (
        f"robosoc serve physics: no hello from a chip within --connect-timeout 0.05 s; what was done is in {out}\n"
    )
    record = json.loads((out / "physics.json").read_text())
    assert record["complete"] is False and (out / "flight.csv").is_file()
    assert "direction  sent  received  lost  duplicated  reordered  truncated  garbage" in result.stdout
    assert f"files: {out}" in result.stdout
    quiet = invoke(*args, "--no-out", "--seed", "3")
    assert quiet.exit_code == exit_codes.PEER_LOST
    assert quiet.stderr == "robosoc serve physics: no hello from a chip within --connect-timeout 0.05 s\n"
    assert "seed 3" in quiet.stdout and "files:" not in quiet.stdout
    both = invoke(*args, "--no-out", "--out", out)
    assert both.exit_code == exit_codes.USAGE and "--out: cannot be combined with --no-out" in both.stderr


def test_serve_chip_without_a_physics_side(tmp_path: Path) -> None:
    out = tmp_path / "chip"
    args = ["serve", "chip", "--seconds", "0.01", "--connect-timeout", "0.05", "--peer", "127.0.0.1:9"]
    result = invoke(*args, "--out", out, "--seed", "4")
    assert result.exit_code == exit_codes.PEER_LOST, result.output
    assert result.stderr == (
        "robosoc serve chip: no sensor data from the physics at 127.0.0.1:9 within --connect-timeout 0.05 s; "
        f"what was done is in {out}\n"
    )
    record = json.loads((out / "chip.json").read_text())
    assert record["firmware"]["build"] == "fixed+mul" and record["ended"] == "peer_lost"
    assert "direction     sent  received" in result.stdout and "to physics" in result.stdout
    default = tmp_path / "default"
    default.mkdir()
    with pytest.MonkeyPatch.context() as patch:
        patch.chdir(default)
        named = invoke(*args, "--seed", "4")
    assert named.exit_code == exit_codes.PEER_LOST
    assert (default / "runs" / "serve-chip-default-s4" / "chip.json").is_file()


@pytest.mark.parametrize("side", ["physics", "chip"])
def test_serve_checks_the_flight_length(side: str, tmp_path: Path) -> None:
    result = invoke("serve", side, "--seconds", "0.005", "--no-out")
    assert result.exit_code == exit_codes.USAGE
    assert result.stderr == (
        f"robosoc serve {side}: --seconds: a flight lasts at least one sensor period (0.01 s at 100 Hz), got 0.005 s\n"
    )
    scenario = tmp_path / "short.toml"
    scenario.write_text("duration_s = 0.005\n")
    result = invoke("serve", side, "--scenario", scenario, "--no-out")
    assert result.exit_code == exit_codes.USAGE
    assert result.stderr == (
        f"robosoc serve {side}: --scenario: {scenario}: duration_s: a flight lasts at least one sensor period "
        "(0.01 s at 100 Hz), got 0.005 s\n"
    )


# --- robosoc report, firmware size --------------------------------------------------------------------


def test_report_writes_the_page_and_the_mcap(host_run: Path, tmp_path: Path) -> None:
    from mcap.reader import make_reader

    page = tmp_path / "pages" / "r.html"
    result = invoke("report", host_run, "--out", page, "--mcap")
    assert result.exit_code == 0, result.output
    assert page.read_text().lstrip().lower().startswith("<!doctype html")
    count = int(re.search(rf"^mcap: {re.escape(str(host_run / 'flight.mcap'))} \((\d+) messages\)$",
                          result.stdout, re.MULTILINE)[1])  # fmt: skip
    with (host_run / "flight.mcap").open("rb") as stream:
        assert sum(1 for _ in make_reader(stream).iter_messages()) == count > 0
    assert f"report: {page}" in result.stdout
    empty = tmp_path / "empty"
    empty.mkdir()
    result = invoke("report", empty, "--mcap")
    assert result.exit_code == exit_codes.USAGE
    assert result.stderr == f"robosoc report: --mcap: {empty}: has no flight.csv to convert\n"
    result = invoke("report", host_run, "--out", host_run / "summary.json")
    assert result.exit_code == exit_codes.USAGE and "is also an input of this command" in result.stderr


def test_firmware_size_lists_top_symbols(hello: Path) -> None:
    result = invoke("firmware", "size", hello, "--top", "2")
    assert result.exit_code == 0, result.output
    out = result.stdout.splitlines()
    assert re.fullmatch(rf"{re.escape(str(hello))}: code \d+ bytes, data \d+ bytes", out[0])
    header = next(i for i, line in enumerate(out) if line.startswith("largest functions and objects"))
    total = int(re.search(r"\(2 of (\d+)\)", out[header])[1])
    assert total > 2 and len(out) == header + 3
    for option in (["--arith", "float"], ["--no-mul"], ["--config", hello]):
        result = invoke("firmware", "size", hello, *option)
        assert result.exit_code == exit_codes.USAGE
        assert result.stderr == (
            f"robosoc firmware size: {option[0].replace('--no-mul', '--mul/--no-mul')}: chooses a build: "
            f"it cannot be combined with an ELF ({hello})\n"
        )


def test_firmware_replay_names_the_log_argument(host_run: Path) -> None:
    result = invoke("firmware", "replay", host_run / "flight.csv", "--seconds", "1")
    assert result.exit_code == exit_codes.USAGE
    assert result.stderr == "robosoc firmware replay: LOG: cannot be combined with --seconds\n"
    summary = invoke("firmware", "replay", host_run / "summary.json")
    assert summary.exit_code == exit_codes.USAGE
    assert summary.stderr.startswith(
        f"robosoc firmware replay: {host_run / 'summary.json'}: not a robosoc flight log ("
    )


# --- robosoc fly: the decoupled mode's checks, the summary, the live server ------------------------------


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--pace", "fast"], "--pace: only with --decoupled"),
        (["--bind", "127.0.0.1:0"], "--bind: only with --decoupled"),
        (["--decoupled", "--controller", "host"],
         "--decoupled: the decoupled mode flies the firmware on the chip (drop --controller host)"),
        (["--decoupled", "--video", "v.mp4"], "--video: not with --decoupled (the physics runs in another process)"),
        (["--decoupled", "--foxglove", "0"], "--foxglove: not with --decoupled (the physics runs in another process)"),
        (["--duration", "0.01", "--seconds", "0.01"], "--duration: cannot be combined with --seconds"),
        (["--scenario", "SCENARIO", "SCENARIO"], "--scenario: cannot be combined with SCENARIO"),
    ],
)  # fmt: skip
def test_fly_refuses_option_combinations(args: list[str], message: str, host_run: Path) -> None:
    scenario = host_run / "scenario.toml"
    result = invoke("fly", *[scenario if a == "SCENARIO" else a for a in args], "--no-out")
    assert result.exit_code == exit_codes.USAGE, result.output
    assert result.stderr == f"robosoc fly: {message}\n"


def test_fly_names_a_scenario_too_short_to_sample(tmp_path: Path) -> None:
    scenario = tmp_path / "short.toml"
    scenario.write_text("duration_s = 0.005\n")
    result = invoke("fly", scenario, "--no-out")
    assert result.exit_code == exit_codes.USAGE
    assert result.stderr == (
        f"robosoc fly: {scenario}: duration_s: a flight lasts at least one sensor period (0.01 s at 100 Hz), "
        "got 0.005 s\n"
    )
    result = invoke("fly", "--duration", "0.005", "--no-out")
    assert result.stderr.startswith("robosoc fly: --duration: a flight lasts at least one sensor period")


def test_fly_serves_foxglove_and_reports_the_summary(tmp_path: Path) -> None:
    result = invoke("fly", "--controller", "host", "--seconds", "0.03", "--no-out", "--foxglove", "0", "--seed", "9")
    assert result.exit_code == 0, result.output
    assert re.search(r"^foxglove: ws://127\.0\.0\.1:\d+ ", result.stdout, re.MULTILINE), result.stdout
    assert "controller host, seed 9, sensors at 100 Hz" in result.stdout
    assert "from --seed: seed\nevery other field: built-in default\n" in result.stdout
    rows = {line.split("│")[0].strip() for line in result.stdout.splitlines()}
    assert {"hover height error RMS", "roll tracking RMS", "attitude estimate RMS"} <= rows
    assert "chip energy" not in result.stdout  # the host controller has no tasks
    assert re.search(r"^real-time factor \d+\.\d\d \(0\.03 s simulated in \d+\.\d s\)$", result.stdout, re.MULTILINE)


# --- robosoc bench: options reach the benchmark -------------------------------------------------------------


def test_bench_core_names_its_build_and_engine() -> None:
    result = invoke("bench", "core", "--runs", "1", "--no-mul", "--engine", "interp", "--no-compare")
    assert result.exit_code == 0, result.output
    assert "robosoc bench core (without multiplier, engine interp)" in result.stdout
    assert re.search(r"^core: \d+ MIPS$", result.stdout, re.MULTILINE)


def _routers(text: str) -> list[str]:
    """The router model of each row of bench noc's table."""
    return [
        line.split()[0] for line in text.splitlines() if re.match(r"\s*(hermes|hermes-before|per-output)\s+0\.", line)
    ]


def test_bench_noc_rows_per_arbiter_and_plot(tmp_path: Path) -> None:
    plot = tmp_path / "lat.png"
    args = ["bench", "noc", "--size", "2x2", "--cycles", "50", "--rates", "0.1,0.2", "--seed", "3"]
    result = invoke(*args, "--plot", plot, "--packet-flits", "8")
    assert result.exit_code == 0, result.output
    routers = _routers(result.stdout)
    assert sorted(routers) == ["hermes", "hermes", "per-output", "per-output"]
    assert "NoC 2x2, uniform random, 8-flit packets" in result.stdout
    assert plot.read_bytes()[:8] == PNG_SIGNATURE
    one = invoke(*args, "--arbiter", "per-output")
    assert _routers(one.stdout) == ["per-output", "per-output"]
    big = invoke("bench", "noc", "--size", "16x16", "--cycles", "200000")
    assert big.exit_code == exit_codes.USAGE
    assert big.stderr == "robosoc bench noc: --cycles: at most 195312 on a 16x16 mesh, got 200000\n"


def test_bench_noc_compares_the_read_pointer_rules_on_the_same_traffic() -> None:
    """--compare-read-pointer adds a hermes-before row per load with the packets that moved; 2-flit
    buffers make every flit leave its buffer empty, so at depth 2 packets do move."""
    args = ["bench", "noc", "--size", "3x3", "--cycles", "300", "--rates", "0.1", "--arbiter", "hermes"]
    result = invoke(*args, "--depth", "2", "--packet-flits", "6-12", "--compare-read-pointer", "--rx-hold", "3")
    assert result.exit_code == 0, result.output
    assert _routers(result.stdout) == ["hermes", "hermes-before"]
    assert "6-12-flit packets, depth 2, receivers hold 3 cycles" in result.stdout.replace("\n", " ")
    before = next(line for line in result.stdout.splitlines() if line.strip().startswith("hermes-before"))
    moved = int(before.split()[7])
    packets = int(before.split()[3])
    assert 0 < moved <= packets
    bad = invoke(*args, "--packet-flits", "12-6")
    assert bad.exit_code == exit_codes.USAGE
    assert bad.stderr == "robosoc bench noc: --packet-flits: expected N or LO-HI with 5 <= LO <= HI <= 64, got '12-6'\n"


def test_bench_chip_and_physics_print_their_last_lines() -> None:
    chip = invoke("bench", "chip", "--runs", "1", "--cycles", "10", "--ticks", "1", "--no-noc")
    assert chip.exit_code == 0, chip.output
    assert re.search(r"^chip: \d+ Mcycles/s$", chip.stdout, re.MULTILINE) and "noc:" not in chip.stdout
    physics = invoke("bench", "physics", "--seconds", "0.01", "--runs", "1")
    assert physics.exit_code == 0, physics.output


def test_bench_fly_whole_milliseconds() -> None:
    result = invoke("bench", "fly", "--duration", "0.0105")
    assert result.exit_code == exit_codes.USAGE
    assert result.stderr == "robosoc bench fly: --duration: must be a whole number of ms, got 0.0105\n"


def _summary_rows(summary: dict) -> tuple[dict[str, list[str]], list[str]]:
    import io

    from rich.console import Console

    from robosoc.cli.fly import print_summary

    buffer = io.StringIO()
    print_summary(Console(file=buffer, width=200), summary)
    lines = buffer.getvalue().splitlines()
    rows = {}
    for line in lines:
        cells = re.split("[│┃]", line)
        if len(cells) > 1:
            name, *values = (cell.strip() for cell in cells)
            rows[name] = values
    return rows, lines


def test_flight_summary_table_of_two_vehicles() -> None:
    """Figures scaled to the units the table names (cm, deg, ms, us, nJ, mJ); n/a for missing or NaN."""
    steps = [{"axis": "roll", "time_s": 0.5, "rise_s": 0.123}, {"axis": "yaw", "time_s": 1.0, "rise_s": 0.2}]
    first = {
        "flight": {
            "hover_rms_m": 0.0123,
            "hover_max_m": 0.05,
            "overshoot_m": float("nan"),
            "tracking_rms_deg": {"roll": 1.234, "pitch": None, "yaw": 0.5},
            "step_rise_s": steps,
            "attitude_estimate_rms_deg": 0.25,
            "height_estimate_rms_m": 0.001,
        },
        "tasks": {
            "ekf": {
                "jobs": 100,
                "response_us_mean": 12.34,
                "response_us_max": 20.0,
                "exec_cycles_mean": 1500.4,
                "energy_nj_mean": 33.35,
            }
        },
        "deadline_misses": 0,
        "energy": {"total_uj": 1234.0},
    }
    second = {"flight": {"step_rise_s": [{"axis": "roll", "time_s": 0.5, "rise_s": None}]}, "tasks": {},
              "deadline_misses": 2, "energy": None}  # fmt: skip
    summary = {"vehicles": [first, second], "simulated_s": 1.0, "host_s": 2.04, "real_time_factor": 0.49,
               "complete": False, "stopped": "interrupted", "min_separation_m": 1.5}  # fmt: skip
    rows, lines = _summary_rows(summary)
    assert lines[0].strip() == "flight summary"
    assert rows["figure"] == ["vehicle 1", "vehicle 2"]
    assert rows["hover height error RMS"] == ["1.23 cm", "n/a"]
    assert rows["hover height error max"] == ["5.00 cm", "n/a"]
    assert rows["overshoot"] == ["n/a", "n/a"]
    assert rows["roll tracking RMS"] == ["1.23 deg", "n/a"]
    assert rows["pitch tracking RMS"] == ["n/a", "n/a"]
    assert rows["yaw tracking RMS"] == ["0.50 deg", "n/a"]
    assert rows["roll step at 0.5 s: 90 % after"] == ["123 ms", "n/a"]
    assert not any(name.startswith("yaw step") for name in rows)  # at the end of the flight: not flown
    assert rows["attitude estimate RMS"] == ["0.25 deg", "n/a"]
    assert rows["height estimate RMS"] == ["0.10 cm", "n/a"]
    assert rows["ekf jobs"] == ["100", "n/a"]
    assert rows["ekf response mean / max"] == ["12.3 / 20.0 us", "n/a / n/a us"]
    assert rows["ekf cycles per job (mean)"] == ["1500", "n/a"]
    assert rows["ekf energy per job (mean)"] == ["33.4 nJ", "n/a"]
    assert rows["deadline misses"] == ["0", "2"]
    assert rows["chip energy"] == ["1.23 mJ", "n/a"]
    assert lines[-1] == (
        "real-time factor 0.49 (1 s simulated in 2.0 s); closest approach 1.50 m (incomplete: interrupted)"
    )


def test_flight_summary_of_one_vehicle_without_tasks() -> None:
    summary = {"flight": {"hover_rms_m": 0.02}, "simulated_s": 0.5, "host_s": 0.25, "real_time_factor": 2.0}
    rows, lines = _summary_rows(summary)
    assert rows["figure"] == ["value"] and rows["hover height error RMS"] == ["2.00 cm"]
    assert "deadline misses" not in rows and "chip energy" not in rows
    assert lines[-1] == "real-time factor 2.00 (0.5 s simulated in 0.2 s)"


def test_bench_fly_flies_the_builds_chosen() -> None:
    """--no-mul: the two builds without the multiplier and no host reference; --arith float --mul: one."""
    result = invoke("bench", "fly", "--duration", "0.01", "--no-mul")
    assert result.exit_code == 0, result.output
    flown = sorted(line.split()[1] for line in result.stdout.splitlines() if line.startswith("chip "))
    assert flown == ["fixed-no-mul", "float-no-mul"]
    assert not any(line.startswith("host") for line in result.stdout.splitlines())
    one = invoke("bench", "fly", "--duration", "0.01", "--arith", "float", "--mul")
    assert [line.split()[1] for line in one.stdout.splitlines() if line.startswith("chip ")] == ["float+mul"]


def test_replay_report_prints_and_writes_the_replay_figures(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """firmware replay's report: the figures of the replay (the library's result) on stdout and in summary.json."""
    import csv

    from robosoc.cli.firmware import _report
    from robosoc.config.firmware import FirmwareConfig
    from robosoc.cosim.replay import built_in_rows, replay

    result = replay(built_in_rows(0.05, 2), FirmwareConfig())
    _report(result, None)
    quiet = capsys.readouterr().out
    assert not (tmp_path / "summary.json").exists() and "wrote" not in quiet
    _report(result, tmp_path)
    out = capsys.readouterr().out.splitlines()
    seconds = result.cycles * result.clock_ns * 1e-9
    assert out[0] == (
        f"fixed+mul: {len(result.samples)} samples, {len(result.commands)} PWM commands, "
        f"{result.deadline_misses} deadline misses, {result.cycles} cycles ({seconds:.2f} s simulated in "
        f"{result.host_seconds:.1f} s)"
    )
    record = json.loads((tmp_path / "summary.json").read_text())
    assert record["firmware"] == "fixed+mul" and record["samples"] == len(result.samples) == 5
    assert (record["commands"], record["cycles"], record["clock_ns"]) == (
        len(result.commands),
        result.cycles,
        result.clock_ns,
    )
    assert record["energy_pj"] == pytest.approx(result.energy_pj)
    for name in ("estimator", "pid"):
        jobs = [j for j in result.jobs if j.task == name]
        figures = record["tasks"][name]
        assert figures["jobs"] == len(jobs) == 5
        assert figures["exec_cycles_max"] == max(j.exec_cycles for j in jobs)
        line = next(line for line in out if line.startswith(f"  {name:<9} "))
        assert line.startswith(f"  {name:<9} {len(jobs)} jobs: exec mean {figures['exec_cycles_mean']:.0f} max ")
        assert f"response mean {figures['response_us_mean']:.1f} max {figures['response_us_max']:.1f} us" in line
        assert f"energy {figures['energy_nj_mean']:.1f} nJ/job (kernel {figures['kernel_energy_share']:.1%})" in line
        assert line.endswith(f"misses {figures['deadline_misses']}")
    with (tmp_path / "jobs.csv").open() as stream:
        assert len(list(csv.DictReader(stream))) == len(result.jobs)
    assert out[-1] == f"wrote {tmp_path / 'jobs.csv'} and {tmp_path / 'summary.json'}"


def test_firmware_build_reads_the_config_file_then_the_options(tmp_path: Path) -> None:
    config = tmp_path / "fw.toml"
    config.write_text('arith = "float"\n')
    result = invoke("firmware", "build", "--config", config)
    assert result.exit_code == 0, result.output
    assert result.stdout.startswith("float+mul: ")
    copy = tmp_path / "copy.elf"
    result = invoke("firmware", "build", "--config", config, "--arith", "fixed", "-o", copy)
    assert result.exit_code == 0, result.output
    assert result.stdout == f"fixed+mul: {copy}\n" and copy.read_bytes()[:4] == b"\x7fELF"


@pytest.mark.parametrize("side", ["physics", "chip"])
def test_serve_names_its_out_and_scenario_options(side: str, tmp_path: Path) -> None:
    scenario = tmp_path / "s.toml"
    scenario.write_text("seed = 3\n")
    a_file = tmp_path / "a-file"
    a_file.write_text("x\n")
    for args, message in (
        (["--out", a_file], f"--out: {a_file}: is a file, expected a folder"),
        (["--scenario", scenario, "--out", scenario], f"--out: {scenario}: is a file, expected a folder"),
        (["--scenario", tmp_path / "none.toml"], f"--scenario: {tmp_path / 'none.toml'}: file not found"),
        (["--seconds", "0.0105", "--no-out"], "--seconds: must be a whole number of 1 ms physics steps, got 0.0105"),
        (
            ["--scenario", scenario, "--seconds", "0.0105", "--no-out"],
            f"--seconds: must be a whole number of 1 ms physics steps, got 0.0105 (with {scenario})",
        ),
    ):
        result = invoke("serve", side, *args)
        assert result.exit_code == exit_codes.USAGE, result.output
        assert result.stderr.splitlines()[0] == f"robosoc serve {side}: {message}"


def test_gdb_tile_errors_name_the_option(hello: Path) -> None:
    """A --tile that is not X,Y is refused naming --tile (it used to print only the reason)."""
    result = invoke("run", hello, "--mesh", "2x2", "--gdb", "0", "--tile", "a,b")
    assert result.exit_code == exit_codes.USAGE
    assert result.stderr == "robosoc run: --tile: expected X,Y such as 1,1, got 'a,b'\n"
