"""``robosoc sweep FILE``: run a sweep file's points on a local pool or a Dask cluster, resumably."""

from __future__ import annotations

import os
from contextlib import ExitStack
from pathlib import Path
from typing import Annotated

import typer

from robosoc import output_files
from robosoc.cli import exit_codes, files, options
from robosoc.cli.console import make_console, note, plain
from robosoc.cli.errors import CliError
from robosoc.cli.typer_apps import app

MAX_WORKERS = 256


def _dask_address(text: str) -> str:
    """``local`` or a scheduler address (``tcp://host:8786``, ``host:8786``)."""
    from robosoc.sweep.runner import LOCAL

    if text == LOCAL:
        return text
    address = text if "://" in text else f"tcp://{text}"
    scheme, _, rest = address.partition("://")
    host, sep, port = rest.rpartition(":")
    if scheme not in ("tcp", "tls", "ws", "wss", "inproc") or not sep or not host or not port.isdigit():
        raise ValueError(f"expected 'local' or a scheduler address such as tcp://host:8786, got {text!r}")
    if not 0 < int(port) < 65536:
        raise ValueError(f"port must be 1..65535, got {port}")
    return address


def _check_dask(ctx: typer.Context, param: typer.CallbackParam, value: str | None) -> str | None:
    if value is None:
        return None
    try:
        return _dask_address(value)
    except ValueError as exc:
        raise options.fail(options.option_name(param), str(exc)) from None


@app.command("sweep", epilog=exit_codes.SWEEP_EPILOG)
def sweep_command(
    file: Annotated[Path, typer.Argument(help="The sweep file (TOML; docs/sweeps.md).", show_default=False)],
    workers: Annotated[
        int | None,
        typer.Option(
            help=f"Worker processes, 1..{MAX_WORKERS} (default: the number of cores).",
            callback=options.int_range(1, MAX_WORKERS),
        ),
    ] = None,
    dask: Annotated[
        str | None,
        typer.Option(
            help="Run on a Dask cluster: a scheduler address (tcp://host:8786), or 'local' for a LocalCluster "
            "of --workers processes with Dask's dashboard.",
            callback=_check_dask,
        ),
    ] = None,
    out: Annotated[
        Path | None, typer.Option(help="Output folder (default runs/sweep-NAME); a re-run resumes in it.")
    ] = None,
    retry_failed: Annotated[bool, typer.Option("--retry-failed", help="Run the points that failed again.")] = False,
) -> None:
    """Fly every point of a sweep file; store each as it finishes; table, Pareto plots and an HTML page."""
    from robosoc.config.sweep import sweep_from_mapping
    from robosoc.config.validate import ConfigError
    from robosoc.sweep.store import FolderInUse, RecordError, SweepStore

    console = make_console()
    files.input_file(file, None, "sweep file")
    try:
        config = sweep_from_mapping(files.read_toml(file), str(file), file.parent, file.stem)
        from robosoc.sweep.plan import plan

        total = len(plan(config))
    except ConfigError as exc:
        raise CliError(str(exc)) from None
    if out is None:
        out = Path("runs") / f"sweep-{config.name}"
    out = files.output_dir(out, "--out", inputs=[file], names=("sweep.toml", "points.csv", "sweep.html"))
    remote = dask is not None and dask != "local"
    if remote and workers is not None:
        raise options.fail("--workers", f"a Dask scheduler ({dask}) brings its own workers: give --workers without it")
    if workers is None:
        workers = os.cpu_count() or 1
    with ExitStack() as held:
        try:
            store = SweepStore(out)
            held.enter_context(store.lock())  # before anything is written into the folder
            store.records()  # every record readable, before the long work
        except FolderInUse as exc:
            raise CliError(f"--out: {exc}") from None
        except RecordError as exc:
            raise CliError(str(exc)) from None
        except OSError as exc:
            raise CliError(f"--out: {_os_error(exc)}") from None
        _sweep(console, config, file, out, total, workers, dask, retry_failed)


