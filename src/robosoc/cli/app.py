"""The typer applications that every command module registers itself on."""

import typer

app = typer.Typer(
    name="robosoc",
    help="Robot control firmware on a cycle-accurate RISC-V MPSoC, closed-loop with physics.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
bench_app = typer.Typer(help="Benchmarks that print simulated speed figures.", no_args_is_help=True)
app.add_typer(bench_app, name="bench")
