"""``aerodock field fit`` and ``field score``: the default jet fitted to real flights, and a fit
scored on any flights."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import numpy as np
import typer

from aerodock.cli.common import (
    ConfigOpt,
    JsonOpt,
    SeedOpt,
    SetOpt,
    TrustOpt,
    err_console,
    fail,
    load_cli_config,
    print_json,
)

if TYPE_CHECKING:
    from aerodock.config import Config
    from aerodock.flightlog import FlightLog
    from aerodock.identify.flights import FlightSamples
    from aerodock.identify.wake_fit import WakeFit


class NoiseMode(StrEnum):
    """``field fit --noise``: the label noise the turbulence is read above."""

    POOLED = "pooled"
    SPEED = "speed"


class CommandsMode(StrEnum):
    """``field fit --commands``: which motor thrusts the labels stand on, where logs carry both."""

    ASKED = "asked"
    SENT = "sent"


CommandsOpt = Annotated[CommandsMode, typer.Option(
    "--commands",
    help="Where the logs carry the per-motor thrusts the firmware asked for and the commands "
         "it sent (Neural-Swarm's do): 'asked' (the labels as logged) or 'sent' (each motor's "
         "command map fitted per flight, and the force and torque labels from what the "
         "commands sent make: the thrust asked for beyond a motor's ceiling taken away; "
         "aerodock/identify/motor_commands.py). Other logs are used as they are either way.")]

FIT_OUTPUTS = ("report.md", "fit.json", "wake.toml", "figures")
JET_FIELD = "aerodock.downwash.jet:RoundJetField"


def field_fit(
    data: Annotated[list[Path], typer.Argument(
        help="FlightLog files (.npz, from `aerodock ingest` or `collect`) with the follower "
             "below the leader; their meta must give both vehicles' masses and rotors and the "
             "follower's diagonal.", show_default=False)],
    holdout: Annotated[list[str] | None, typer.Option(
        "--holdout", help="Flights to score but not fit: a shell pattern on the flight name "
                          "(e.g. 'swap_ss_0[56]'; a log's name less its follower id). "
                          "Repeatable.")] = None,
    estimate_rotor: Annotated[list[str] | None, typer.Option(
        "--estimate-rotor", help="A vehicle id (the logs' leader_id/follower_id) whose rotor "
                                 "radius the logs do not know: fitted too. Repeatable.")] = None,
    bootstrap: Annotated[int, typer.Option(
        help="Refits on flights resampled with replacement, for the uncertainty (0: none).")]
        = 20,
    noise: Annotated[NoiseMode, typer.Option(
        help="The label noise the turbulence is read above: 'pooled' (each follower "
             "vehicle's free-air variance over all its free-air samples) or 'speed' (its "
             "free-air variance at the follower's speed at each sample; the noise grows with "
             "the vehicle's own manoeuvres; the correlation time is read above the pooled "
             "noise either way).")] = "pooled",
    torque: Annotated[bool, typer.Option(
        "--torque/--no-torque",
        help="Where the logs carry the torque the follower's motors answer (Neural-Swarm's "
             "do), fit the jet's disk torque beside the force, and the body's share of the "
             "force with it (body_area_ratio). Without such logs the fit is the force's "
             "alone either way.")] = True,
    commands: CommandsOpt = CommandsMode.ASKED,
    folds: Annotated[int, typer.Option(
        help="Cross-validation over flights: every flight held out once, in this many folds, "
             "each scored by a fit on the others; the spread a new flight should expect "
             "(0: none).")] = 0,
    out: Annotated[Path, typer.Option(
        "--out", help="Folder for report.md, fit.json, wake.toml and figures/ (replaced as a "
                      "whole).")] = Path("out/wake_fit"),
    config_out: Annotated[Path | None, typer.Option(
        "--config-out", help="Also write the fitted TOML fragment here (a world loads it with "
                             "--config).")] = None,
    config: ConfigOpt = None,
    sets: SetOpt = None,
    trust: TrustOpt = None,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Fit the default jet's parameters (width and growth, ingest law, planar part, per-disk
    turbulence and its time scale) to real flights; score held-out flights against the targets;
    write a report, figures and the TOML a world loads. The table of the report's last section
    is the fitted wake on the vehicles of --config (the paper's by default)."""
    from aerodock.experiments.wake_report import config_fragment
    from aerodock.fileio import check_output_dir, check_writable_target, json_ready
    from aerodock.identify import wake_score as ws

    if not 0 <= bootstrap <= 1000:
        fail(f"--bootstrap must be between 0 and 1000, got {bootstrap}")
    if folds == 1 or not 0 <= folds <= 100:
        fail(f"--folds must be 0 (none) or between 2 and 100, got {folds}")
    cfg = load_cli_config(config, sets, trust)
    check_output_dir(out, FIT_OUTPUTS)
    if config_out is not None:
        check_writable_target(config_out)
    logs = _read_flightlogs(data, commands)
    fit, flights, fitted, held, cross = _fit_flights(
        logs, holdout or [], estimate_rotor or [], bootstrap=bootstrap, noise=noise,
        folds=folds, seed=seed, quiet=as_json, torque_of=cfg if torque else None)
    scores = ws.score_wake(fit.params, held, fit.rotor_radii_m)
    fit_scores = ws.score_wake(fit.params, fitted, fit.rotor_radii_m)
    checks = _fit_checks(cfg, fit, logs, flights, fitted, held)
    paper = {"config": cfg.source, "rows": _fitted_wake_table(fit, cfg)}
    command = _fit_command(data, holdout or [], estimate_rotor or [], bootstrap=bootstrap,
                           seed=seed, noise=noise, folds=folds, config=config, sets=sets or [],
                           torque=torque, commands=commands)
    held_names = sorted({f.flight for f in held})
    toml_text = config_fragment(fit, held_names, command)
    result = {
        "params": fit.field_params(), "rotor_radii_m": fit.rotor_radii_m,
        "bootstrap": fit.bootstrap, "bootstrap_runs": fit.bootstrap_runs,
        "fitted_flights": fit.flights, "held_out_flights": held_names,
        "samples": fit.samples, "mean_rms_mps2": fit.mean_rms_mps2,
        "torque_flights": fit.torque_flights, "torque_rms_mps2": fit.torque_rms_mps2,
        "held_out": scores, "fitted": fit_scores, "turbulence_bins": fit.turbulence_bins,
        "world": paper, "command": command, "noise": noise, "commands": str(commands),
        **checks,
        "cross_validation": cross,
    }
    _write_fit_outputs(out, config_out, fit, scores, fit_scores, paper, command,
                       {**checks, "cross_validation": cross, "noise": noise,
                        "commands": str(commands)}, toml_text, result)
    if as_json:
        print_json(json_ready(result))
        return
    _print_fit(fit, held_names, scores, cross, out, config_out)


