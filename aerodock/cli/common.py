"""What every command shares: the common options, the one ``fail``, the one ``print_json``,
``check_number`` and the progress bars (on stderr, so that ``--json`` output stays clean)."""

from __future__ import annotations

import contextlib
import math
import os
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, NoReturn

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TaskID, TextColumn, TimeElapsedColumn

from aerodock.fileio import dumps_json

if TYPE_CHECKING:
    from aerodock.config import Config

ConfigOpt = Annotated[
    Path | None, typer.Option("--config", help="TOML file overriding aerodock's defaults.")
]
SetOpt = Annotated[list[str] | None, typer.Option(
    "--set", metavar="SECTION.KEY=VALUE",
    help="Set a config key after --config, e.g. platform.cable_length_m=0.64 (repeatable).")]
TrustOpt = Annotated[list[str] | None, typer.Option(
    "--trust-plugin", metavar="MODULE",
    help="Trust the config's plug-in field from MODULE: it runs that code (repeatable).")]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print the numbers as JSON.")]
SeedOpt = Annotated[int, typer.Option("--seed", help="Random seed.")]

err_console = Console(stderr=True)


def load_cli_config(config: Path | None, sets: list[str] | None = None,
                    trust: list[str] | None = None) -> Config:
    """The config of ``--config``, ``--set`` and ``--trust-plugin`` (ConfigError: one line)."""
    from aerodock.config import load_config

    return load_config(config, sets or (), trust or ())


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


@contextlib.contextmanager
def config_for_children(cfg: Config, config: Path | None, sets: list[str] | None,
                        trust: list[str] | None) -> Iterator[Path | None]:
    """The ``--config`` file a child process is to read: the user's own, or (with ``--set``)
    ``cfg`` written to a temporary file; ``--trust-plugin`` is added to the children's
    ``AERODOCK_TRUST_PLUGINS`` meanwhile (restored after)."""
    from aerodock.config.plugins import TRUST_ENV

    saved = os.environ.get(TRUST_ENV)
    with tempfile.TemporaryDirectory(prefix="aerodock-config-") as tmp:
        path = config
        if sets:
            path = Path(tmp) / "resolved.toml"
            path.write_text(cfg.to_toml())
        if trust:
            os.environ[TRUST_ENV] = ",".join([*trust, *([saved] if saved else [])])
        try:
            yield path
        finally:
            if saved is None:
                os.environ.pop(TRUST_ENV, None)
            else:
                os.environ[TRUST_ENV] = saved

LOG_EVERY_S = 30.0
"""Without a terminal (a log file, a pipe, a batch job), how often a progress line is printed."""


class LoggedProgress(Progress):
    """A Rich progress bar that, when stderr is not a terminal (where Rich draws nothing), prints
    a plain line on stderr at most every :data:`LOG_EVERY_S` seconds while its work goes on:
    ``reading logs: 120/400 (30 %), 0:01:05``. Work shorter than that prints nothing."""

    def __init__(self, *columns: Any, **kwargs: Any):
        kwargs.setdefault("console", err_console)
        super().__init__(*columns, **kwargs)
        self._logged_at = time.monotonic()

    def start(self) -> None:
        """Draw the bar on a terminal; elsewhere draw nothing (Rich would end with a bare line)."""
        if self.console.is_terminal:
            super().start()

    def stop(self) -> None:
        if self.console.is_terminal:
            super().stop()

    def update(self, task_id: TaskID, **kwargs: Any) -> None:  # type: ignore[override]
        super().update(task_id, **kwargs)
        self._log(task_id)

    def advance(self, task_id: TaskID, advance: float = 1) -> None:
        super().advance(task_id, advance)
        self._log(task_id)

    def _log(self, task_id: TaskID) -> None:
        now = time.monotonic()
        if self.console.is_terminal or now - self._logged_at < LOG_EVERY_S:
            return
        self._logged_at = now
        task = next(t for t in self.tasks if t.id == task_id)
        done, total, what = task.completed, task.total, task.description or "working"
        elapsed = task.elapsed or 0.0
        if not total:
            share = f"{done:g}"
        elif total == 1:  # a fraction done (a campaign's progress)
            share = f"{100 * done:.0f} %"
        else:
            share = f"{done:g}/{total:g} ({100 * done / total:.0f} %)"
        minutes, seconds = divmod(int(elapsed), 60)
        self.console.file.write(f"{what}: {share}, {minutes // 60}:{minutes % 60:02d}:"
                                f"{seconds:02d}\n")
        self.console.file.flush()


def progress_bar() -> Progress:
    """A Rich progress bar on stderr (stdout stays clean for --json); without a terminal, a plain
    line now and then (:class:`LoggedProgress`)."""
    return LoggedProgress(TextColumn("{task.description}"), BarColumn(),
                          TextColumn("{task.percentage:>3.0f}%"), TimeElapsedColumn(),
                          transient=True)


def bar_callback(bar: Progress) -> Callable[[str, int, int], None]:
    """``update(description, done, total)`` driving one task of ``bar`` (shown from the first
    update): for work that reports its own steps (training epochs, sample-efficiency runs)."""
    task = bar.add_task("", total=None, visible=False)

    def update(description: str, done: int, total: int) -> None:
        bar.update(task, description=description, completed=done, total=total, visible=True)

    return update
