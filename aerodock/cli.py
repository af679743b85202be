"""The ``aerodock`` command line (Typer). Every command has ``--help``; numbers print as JSON
with ``--json``; bad input gives a one-line ``error:`` message and exit code 2 (set
``AERODOCK_DEBUG=1`` for a traceback)."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from aerodock.config import Config, load_config
from aerodock.fileio import json_default

app = typer.Typer(
    add_completion=False, no_args_is_help=True, pretty_exceptions_enable=False,
    help="Docking two multirotors in close proximity with learnt downwash models.",
)
field_app = typer.Typer(no_args_is_help=True, help="Inspect a downwash field or a learnt model.")
app.add_typer(field_app, name="field")

ConfigOpt = Annotated[
    Path | None, typer.Option("--config", help="TOML file overriding aerodock's defaults.")
]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print the numbers as JSON.")]
SeedOpt = Annotated[int, typer.Option("--seed", help="Random seed.")]


def fail(message: str, code: int = 2) -> None:
    """Print a one-line error to stderr and exit."""
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code)


def print_json(obj: Any) -> None:
    """Print ``obj`` as indented JSON on stdout."""
    typer.echo(json.dumps(obj, indent=2, default=json_default))



def _config(path: Path | None) -> Config:
    return load_config(path)


@field_app.command("probe")
def field_probe(
    separation: Annotated[float, typer.Option(help="Depth of the follower below the leader, m.")],
    radial: Annotated[float, typer.Option(help="Horizontal offset from the leader's axis, m.")],
    leader_speed: Annotated[float, typer.Option(help="Leader speed towards north, m/s.")] = 0.0,
    samples: Annotated[int, typer.Option(help="Turbulence samples at the physics rate.")] = 5000,
    model: Annotated[
        Path | None, typer.Option(help="A trained model DIR to probe instead of the field.")
    ] = None,
    bar: Annotated[bool, typer.Option(
        "--bar", help="Probe the force on the docking bar (held still, hovering leader).")] = False,
    config: ConfigOpt = None,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Mean and sd of the acceleration (m/s², NED) on a follower below the leader (or, with
    --bar, of the force in N on the docking bar there)."""
    from aerodock.downwash import build_field
    from aerodock.downwash.probe import probe_bar, probe_bodies, probe_field

    cfg = _config(config)
    if samples < 2:
        fail(f"--samples must be >= 2, got {samples}")
    mass, g = cfg.vehicle.mass_kg, cfg.sim.gravity_mps2
    dt = 1.0 / cfg.sim.physics_rate_hz
    if bar:
        if model is not None or leader_speed != 0.0:
            fail("--bar probes the field under a hovering leader (no --model, no --leader-speed)")
        area = cfg.platform.bar_length_m * cfg.platform.bar_diameter_m
        result = probe_bar(build_field(cfg), separation, radial, samples, dt,
                           np.random.default_rng(seed), area, mass, g)
        if result is None:
            result = {"separation_m": separation, "radial_m": radial, "mean_n": None,
                      "sd_n": None, "lateral_sd_over_vertical_mean": None,
                      "note": "the field has no bar_force_n(): the world applies no wake force "
                              "to the bar"}
        result["source"] = cfg.downwash.field
        if as_json:
            print_json(result)
            return
        typer.echo(f"{result['source']} on the bar at {separation:g} m below, {radial:g} m off "
                   "axis, hovering leader:")
        if result["mean_n"] is None:
            typer.echo(f"  {result['note']}")
            return
        typer.echo("  mean [N, NED] = " + "  ".join(f"{v:+.5f}" for v in result["mean_n"]))
        typer.echo("  sd   [N, NED] = " + "  ".join(f"{v:.5f}" for v in result["sd_n"]))
        ratio = result["lateral_sd_over_vertical_mean"]
        if ratio is not None:
            typer.echo(f"  sd across the bar / mean vertical drag = {ratio:.3f}")
        return
    if model is not None:
        from aerodock.learning.runtime import Predictor

        predictor = Predictor.load(model)
        leader, follower = probe_bodies(separation, radial, leader_speed, mass, g)
        mean = predictor.predict_bodies(leader, follower)[0]
        result = {
            "separation_m": separation, "radial_m": radial, "leader_speed_mps": leader_speed,
            "samples": 1, "frame": "NED", "unit": "m/s^2", "source": str(model),
            "mean_mps2": mean.tolist(), "sd_mps2": [0.0, 0.0, 0.0],
        }
    else:
        result = probe_field(build_field(cfg), separation, radial, leader_speed, samples, dt,
                             np.random.default_rng(seed), mass, g)
        result["source"] = cfg.downwash.field
    if as_json:
        print_json(result)
        return
    m, s = result["mean_mps2"], result["sd_mps2"]
    typer.echo(f"{result['source']} at {separation:g} m below, {radial:g} m off axis, "
               f"leader {leader_speed:g} m/s:")
    typer.echo("  mean [m/s², NED] = " + "  ".join(f"{v:+.3f}" for v in m))
    typer.echo("  sd   [m/s², NED] = " + "  ".join(f"{v:.3f}" for v in s))
    if "field_mean_mps2" in result:
        typer.echo("  field mean       = " + "  ".join(f"{v:+.3f}" for v in
                                                      result["field_mean_mps2"])
                   + f"  ({result['field_mean_source']})")