def _fit_flights(logs: list[FlightLog], holdout: list[str], estimate_rotor: list[str], *,
                 bootstrap: int, noise: str, folds: int, seed: int, quiet: bool,
                 torque_of: Config | None = None,
                 ) -> tuple[WakeFit, list[FlightSamples], list[FlightSamples],
                            list[FlightSamples], dict | None]:
    """``field fit``'s fit: the flights, their split, the jet fitted and the cross-validation.

    A fit that cannot be made (:class:`aerodock.identify.wake_fit.WakeFitError`) is a one-line
    error, as is a ``--holdout`` that matches no flight or leaves none to fit.

    Args:
        logs: the FlightLogs.
        holdout: ``--holdout`` patterns.
        estimate_rotor: vehicle ids whose rotor radius is fitted too.
        bootstrap: refits on resampled flights.
        noise: ``"pooled"`` or ``"speed"`` (:class:`NoiseMode`).
        folds: cross-validation folds (0: none).
        seed: the bootstrap's seed.
        quiet: no progress or warnings on stderr (``--json``).
        torque_of: fit the logged torque too (where the logs carry it), the followers'
            inertias scaled from this config's vehicle (None: the force alone).

    Returns:
        ``(fit, flights, fitted, held, cross)``: the fit, every flight, the flights fitted and
        held out, and the cross-validation (None without ``folds``).
    """
    from aerodock.fileio import one_line
    from aerodock.identify import flights as fl
    from aerodock.identify import wake_fit as wf

    try:
        flights = _flights_with_noise(logs, noise, quiet)
        fitted, held = fl.select_flights(flights, holdout)
        if holdout and not held:
            fail(f"--holdout {' '.join(holdout)} matches no flight with samples in the wake "
                 f"(flights: {', '.join(sorted({f.flight for f in flights}))})")
        if not fitted:
            fail("--holdout leaves no flight to fit")

        def say(done: int, total: int) -> None:
            if not quiet:
                err_console.print(f"[dim]bootstrap {done}/{total}[/dim]")

        labels = None
        if torque_of is not None:
            from aerodock.identify.field_score import scaled_inertia
            from aerodock.identify.torque_labels import torque_labels

            vehicle = torque_of.vehicle
            labels = torque_labels(flights, logs, scaled_inertia(
                flights, vehicle.mass_kg, vehicle.diagonal_m, vehicle.inertia_kgm2))
        fit = wf.fit_wake(fitted, estimate_rotor_for=estimate_rotor, bootstrap=bootstrap,
                          seed=seed, progress=say, torque=labels)
        cross = None
        if folds:
            from aerodock.identify.wake_folds import cross_validate, flight_turbulence

            def say_fold(done: int, total: int) -> None:
                if not quiet:
                    err_console.print(f"[dim]cross-validation fold {done}/{total}[/dim]")

            cross = cross_validate(flights, folds, estimate_rotor_for=estimate_rotor,
                                   progress=say_fold, torque=labels)
            cross["per_flight"] = flight_turbulence(fit.params, flights, fit.rotor_radii_m)
    except wf.WakeFitError as err:
        fail(one_line(err))
    return fit, flights, fitted, held, cross


