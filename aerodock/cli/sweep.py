"""``aerodock sweep SPEC.toml``: run a study, write its tidy table and summary figures."""

from __future__ import annotations

import time
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from aerodock.cli.common import TrustOpt, fail, print_json, progress_bar

OUTPUTS = ("results.csv", "results.parquet", "summary.json", "figures")
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
    as_json: Annotated[bool, typer.Option("--json", help="Print the summary as JSON.")] = False,
    trust: TrustOpt = None,
) -> None:
    """A grid or random study of docking campaigns (cable length x leader speed x noise x fault
    x compensation x seed): results.csv (+ results.parquet with pyarrow), summary.json and
    figures/sweep_success.png, figures/sweep_error.png."""
    from rich.console import Console
    from rich.table import Table

    from aerodock.config import load_config
    from aerodock.fileio import building_dir, check_output_dir, json_ready, write_json
    from aerodock.sweep.figures import cell_summaries, plot_sweep
    from aerodock.sweep.run import run_sweep, write_table
    from aerodock.sweep.spec import check_against_config, load_spec

    spec = load_spec(spec_path)
    if address is not None and backend != Backend.RAY:
        fail("--address needs --backend ray")
    cfg = load_config(spec.config, trusted=trust or ())  # the spec's config: same trust rules
    check_against_config(spec, cfg)  # every cell as dock would check it, before any runs
    check_output_dir(out, OUTPUTS)  # refused now, not after the study has run
    started = time.perf_counter()
    with progress_bar() as bar:
        task = bar.add_task(f"sweep: {len(spec.cells)} campaigns x {spec.trials} trials "
                            f"({backend.value})", total=len(spec.cells))
        rows = run_sweep(spec, cfg, backend=backend.value, jobs=jobs, address=address,
                         progress=lambda d, n: bar.update(task, completed=d))
    # The folder is built beside --out and swapped in whole: a kill leaves the old study or the
    # new one, never the new table beside the old summary and figures.
    with building_dir(out, OUTPUTS) as work:
        def named(path: str | Path) -> str:
            return str(out / Path(path).relative_to(work))

        files = {kind: named(p) for kind, p in write_table(rows, work).items()}
        figures = [named(p) for p in plot_sweep(rows, work / "figures", spec.name)]
        summary = {"name": spec.name, "kind": spec.kind, "spec": str(spec_path),
                   "backend": backend.value, "campaigns": len(spec.cells), "trials": len(rows),
                   "docked": sum(r["docked"] for r in rows),
                   "wall_s": time.perf_counter() - started,
                   "files": files, "figures": figures, "cells": cell_summaries(rows)}
        write_json(work / "summary.json", json_ready(summary))
    if as_json:
        print_json(summary)
        return
    table = Table(title=f"{spec.name}: {len(rows)} trials, {len(spec.cells)} campaigns")
    for col in ("cell", "d_p [m]", "speed [m/s]", "noise", "fault", "compensation", "seed",
                "docked"):
        table.add_column(col)
    for c in summary["cells"]:
        lo, hi = c["success_wilson95"]
        table.add_row(str(c["cell"]), f"{c['cable_length_m']:g}", f"{c['leader_speed_mps']:g}",
                      f"{c['mocap_noise_scale']:g}", c["fault"], c["compensation"],
                      str(c["seed"]), f"{c['docked']}/{c['trials']} ({lo:.0%}-{hi:.0%})")
    Console().print(table)
    typer.echo(f"wrote {', '.join(files.values())}, {out / 'summary.json'} and "
               f"{len(figures)} figures in {out / 'figures'} ({summary['wall_s']:.0f} s)")
