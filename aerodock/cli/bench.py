"""``aerodock bench``: every hot path's speed, as a table or as JSON (:mod:`aerodock.bench`)."""

from __future__ import annotations

from enum import StrEnum
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from aerodock.bench import PARTS
from aerodock.cli.common import (
    ConfigOpt,
    JsonOpt,
    SetOpt,
    TrustOpt,
    config_for_children,
    fail,
    load_cli_config,
    print_json,
)
from aerodock.fileio import json_ready

BenchPart = StrEnum("BenchPart", {part: part for part in PARTS})
"""``--only``'s choices: the parts of :func:`aerodock.bench.run_all`."""


def bench_command(
    quick: Annotated[bool, typer.Option(
        "--quick", help="Fewer, shorter repetitions; skips `reproduce --quick`.")] = False,
    as_json: JsonOpt = False,
    config: ConfigOpt = None,
    sets: SetOpt = None,
    trust: TrustOpt = None,
    only: Annotated[BenchPart | None, typer.Option(
        "--only", help="Measure one part alone.")] = None,
) -> None:
    """Measure the speed of every hot path: simulator, docking, learnt model, training,
    `reproduce --quick`, memory, and RotorPy and crazyflow on the same scenario (if
    installed)."""
    if only is not None and only not in PARTS:
        fail(f"unknown --only {only!r}; choose one of {', '.join(PARTS)}")

    from aerodock.bench import run_all, table_rows  # (NumPy and the bench's modules: on use)

    cfg = load_cli_config(config, sets, trust)
    err = Console(stderr=True)
    with config_for_children(cfg, config, sets, trust) as child_config, \
            err.status("benchmarking") as status:
        def progress(msg: str) -> None:
            if err.is_terminal:
                status.update(f"benchmarking: {msg}")
            else:
                err.print(f"bench: {msg}", highlight=False)

        doc = run_all(cfg, quick=quick, progress=progress, config_path=child_config,
                      only=None if only is None else str(only))
    if as_json:
        print_json(json_ready(doc))  # a figure that could not be computed is null
        return
    m = doc["machine"]
    load = m.get("load_average_1_5_15_min")
    table = Table(title=f"aerodock bench{' --quick' if quick else ''}: {m['cpu']}, "
                  f"{m['cores']} cores, Python {m['versions']['python']}"
                  + (f", load average {load[0]:g} / {load[1]:g} / {load[2]:g} (1/5/15 min, "
                     "at the end)" if load else ""))
    for col, justify in (("figure", "left"), ("median", "right"), ("spread (min - max)", "right"),
                         ("unit", "left"), ("note", "left")):
        table.add_column(col, justify=justify)  # type: ignore[arg-type]
    for row in table_rows(doc):
        table.add_row(*row)
    console = Console()
    console.print(table)
    for t in doc["targets"]:
        mark = {True: "met", False: "NOT met", None: "not measured"}[t["met"]]
        value = t["measured"]
        measured = ("-" if value is None else f"{value:,.0f}" if value >= 1000
                    else f"{value:.3g}")
        console.print(f"target {t['target']} {t['threshold']}: {measured} ({mark})")
