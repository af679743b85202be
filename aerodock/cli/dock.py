"""``aerodock dock`` and ``aerodock faults``: docking campaigns, with and without faults."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.table import Table

from aerodock.cli.common import (
    ConfigOpt,
    JsonOpt,
    SeedOpt,
    SetOpt,
    TrustOpt,
    check_number,
    fail,
    load_cli_config,
    print_json,
    progress_bar,
)
from aerodock.control.compensation import Compensation


class Controller(StrEnum):
    """The follower's controller profile (:mod:`aerodock.control.profiles`)."""

    PAPER = "paper"
    TUNED = "tuned"
    OURS = "ours"


COMPENSATION_HELP = (
    "What the follower subtracts before inversion. none: nothing, every observer off (plain LQR; "
    "with --controller ours that turns off the accelerometer observer too, so it is not 'ours "
    "without model'); observer: the bias observer, and with ours its accelerometer observer "
    "(the paper's 'without model'); model: observer + the learnt model ('with model'); "
    "oracle: observer + the simulator's true mean field (an upper bound).")


def _load_predictor(model: Path | None, comp: Compensation):
    if comp != Compensation.MODEL:
        return None
    if model is None:
        fail("--compensation model needs --model DIR (a trained model)")
    from aerodock.learning.runtime import Predictor

    return Predictor.load(model)


def dock(
    trials: Annotated[int, typer.Option(help="Number of docking trials (one batch).")] = 50,
    offset: Annotated[float | None, typer.Option(help="Cable length d_p, m.")] = None,
    leader_speed: Annotated[float, typer.Option(help="Leader speed (north), m/s.")] = 0.0,
    leader_fixed: Annotated[bool, typer.Option(help="Leader on a rigid stand.")] = False,
    compensation: Annotated[Compensation, typer.Option(help=COMPENSATION_HELP)] = (
        Compensation.OBSERVER),
    model: Annotated[Path | None, typer.Option(help="Trained model DIR (for 'model').")] = None,
    controller: Annotated[Controller, typer.Option(
        help="paper: as its flight stack (Freyja) publishes it: its LQR weights in every phase, "
             "its bias estimator and state filter, 50 Hz, no reference feed-forward; tuned: the "
             "config's weights (stiffer terminal phase by default); ours: tuned + the "
             "accelerometer observer (on unless --compensation none).")] = Controller.TUNED,
    faults: Annotated[Path | None, typer.Option(
        help="TOML file of [[fault]] entries injected into every trial (see examples/).")] = None,
    seed: SeedOpt = 0,
    save_logs: Annotated[Path | None, typer.Option(help="Write the FlightLogs to DIR.")] = None,
    config: ConfigOpt = None,
    sets: SetOpt = None,
    trust: TrustOpt = None,
    as_json: JsonOpt = False,
) -> None:
    """Fly a docking campaign and report success (Wilson 95 %), errors, slips, aborts."""
    from aerodock.control.profiles import controller_config
    from aerodock.flightlog import save_flightlogs
    from aerodock.mission.checks import DOCK_NAMES, check_mission
    from aerodock.mission.faults import load_faults
    from aerodock.mission.spec import MissionSpec

    check_number("--offset", offset, 0.0, 100.0)
    check_number("--leader-speed", leader_speed, -100.0, 100.0)
    if trials < 1:
        fail(f"--trials must be >= 1, got {trials}")
    # the fault file before the configuration: its check needs no field (the configuration's
    # does, and loads the compiled wake), so a bad file is refused in about half the time
    injected = tuple(load_faults(faults)) if faults is not None else ()
    try:
        cfg = controller_config(load_cli_config(config, sets, trust), controller.value)
    except ValueError as exc:
        fail(str(exc))
    if controller == Controller.OURS and compensation == Compensation.NONE:
        typer.echo("warning: --compensation none turns off every observer, the accelerometer "
                   "observer of 'ours' too (plain LQR); ours without a model is --compensation "
                   "observer", err=True)
    spec = MissionSpec(trials=trials, offset_m=offset, leader_speed_mps=leader_speed,
                       leader_fixed=leader_fixed, compensation=compensation, seed=seed,
                       faults=injected)
    # The validation sweep and the environments share: the cable length like a config value
    # (range, docking point above the ground), the faults, and the run's size.
    cfg = check_mission(cfg, spec, DOCK_NAMES, size=True, keep_logs=save_logs is not None)
    if save_logs is not None:
        from aerodock.fileio import check_writable_target

        check_writable_target(save_logs / f"dock-{compensation.value}-seed{seed}.npz")
    predictor = _load_predictor(model, compensation)
    from aerodock.deploy.compatibility import model_warnings
    from aerodock.mission.batch import run_campaign  # the compiled world: once the input is checked

    for note in model_warnings(predictor, cfg):
        typer.echo(f"warning: {note}", err=True)
    with progress_bar() as bar:
        task = bar.add_task(f"docking x{trials} ({compensation.value})", total=1.0)
        result = run_campaign(cfg, spec, predictor,
                              record="full" if save_logs is not None else "summary",
                              progress=lambda f: bar.update(task, completed=f))
    summary = result.summary()
    summary.update({"compensation": compensation.value, "controller": controller.value,
                    "offset_m": offset
                    or cfg.platform.cable_length_m, "leader_speed_mps": leader_speed,
                    "leader_fixed": leader_fixed, "seed": seed})
    if save_logs is not None:
        path = save_flightlogs(save_logs / f"dock-{compensation.value}-seed{seed}.npz",
                               result.logs)
        summary["logs"] = str(path)
    if as_json:
        from aerodock.mission.outcome import DEPRECATED_KEYS

        print_json({**summary, "deprecated_keys": DEPRECATED_KEYS})
        return
    table = Table(title=f"docking, d_p = {summary['offset_m']:g} m, {compensation.value}, "
                        f"{controller} controller")
    table.add_column("figure")
    table.add_column("value", justify="right")
    lo, hi = summary["success_wilson95"]
    table.add_row("docked", f"{summary['docked']}/{trials} = {summary['success_rate']:.0%} "
                  f"(95 % CI {lo:.0%}-{hi:.0%})")
    table.add_row("terminal error down, median", f"{summary['terminal_err_down_median_m']:.3f} m")
    table.add_row("terminal error 3D, median", f"{summary['terminal_err_3d_median_m']:.3f} m")
    table.add_row("slip-throughs", str(summary["slip_throughs"]))
    table.add_row("missed (gate closed empty)", str(summary["missed"]))
    table.add_row("sensed not held, backed off (missed included)", str(summary["sensed_misses"]))
    table.add_row("aborts", aborts_text(summary))
    table.add_row("clearance violations", str(summary["clearance_violations"]))
    table.add_row("rotor strikes / ground contacts",
                  f"{summary['rotor_strikes']} / {summary['ground_contacts']}")
    table.add_row("terminal tilt RMS, median", f"{summary['terminal_tilt_rms_deg_median']:.1f} deg")
    sink = summary["post_dock_sink_median_m"]
    if sink is not None:
        table.add_row("leader's sink after docking",
                      f"{sink:.2f} m median, {summary['post_dock_sink_max_m']:.2f} m max")
    Console().print(table)
    if save_logs is not None:
        typer.echo(f"wrote {summary['logs']}")


