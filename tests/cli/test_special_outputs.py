"""Outputs onto anything but a regular file or a folder (issue 34, item 1): a character device, a FIFO
or a socket is refused with exit 2 and a message naming the option and the path; it is never
renamed over (as root that would replace /dev/null) and never opened (a FIFO waits for a reader).

Character devices are only tested through checks that cannot replace them: the library's writers
with ``os.replace`` and every open for writing made to fail first, and the command line's check,
which refuses before any write."""

from __future__ import annotations

import os
import socket
import stat
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from typer.testing import CliRunner

from robosoc import output_files
from robosoc.cli import app, exit_codes, files
from robosoc.cli.errors import CliError
from robosoc.output_files import NotRegularFileError
from run_folders import host_rows, write_host_run

runner = CliRunner()
DEVICES = [d for d in ("/dev/null", "/dev/full") if Path(d).exists() and stat.S_ISCHR(os.stat(d).st_mode)]


def fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


@pytest.fixture
def unix_socket(tmp_path: Path) -> Iterator[Callable[[Path], Path]]:
    """Binds a Unix socket at a path (kept open for the test)."""
    opened: list[socket.socket] = []

    def make(path: Path) -> Path:
        s = socket.socket(socket.AF_UNIX)
        s.bind(str(path))
        opened.append(s)
        return path

    yield make
    for s in opened:
        s.close()


def node(path: Path) -> tuple[int, int]:
    st = os.stat(path)
    return stat.S_IFMT(st.st_mode), st.st_ino


@pytest.fixture(params=["fifo", "socket"])
def special(request, tmp_path: Path, unix_socket) -> Callable[[Path], Path]:
    """Makes a FIFO or a socket at a path."""
    return fifo if request.param == "fifo" else unix_socket


@pytest.fixture
def no_writes(monkeypatch) -> None:
    """Any rename or open for writing fails the test (so that a device is never replaced or written)."""

    def forbidden(*args, **kwargs):
        raise AssertionError(f"a write was attempted: {args}")

    monkeypatch.setattr(output_files.os, "replace", forbidden)
    real_open = Path.open

    def guarded_open(self, mode="r", *args, **kwargs):
        if any(c in mode for c in "wax+"):
            forbidden(self, mode)
        return real_open(self, mode, *args, **kwargs)

    monkeypatch.setattr(Path, "open", guarded_open)


def invoke(*args: object, timeout: float = 120.0):
    """The command line in a thread: a FIFO opened for writing would hang it, which fails the test."""
    box: list = []
    worker = threading.Thread(target=lambda: box.append(runner.invoke(app, [str(a) for a in args])), daemon=True)
    worker.start()
    worker.join(timeout)
    assert box, f"robosoc {' '.join(map(str, args))} hung (did it open a FIFO for writing?)"
    return box[0]


# --- the library's writers --------------------------------------------------------------------------


def test_not_regular_names_what_a_path_is(tmp_path: Path, unix_socket) -> None:
    (tmp_path / "file").write_text("x")
    assert output_files.not_regular(tmp_path / "file") is None
    assert output_files.not_regular(tmp_path) is None
    assert output_files.not_regular(tmp_path / "missing") is None
    assert output_files.not_regular(fifo(tmp_path / "fifo")) == "a FIFO (named pipe)"
    assert output_files.not_regular(unix_socket(tmp_path / "sock")) == "a socket"
    for device in DEVICES:
        assert output_files.not_regular(device) == "a character device"


@pytest.mark.parametrize(
    "write",
    [
        lambda p: output_files.write_atomic(p, "text"),
        lambda p: output_files.write_atomic(p, b"bytes", fsync=True),
        lambda p: output_files.atomic_open(p, "w").__enter__(),
        lambda p: output_files.open_in_place(p, "w"),
    ],
    ids=["write_atomic", "write_atomic-bytes", "atomic_open", "open_in_place"],
)
def test_writers_refuse_a_fifo_or_socket_and_leave_it(write, tmp_path: Path, special) -> None:
    target = special(tmp_path / "out.json")
    before = node(target)
    with pytest.raises(NotRegularFileError, match=r"out.json: is a (FIFO|socket)"):
        write(target)
    assert node(target) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.json"]  # no scratch file left


@pytest.mark.parametrize("device", DEVICES)
def test_writers_refuse_a_character_device_before_any_write(device: str, no_writes) -> None:
    before = node(Path(device))
    for write in (
        lambda: output_files.write_atomic(device, "x"),
        lambda: output_files.atomic_open(device, "wb").__enter__(),
        lambda: output_files.open_in_place(device, "w"),
    ):
        with pytest.raises(NotRegularFileError, match="is a character device"):
            write()
    assert node(Path(device)) == before


def test_a_file_is_still_replaced_whole(tmp_path: Path) -> None:
    target = tmp_path / "out.txt"
    target.write_text("old")
    output_files.write_atomic(target, "new")
    assert target.read_text() == "new"
    with pytest.raises(RuntimeError), output_files.atomic_open(target) as handle:
        handle.write("half")
        raise RuntimeError
    assert target.read_text() == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.txt"]


# --- the command line's check when a command starts ---------------------------------------------------


