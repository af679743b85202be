"""``aerodock reproduce`` and ``aerodock targets``: the paper's experiments and the docking
targets beyond it."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from aerodock.cli.common import (
    ConfigOpt,
    JsonOpt,
    SeedOpt,
    SetOpt,
    TrustOpt,
    bar_callback,
    err_console,
    fail,
    load_cli_config,
    print_json,
    progress_bar,
)
from aerodock.fileio import one_line

TARGETS_OUTPUTS = ("data", "targets.json")
"""What ``targets --out`` holds: the folder is replaced as a whole by the next run."""


def reproduce(
    quick: Annotated[bool, typer.Option(help="A smaller run (a few minutes).")] = False,
    smoke: Annotated[bool, typer.Option(
        help="The smallest run that crosses every step (a plug-in field or a config checked "
             "end to end; no figure worth quoting).")] = False,
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("out/reproduce"),
    config: ConfigOpt = None,
    sets: SetOpt = None,
    trust: TrustOpt = None,
    seed: SeedOpt = 0,
    real_data: Annotated[bool, typer.Option(
        help="Run the real-data study (step 5: the Neural-Swarm flights in the data location; it "
             "does not depend on --config).")] = True,
    data_dir: Annotated[Path | None, typer.Option(
        "--data-dir", help="The data location holding neural-swarm/ (default: $AERODOCK_DATA_DIR, "
                           "else ../shared/data in this repository; docs/real-logs.md).")] = None,
) -> None:
    """The paper's experiments end to end: results.json, report.md and figures/."""
    from aerodock.experiments.reproduce import ReportError, run_reproduce
    from aerodock.mission.limits import check_campaign_size

    cfg = load_cli_config(config, sets, trust)
    # Its docking campaigns come after minutes of curriculum: a trial the limits refuse is
    # refused now, not there (each campaign checks its own trials x steps as it starts).
    check_campaign_size(cfg, 1)
    from aerodock.ingest.data_dir import find_data_dir

    located = find_data_dir(data_dir)
    if real_data and located.problem():
        fail(located.problem())
    data = located.path if real_data else None

    def say(msg: str) -> None:
        err_console.print(msg)

    try:
        with progress_bar() as bar:
            results = run_reproduce(cfg, out, quick=quick, seed=seed, say=say,
                                    shared_data=data, bar=bar_callback(bar), smoke=smoke)
    except ReportError as err:
        fail(one_line(str(err)), code=1)
    typer.echo(f"report: {out / 'report.md'}  (results.json, figures/ beside it; "
               f"{results.total_s:.0f} s)")


def targets_command(
    out: Annotated[Path, typer.Option(help="Folder for the curriculum (when no --model) and "
                                           "targets.json.")] = Path("out/targets"),
    model: Annotated[Path | None, typer.Option(
        help="A trained model DIR (default: fly the deep curriculum first, into OUT/data).")
    ] = None,
    trials: Annotated[int, typer.Option(help="Trials per scenario and row.")] = 100,
    config: ConfigOpt = None,
    sets: SetOpt = None,
    trust: TrustOpt = None,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Docking targets beyond the paper (d_p 0.36 and 0.27 m; leader at 0.25 and 0.5 m/s) for
    the paper's controller and ours, with the learnt model, on the configured field."""
    from dataclasses import replace

    from aerodock.control.profiles import controller_config
    from aerodock.experiments.records import TargetsProvenance
    from aerodock.experiments.report_controllers import targets_markdown
    from aerodock.experiments.targets import targets
    from aerodock.fileio import building_dir, check_output_dir, json_ready, write_json
    from aerodock.learning.runtime import Predictor
    from aerodock.mission.limits import check_campaign_size

    if trials < 1:
        fail(f"--trials must be >= 1, got {trials}")
    cfg = load_cli_config(config, sets, trust)
    check_campaign_size(cfg, trials)

    def say(msg: str) -> None:
        err_console.print(f"[dim]{msg}[/dim]")

    check_output_dir(out, TARGETS_OUTPUTS)
    if model is not None and out.resolve() in (model.resolve(), *model.resolve().parents):
        fail(f"--model {model} is inside --out {out}, which this run replaces as a whole; "
             "copy the model elsewhere or give another --out")
    # The folder is built beside --out and swapped in whole: a kill leaves the old curriculum
    # and targets.json or the new ones, never one run's data beside the other's results.
    with building_dir(out, TARGETS_OUTPUTS) as work:
        if model is None:
            from aerodock.collect.curriculum import run_curriculum

            say("curriculum (the paper's stages, then the deep ones)")
            run_curriculum(cfg, work / "data", seed=seed, progress=lambda m: say("  " + m),
                           name_as=out / "data")
            predictor = Predictor.load(work / "data" / "models" / "final")
            model = out / "data" / "models" / "final"
        else:
            predictor = Predictor.load(model)
        from aerodock.deploy.compatibility import model_warnings

        for note in model_warnings(predictor, cfg):
            typer.echo(f"warning: {note}", err=True)
        res = targets({"paper's controller + model": (controller_config(cfg, "paper"), predictor),
                       "ours + model": (controller_config(cfg, "ours"), predictor)},
                      trials, predictor, seed, say)
        res = replace(res, provenance=TargetsProvenance(str(model), cfg.source,
                                                        cfg.downwash.field))
        write_json(work / "targets.json", json_ready(res.to_json()))
    if as_json:
        print_json(res.to_json())
        return
    typer.echo("\n".join(targets_markdown(res)))
    typer.echo(f"wrote {out / 'targets.json'}")
