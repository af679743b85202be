"""``aerodock view LOG.npz``: a flight as a GIF (or MP4), optionally streamed to rerun."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from aerodock.cli.common import SetOpt, TrustOpt, fail, load_cli_config, progress_bar


def view_command(
    log: Annotated[Path, typer.Argument(help="A FlightLog file (.npz): simulated or ingested.")],
    out: Annotated[Path | None, typer.Option(
        help="Video to write: .gif (always) or .mp4 (needs ffmpeg). Default: LOG.gif.")] = None,
    flight: Annotated[int, typer.Option(help="Which flight of the file (0-based).")] = 0,
    fps: Annotated[float, typer.Option(help="Frames per second of the video.")] = 15.0,
    speed: Annotated[float, typer.Option(help="Seconds of flight per second of video.")] = 1.0,
    start: Annotated[float, typer.Option(help="Start this many seconds into the flight.")] = 0.0,
    duration: Annotated[float | None, typer.Option(help="Seconds of flight to show.")] = None,
    max_frames: Annotated[int, typer.Option(help="At most this many frames.")] = 300,
    rerun: Annotated[Path | None, typer.Option(
        "--rerun", help="Also stream to rerun, saved to this .rrd file (needs aerodock[viz]).")]
    = None,
    config: Annotated[Path | None, typer.Option(
        "--config", help="TOML file overriding aerodock's defaults (bar geometry).")] = None,
    sets: SetOpt = None,
    trust: TrustOpt = None,
) -> None:
    """Watch a trial: both vehicles, the bar and its cables, the gate's state and the predicted
    force, in a side and a top view."""
    from aerodock.fileio import check_writable_target
    from aerodock.flightlog import load_flightlogs

    if rerun is not None:  # an output: refused now (a FIFO would block), not after rendering
        check_writable_target(rerun)
    if max_frames < 1:
        fail(f"--max-frames must be at least 1, got {max_frames}")
    logs = load_flightlogs(log)
    if not 0 <= flight < len(logs):
        fail(f"{log}: --flight {flight} out of range (the file holds {len(logs)} flights)")
    flown = logs[flight]
    if flown.n_samples < 2:
        fail(f"{log}: flight {flight} holds {flown.n_samples} samples; at least 2 are needed "
             "to draw it")
    t = flown.t_s - flown.t_s[0]
    end = t[-1] if duration is None else start + duration
    keep = (t >= start) & (t <= end)
    if keep.sum() < 2:
        fail(f"{log}: no samples between {start:g} s and {end:g} s "
             f"(the flight lasts {t[-1]:.1f} s)")
    first = int(keep.argmax())
    flown = flown.slice(first, first + int(keep.sum()))
    # the configuration and the renderer after the log: they load the compiled world (about
    # half a second), which a refused input need not wait for
    from aerodock.view.render import render_animation, track_from_flightlog

    cfg = load_cli_config(config, sets, trust)
    track = track_from_flightlog(flown, cfg)
    out = out if out is not None else log.with_suffix(".gif")
    with progress_bar() as bar:
        task = bar.add_task(f"rendering {out.name}", total=None)
        path = render_animation(track, out, fps=fps, speed=speed, max_frames=max_frames,
                                progress=lambda d, n: bar.update(task, completed=d, total=n))
    typer.echo(f"wrote {path}")
    if rerun is not None:
        from aerodock.view.rerun_stream import stream_to_rerun

        typer.echo(f"wrote {stream_to_rerun(track, save=rerun)}")