def _flights_with_noise(logs: list[FlightLog], noise: str, quiet: bool) -> list[FlightSamples]:
    """The logs' flights, with the label noise by speed for ``noise == "speed"``.

    A follower vehicle with too little free air to table its noise by speed keeps the pooled
    noise (a warning on stderr unless ``quiet``).

    Raises:
        WakeFitError: the flights cannot be prepared (:mod:`aerodock.identify.flights`).
    """
    from aerodock.identify import flights as fl

    flights = fl.prepare_flights(logs)
    if noise == "speed":
        from aerodock.identify.label_noise import noise_by_speed, with_speed_noise

        flights = with_speed_noise(flights, noise_by_speed(logs))
        pooled = sorted({str(f.vehicles.get("follower")) for f in flights
                         if f.noise_var_mps4 is None})
        if pooled and not quiet:
            err_console.print(f"warning: too little free air to table the noise by speed "
                              f"for {', '.join(pooled)}: their flights keep the pooled "
                              f"noise")
    return flights


def _fitted_wake_table(fit: WakeFit, cfg: Config) -> list[dict]:
    """The fitted wake on ``cfg``'s vehicles per separation, with each figure's 95 % bootstrap
    interval (``"bootstrap"``: 2.5 and 97.5 percentiles over the draws) when there are draws."""
    from aerodock.identify import wake_score as ws

    rows = ws.wake_at_separations(fit.params, cfg)
    if fit.bootstrap_draws:
        tables = [ws.wake_at_separations({**fit.params, **d}, cfg) for d in fit.bootstrap_draws]
        for i, row in enumerate(rows):
            row["bootstrap"] = {k: [float(np.percentile([t[i][k] for t in tables], q))
                                    for q in (2.5, 97.5)]
                                for k in row if k != "separation_m"}
    return rows


def _fit_command(data: list[Path], holdout: list[str], estimate_rotor: list[str], *,
                 bootstrap: int, seed: int, noise: str, folds: int, config: Path | None,
                 sets: list[str], torque: bool = True, commands: str = "asked") -> str:
    """The ``aerodock field fit`` command line that repeats this fit (for the report and TOML);
    options at their defaults are left out, except ``--bootstrap`` and ``--seed``."""
    import shlex

    words = [str(p) for p in data]
    words += [w for pattern in holdout for w in ("--holdout", pattern)]
    words += [w for vid in estimate_rotor for w in ("--estimate-rotor", vid)]
    words += ["--bootstrap", str(bootstrap), "--seed", str(seed)]
    words += ["--noise", noise] if noise != "pooled" else []
    words += ["--folds", str(folds)] if folds else []
    words += [] if torque else ["--no-torque"]
    words += ["--commands", str(commands)] if commands != "asked" else []
    words += ["--config", str(config)] if config is not None else []
    words += [w for text in sets for w in ("--set", text)]
    return "aerodock field fit " + " ".join(shlex.quote(w) for w in words)


