"""No finished work lost: intervals that hold k/n, all-docked cells, a figure that fails after the
campaigns ran, and ``sweep --resume`` reusing the cells already flown (and only those)."""

from __future__ import annotations

import csv
import io
import json
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import pytest
from short_mission import short_mission_toml

from aerodock.mission import wilson_interval

# The mission's waiting times cut and the world at its cheapest (point-mass vehicles, physics at
# the control rate): what is tested is the bookkeeping, not what the campaigns achieve.
FAST_WORLD = '[vehicle]\nmodel = "point-mass"\n[sim]\nphysics_rate_hz = 100.0\n'


def test_wilson_interval_holds_the_proportion_inside_zero_one():
    for n in range(1, 120):
        for k in range(n + 1):
            lo, hi = wilson_interval(k, n)
            assert 0.0 <= lo <= k / n <= hi <= 1.0, (k, n, lo, hi)
    # the audit's cases: all docked gave 0.9999999999999999 at n = 4, 10, 14, 19, ...
    for n in (4, 10, 14, 19, 24, 29, 33, 34, 44, 45, 50):
        assert wilson_interval(n, n)[1] == 1.0
        assert wilson_interval(0, n)[0] == 0.0
    lo, hi = wilson_interval(5, 10)
    assert 0.2 < lo < 0.5 < hi < 0.8  # a real interval, not [0, 1]


def _study(tmp_path: Path, axes: str, trials: int = 2, seeds: str = "[0]",
           name: str = "spec.toml") -> Path:
    (tmp_path / "fast.toml").write_text(FAST_WORLD + short_mission_toml())
    spec = tmp_path / name
    spec.write_text(f'[sweep]\ntrials = {trials}\nseeds = {seeds}\nconfig = "fast.toml"\n'
                    f"[axes]\n{axes}\n")
    return spec


class Run:
    """One in-process ``aerodock`` run: exit code, stdout, stderr."""

    def __init__(self, args: list) -> None:
        from aerodock.cli import run

        out, err = io.StringIO(), io.StringIO()
        with redirect_stdout(out), redirect_stderr(err):
            self.rc = run([str(a) for a in args])
        self.out, self.err = out.getvalue(), err.getvalue()


run_cli = Run


def _rows(out: Path) -> list[dict[str, str]]:
    with open(out / "results.csv") as fh:
        return list(csv.DictReader(fh))


def test_all_docked_cells_at_four_trials_write_tables_and_figures(tmp_path):
    """The audit's 2 x 2 grid at trials = 4: every campaign runs, then everything is written."""
    spec = _study(tmp_path, 'cable_length_m = [0.64, 1.35]\ncompensation = ["observer", '
                  '"oracle"]', trials=4)
    out = tmp_path / "out"
    res = run_cli(["sweep", spec, "--out", out, "--jobs", "1", "--json"])
    assert res.rc == 0, res.err
    summary = json.loads((out / "summary.json").read_text())
    full = [c for c in summary["cells"] if c["docked"] == c["trials"] == 4]
    assert full, "no all-docked cell: the case under test did not happen"
    assert all(c["success_wilson95"][1] == 1.0 for c in full)
    assert len(_rows(out)) == 16
    for name in ("sweep_success.png", "sweep_error.png"):
        assert (out / "figures" / name).read_bytes()[:4] == b"\x89PNG"
    assert summary["flown"] == 4 and summary["reused"] == 0
    assert len(list((out / "cells").glob("*.json"))) == 4
    assert not (tmp_path / ".out.cells").exists()  # the cells are in the study now


