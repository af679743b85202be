"""The ``aerodock`` app: every command registered in one place, and ``run``/``main`` around it.

Each command area has its module in :mod:`aerodock.cli` (``field``, ``dock``, ``learning``,
``compensation``, ``experiments``, ``ingest``, ``node``, ``view``, ``sweep``, ``bench``) holding
plain functions;
nothing registers itself on import. The order below is the order of ``aerodock --help``. Heavy
dependencies (PyTorch, rclpy, Ray, rerun; numba and SciPy, through the modules that fly or fit)
are imported inside the commands that need them, so ``aerodock --help`` stays fast (tested:
``test_help_does_not_load_the_compiled_world``) and every other command works without the
extras.
"""

from __future__ import annotations

import functools
import inspect
import os
import re
import signal
import sys
from typing import Annotated, Any

import typer
from rich.markup import escape

from aerodock.cli import (
    bench,
    compensation,
    dock,
    experiments,
    field,
    field_fit,
    ingest,
    learning,
    node,
    sweep,
    view,
)
from aerodock.fileio import one_line

app = typer.Typer(
    add_completion=False, no_args_is_help=True, pretty_exceptions_enable=False,
    help="Docking two multirotors in close proximity with learnt downwash models.",
)
field_app = typer.Typer(no_args_is_help=True, help="Inspect a downwash field or a learnt model.")


def _print_version(value: bool) -> None:
    if value:
        import aerodock

        typer.echo(f"aerodock {aerodock.__version__}")
        raise typer.Exit()


@app.callback()
def _root(version: Annotated[bool, typer.Option(
        "--version", callback=_print_version, is_eager=True,
        help="Print aerodock's version and exit.")] = False) -> None:
    pass  # the options of ``aerodock`` itself (before a command)


app.add_typer(field_app, name="field")

app.command("dock")(dock.dock)
app.command("faults")(dock.faults_command)
app.command("bench")(bench.bench_command)
app.command("ingest")(ingest.ingest_command)
app.command("train")(learning.train_command)
app.command("evaluate")(learning.evaluate_command)
app.command("evaluate-compensation")(compensation.evaluate_compensation_command)
app.command("export")(learning.export_command)
app.command("node", context_settings=node.CONTEXT_SETTINGS,
            options_metavar=node.OPTIONS_METAVAR)(node.node_command)
app.command("view")(view.view_command)
app.command("sweep")(sweep.sweep_command)
app.command("collect")(learning.collect)
app.command("reproduce")(experiments.reproduce)
app.command("targets")(experiments.targets_command)
field_app.command("probe")(field.field_probe)
field_app.command("plot")(field.field_plot)
field_app.command("fit")(field_fit.field_fit)
field_app.command("score")(field_fit.field_score)


def as_written(text: str | None) -> str | None:
    """A help text as Rich's help should show it, as written: code quoted in double or single
    backticks (RST, Markdown) is quoted in single quotes instead, and brackets are escaped so
    that Rich does not take ``[[fault]]`` or ``aerodock[viz]`` for markup and drop them."""
    if not text:
        return text
    text = re.sub(r"``([^`]+)``", r"'\1'", text)
    text = re.sub(r"`([^`]+)`", r"'\1'", text)
    return escape(text)


def _readable(command: Any) -> Any:
    """``command`` (a Click command or group) with every help text of it and of its
    subcommands and parameters passed through :func:`as_written`, and its line in a group's
    list of commands the help's first paragraph as one line; returns ``command``."""
    if not getattr(command, "short_help", None) and getattr(command, "help", None):
        command.short_help = " ".join(inspect.cleandoc(command.help).split("\n\n")[0].split())
    for attr in ("help", "short_help", "epilog"):
        setattr(command, attr, as_written(getattr(command, attr, None)))
    for param in getattr(command, "params", []):
        if hasattr(param, "help"):
            param.help = as_written(param.help)
    for sub in getattr(command, "commands", {}).values():
        _readable(sub)
    return command


@functools.cache
def command() -> Any:
    """The whole command line as a Click group, its help texts readable (:func:`_readable`).

    Built once per process: Typer builds it from the commands' signatures, evaluating every
    annotation (about 0.15 s here), and each run parses its arguments with a new context of
    the same group (a process that runs the command line a hundred times, as the fuzz suite
    does, built it twice a run)."""
    return _readable(typer.main.get_command(app))


