"""``aerodock evaluate-compensation``: the compensations a follower can fly, replayed causally
over real flights, and the disturbance each leaves (:mod:`aerodock.experiments.compensation_study`).
"""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from aerodock.cli.common import (
    ConfigOpt,
    JsonOpt,
    SeedOpt,
    SetOpt,
    TrustOpt,
    bar_callback,
    check_number,
    err_console,
    fail,
    load_cli_config,
    print_json,
    progress_bar,
)
from aerodock.fileio import one_line
from aerodock.learning.kinds import REGISTRY

if TYPE_CHECKING:
    from aerodock.config import Config

KINDS = tuple(name for name, k in REGISTRY.items() if k.has_network and not k.torque)
"""Model kinds it trains (the force models; ``so2-wrench`` needs torque labels the logs lack)."""
TrainedKind = StrEnum("TrainedKind", {kind: kind for kind in KINDS})
"""``--kind``'s choices."""


def default_data_root(data_dir: Path | None = None) -> Path:
    """``neural-swarm`` in the data location (:func:`aerodock.ingest.data_dir.find_data_dir`:
    ``--data-dir``, ``$AERODOCK_DATA_DIR``, else ``../shared/data`` in this repository)."""
    from aerodock.ingest.data_dir import NEURAL_SWARM, find_data_dir

    located = find_data_dir(data_dir)
    if located.problem():
        fail(located.problem())
    if located.path is None:
        fail("no Neural-Swarm flights: give --data (the neural-swarm folder) or --data-dir, or "
             "set AERODOCK_DATA_DIR (docs/real-logs.md says where to get them)")
    return located.path / NEURAL_SWARM


