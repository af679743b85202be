"""``aerodock sweep SPEC.toml``: run a study, write its tidy table and summary figures."""

from __future__ import annotations

import shutil
import time
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer

from aerodock.cli.common import TrustOpt, fail, print_json, progress_bar

OUTPUTS = ("results.csv", "results.parquet", "summary.json", "figures", "cells")
"""What ``sweep --out`` holds: the folder is replaced as a whole by the next sweep into it."""


class Backend(StrEnum):
    """Where the cells run."""

    LOCAL = "local"
    RAY = "ray"


def sweep_command(
    spec_path: Annotated[Path, typer.Argument(metavar="SPEC.toml",
                                              help="The study (see aerodock/sweep/spec.py).")],
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("out/sweep"),
    backend: Annotated[Backend, typer.Option(help="local processes, or Ray.")] = Backend.LOCAL,
    address: Annotated[str | None, typer.Option(
        help="An existing Ray cluster (e.g. auto or ray://host:10001); --backend ray.")] = None,
    jobs: Annotated[int | None, typer.Option(
        help="Parallel workers (default: all CPUs).")] = None,
    resume: Annotated[bool, typer.Option(
        help="Reuse the cells already flown into --out (by an interrupted or an earlier run) "
             "whose settings are unchanged; fly the rest.")] = False,
    as_json: Annotated[bool, typer.Option("--json", help="Print the summary as JSON.")] = False,
    trust: TrustOpt = None,
) -> None:
    """A grid or random study of docking campaigns (cable length x leader speed x noise x fault
    x compensation x controller x any config key x seed): results.csv (+ results.parquet with
    pyarrow), summary.json, figures/sweep_success.png, figures/sweep_error.png and cells/ (each
    campaign's outcomes, what --resume reuses). If the figures fail after the campaigns ran,
    the rest is written and the command exits 1 with one error line."""
    from aerodock.config import load_config
    from aerodock.fileio import building_dir, check_output_dir, json_ready, one_line, write_json
    from aerodock.sweep.figures import cell_summaries, plot_sweep
    from aerodock.sweep.run import run_sweep, write_table
    from aerodock.sweep.spec import check_against_config, load_spec
    from aerodock.sweep.store import CellStore, partial_folder

    spec = load_spec(spec_path)
    if address is not None and backend != Backend.RAY:
        fail("--address needs --backend ray")
    cfg = load_config(spec.config, trusted=trust or ())  # the spec's config: same trust rules
    check_against_config(spec, cfg)  # every cell as dock would check it, before any runs
    check_output_dir(out, OUTPUTS)  # refused now, not after the study has run
    partial = partial_folder(out)
    store = CellStore(partial, reuse_from=(out / "cells", partial) if resume else ())
    started = time.perf_counter()
    with progress_bar() as bar:
        task = bar.add_task(f"sweep: {len(spec.cells)} campaigns x {spec.trials} trials "
                            f"({backend.value})", total=len(spec.cells))
        rows = run_sweep(spec, cfg, backend=backend.value, jobs=jobs, address=address,
                         progress=lambda d, n: bar.update(task, completed=d), store=store)
    # The folder is built beside --out and swapped in whole: a kill leaves the old study or the
    # new one, never the new table beside the old summary and figures.
    figure_error = None
    with building_dir(out, OUTPUTS) as work:
        def named(path: str | Path) -> str:
            return str(out / Path(path).relative_to(work))

        files = {kind: named(p) for kind, p in write_table(rows, work).items()}
        store.export(store.keys.values(), work / "cells")
        figures: list[str] = []
        try:  # the campaigns ran: a figure that fails must not cost the table
            figures = [named(p) for p in plot_sweep(rows, work / "figures", spec.name)]
        except Exception as err:  # noqa: BLE001 - reported in one line below, exit 1
            figure_error = f"{type(err).__name__}: {one_line(err)}"
            shutil.rmtree(work / "figures", ignore_errors=True)
        summary = {"name": spec.name, "kind": spec.kind, "spec": str(spec_path),
                   "backend": backend.value, "campaigns": len(spec.cells), "trials": len(rows),
                   "docked": sum(r["docked"] for r in rows),
                   "flown": len(store.flown), "reused": len(store.reused),
                   "wall_s": time.perf_counter() - started,
                   "files": files, "figures": figures, "cells": cell_summaries(rows)}
        if figure_error is not None:
            summary["figures_error"] = figure_error
        write_json(work / "summary.json", json_ready(summary))
    store.discard()  # its cells are in OUT/cells now
    if as_json:
        print_json(summary)
    else:
        _print_table(spec, summary)
        drawn = f"{len(figures)} figures in {out / 'figures'}" if figures else "no figures"
        typer.echo(f"wrote {', '.join(files.values())}, {out / 'summary.json'}, "
                   f"{out / 'cells'} and {drawn} ({summary['wall_s']:.0f} s; "
                   f"{len(store.flown)} campaigns flown, {len(store.reused)} reused)")
    if figure_error is not None:
        fail(f"the figures failed ({figure_error}); the tables, cells/ and summary.json are "
             f"written in {out}", code=1)


def _print_table(spec: Any, summary: dict[str, Any]) -> None:
    """The per-cell table on stdout: settings, then docked with its Wilson 95 % interval."""
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    keys = [k for k, _ in spec.axes.items() if "." in k]
    table = Table(title=escape(f"{spec.name}: {summary['trials']} trials, "
                               f"{summary['campaigns']} campaigns"))
    for col in ("cell", "d_p [m]", "speed [m/s]", "noise", "fault", "compensation",
                "controller", *keys, "seed", "docked"):
        table.add_column(escape(col))
    for c in summary["cells"]:
        lo, hi = c["success_wilson95"]
        table.add_row(str(c["cell"]), f"{c['cable_length_m']:g}", f"{c['leader_speed_mps']:g}",
                      f"{c['mocap_noise_scale']:g}", c["fault"], c["compensation"],
                      c["controller"], *(escape(str(c[k])) for k in keys), str(c["seed"]),
                      f"{c['docked']}/{c['trials']} ({lo:.0%}-{hi:.0%})")
    Console().print(table)
