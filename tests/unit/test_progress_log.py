"""Progress without a terminal: Rich draws nothing into a log file or a pipe, so long work
prints a plain line now and then (aerodock.cli.common.LoggedProgress)."""

from __future__ import annotations

import io

from rich.console import Console
from rich.progress import TextColumn

from aerodock.cli import common


def _bar(out: io.StringIO) -> common.LoggedProgress:
    console = Console(file=out, force_terminal=False)
    return common.LoggedProgress(TextColumn("{task.description}"), console=console,
                                 transient=True)  # as the commands' bars


def test_without_a_terminal_long_work_prints_a_line_per_interval(monkeypatch):
    monkeypatch.setattr(common, "LOG_EVERY_S", 0.0)
    out = io.StringIO()
    with _bar(out) as bar:
        task = bar.add_task("flying trials", total=4)
        bar.update(task, completed=1)
        bar.advance(task)
    lines = out.getvalue().splitlines()
    assert lines[0].startswith("flying trials: 1/4 (25 %), 0:00:0")
    assert lines[1].startswith("flying trials: 2/4 (50 %), ")
    assert len(lines) == 2
    out = io.StringIO()
    with _bar(out) as bar:  # a campaign reports the fraction it has flown
        task = bar.add_task("docking x100 (model)", total=1.0)
        bar.update(task, completed=0.25)
    assert out.getvalue().startswith("docking x100 (model): 25 %, 0:00:0")


def test_short_work_prints_nothing_and_a_terminal_gets_the_bar_only():
    out = io.StringIO()
    with _bar(out) as bar:  # the interval (30 s) is not reached
        task = bar.add_task("flying trials", total=4)
        for _ in range(4):
            bar.advance(task)
    assert out.getvalue() == ""  # not even the bare line Rich ends a bar with
    tty = io.StringIO()
    bar = common.LoggedProgress(TextColumn("{task.description}"),
                                console=Console(file=tty, force_terminal=True))
    bar._logged_at -= 3600  # long past the interval: a terminal still gets no log line
    task = bar.add_task("x", total=2)
    bar.update(task, completed=1)
    assert "1/2" not in tty.getvalue()