@pytest.mark.parametrize("device", DEVICES)
def test_output_file_refuses_a_character_device_before_any_write(device: str, no_writes) -> None:
    with pytest.raises(CliError, match=f"^--stats: {device}: is a character device, expected a regular file"):
        files.output_file(device, "--stats")


def test_output_file_and_dir_refuse_a_fifo_or_socket(tmp_path: Path, special) -> None:
    target = special(tmp_path / "x.json")
    with pytest.raises(CliError, match=r"^--stats: .*x.json: is a (FIFO \(named pipe\)|socket), expected a regular"):
        files.output_file(target, "--stats")
    with pytest.raises(CliError, match=r"^--out: .*x.json: is a (FIFO|socket).*, expected a folder"):
        files.output_dir(target, "--out")
    folder = tmp_path / "run"
    folder.mkdir()
    special(folder / "summary.json")
    with pytest.raises(CliError, match=r"^--out: .*run: summary.json in it is a (FIFO|socket)"):
        files.output_dir(folder, "--out", names=("flight.csv", "summary.json"))


@pytest.fixture(scope="module")
def host_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_host_run(tmp_path_factory.mktemp("run") / "run", host_rows())


def _commands(tmp: Path, elves: dict[str, Path], host_run: Path, target: Path) -> list[tuple[list[object], str]]:
    source = tmp / "prog.c"
    source.write_text("int main(void) { return 0; }\n")
    sweep = tmp / "sweep.toml"
    sweep.write_text("[base]\nduration_s = 0.1\ncontroller = 'host'\n")
    return [
        (["run", elves["ok"], "--stats", target], "--stats"),
        (["run", elves["ok"], "--mesh", "2x1", "--stats", target], "--stats"),
        (["cc", source, "-o", target], "--output"),
        (["firmware", "build", "-o", target], "--output"),
        (["report", host_run, "--out", target], "--out"),
        (["bench", "noc", "--plot", target.with_name(target.name + ".png")], "--plot"),
        (["fly", "--controller", "host", "--seconds", "0.1", "--no-out", "--video", target.with_suffix(".mp4")],
         "--video"),
    ]  # fmt: skip


@pytest.mark.parametrize("kind", ["fifo", "socket"])
def test_every_output_option_refuses_a_fifo_or_socket(
    kind: str, tmp_path: Path, elves: dict[str, Path], host_run: Path, unix_socket
) -> None:
    make = fifo if kind == "fifo" else unix_socket
    for args, option in _commands(tmp_path, elves, host_run, tmp_path / "target"):
        target = Path(str(args[-1]))
        make(target)
        before = node(target)
        result = invoke(*args)
        assert result.exit_code == exit_codes.USAGE, (args, result.output)
        first = result.output.splitlines()[0]
        assert first.startswith(f"robosoc {args[0]}") and f"{option}: {target}: is a " in first, first
        assert "Traceback" not in result.output
        assert node(target) == before, args
        target.unlink()


@pytest.mark.parametrize("kind", ["fifo", "socket"])
def test_output_folders_refuse_a_fifo_or_socket_among_their_files(
    kind: str, tmp_path: Path, host_run: Path, unix_socket
) -> None:
    make = fifo if kind == "fifo" else unix_socket
    sweep = tmp_path / "sweep.toml"
    sweep.write_text("[base]\nduration_s = 0.1\ncontroller = 'host'\n")
    cases = [
        (["fly", "--controller", "host", "--seconds", "0.1", "--out"], "summary.json"),
        (["fly", "--controller", "host", "--seconds", "0.1", "--out"], "flight.csv"),
        (["sweep", sweep, "--out"], "sweep.toml"),
        (["table", "--out"], "table.csv"),
        (["serve", "physics", "--bind", "127.0.0.1:0", "--out"], "flight.csv"),
    ]
    for i, (args, name) in enumerate(cases):
        folder = tmp_path / f"out{i}"
        folder.mkdir()
        target = make(folder / name)
        before = node(target)
        result = invoke(*args, folder)
        assert result.exit_code == exit_codes.USAGE, (args, result.output)
        first = result.output.splitlines()[0]
        assert f"--out: {folder}: {name} in it is a " in first, first
        assert node(target) == before


def test_report_mcap_checks_the_mcap_file_before_writing(tmp_path: Path, host_run: Path) -> None:
    run = write_host_run(tmp_path / "run", host_rows(0.2))
    target = fifo(run / "flight.mcap")
    result = invoke("report", run, "--mcap")
    assert result.exit_code == exit_codes.USAGE, result.output
    assert f"--mcap: {target}: is a FIFO" in result.output
    assert not (run / "report.html").exists()  # refused before the report was written
    assert stat.S_ISFIFO(os.stat(target).st_mode)


def test_a_fifo_met_inside_a_folder_is_a_usage_error_naming_it(tmp_path: Path, monkeypatch) -> None:
    """What the start-up checks cannot foresee (a vehicle's sub-folder) still ends with exit 2, not a hang."""
    from robosoc.cli.errors import run_guarded

    target = fifo(tmp_path / "late.json")

    def main() -> None:
        output_files.write_atomic(target, "x")

    assert run_guarded(main) == exit_codes.USAGE
    assert stat.S_ISFIFO(os.stat(target).st_mode)