def _click_exceptions() -> Any:
    """Click's exceptions module, of the click Typer runs on (recent Typer vendors a copy)."""
    import importlib

    import typer.core

    package = getattr(typer.core, "_click", None) or typer.core.click
    return importlib.import_module(f"{package.__name__}.exceptions")


def _expand_repeatable(args: list[str]) -> list[str]:
    """``--data a b`` -> ``--data a --data b`` for the repeatable options of the subcommand.

    Only in commands without positional arguments (there a value list is unambiguous); a value
    list ends at the next token starting with ``-``.
    """
    group = command()
    names = [a for a in args if not a.startswith("-")]
    chosen: Any = group
    for name in names[:2]:
        sub = getattr(chosen, "commands", {}).get(name)
        if sub is None:
            break
        chosen = sub
    params = getattr(chosen, "params", [])
    if chosen is group or any(p.param_type_name == "argument" for p in params):
        return args
    repeatable = {o for p in params
                  if p.param_type_name == "option" and getattr(p, "multiple", False)
                  for o in p.opts}
    out: list[str] = []
    current: str | None = None
    taken = 0
    for arg in args:
        flag = arg.split("=", 1)[0]
        if flag in repeatable:
            current, taken = flag, int("=" in arg)
            out.append(arg)
        elif current is not None and not arg.startswith("-"):
            if taken:
                out.append(current)
            out.append(arg)
            taken += 1
        else:
            current = None
            out.append(arg)
    return out


def run(argv: list[str] | None = None) -> int:
    """The command line as a function: run ``argv`` and return the exit code.

    Usage errors and bad input print one ``error:`` line on stderr and return 2; an interrupt
    returns 130; an unexpected failure (a bug) returns 1 with its type name.
    """
    click = _click_exceptions()
    args = list(sys.argv[1:] if argv is None else argv)
    try:
        args = _expand_repeatable(args)
        rv = command().main(args=args, prog_name="aerodock", standalone_mode=False)
        if rv == 130:  # Typer turns a KeyboardInterrupt in a command into a silent Exit(130)
            typer.echo("interrupted", err=True)
        return rv if isinstance(rv, int) else 0
    except getattr(click, "NoArgsIsHelpError", ()) as err:
        typer.echo(err.ctx.get_help())
        return 0
    except click.UsageError as err:
        hint = f" (see '{err.ctx.command_path} --help')" if err.ctx is not None else ""
        typer.echo(f"error: {one_line(err.format_message())}{hint}", err=True)
        return 2
    except click.ClickException as err:
        typer.echo(f"error: {one_line(err.format_message())}", err=True)
        return 2
    except (KeyboardInterrupt, typer.Abort):
        typer.echo("interrupted", err=True)
        return 130
    except Exception as err:  # noqa: BLE001 - the one place errors become messages
        if _from_interrupt(err):
            typer.echo("interrupted", err=True)
            return 130
        if os.environ.get("AERODOCK_DEBUG"):
            raise
        expected = isinstance(err, ValueError | OSError | MemoryError)
        if isinstance(err, MemoryError):
            detail = "out of memory (the input or the run is too large)"
        elif isinstance(err, OSError) and err.strerror and err.filename:
            detail = f"{err.filename}: {err.strerror}"
        else:
            detail = one_line(err)
        msg = detail if expected else f"{type(err).__name__}: {detail}"
        typer.echo(f"error: {msg}", err=True)
        if not expected:
            typer.echo("(set AERODOCK_DEBUG=1 for a traceback)", err=True)
        return 2 if expected else 1


def _from_interrupt(err: BaseException) -> bool:
    """Whether ``err`` came of a Ctrl-C: a ``KeyboardInterrupt`` among its causes. The
    interrupt can land while a compiled kernel returns (numba's kernels release the GIL, and
    the signal's handler runs when they take it back); Python then reports "returned a result
    with an exception set" as a ``SystemError`` caused by the interrupt."""
    seen: set[int] = set()
    cause: BaseException | None = err
    while cause is not None and id(cause) not in seen:
        if isinstance(cause, KeyboardInterrupt):
            return True
        seen.add(id(cause))
        cause = cause.__cause__ or cause.__context__
    return False


def _terminate(signum: int, frame: Any) -> None:
    # SIGTERM unwinds like an interrupt, so atomic writes remove their temporary files.
    raise SystemExit(128 + signum)


def main() -> None:
    """Console entry point: run the app; turn errors into one-line messages."""
    signal.signal(signal.SIGTERM, _terminate)
    code = run()
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # done: a late Ctrl-C does not break the exit
    sys.exit(code)