def _write_fit_outputs(out: Path, config_out: Path | None, fit: WakeFit, scores: dict,
                       fit_scores: dict, paper: dict, command: str, report_extras: dict,
                       toml_text: str, result: dict) -> None:
    """Write ``field fit``'s folder (figures/, report.md, wake.toml, fit.json; replaced as a
    whole) and, with ``--config-out``, the TOML fragment there too.

    Args:
        out: the output folder.
        config_out: where else to write the TOML fragment (None: nowhere).
        fit: the fit.
        scores: the held-out flights' scores.
        fit_scores: the fitted flights' scores.
        paper: the fitted wake on the configured vehicles (``config``, ``rows``).
        command: the command line that repeats the fit.
        report_extras: the checks, cross-validation and noise mode for the report.
        toml_text: the TOML fragment a world loads.
        result: fit.json's content.
    """
    from aerodock.experiments.wake_report import report_markdown, write_figures
    from aerodock.fileio import atomic_open, building_dir, json_ready, write_json

    with building_dir(out, FIT_OUTPUTS) as work:
        figures = write_figures(fit, scores, fit_scores, work / "figures")
        (work / "report.md").write_text(report_markdown(
            fit, scores, fit_scores, paper, command, [str(p) for p in figures], report_extras))
        (work / "wake.toml").write_text(toml_text)
        write_json(work / "fit.json", json_ready(result))
    if config_out is not None:
        with atomic_open(config_out, "w") as fh:
            fh.write(toml_text)


def _print_fit(fit: WakeFit, held_names: list[str], scores: dict, cross: dict | None,
               out: Path, config_out: Path | None) -> None:
    """``field fit``'s human summary: the fitted parameters and rotor radii, the targets met
    by the held-out flights and the cross-validation folds, and what was written."""
    typer.echo(f"fitted on {len(fit.flights)} flights, held out {len(held_names)}:")
    for key, value in fit.field_params().items():
        typer.echo(f"  {key} = {value:.4g}")
    for vid, radius in fit.rotor_radii_m.items():
        typer.echo(f"  rotor radius of {vid} = {radius:.4g} m")
    for pair, entry in scores["pairs"].items():
        met = [k for k in ("mean_vertical", "half_width", "vertical_sd", "lateral_sd")
               if entry[k]["met"]]
        typer.echo(f"  held out, {pair}: targets met: {', '.join(met) or 'none'}")
    if cross is not None:
        for pair, row in cross["summary"].items():
            cells = ", ".join(f"{k} {r['met']}/{r['scored']} (flights' own {r['reference_met']})"
                              for k, r in row.items())
            typer.echo(f"  cross-validated, {pair}: folds met: {cells}")
    typer.echo(f"wrote {out / 'report.md'}" + (f" and {config_out}" if config_out else ""))


def field_score(
    fit: Annotated[Path, typer.Argument(
        help="The wake to score: a `field fit --out` folder (its fit.json: the fitted "
             "parameters and rotor radii) or a world's config (.toml: its [downwash.params]; "
             "the default jet's field only).", show_default=False)],
    more: Annotated[list[Path] | None, typer.Argument(
        help="More FlightLog files (what follows --data's first file).", show_default=False,
        metavar="[FLIGHTS]...")] = None,
    data: Annotated[list[Path] | None, typer.Option(
        "--data", help="FlightLog files (.npz, from `aerodock ingest`) with the follower below "
                       "the leader; their meta must give both vehicles' masses and rotors and "
                       "the follower's diagonal. Repeatable.", show_default=False)] = None,
    torque_separation: Annotated[tuple[float, float], typer.Option(
        "--torque-separation", help="The depths below the leader the torque is read over, "
                                    "m: LOW HIGH.")] = (0.10, 0.70),
    commands: CommandsOpt = CommandsMode.ASKED,
    config: ConfigOpt = None,
    sets: SetOpt = None,
    trust: TrustOpt = None,
    as_json: JsonOpt = False,
) -> None:
    """Score a wake on flights, pairing by pairing: the mean per separation bin, the half-width,
    the vertical and lateral turbulence sd, and the inward torque 4-10 cm off the axis, each as
    the world against the flights (signed: world over flights minus one), beside the flights'
    own reference (one half of a pairing's flights against the other). The follower's inertia,
    for the torque, is scaled from --config's vehicle (a fit folder) or FIT's (a config)."""
    from aerodock.fileio import json_ready, one_line
    from aerodock.identify import field_score as fs
    from aerodock.identify import flights as fl
    from aerodock.identify.wake_fit import WakeFitError

    paths = list(data or []) + list(more or [])
    lo, hi = torque_separation
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi):
        fail(f"--torque-separation must be two depths LOW < HIGH in metres, got {lo} {hi}")
    if not paths:
        fail("no flights: give FlightLog files with --data")
    params, radii, cfg = _scored_wake(fit, config, sets, trust)
    logs = _read_flightlogs(paths, commands)
    try:
        flights = fl.prepare_flights(logs)
        inertia = fs.scaled_inertia(flights, cfg.vehicle.mass_kg, cfg.vehicle.diagonal_m,
                                    cfg.vehicle.inertia_kgm2)
        scores = fs.score_field(params, flights, logs, inertia, rotor_radii_m=radii,
                                torque_separation_m=(lo, hi))
    except WakeFitError as err:
        fail(one_line(err))
    result = {"fit": str(fit), "params": params, "rotor_radii_m": radii,
              "targets": fs.TARGETS, "torque_bins_m": [list(b) for b in fs.TORQUE_BINS_M],
              "torque_separation_m": [lo, hi], "commands": str(commands),
              "pairs": [s.as_dict() for s in scores]}
    if as_json:
        print_json(json_ready(result))
        return
    _print_scores(scores)


