"""What every command shares: the common options, the one ``fail``, the one ``print_json``,
``check_number`` and the progress bars (on stderr, so that ``--json`` output stays clean)."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any, NoReturn

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from aerodock.fileio import dumps_json

ConfigOpt = Annotated[
    Path | None, typer.Option("--config", help="TOML file overriding aerodock's defaults.")
]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print the numbers as JSON.")]
SeedOpt = Annotated[int, typer.Option("--seed", help="Random seed.")]

err_console = Console(stderr=True)


def fail(message: str, code: int = 2) -> NoReturn:
    """Print ``error: MESSAGE`` on stderr and exit with ``code`` (2: bad input).

    ``message`` is printed as given; a caller whose text may hold newlines (an exception's)
    makes it one line first with :func:`aerodock.fileio.one_line`.
    """
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code)


def print_json(obj: Any, indent: int | None = 2) -> None:
    """Print ``obj`` as strict JSON on stdout (indented by ``indent``; one line if None).

    A NaN or an infinity anywhere in ``obj`` is refused (JSON has no such numbers): a one-line
    error naming the key, exit code 2, nothing on stdout. A command whose document may lack a
    figure passes it through :func:`aerodock.fileio.json_ready` first (the figure is null).
    """
    try:
        text = dumps_json(obj, indent)
    except ValueError as err:
        fail(str(err))
    typer.echo(text)


def check_number(option: str, value: float | None, low: float, high: float) -> None:
    """Refuse a numeric option that is not finite or lies outside ``[low, high]``."""
    if value is None:
        return
    if not math.isfinite(value):
        fail(f"{option} must be a finite number, got {value}")
    if not low <= value <= high:
        fail(f"{option} must be between {low:g} and {high:g}, got {value!r}")


def progress_bar() -> Progress:
    """A Rich progress bar on stderr (stdout stays clean for --json)."""
    return Progress(TextColumn("{task.description}"), BarColumn(),
                    TextColumn("{task.percentage:>3.0f}%"), TimeElapsedColumn(),
                    console=err_console, transient=True)


def bar_callback(bar: Progress) -> Callable[[str, int, int], None]:
    """``update(description, done, total)`` driving one task of ``bar`` (shown from the first
    update): for work that reports its own steps (training epochs, sample-efficiency runs)."""
    task = bar.add_task("", total=None, visible=False)

    def update(description: str, done: int, total: int) -> None:
        bar.update(task, description=description, completed=done, total=total, visible=True)

    return update