def evaluate_compensation_command(
    data: Annotated[Path | None, typer.Option(
        "--data", help="Neural-Swarm folder holding swap_ss and swap_sl_2020-06-19 (default: "
                       "neural-swarm in the data location).")] = None,
    data_dir: Annotated[Path | None, typer.Option(
        "--data-dir", help="The data location holding neural-swarm/ (default: $AERODOCK_DATA_DIR, "
                           "else ../shared/data in this repository; docs/real-logs.md).")] = None,
    model: Annotated[Path | None, typer.Option(
        "--model", help="A trained model DIR to fly (default: train one on swap_ss 00-04 and "
                        "swap_sl 00-07).")] = None,
    kind: Annotated[TrainedKind, typer.Option(
        "--kind", help="Model kind to train without --model.")] = "so2",
    quick: Annotated[bool, typer.Option(
        "--quick", help="Train for at most 30 epochs (without --model).")] = False,
    warmup: Annotated[float, typer.Option(
        "--warmup", help="Seconds at the start of each replayed segment not scored (the "
                         "observers start from nothing).")] = 2.0,
    lateral_radius: Annotated[float, typer.Option(
        "--lateral-radius", help="Interaction region radius, m.")] = 0.2,
    figure: Annotated[Path | None, typer.Option(
        "--figure", help="Also draw the residual against each compensation along a held-out "
                         "pass to this PNG file.")] = None,
    config: ConfigOpt = None,
    sets: SetOpt = None,
    trust: TrustOpt = None,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Score the compensations on real flights: none, the paper's bias observer (Freyja's, at
    the paper's rates), our accelerometer observer, the learnt model, and each observer with the
    model, replayed causally over held-out flights (swap_ss 05-06, swap_sl 08-11)."""
    check_number("--warmup", warmup, 0.0, 10.0)
    check_number("--lateral-radius", lateral_radius, 1e-3, 10.0)
    if model is None and kind not in KINDS:
        fail(f"--kind must be one of {', '.join(KINDS)}, got {kind!r}")
    if figure is not None and figure.is_dir():
        fail(f"{figure}: is a directory; give a file name such as compensation.png")
    if model is not None and not model.is_dir():
        fail(f"--model {model}: no such model directory")
    if data is not None and data_dir is not None:
        fail("give --data (the neural-swarm folder) or --data-dir (the folder holding it), "
             "not both")
    root = data if data is not None else default_data_root(data_dir)
    if not root.is_dir():
        fail(f"{root}: no such folder (give --data, the Neural-Swarm folder holding swap_ss and "
             "swap_sl_2020-06-19)")
    cfg = load_cli_config(config, sets, trust)
    result = _run_study(root, cfg, model_dir=model, kind=str(kind), seed=seed, quick=quick,
                        warmup_s=warmup, lateral_radius_m=lateral_radius, figure=figure)
    if as_json:
        print_json(result)
        return
    _print_study(result)


def _run_study(root: Path, cfg: Config, *, model_dir: Path | None, kind: str, seed: int,
               quick: bool, warmup_s: float, lateral_radius_m: float,
               figure: Path | None) -> dict:
    """:func:`aerodock.experiments.compensation_study.compensation_study` under a progress bar,
    its messages dimmed on stderr; a missing PyTorch or unreadable flights or model is a
    one-line error.

    Args:
        root: the Neural-Swarm folder.
        cfg: the world's config.
        model_dir: a trained model to fly (None: train one).
        kind: the model kind to train without ``model_dir``.
        seed: the training seed.
        quick: train for at most 30 epochs.
        warmup_s: unscored seconds at the start of each segment.
        lateral_radius_m: the interaction region's radius, m.
        figure: a PNG file to draw the residuals to (None: none).

    Returns:
        The study's result.
    """
    from aerodock.experiments.compensation_study import compensation_study
    from aerodock.ingest.errors import IngestError
    from aerodock.learning.modelfile import ModelFileError

    def say(msg: str) -> None:
        err_console.print(f"[dim]{msg}[/dim]")

    with progress_bar() as bar:
        update = bar_callback(bar)
        try:
            result = compensation_study(
                root, cfg=cfg, model_dir=model_dir, kind=kind, seed=seed, quick=quick,
                warmup_s=warmup_s, lateral_radius_m=lateral_radius_m, figure=figure, say=say,
                train_progress=lambda e, n, *_: update("training epochs", e, n))
        except ImportError:
            fail("training a model needs PyTorch: pip install 'aerodock[learn]' (or give --model)")
        except (FileNotFoundError, IngestError, ModelFileError) as err:
            fail(one_line(err, first_line=True))
    return result


def _print_study(result: dict) -> None:
    """The study's human summary: the model and settings, then one table per region and axis
    (:func:`aerodock.experiments.compensation_study.table_rows`), and the figure written."""
    from rich.console import Console
    from rich.table import Table

    from aerodock.experiments.compensation_study import table_rows, table_title

    console = Console()
    m = result["model"]
    trained = (f"trained here on swap_ss 00-04 and swap_sl 00-07 ({m['epochs']} epochs)"
               if m["trained_here"] else f"from {m['model_dir']}")
    console.print(f"model {m['kind']} {trained}; held out: swap_ss 05-06, swap_sl 08-11, each "
                  "vehicle as the follower")
    st = result["settings"]
    console.print(f"freyja: Freyja's bias estimator (the paper's stack; propagated at "
                  f"{st['freyja_propagation_rate_hz']:g} Hz); accel: our accelerometer observer "
                  f"(tau {st['accel_tau_s']:g} s, axes {st['accel_axes']}); model: the learnt "
                  f"model; a+b: both; the first {st['warmup_s']:g} s of each segment unscored")
    rates = ", ".join(f"{name} {c['rate_hz']:g} Hz" for name, c in
                      result["compensations"].items() if c["rate_hz"] is not None)
    for region in ("interaction", "all"):
        for axis in ("vertical", "planar"):
            header, rows = table_rows(result, region, axis, short=True)
            table = Table(title=table_title(result, region, axis), title_justify="left",
                          caption=f"follower/leader: S small, L large; rates: {rates}",
                          caption_justify="left")
            for i, col in enumerate(header):
                table.add_column(col, justify="left" if i == 0 else "right", no_wrap=True)
            for row in rows:
                table.add_row(*row)
            console.print(table)
    if result["figure"]:
        typer.echo(f"wrote {result['figure']}")