def _read_flightlogs(paths: list[Path],
                     commands: CommandsMode = CommandsMode.ASKED) -> list[FlightLog]:
    """Every FlightLog of ``paths``, those with motor commands taken as sent for
    ``--commands sent`` (:func:`aerodock.identify.motor_commands.sent_where_logged`); a file
    that is not one, or commands whose maps cannot be fitted, is a one-line error."""
    from aerodock.fileio import one_line
    from aerodock.flightlog import FlightLogError, load_flightlogs
    from aerodock.identify.flights import WakeFitError
    from aerodock.identify.motor_commands import sent_where_logged

    logs: list[FlightLog] = []
    for path in paths:
        try:
            logs += load_flightlogs(path)
        except (FlightLogError, OSError) as err:
            fail(one_line(err))
    if commands != CommandsMode.SENT:
        return logs
    try:
        return sent_where_logged(logs)
    except WakeFitError as err:
        fail(one_line(err))


def _scored_wake(fit: Path, config: Path | None, sets: list[str] | None,
                 trust: list[str] | None) -> tuple[dict[str, float], dict[str, float], Config]:
    """``field score``'s FIT read: the jet's parameters, rotor radii by vehicle id, and the
    config whose vehicle gives the inertia."""
    import json

    from aerodock.identify.wake_fit import FITTED_PARAMS, TORQUE_PARAMS, WORLD_PARAMS

    if fit.is_dir():
        path = fit / "fit.json"
        try:
            raw = json.loads(path.read_text())
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
            fail(f"{fit}: not a `field fit --out` folder (reading fit.json: "
                 f"{type(err).__name__})")
        params = raw.get("params") if isinstance(raw, dict) else None
        radii = raw.get("rotor_radii_m", {}) if isinstance(raw, dict) else None
        if not isinstance(params, dict) or not set(FITTED_PARAMS) <= set(params) \
                or not set(params) <= set(FITTED_PARAMS + TORQUE_PARAMS) \
                or not all(_finite(v) for v in params.values()):
            fail(f"{path}: 'params' must hold the fitted parameters "
                 f"({', '.join(FITTED_PARAMS)}; with the torque, {', '.join(TORQUE_PARAMS)}) "
                 f"as finite numbers")
        if not isinstance(radii, dict) or not all(isinstance(k, str) and _finite(v) and v > 0
                                                  for k, v in radii.items()):
            fail(f"{path}: 'rotor_radii_m' must map vehicle ids to positive radii in metres")
        return ({k: float(v) for k, v in params.items()},
                {k: float(v) for k, v in radii.items()}, load_cli_config(config, sets, trust))
    if config is not None:
        fail("--config is FIT's own when FIT is a config: give one or the other")
    if not fit.is_file():
        fail(f"{fit}: no such file or folder")
    cfg = load_cli_config(fit, sets, trust)
    if cfg.downwash.field != JET_FIELD:
        fail(f"{fit}: its field is {cfg.downwash.field}; field score scores the default jet "
             f"({JET_FIELD})")
    keys = FITTED_PARAMS + WORLD_PARAMS
    return ({k: float(v) for k, v in cfg.downwash.params.items() if k in keys}, {}, cfg)


def _finite(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) \
        and bool(np.isfinite(value))