def _os_error(exc: OSError) -> str:
    """An OSError as the user reads it: the file, then what is wrong (``runs/x/points.csv: no space left``)."""
    reason = exc.strerror.lower() if exc.strerror else str(exc)
    where = exc.filename if exc.filename is not None else None
    return f"{where}: {reason}" if where is not None else reason


def _sweep(
    console, config, file: Path, out: Path, total: int, workers: int, dask: str | None, retry_failed: bool
) -> None:
    """The sweep itself, with the folder held."""
    from rich.markup import escape
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    from robosoc.sweep.plots import sweep_html, write_sweep_plots
    from robosoc.sweep.point import OK
    from robosoc.sweep.runner import SchedulerError, run_sweep
    from robosoc.sweep.store import RecordError

    remote = dask is not None and dask != "local"
    copy = out / "sweep.toml"
    try:
        if not copy.exists() or copy.read_bytes() != file.read_bytes():
            output_files.write_atomic(copy, file.read_bytes())
    except OSError as exc:
        raise CliError(f"--out: {_os_error(exc)}") from None

    # a scheduler's workers are counted once connected (run_sweep says how many), not os.cpu_count() here
    where = (
        f"Dask at {escape(dask)}"
        if remote and dask is not None
        else f"{'a Dask LocalCluster' if dask else 'a local pool'} of {workers} workers"
    )
    console.print(
        f"sweep [bold]{escape(config.name)}[/bold]: {total} runs "
        f"({config.point_count()} points × {len(config.seeds)} seeds) on {where}"
    )
    state = {"failed": 0}
    with Progress(
        TextColumn("points"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("{task.fields[failed]} failed"),
        TimeRemainingColumn(),
        console=console,
        transient=True,
    ) as progress:
        task = progress.add_task("sweep", total=total, failed=0)

        def on_start(todo: int, done: int) -> None:
            progress.update(task, completed=done)
            if done:
                progress.console.print(f"resuming in {escape(str(out))}: {done} of {total} runs already done")

        def on_point(point, record) -> None:
            if record["status"] != OK:
                state["failed"] += 1
                progress.console.print(escape(f"failed: {point.label}: {record['error']}"))
            progress.update(task, advance=1, failed=state["failed"])

        try:
            outcome = run_sweep(
                config,
                out,
                workers=workers,
                dask=dask,
                retry_failed=retry_failed,
                on_start=on_start,
                on_point=on_point,
                on_status=lambda text: progress.console.print(escape(text)),
            )
        except KeyboardInterrupt:
            note(console, f"interrupted; the finished points are kept in {out}: run the same command to resume")
            raise typer.Exit(exit_codes.INTERRUPTED) from None
        except SchedulerError as exc:
            raise CliError(f"--dask: {exc}") from None
        except RecordError as exc:
            raise CliError(str(exc)) from None
        except OSError as exc:  # the output folder: full, removed, made read-only meanwhile
            raise CliError(f"--out: {_os_error(exc)}") from None

    records = [outcome.records[p.key] for p in outcome.points if p.key in outcome.records]
    try:
        plots = write_sweep_plots(out, records, config.varied(), config.metrics)
        page = out / "sweep.html"
        output_files.write_atomic(page, sweep_html(f"sweep {config.name}", records, plots, outcome.table.read_text()))
    except OSError as exc:
        raise CliError(f"--out: {_os_error(exc)}") from None
    ok = sum(1 for r in records if r["status"] == OK)
    console.print(f"{outcome.ran} runs now, {outcome.skipped} done before; {ok} ok, {len(records) - ok} failed")
    for record in outcome.failures:
        console.print(
            escape(f"  failed: point {record['index']} {record['values']} seed {record['seed']}: {record['error']}")
        )
    plain(console, f"table: {outcome.table}  plots: {out / 'plots'}  page: {page}")
    if records and not ok:
        note(console, f"every one of the {len(records)} runs failed")
        raise typer.Exit(exit_codes.ALL_FAILED)