def test_failing_figures_still_write_the_tables_and_summary(tmp_path, monkeypatch):
    import aerodock.sweep.figures as figures

    def broken(rows, fig_dir, title="sweep"):
        Path(fig_dir).mkdir(parents=True)
        (Path(fig_dir) / "sweep_success.png").write_bytes(b"half")
        raise ValueError("'yerr' must not contain\nnegative values")

    monkeypatch.setattr(figures, "plot_sweep", broken)
    spec = _study(tmp_path, 'compensation = ["oracle"]')
    out = tmp_path / "out"
    res = run_cli(["sweep", spec, "--out", out, "--jobs", "1"])
    assert res.rc == 1
    errors = [line for line in res.err.splitlines() if line.strip()]
    assert len(errors) == 1 and errors[0].startswith("error: the figures failed")
    assert "yerr" in errors[0] and "Traceback" not in res.err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["figures"] == [] and "yerr" in summary["figures_error"]
    assert len(_rows(out)) == summary["trials"] == 2
    assert not (out / "figures").exists()  # no half-drawn figure
    assert len(list((out / "cells").glob("*.json"))) == 1


@pytest.fixture
def flights(monkeypatch) -> list[int]:
    """The cells flown in this process: one entry (its seed) per cell, however many cells one
    ``run_campaign`` flies as a batch (one per campaign seed)."""
    import aerodock.mission as mission

    flown: list[int] = []
    real = mission.run_campaign

    def counting(cfg, spec, *args, **kwargs):
        seeds = kwargs.get("seeds")
        flown.extend([spec.seed] if seeds is None else sorted(set(int(s) for s in seeds)))
        return real(cfg, spec, *args, **kwargs)

    monkeypatch.setattr(mission, "run_campaign", counting)
    return flown


def test_resume_reuses_finished_cells_and_only_those(tmp_path, flights):
    out = tmp_path / "out"
    axes = 'compensation = ["oracle"]\ndownwash.params.turb_vertical = [0.1, 0.3]'
    spec = _study(tmp_path, axes, seeds="[0]")
    assert run_cli(["sweep", spec, "--out", out, "--jobs", "1"]).rc == 0
    assert len(flights) == 2
    first = _rows(out)

    # one more seed: the two cells flown are reused, the two new ones flown
    spec = _study(tmp_path, axes, seeds="[0, 1]")
    res = run_cli(["sweep", spec, "--out", out, "--jobs", "1", "--resume", "--json"])
    assert res.rc == 0, res.err
    assert len(flights) == 4
    summary = json.loads(res.out)
    assert (summary["flown"], summary["reused"]) == (2, 2)
    again = _rows(out)
    old = {(r["downwash.params.turb_vertical"], r["trial"]): r for r in first}
    for r in again:
        if r["seed"] == "0":  # the same outcomes, renumbered into the new grid
            assert {k: v for k, v in r.items() if k != "cell"} == {
                k: v for k, v in old[r["downwash.params.turb_vertical"], r["trial"]].items()
                if k != "cell"}

    # a changed setting is another cell: nothing stale is reused
    spec = _study(tmp_path, axes.replace("0.3", "0.35"), seeds="[0, 1]")
    res = run_cli(["sweep", spec, "--out", out, "--jobs", "1", "--resume", "--json"])
    assert res.rc == 0, res.err
    assert (json.loads(res.out)["flown"], len(flights)) == (2, 6)  # turb 0.35, both seeds

    # without --resume, everything flies
    res = run_cli(["sweep", spec, "--out", out, "--jobs", "1", "--json"])
    assert json.loads(res.out)["reused"] == 0 and len(flights) == 10