def _print_scores(scores: list) -> None:
    """``field score``'s human table: one row per pairing, each figure world / flights' own."""
    from rich.table import Table

    from aerodock.identify.field_score import TARGETS, TORQUE_BINS_M

    def pct(x: float) -> str:
        return f"{100 * x:+.0f} %" if np.isfinite(x) else "-"

    def ratios(xs: list[float]) -> str:
        return " ".join(f"{x:.2f}" if np.isfinite(x) else "-" for x in xs) or "no torque"

    table = Table(title="The wake against the flights: world / flights - 1 (torque: world / "
                        "flights); below each pairing, its flights' own: half / other half")
    for name in ("follower under leader", "flights", "mean, worst bin", "half-width",
                 "vertical sd", "lateral sd", "torque " + "/".join(
                     f"{100 * lo:.0f}-{100 * hi:.0f}" for lo, hi in TORQUE_BINS_M) + " cm"):
        table.add_column(name, no_wrap=True)
    keys = ("mean_worst_bin_rel", "half_width_rel", "turb_vertical_rel", "turb_lateral_rel")
    for s in scores:
        table.add_row(f"{s.follower} under {s.leader}", str(s.flights),
                      *(pct(getattr(s, k)) for k in keys), ratios(s.torque_ratio_bins))
        table.add_row("  flights' own", "", *(pct(s.reference[k]) for k in keys),
                      ratios(s.reference["torque_ratio_bins"]), style="dim")
    from rich.console import Console

    Console(width=max(120, Console().width)).print(table)
    lo, hi = TARGETS["torque_ratio"]
    typer.echo(f"targets: mean, half-width within {100 * TARGETS['mean_worst_bin_rel']:.0f} %; "
               f"sd within {100 * TARGETS['turb_vertical_rel']:.0f} %; torque ratio "
               f"{lo}-{hi}")
    for s in scores:
        met = [k for k, ok in s.met.items() if ok]
        typer.echo(f"  {s.follower} under {s.leader}: met {len(met)}/5"
                   + (f" ({', '.join(met)})" if met else ""))
    typer.echo("beyond the edge (3.5-6 leader equivalent radii off the axis), mean vertical "
               "acceleration, down +, m/s^2: world / flights (se)")
    for s in scores:
        e = s.edge_mps2
        if e and e["samples"]:
            typer.echo(f"  {s.follower} under {s.leader}: {e['world']:+.3f} / "
                       f"{e['flights']:+.3f} ({e['flights_se']:.3f}), {e['samples']} samples")


def _fit_checks(cfg: Config, fit: WakeFit, logs: list[FlightLog],
                flights: list[FlightSamples], fitted: list[FlightSamples],
                held: list[FlightSamples]) -> dict:
    """What the fit's report adds beside the fit: the turbulence read above the labels' noise at
    the follower's own speed, the motors' ceiling where the logs carry the commands
    (:func:`aerodock.identify.motor_commands.ceiling_by_vehicle`), and the wake's torque where
    the logs carry the motors' torque
    (the follower's inertia scaled from the configured vehicle's by its mass and diagonal
    squared: an assumption, for a term, J dw/dt, that averages out in the profile)."""
    from dataclasses import asdict

    from aerodock.identify import wake_fit as wf
    from aerodock.identify.field_score import scaled_inertia
    from aerodock.identify.label_noise import noise_by_speed, speed_matched_turbulence
    from aerodock.identify.motor_commands import ceiling_by_vehicle, command_maps
    from aerodock.identify.wake_torque import has_motor_torque, torque_profile

    out: dict = {"turbulence_above_speed_noise": None, "wake_torque": None,
                 "motor_ceiling": ceiling_by_vehicle(command_maps(logs)) or None}
    try:
        noise = noise_by_speed(logs)
    except wf.WakeFitError:
        noise = None
    if noise is not None:
        out["turbulence_above_speed_noise"] = {
            part: speed_matched_turbulence(fit.params, group, noise,
                                           rotor_radii_m=fit.rotor_radii_m)
            for part, group in (("held_out", held), ("fitted", fitted)) if group}
    if any(has_motor_torque(log) for log in logs):
        inertia = scaled_inertia(flights, cfg.vehicle.mass_kg, cfg.vehicle.diagonal_m,
                                 cfg.vehicle.inertia_kgm2)
        try:
            profile = torque_profile(fit.params, flights, logs, inertia,
                                     rotor_radii_m=fit.rotor_radii_m)
        except wf.WakeFitError:
            profile = None
        if profile is not None:
            out["wake_torque"] = {pair: [{**asdict(b), "lever_m": b.lever_m} for b in bins]
                                  for pair, bins in profile.items()}
    return out
