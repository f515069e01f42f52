"""``robosoc profile``'s helpers: the table it and ``fly --profile`` print, from a hand-built profile,
and the reading of a run's ``summary.json``.

The expected lines are written from the profile's numbers by hand (shares of the task's cycles,
the rows past ``top`` summed into one "(k more)" row, energy in nJ per row and uJ per tile).
"""

from __future__ import annotations

import io
from pathlib import Path

import pytest
from rich.console import Console

from robosoc.chip.function_profile import FunctionProfile, ProfileRow
from robosoc.cli.errors import CliError
from robosoc.cli.profile import _read_summary, print_profile


def _row(tile, task, name, function, cycles, instructions, energy_pj) -> ProfileRow:
    return ProfileRow(tile, task, name, function, cycles, instructions, {}, energy_pj)


PROFILE = FunctionProfile(
    rows=[
        _row((0, 0), 1, "ekf", "predict", 6000, 3000, 1_500_000.0),
        _row((0, 0), 1, "ekf", "update", 3000, 1500, 700_000.0),
        _row((0, 0), 1, "ekf", "memcpy", 800, 400, 150_000.0),
        _row((0, 0), 1, "ekf", "(interrupt entry)", 200, 0, 50_000.0),
        _row((0, 0), 0, "idle", "(sleep)", 10_000, 0, 100_000.0),
        _row((1, 0), 2, "pid", "pid_step", 2500, 1200, 400_000.0),
        _row(None, None, "", "(NoC)", 0, 0, 2_345_000.0),
    ],
    clock_ns=4.0,
)


def _printed(top: int, title: str = "", profile: FunctionProfile = PROFILE) -> list[str]:
    buffer = io.StringIO()
    console = Console(file=buffer, width=200, color_system=None, force_terminal=False)
    print_profile(console, profile, top, title)
    return [" ".join(line.replace("│", " ").replace("┃", " ").split()) for line in buffer.getvalue().splitlines()]


def test_each_tile_gets_a_table_with_its_total_and_its_tasks_top_functions() -> None:
    lines = _printed(2)
    # tile 0,0: 6000 + 3000 + 800 + 200 + 10000 cycles; 2.5 uJ (1.5 + 0.7 + 0.15 + 0.05 + 0.1)
    assert "tile 0,0: 20,000 cycles, 2.500 uJ" in lines
    assert "tile 1,0: 2,500 cycles, 0.400 uJ" in lines
    assert "task function cycles % instructions energy nJ" in lines
    # task 0 first (sorted by number); its one row is 100 % of its cycles
    assert "idle (0) (sleep) 10,000 100.0 0 100.0" in lines
    # task 1: 10,000 cycles; the two largest, then the other two summed
    assert "ekf (1) predict 6,000 60.0 3,000 1,500.0" in lines
    assert "ekf (1) update 3,000 30.0 1,500 700.0" in lines
    assert "(2 more) 1,000 10.0 400 200.0" in lines
    assert "pid (2) pid_step 2,500 100.0 1,200 400.0" in lines
    assert lines.index("tile 0,0: 20,000 cycles, 2.500 uJ") < lines.index("tile 1,0: 2,500 cycles, 0.400 uJ")
    assert lines.index("idle (0) (sleep) 10,000 100.0 0 100.0") < lines.index(
        "ekf (1) predict 6,000 60.0 3,000 1,500.0"
    )
    assert lines[-1] == "NoC (routers): 2.345 uJ"
    assert not any("memcpy" in line for line in lines)


def test_a_top_that_shows_everything_has_no_more_row_and_the_title_leads() -> None:
    lines = _printed(10, "vehicle 2, ")
    assert "vehicle 2, tile 0,0: 20,000 cycles, 2.500 uJ" in lines
    assert "ekf (1) memcpy 800 8.0 400 150.0" in lines
    assert "ekf (1) (interrupt entry) 200 2.0 0 50.0" in lines
    assert not any("more)" in line for line in lines)


def test_without_noc_rows_there_is_no_noc_line() -> None:
    profile = FunctionProfile(rows=[r for r in PROFILE.rows if r.tile is not None], clock_ns=4.0)
    lines = _printed(1, profile=profile)
    assert not any(line.startswith("NoC") for line in lines)
    assert "(3 more) 4,000 40.0 1,900 900.0" in lines


def test_summary_json_is_read_or_refused_by_name(tmp_path: Path) -> None:
    path = tmp_path / "summary.json"
    path.write_text('{"cycles": {"tiles": {"0,0": 5}}}')
    assert _read_summary(path) == {"cycles": {"tiles": {"0,0": 5}}}
    path.write_bytes(b'{"name": "caf\xe9"}')
    with pytest.raises(CliError) as caught:
        _read_summary(path)
    assert caught.value.message == f"{path}: not UTF-8 text (byte 0xe9 at offset 13): expected a JSON file"
    path.write_text("[1, 2]")
    with pytest.raises(CliError) as caught:
        _read_summary(path)
    assert caught.value.message == f"{path}: expected a JSON object (a run's summary.json)"
    path.write_text("{oops")
    with pytest.raises(CliError, match=rf"^{path}: not JSON: "):
        _read_summary(path)


def test_the_table_aligns_names_left_and_figures_right_under_a_left_title() -> None:
    buffer = io.StringIO()
    console = Console(file=buffer, width=200, color_system=None, force_terminal=False)
    print_profile(console, PROFILE, 2)
    raw = buffer.getvalue().splitlines()
    assert raw[0].rstrip() == "tile 0,0: 20,000 cycles, 2.500 uJ"  # the title starts at the left edge
    header = next(line for line in raw if "function" in line and "cycles" in line)
    row = next(line for line in raw if "predict" in line)
    assert row.index("ekf (1)") == header.index("task")  # names start under their headings
    assert row.index("predict") == header.index("function")
    for heading, cell in (("cycles", "6,000"), ("%", "60.0"), ("instructions", "3,000"), ("energy nJ", "1,500.0")):
        assert row.index(cell) + len(cell) == header.index(heading) + len(heading), heading  # figures end under them


def test_the_rest_row_is_dim_and_large_energies_keep_their_digits() -> None:
    buffer = io.StringIO()
    console = Console(file=buffer, width=200, color_system="standard", force_terminal=True)
    print_profile(console, PROFILE, 2)
    (more,) = [line for line in buffer.getvalue().splitlines() if "(2 more)" in line]
    assert "\x1b[2m" in more  # dim
    big = FunctionProfile([_row((0, 0), 1, "ekf", "f", 1, 1, 5e9), _row(None, None, "", "(NoC)", 0, 0, 7e9)], 4.0)
    lines = _printed(5, profile=big)
    assert "tile 0,0: 1 cycles, 5000.000 uJ" in lines and lines[-1] == "NoC (routers): 7000.000 uJ"
