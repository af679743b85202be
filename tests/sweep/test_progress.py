"""Progress bars: the sweep reports every campaign; the bar callback drives a Rich task."""

from __future__ import annotations

from rich.console import Console
from rich.progress import Progress

from aerodock.cli.common import bar_callback
from aerodock.sweep import parse_spec, run_sweep


def test_sweep_reports_each_campaign(short_cfg):
    # (whatever the mission's timing and the campaigns: the short timing, tests/short_mission.py,
    # and the oracle, whose trials end when they dock rather than at the time limit)
    spec = parse_spec({"sweep": {"trials": 1, "seeds": [0, 1]},
                       "axes": {"compensation": ["oracle"]}})
    seen = []
    run_sweep(spec, short_cfg, jobs=1, progress=lambda d, n: seen.append((d, n)))
    assert seen == [(1, 2), (2, 2)]


def test_bar_callback_shows_description_and_counts():
    console = Console(record=True, force_terminal=True, width=80)
    with Progress(console=console, auto_refresh=False) as bar:
        update = bar_callback(bar)
        (task,) = bar.tasks
        assert not task.visible
        update("training epochs", 3, 10)
        bar.refresh()
        assert task.visible and task.completed == 3 and task.total == 10
    assert "training epochs" in console.export_text()
