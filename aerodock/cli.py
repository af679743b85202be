"""The ``aerodock`` command line (Typer). Every command has ``--help``; numbers print as JSON
with ``--json`` (strict JSON: a NaN or an infinity is refused, never printed); bad input, usage
errors included, give a one-line ``error:`` message and exit code 2 (set ``AERODOCK_DEBUG=1`` for
a traceback). A repeatable option takes several values after one flag (``--data a.npz b.npz``)
in commands without positional arguments.

``run(argv)`` is the whole command line as a function returning the exit code (what the tests
call in-process); ``main()`` is the console entry point around it.
"""

from __future__ import annotations

import math
import os
import signal
import sys
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from aerodock.config import Config, load_config
from aerodock.fileio import dumps_json, one_line

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


def print_json(obj: Any, indent: int | None = 2) -> None:
    """Print ``obj`` as strict JSON on stdout (indented by ``indent``; one line if None).

    A NaN or an infinity anywhere in ``obj`` is refused (JSON has no such numbers): a one-line
    error naming the key, exit code 2, nothing on stdout.
    """
    try:
        text = dumps_json(obj, indent)
    except ValueError as err:
        fail(str(err))
    typer.echo(text)


def check_number(option: str, value: float | None, low: float, high: float) -> None:
    """Refuse a numeric option that is not finite or lies outside ``[low, high]``."""
    if value is None:
        return
    if not math.isfinite(value):
        fail(f"{option} must be a finite number, got {value}")
    if not low <= value <= high:
        fail(f"{option} must be between {low:g} and {high:g}, got {value!r}")


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
    from aerodock.mission.limits import MAX_PROBE_SAMPLES

    check_number("--separation", separation, -100.0, 100.0)
    check_number("--radial", radial, -100.0, 100.0)
    check_number("--leader-speed", leader_speed, -100.0, 100.0)
    check_number("--samples", samples, 2, MAX_PROBE_SAMPLES)
    cfg = _config(config)
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
    from aerodock.fileio import check_writable_target

    check_number("--leader-speed", leader_speed, -100.0, 100.0)
    check_writable_target(out)
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


def _click_exceptions() -> Any:
    """Click's exceptions module, of the click Typer runs on (recent Typer vendors a copy)."""
    import importlib

    import typer.core

    package = getattr(typer.core, "_click", None) or typer.core.click
    return importlib.import_module(f"{package.__name__}.exceptions")


def _expand_repeatable(args: list[str]) -> list[str]:
    """``--data a b`` -> ``--data a --data b`` for the repeatable options of the subcommand.

    Only in commands without positional arguments (there a value list is unambiguous); a value
    list ends at the next token starting with ``-``.
    """
    group = typer.main.get_command(app)
    names = [a for a in args if not a.startswith("-")]
    command: Any = group
    for name in names[:2]:
        sub = getattr(command, "commands", {}).get(name)
        if sub is None:
            break
        command = sub
    params = getattr(command, "params", [])
    if command is group or any(p.param_type_name == "argument" for p in params):
        return args
    repeatable = {o for p in params
                  if p.param_type_name == "option" and getattr(p, "multiple", False)
                  for o in p.opts}
    out: list[str] = []
    current: str | None = None
    taken = 0
    for arg in args:
        flag = arg.split("=", 1)[0]
        if flag in repeatable:
            current, taken = flag, int("=" in arg)
            out.append(arg)
        elif current is not None and not arg.startswith("-"):
            if taken:
                out.append(current)
            out.append(arg)
            taken += 1
        else:
            current = None
            out.append(arg)
    return out


def run(argv: list[str] | None = None) -> int:
    """The command line as a function: run ``argv`` and return the exit code.

    Usage errors and bad input print one ``error:`` line on stderr and return 2; an interrupt
    returns 130; an unexpected failure (a bug) returns 1 with its type name.
    """
    click = _click_exceptions()
    _register_optional()
    args = list(sys.argv[1:] if argv is None else argv)
    try:
        args = _expand_repeatable(args)
        rv = typer.main.get_command(app).main(args=args, prog_name="aerodock",
                                              standalone_mode=False)
        return rv if isinstance(rv, int) else 0
    except getattr(click, "NoArgsIsHelpError", ()) as err:
        typer.echo(err.ctx.get_help())
        return 0
    except click.UsageError as err:
        hint = f" (see '{err.ctx.command_path} --help')" if err.ctx is not None else ""
        typer.echo(f"error: {one_line(err.format_message())}{hint}", err=True)
        return 2
    except click.ClickException as err:
        typer.echo(f"error: {one_line(err.format_message())}", err=True)
        return 2
    except (KeyboardInterrupt, typer.Abort):
        typer.echo("interrupted", err=True)
        return 130
    except Exception as err:  # noqa: BLE001 - the one place errors become messages
        if os.environ.get("AERODOCK_DEBUG"):
            raise
        expected = isinstance(err, ValueError | OSError | MemoryError)
        if isinstance(err, MemoryError):
            detail = "out of memory (the input or the run is too large)"
        elif isinstance(err, OSError) and err.strerror and err.filename:
            detail = f"{err.filename}: {err.strerror}"
        else:
            detail = one_line(err)
        msg = detail if expected else f"{type(err).__name__}: {detail}"
        typer.echo(f"error: {msg}", err=True)
        if not expected:
            typer.echo("(set AERODOCK_DEBUG=1 for a traceback)", err=True)
        return 2 if expected else 1


def _terminate(signum: int, frame: Any) -> None:
    # SIGTERM unwinds like an interrupt, so atomic writes remove their temporary files.
    raise SystemExit(128 + signum)


def main() -> None:
    """Console entry point: run the app; turn errors into one-line messages."""
    signal.signal(signal.SIGTERM, _terminate)
    sys.exit(run())
