"""The headline tables (README, docs/results/headline.md) from a reproduction's results.json, so
that every figure in them is read by code from the run that computed it.

    .venv/bin/python studies/headline_table.py out/full/results.json [--before OLD.json]
        [--smoke]    # accepted for the suite: the script only reads the file

With ``--before``, each cell is followed by the other run's figure in brackets (a run of the same
size, e.g. before a change of the world). An offset of the cable study counts as docked when more
than half of its repetitions dock.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from _smoke import add_smoke_option  # studies/, on sys.path

HOVER, MOVING, CABLE = "hover_docking", "moving_leader", "cable_study"
# What the paper reports for each row (docking-paper.tex), quoted beside the run's figures.
PAPER = {"hover docking, d_p 0.36 m": "8/10 with model",
         "terminal vertical error, median": "< 0.06 m with model",
         "leader's sink when the post-dock window ends (hover, median)": "the leader dips",
         "terminal tilt RMS (hover, median)": "-",
         "leader moving": "very limited",
         "cable study (leader on a stand), offsets docked": "6/6 with vs 0/6 without"}


def _rate(cell: dict[str, Any]) -> str:
    lo, hi = cell["success_wilson95"]
    return f"{cell['docked']}/{cell['trials']} ({100 * lo:.0f}%-{100 * hi:.0f}%)"


def _count(cell: dict[str, Any]) -> str:
    return f"{cell['docked']}/{cell['trials']}"


def _fig(value: float | None, fmt: str, unit: str) -> str:
    """A figure, or "-" where the run has none (e.g. no trial docked)."""
    return "-" if value is None else f"{value:{fmt}} {unit}"


def _offsets_docked(rows: list[dict[str, Any]]) -> str:
    docked = sum(1 for r in rows if r["docked"] > r["trials"] / 2)
    return f"{docked}/{len(rows)}"


def _runs(results: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """The paper's controller's sections and ours' (``controllers.ours``)."""
    return {"paper": results, "ours": results["controllers"]["ours"]}


def headline_cells(results: dict[str, Any]) -> dict[str, list[str]]:
    """Row name -> cells: the paper's controller without and with its model, ours without and
    with the deep model."""
    runs = _runs(results)
    rows: dict[str, list[str]] = {}

    def per_mode(section: str, fmt: Any) -> list[str]:
        return [fmt(runs[who][section][mode]) for who in ("paper", "ours")
                for mode in ("without_model", "with_model")]

    rows["hover docking, d_p 0.36 m"] = per_mode(HOVER, _rate)
    rows["terminal vertical error, median"] = per_mode(
        HOVER, lambda c: _fig(c["terminal_err_down_median_m"], ".3f", "m"))
    rows["leader's sink when the post-dock window ends (hover, median)"] = per_mode(
        HOVER, lambda c: _fig(c["post_dock_sink_median_m"], ".2f", "m"))
    rows["terminal tilt RMS (hover, median)"] = per_mode(
        HOVER, lambda c: _fig(c["terminal_tilt_rms_deg_median"], ".1f", "deg"))
    speed = results[MOVING]["leader_speed_mps"]
    rows[f"leader moving {speed:g} m/s"] = per_mode(MOVING, _rate)
    rows["cable study (leader on a stand), offsets docked"] = [
        _offsets_docked(runs[who][CABLE][mode]) for who in ("paper", "ours")
        for mode in ("without_model", "with_model")]
    return rows


def targets_cells(results: dict[str, Any]) -> dict[str, list[str]]:
    """Row (controller + model) -> cells: each scenario's docked count (with its interval),
    then the hover scenario's terminal error, tilt and the rotor strikes over all scenarios."""
    out = {}
    for name, row in results["targets"]["rows"].items():
        cells = row["scenarios"]
        first = next(iter(cells.values()))
        strikes = sum(c["rotor_strikes"] for c in cells.values())
        out[name] = [_rate(c) + (" met" if c["met"] else "") for c in cells.values()] + [
            _fig(first["terminal_err_down_median_m"], ".4f", "m"),
            _fig(first["terminal_tilt_rms_deg_median"], ".1f", "deg"), str(strikes)]
    return out


def _table(header: list[str], rows: dict[str, list[str]],
           before: dict[str, list[str]] | None, quoted: dict[str, str] | None = None) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for name, cells in rows.items():
        old = (before or {}).get(name)
        shown = [c if old is None else f"{c} [{o}]" for c, o in zip(cells, old or cells)]
        lead = [] if quoted is None else [next((v for k, v in quoted.items()
                                                if name.startswith(k)), "-")]
        lines.append("| " + " | ".join([name, *lead, *shown]) + " |")
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", type=Path)
    parser.add_argument("--before", type=Path, default=None)
    add_smoke_option(parser)
    args = parser.parse_args()
    try:
        results = json.loads(args.results.read_text())
        before = json.loads(args.before.read_text()) if args.before else None
        head = headline_cells(results)
        targets = targets_cells(results)
        old_head = headline_cells(before) if before else None
        old_targets = targets_cells(before) if before else None
    except (OSError, ValueError, KeyError, TypeError) as err:
        print(f"error: cannot read the headline from {args.results}: "
              f"{type(err).__name__}: {err}", file=sys.stderr)
        return 2
    print(_table(["experiment", "paper", "paper's controller, without model", "with model",
                  "ours, without model", "with model"], head, old_head, PAPER))
    print()
    names = [s["name"] for s in results["targets"]["scenarios"]]
    print(_table(["controller + model", *names, "terminal err down (hover)", "tilt RMS (hover)",
                  "rotor strikes"], targets, old_targets))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
