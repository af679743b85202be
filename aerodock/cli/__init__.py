"""The ``aerodock`` command line (Typer). Every command has ``--help``; numbers print as JSON
with ``--json`` (strict JSON: a NaN or an infinity is refused, never printed; where a figure may
legitimately be missing, as in ``bench`` and ``ingest``, it is null); bad input, usage errors
included, give a one-line ``error:`` message and exit code 2 (set ``AERODOCK_DEBUG=1`` for a
traceback). A repeatable option takes several values after one flag (``--data a.npz b.npz``)
in commands without positional arguments.

``run(argv)`` is the whole command line as a function returning the exit code (what the tests
call in-process); ``main()`` is the console entry point around it.

The top layer of the package: nothing else in ``aerodock`` imports this package or Typer.
:mod:`aerodock.cli.common` holds what the commands share, :mod:`aerodock.cli.app` registers
them; each command area has its module here.
"""

from __future__ import annotations


def run(argv: list[str] | None = None) -> int:
    """The command line as a function: run ``argv`` and return the exit code (see
    :func:`aerodock.cli.app.run`)."""
    from aerodock.cli.app import run as run_app

    return run_app(argv)


def main() -> None:
    """Console entry point (``aerodock``): see :func:`aerodock.cli.app.main`."""
    try:
        from aerodock.cli.app import main as main_app
    except KeyboardInterrupt:  # Ctrl-C while the commands load: the same one line as later
        import sys

        sys.stderr.write("interrupted\n")
        raise SystemExit(130) from None
    main_app()