def aborts_text(summary: dict[str, Any]) -> str:
    """A campaign summary's aborts as a person reads them: ``3 (timeout 2, leader lost 1)``, or
    ``0``."""
    reasons = ", ".join(f"{reason.replace('_', ' ')} {count}"
                        for reason, count in summary["abort_reasons"].items() if count)
    return f"{summary['aborts']} ({reasons})" if reasons else str(summary["aborts"])


def faults_command(
    fault_file: Annotated[Path, typer.Argument(help="TOML file of [[fault]] entries.")],
    trials: Annotated[int, typer.Option(help="Trials per fault (one batch each).")] = 40,
    compensation: Annotated[Compensation, typer.Option(
        help="What the follower subtracts before inversion (as in 'aerodock dock --help'); "
             "oracle by default, so that the fault, not the wake, decides.")] = (
        Compensation.ORACLE),
    model: Annotated[Path | None, typer.Option(help="Trained model DIR (for 'model').")] = None,
    seed: SeedOpt = 0,
    config: ConfigOpt = None,
    sets: SetOpt = None,
    trust: TrustOpt = None,
    markdown: Annotated[bool, typer.Option(help="Print the table as Markdown.")] = False,
    as_json: JsonOpt = False,
) -> None:
    """Fly one docking campaign per injected fault (and one without): how each trial the fault
    struck ended (docked, missed, not held, safe or unsafe abort, other), and its clearance
    violations, collisions and NaN."""
    from aerodock.mission.faults import load_faults
    from aerodock.mission.limits import check_campaign_size

    if not 1 <= trials <= 4096:
        fail(f"--trials must be in 1..4096, got {trials}")
    # the fault file and the model before the configuration, whose field loads the compiled
    # wake (as dock's --faults): a bad input is refused in about half the time
    faults = load_faults(fault_file)
    predictor = _load_predictor(model, compensation)
    cfg = load_cli_config(config, sets, trust)
    check_campaign_size(cfg, trials)
    from aerodock.experiments.faults import fault_campaign, rows_markdown

    with progress_bar() as bar:
        task = bar.add_task("faults", total=len(faults) + 1)

        def step(name: str) -> None:
            bar.update(task, description=f"fault: {name}", advance=1)

        rows = fault_campaign(cfg, faults, trials, seed, compensation, predictor, step)
    if as_json:
        print_json({"compensation": compensation.value, "seed": seed, "rows": rows})
    elif markdown:
        typer.echo(rows_markdown(rows))
    else:
        from aerodock.experiments.faults import table_cells, table_headers

        table = Table(title=f"fault campaign, {trials} trials per fault, {compensation.value}")
        for col in table_headers():
            table.add_column(col, justify="left" if col == "fault" else "right")
        for r in rows:
            table.add_row(*table_cells(r))
        Console().print(table)
