"""``aerodock field probe`` and ``field plot``: a downwash field or a learnt model at a point or
on a slice (the jet fitted to and scored on real flights: :mod:`aerodock.cli.field_fit`)."""

from __future__ import annotations

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
    check_number,
    fail,
    load_cli_config,
    print_json,
)

if TYPE_CHECKING:
    from aerodock.learning.runtime import Predictor


def _load_model(model: Path | None) -> Predictor | None:
    """The trained model ``model`` (None: none), loaded before the configuration so that a bad
    one is refused before the compiled wake loads."""
    if model is None:
        return None
    from aerodock.learning.runtime import Predictor

    return Predictor.load(model)


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
    sets: SetOpt = None,
    trust: TrustOpt = None,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Mean and sd of the acceleration (m/s², NED) on a follower below the leader (or, with
    --bar, of the force in N on the docking bar there)."""
    from aerodock.downwash import build_field
    from aerodock.downwash.probe import probe_bar, probe_bodies, probe_field
    from aerodock.mission.limits import MAX_PROBE_SAMPLES

    check_number("--separation", separation, -100.0, 100.0)
    check_number("--radial", radial, -100.0, 100.0)
    check_number("--leader-speed", leader_speed, -100.0, 100.0)
    check_number("--samples", samples, 2, MAX_PROBE_SAMPLES)
    if bar and (model is not None or leader_speed != 0.0):
        fail("--bar probes the field under a hovering leader (no --model, no --leader-speed)")
    predictor = _load_model(model)  # before the configuration, which loads the compiled wake
    cfg = load_cli_config(config, sets, trust)
    mass, g = cfg.vehicle.mass_kg, cfg.sim.gravity_mps2
    lead_mass = cfg.leader.mass_kg
    dt = cfg.timing.physics_dt_s
    if bar:
        area = cfg.platform.bar_length_m * cfg.platform.bar_diameter_m
        result = probe_bar(build_field(cfg), separation, radial, samples, dt,
                           np.random.default_rng(seed), area, mass, g,
                           leader_mass_kg=lead_mass)
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
    if predictor is not None:
        from aerodock.mission.params import fly_on_configured_rotors

        fly_on_configured_rotors(predictor, cfg)  # a leader-aware model: this world's rotors
        leader, follower = probe_bodies(separation, radial, leader_speed, mass, g,
                                        leader_mass_kg=lead_mass)
        mean = predictor.predict_bodies(leader, follower)[0]
        result = {
            "separation_m": separation, "radial_m": radial, "leader_speed_mps": leader_speed,
            "samples": 1, "frame": "NED", "unit": "m/s^2", "source": str(model),
            "mean_mps2": mean.tolist(), "sd_mps2": [0.0, 0.0, 0.0],
        }
    else:
        result = probe_field(build_field(cfg), separation, radial, leader_speed, samples, dt,
                             np.random.default_rng(seed), mass, g, leader_mass_kg=lead_mass)
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


def field_plot(
    out: Annotated[Path, typer.Option(help="PNG file to write.")] = Path("field.png"),
    leader_speed: Annotated[float, typer.Option(help="Leader speed towards north, m/s.")] = 0.0,
    model: Annotated[Path | None, typer.Option(help="Plot a trained model DIR instead.")] = None,
    config: ConfigOpt = None,
    sets: SetOpt = None,
    trust: TrustOpt = None,
) -> None:
    """Draw the field's mean (or a learnt model) as a vertical slice through the wake; a field
    without mean_acceleration() is drawn from an estimate of its mean (said in the title)."""
    from aerodock.downwash import build_field
    from aerodock.downwash.mean import EstimatedMean, mean_acceleration_fn
    from aerodock.downwash.probe import plot_field_slice
    from aerodock.fileio import check_writable_target

    check_number("--leader-speed", leader_speed, -100.0, 100.0)
    check_writable_target(out)
    predictor = _load_model(model)  # before the configuration, which loads the compiled wake
    cfg = load_cli_config(config, sets, trust)
    if predictor is not None:
        from aerodock.mission.params import fly_on_configured_rotors

        fly_on_configured_rotors(predictor, cfg)
        mean_fn, title = predictor.predict_bodies, f"learnt model {model.name}"
    else:
        field = build_field(cfg)
        mean_fn = mean_acceleration_fn(field, dt_s=cfg.timing.physics_dt_s)
        title = cfg.downwash.field.rsplit(":", 1)[-1]
        if isinstance(mean_fn, EstimatedMean):
            title += f" (mean estimated, {mean_fn.samples} samples)"
    path = plot_field_slice(mean_fn, out, cfg.vehicle.mass_kg, cfg.sim.gravity_mps2,
                            leader_speed, title)
    typer.echo(f"wrote {path}")
