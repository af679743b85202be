"""``aerodock ingest``: read real flight logs and write them as one FlightLog file."""

from __future__ import annotations

import warnings
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer
from rich.progress import BarColumn, MofNCompleteColumn, TextColumn, TimeElapsedColumn

from aerodock.cli.common import LoggedProgress, fail, print_json
from aerodock.fileio import json_ready, one_line
from aerodock.flightlog import FlightLog, FlightLogError, save_flightlogs
from aerodock.ingest import expand_paths, read_logs
from aerodock.ingest.errors import IngestError, IngestWarning


class LogFormat(StrEnum):
    """Log formats ``aerodock ingest`` reads."""

    neural_swarm = "neural-swarm"
    csv = "csv"
    rosbag = "rosbag"
    ulog = "ulog"


def summarize(logs: list[FlightLog]) -> list[dict[str, object]]:
    """Name, duration, sample count, label basis and source of each flight."""
    return [
        {
            "name": log.name,
            "duration_s": round(log.duration_s, 3),
            "n_samples": log.n_samples,
            "label_basis": log.meta.get("label_basis"),
            "source": log.meta.get("source"),
        }
        for log in logs
    ]


def ingest_command(
    paths: Annotated[list[Path], typer.Argument(
        help="Log files or folders (a folder gives its files of the format, sorted). ULog: "
             "LEADER.ulg FOLLOWER.ulg pairs, in that order.", show_default=False)],
    fmt: Annotated[LogFormat, typer.Option(
        "--format", "-f", help="Log format.", case_sensitive=False, show_default=False)],
    out: Annotated[Path, typer.Option(
        "--out", "-o", help="Output FlightLog file (.npz), written atomically.",
        show_default=False)],
    mass_kg: Annotated[float | None, typer.Option(
        "--mass-kg", help="Mass of every vehicle, kg (overrides tables, mappings, metadata).")]
        = None,
    vehicle: Annotated[str | None, typer.Option(
        "--vehicle", help="neural-swarm: vehicle type for the mass table: small (0.032 kg), "
                          "large (0.067 kg), or per vehicle 'cf50=small,cf51=large'. "
                          "[default: small]")] = None,
    mapping: Annotated[Path | None, typer.Option(
        "--mapping", help="rosbag: TOML topic mapping (default: a Freyja-like setup, see the "
                          "README).")] = None,
    single: Annotated[bool, typer.Option(
        "--single", help="ulog: each file is a follower alone, with a still virtual leader "
                         "100 m above.")] = False,
    hover_thrust: Annotated[float | None, typer.Option(
        "--hover-thrust", help="ulog: normalised hover thrust (default: from the log).")] = None,
    json_output: Annotated[bool, typer.Option(
        "--json", help="Print the summary as JSON.")] = False,
) -> None:
    """Read real flight logs (Neural-Swarm CSV, generic CSV, ROS 2 bag, PX4 ULog) into FlightLogs.

    All flights go to one FlightLog file (NED, SI); one summary line per flight.
    """
    options = {"mass_kg": mass_kg, "vehicle": vehicle, "mapping": mapping, "single": single,
               "hover_thrust": hover_thrust}
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", IngestWarning)
            files = expand_paths(fmt.value, paths)
            # a bag reports progress per message, so one bag gets a bar too
            if len(files) > 1 or fmt.value == "rosbag":
                with LoggedProgress(TextColumn("reading logs"), BarColumn(),
                                    MofNCompleteColumn(), TimeElapsedColumn(),
                                    transient=True) as bar:
                    task = bar.add_task("ingest", total=len(files))

                    def progress(done: int, total: int) -> None:
                        bar.update(task, completed=done, total=total)

                    logs = read_logs(fmt.value, files, progress=progress, **options)
            else:
                logs = read_logs(fmt.value, files, **options)
        shown: set[str] = set()
        for warning in caught:
            text = str(warning.message)
            if issubclass(warning.category, IngestWarning) and text not in shown:
                shown.add(text)
                typer.echo(f"warning: {text}", err=True)
        if not logs:
            raise IngestError(fmt.value, "no flights read")
        if out.is_dir():
            raise IngestError(out, "--out is a folder; give a file name such as flights.npz")
        written = save_flightlogs(out, logs)
    except (IngestError, FlightLogError) as error:
        fail(str(error))
    except OSError as error:
        if error.strerror is None:  # aerodock's own message, which names the path
            fail(one_line(error))
        fail(f"{getattr(error, 'filename', None) or out}: {error.strerror}")
    summary = summarize(logs)
    if json_output:
        print_json(json_ready({"out": str(written), "flights": summary}), indent=None)
        return
    for item in summary:
        typer.echo(f"{item['name']}: {item['duration_s']:.1f} s, {item['n_samples']} samples "
                   f"({item['source']}, label basis {item['label_basis']})")
    typer.echo(f"wrote {len(logs)} flight{'s' if len(logs) != 1 else ''} to {written}")