@field_app.command("plot")
def field_plot(
    out: Annotated[Path, typer.Option(help="PNG file to write.")] = Path("field.png"),
    leader_speed: Annotated[float, typer.Option(help="Leader speed towards north, m/s.")] = 0.0,
    model: Annotated[Path | None, typer.Option(help="Plot a trained model DIR instead.")] = None,
    config: ConfigOpt = None,
) -> None:
    """Draw the field's mean (or a learnt model) as a vertical slice through the wake; a field
    without mean_acceleration() is drawn from an estimate of its mean (said in the title)."""
    from aerodock.downwash import build_field
    from aerodock.downwash.mean import EstimatedMean, mean_acceleration_fn
    from aerodock.downwash.probe import plot_field_slice

    cfg = _config(config)
    if model is not None:
        from aerodock.learning.runtime import Predictor

        predictor = Predictor.load(model)
        mean_fn, title = predictor.predict_bodies, f"learnt model {model.name}"
    else:
        field = build_field(cfg)
        mean_fn = mean_acceleration_fn(field, dt_s=1.0 / cfg.sim.physics_rate_hz)
        title = cfg.downwash.field.rsplit(":", 1)[-1]
        if isinstance(mean_fn, EstimatedMean):
            title += f" (mean estimated, {mean_fn.samples} samples)"
    path = plot_field_slice(mean_fn, out, cfg.vehicle.mass_kg, cfg.sim.gravity_mps2,
                            leader_speed, title)
    typer.echo(f"wrote {path}")


def _register_optional() -> None:
    """Commands from the other subpackages (kept importable without their heavy deps)."""
    from aerodock import commands  # noqa: F401  (registers dock, reproduce, ... on `app`)


def main() -> None:
    """Console entry point: run the app; turn errors into one-line messages."""
    _register_optional()
    try:
        app()
    except KeyboardInterrupt:
        typer.echo("interrupted", err=True)
        sys.exit(130)
    except Exception as err:  # noqa: BLE001 - the one place errors become messages
        if os.environ.get("AERODOCK_DEBUG"):
            raise
        expected = isinstance(err, ValueError | OSError)
        detail = str(err).splitlines()[0] if str(err) else type(err).__name__
        msg = detail if expected else f"{type(err).__name__}: {detail}"
        typer.echo(f"error: {msg}", err=True)
        if not expected:
            typer.echo("(set AERODOCK_DEBUG=1 for a traceback)", err=True)
        sys.exit(2 if expected else 1)