def test_resume_after_an_interrupt_gives_the_uninterrupted_table(tmp_path, flights,
                                                                  monkeypatch):
    import aerodock.mission as mission

    # two points of two seeds: two batches (a batch flies a point's seeds together)
    axes = 'compensation = ["oracle"]\ndownwash.params.turb_vertical = [0.1, 0.3]'
    spec = _study(tmp_path, axes, seeds="[0, 1]")
    whole = tmp_path / "whole"
    assert run_cli(["sweep", spec, "--out", whole, "--jobs", "1"]).rc == 0
    assert len(flights) == 4
    counting = mission.run_campaign
    campaigns: list[int] = []

    def interrupted_second(cfg, spec, *args, **kwargs):
        campaigns.append(spec.trials)
        if len(campaigns) == 2:  # the second batch of the run below
            raise KeyboardInterrupt
        return counting(cfg, spec, *args, **kwargs)

    monkeypatch.setattr(mission, "run_campaign", interrupted_second)
    out = tmp_path / "out"
    res = run_cli(["sweep", spec, "--out", out, "--jobs", "1"])
    assert (res.rc, res.err.strip()) == (130, "interrupted")
    assert not out.exists()  # nothing half-written
    assert len(list((tmp_path / ".out.cells").glob("*.json"))) == 2  # the first batch's cells
    monkeypatch.setattr(mission, "run_campaign", counting)
    res = run_cli(["sweep", spec, "--out", out, "--jobs", "1", "--resume", "--json"])
    assert res.rc == 0, res.err
    assert (json.loads(res.out)["reused"], json.loads(res.out)["flown"]) == (2, 2)
    assert (out / "results.csv").read_bytes() == (whole / "results.csv").read_bytes()
    assert not (tmp_path / ".out.cells").exists()


def test_a_damaged_cell_file_is_flown_again(tmp_path, flights):
    spec = _study(tmp_path, 'compensation = ["oracle"]', seeds="[0, 1, 2]")
    out = tmp_path / "out"
    assert run_cli(["sweep", spec, "--out", out, "--jobs", "1"]).rc == 0
    cells = sorted((out / "cells").glob("*.json"))
    cells[0].write_text(cells[0].read_text()[:-40])  # cut short
    doc = json.loads(cells[1].read_text())
    doc["outcomes"][0]["docked"] = "yes"  # a value the flown cell would not hold
    cells[1].write_text(json.dumps(doc))
    before = len(flights)
    res = run_cli(["sweep", spec, "--out", out, "--jobs", "1", "--resume", "--json"])
    assert res.rc == 0, res.err
    assert json.loads(res.out)["reused"] == 1 and len(flights) == before + 2


def test_crafted_cell_files_are_flown_again_not_errors(tmp_path, flights):
    """Numbers a flown cell never holds (NaN, Infinity, an integer too large for a float, an
    abort reason that is no reason) make the file unusable, not the resume."""
    spec = _study(tmp_path, 'compensation = ["oracle"]', seeds="[0, 1, 2]")
    out = tmp_path / "out"
    assert run_cli(["sweep", spec, "--out", out, "--jobs", "1"]).rc == 0
    cells = sorted((out / "cells").glob("*.json"))
    edits = ('"min_clearance_m": NaN', '"min_clearance_m": ' + "9" * 400,
             '"abort_reason": "gremlins"')
    for path, edit in zip(cells, edits, strict=True):
        text = path.read_text()
        key = edit.split(":")[0]
        start = text.index(key)
        end = text.index(",", start)
        path.write_text(text[:start] + edit + text[end:])
    before = len(flights)
    res = run_cli(["sweep", spec, "--out", out, "--jobs", "1", "--resume", "--json"])
    assert res.rc == 0, res.err
    assert json.loads(res.out)["reused"] == 0 and len(flights) == before + 3


def test_a_cell_flown_by_other_code_is_not_reused(tmp_path, flights, monkeypatch):
    """The version number stays the same across commits of an editable install: the cell's key
    holds a digest of aerodock's sources."""
    from aerodock.sweep import store

    spec = _study(tmp_path, 'compensation = ["oracle"]')
    out = tmp_path / "out"
    assert run_cli(["sweep", spec, "--out", out, "--jobs", "1"]).rc == 0
    monkeypatch.setattr(store, "_DIGESTS", {})
    monkeypatch.setattr(store, "code_digest", lambda cfg=None: "other code")
    before = len(flights)
    res = run_cli(["sweep", spec, "--out", out, "--jobs", "1", "--resume", "--json"])
    assert res.rc == 0, res.err
    assert json.loads(res.out)["reused"] == 0 and len(flights) == before + 1
