"""``aerodock train``, ``evaluate``, ``export`` (a downwash model from flight logs) and
``collect`` (the curriculum that flies, trains and deploys it stage by stage).

Bad input (missing/corrupt data or model files, unknown model kind, too little or degenerate
data) prints ``error: <one line>`` on stderr and exits with code 2, without a traceback; an
error's text is cut to its first line (a path keeps its spaces). ``train`` refuses to write a
model whose training did not give finite weights, so a good model already in ``--out`` is never
replaced by a broken one. Progress goes to stderr, so ``--json`` output on stdout stays
machine-readable. PyTorch is imported only by the commands that need it (``train``,
``export``, ``collect``).
"""

from __future__ import annotations

import math
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer

from aerodock.cli.common import (
    ConfigOpt,
    JsonOpt,
    LoggedProgress,
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
from aerodock.fileio import one_line, refuse_symlink
from aerodock.learning.kinds import KINDS, kinds_help, trained_kinds

TRAINABLE = KINDS
# The kinds a curriculum trains and flies at each stage (the zero model would fly nothing).
COLLECTABLE = trained_kinds()
ModelKind = StrEnum("ModelKind", {kind: kind for kind in TRAINABLE})
CollectKind = StrEnum("CollectKind", {kind: kind for kind in COLLECTABLE})
SPLITS = ("auto", "flight", "time-blocks")
Split = StrEnum("Split", {split: split for split in SPLITS})
GraphDtype = StrEnum("GraphDtype", {"float32": "float32", "float64": "float64"})
"""``--split`` values (``aerodock.learning.train.SPLITS``; not imported: that needs PyTorch)."""

DataOpt = Annotated[
    list[Path],
    typer.Option(
        "--data",
        help="FlightLog file, dataset file, or folder of them; several after one --data "
             "(--data a.npz b.npz) or --data repeated.",
    ),
]
JsonStdoutOpt = Annotated[bool, typer.Option("--json", help="Print the numbers as JSON on stdout.")]


def _load_data(paths: list[Path]) -> Any:
    from aerodock.learning.datafiles import load_data_paths
    from aerodock.learning.dataset import DataError

    try:
        return load_data_paths(paths)
    except (DataError, OSError, ValueError) as err:
        fail(one_line(err, first_line=True))


def _fmt(v: float | None, digits: int = 3) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return f"{v:.{digits}f}"


_TORQUE_FIGURES = ("train_rmse_torque_nm", "val_rmse_torque_nm", "val_torque_vs_true_rmse_nm",
                   "val_true_torque_rms_nm")


def _torque_figures(fit: Any) -> dict[str, float]:
    """A wrench model's torque figures that were computed (a ``FitRecord``'s), by name."""
    return {key: getattr(fit, key) for key in _TORQUE_FIGURES if getattr(fit, key) is not None}


def train_command(
    data: DataOpt,
    out: Annotated[Path, typer.Option("--out", help="Model directory to write.")],
    model: Annotated[
        ModelKind, typer.Option("--model", help=f"Model kind: {kinds_help()}.")
    ] = "so2",
    minutes: Annotated[
        float | None,
        typer.Option("--minutes", help="Train on only this many minutes of the data."),
    ] = None,
    seed: SeedOpt = 0,
    spectral_norm: Annotated[
        bool, typer.Option("--spectral-norm", help="Spectrally normalise the layers.")
    ] = False,
    max_epochs: Annotated[int, typer.Option("--max-epochs", help="Epoch limit.")] = 200,
    split: Annotated[
        Split, typer.Option("--split", help="Validation split: auto (by flight with 20 flights or "
                                          "more, else 5 s time blocks of every flight), flight "
                                          "or time-blocks.")
    ] = "auto",
    curve: Annotated[
        Path | None,
        typer.Option("--curve", help="Also draw the learning curves (training and validation "
                                     "RMSE per epoch) to this PNG file."),
    ] = None,
    as_json: JsonStdoutOpt = False,
) -> None:
    """Train a downwash model on flight logs and write it to a model directory.

    The per-epoch training and validation losses (the learning curves) are in the ``--json``
    output (``history``) and in ``model.json`` (``training.history``); ``--curve`` draws them.
    """
    import numpy as np

    model = str(model)
    if model not in TRAINABLE:
        fail(f"unknown model kind {model!r} (expected one of {', '.join(TRAINABLE)})")
    if split not in SPLITS:
        fail(f"--split must be one of {', '.join(SPLITS)}, got {split!r}")
    if curve is not None:
        if curve.is_dir():
            fail(f"{curve}: is a directory; give a file name such as learning_curve.png")
        if curve.resolve().parent == out.resolve():
            fail(f"{curve}: not inside the model directory (it holds only the model's files)")
    if minutes is not None and not (minutes > 0 and math.isfinite(minutes)):
        fail(f"--minutes must be a positive finite number, got {minutes}")
    if max_epochs < 1:
        fail(f"--max-epochs must be at least 1, got {max_epochs}")
    refuse_symlink(out)  # the model folder is swapped in whole: a link would be replaced
    if out.exists() and not out.is_dir():
        fail(f"{out}: exists and is not a directory")
    ds = _load_data(data)
    available = ds.minutes
    if minutes is not None:
        from aerodock.learning.splits import take_minutes

        ds = take_minutes(ds, minutes, np.random.default_rng(seed))
    try:
        from aerodock.learning.train import check_trainable, train_model
    except ImportError:
        fail("training needs PyTorch: pip install 'aerodock[learn]'")
    try:
        check_trainable(ds, kind=model)
    except ValueError as err:
        fail(one_line(err, first_line=True))
    from rich.progress import BarColumn, TextColumn, TimeElapsedColumn

    with LoggedProgress(
        TextColumn("[bold]train {task.fields[kind]}"), BarColumn(),
        TextColumn("epoch {task.completed}/{task.total}"),
        TextColumn("{task.fields[loss]}"), TimeElapsedColumn(),
        transient=True,
    ) as bar:
        task = bar.add_task(f"train {model} (epochs)", total=max_epochs, kind=model, loss="")

        def progress(epoch: int, total: int, train_loss: float, val_loss: float | None) -> None:
            loss = f"val RMSE {math.sqrt(val_loss):.3f} m/s²" if val_loss is not None else ""
            bar.update(task, completed=epoch, loss=loss)

        try:
            trained = train_model(model, ds, seed=seed, spectral_norm=spectral_norm,
                                  max_epochs=max_epochs, split=str(split), progress=progress)
        except ValueError as err:
            fail(one_line(err, first_line=True))
    try:
        path = trained.save(out)
    except (OSError, ValueError) as err:
        fail(f"{out}: cannot write model ({one_line(err, first_line=True)})")
    result = _train_result(trained, path, model, seed, ds, available)
    if curve is not None and model != "zero":
        from aerodock.learning.curves import plot_learning_curve

        try:
            result["learning_curve"] = str(plot_learning_curve(trained.info, curve))
        except OSError as err:
            fail(f"{curve}: cannot write the learning curve ({one_line(err, first_line=True)})")
    if as_json:
        print_json(result)
        return
    _echo_trained(result, model, ds, path)


def _train_result(trained: Any, path: Path, model: str, seed: int, ds: Any,
                  available: float) -> dict[str, Any]:
    """``train --json``'s object, from the training record (``TrainedModel.record``)."""
    rec = trained.record
    assert rec is not None  # train_model always records its training
    done = rec.outcome  # None: a kind with nothing to train
    fit = None if done is None else done.fit
    return {
        "model_dir": str(path),
        "kind": model,
        "seed": seed,
        "n_samples": ds.n,
        "n_flights": ds.n_flights,
        "minutes": round(ds.minutes, 4),
        "minutes_available": round(available, 4),
        "split": None if done is None else done.split,
        "epochs": None if done is None else done.epochs,
        "best_epoch": None if done is None else done.best_epoch,
        "stopped": None if done is None else done.stopped,
        "train_rmse_mps2": None if fit is None else fit.train_rmse_mps2,
        "val_rmse_mps2": None if fit is None else fit.val_rmse_mps2,
        **({} if fit is None else _torque_figures(fit)),
        "train_time_s": rec.train_time_s,
        "history": rec.history,
        "learning_curve": None,
        "warnings": ds.meta.get("warnings", []),
    }


def _echo_trained(result: dict[str, Any], model: str, ds: Any, path: Path) -> None:
    """``train``'s text output: the warnings, the training's figures, what was written."""
    for note in result["warnings"]:
        typer.echo(f"warning: {note}", err=True)
    typer.echo(
        f"trained {model} on {ds.n} samples ({ds.minutes:.2f} min, {ds.n_flights} flights) in "
        f"{_fmt(result['train_time_s'], 1)} s, {result['epochs']} epochs ({result['stopped']}, "
        f"best epoch {result['best_epoch']}); validation RMSE {_fmt(result['val_rmse_mps2'])} "
        f"m/s² ({result['split']} split)"
    )
    if "val_rmse_torque_nm" in result:
        truth = ""
        if "val_torque_vs_true_rmse_nm" in result:
            truth = (f", {_fmt(result['val_torque_vs_true_rmse_nm'], 4)} N m against the true "
                     f"wake torque (its RMS {_fmt(result['val_true_torque_rms_nm'], 4)} N m)")
        typer.echo(f"torque: validation RMSE {_fmt(result['val_rmse_torque_nm'], 4)} N m "
                   f"against the labels{truth}")
    if result["learning_curve"]:
        typer.echo(f"wrote {result['learning_curve']}")
    typer.echo(f"wrote {path}")


def _metrics_table(title: str, region: dict[str, Any]) -> Any:
    from rich.table import Table

    table = Table(title=f"{title} ({region['n']} samples)", title_justify="left")
    cols = [("model", region["model"]), ("zero model", region["zero"])]
    if region.get("error_floor"):
        cols.append(("error floor", region["error_floor"]))
    table.add_column("metric")
    for name, _ in cols:
        table.add_column(name, justify="right")
    for axis in ("x", "y", "z", "overall"):
        table.add_row(f"RMSE {axis} [m/s²]", *[_fmt(m["rmse_mps2"][axis]) for _, m in cols])
    for axis in ("x", "y", "z", "overall"):
        table.add_row(f"R² {axis}", *[_fmt(m["r2"][axis]) for _, m in cols])
    return table


def _torque_table(title: str, region: dict[str, Any]) -> Any:
    from rich.table import Table

    table = Table(title=f"torque, {title} ({region['n']} samples)", title_justify="left")
    cols = [("model", region["model"]), ("zero model", region["zero"])]
    if region.get("true_torque"):
        cols.append(("true torque", region["true_torque"]))
        cols.append(("model vs true", region["model_vs_true"]))
    table.add_column("metric")
    for name, _ in cols:
        table.add_column(name, justify="right")
    for axis in ("x", "y", "z", "overall"):
        table.add_row(f"RMSE {axis} [N m]", *[_fmt(m["rmse_nm"][axis], 4) for _, m in cols])
    if region.get("true_rms_nm") is not None:
        table.caption = (f"RMS of the true wake torque (one component): "
                         f"{region['true_rms_nm']:.4f} N m")
    return table


def evaluate_command(
    model: Annotated[Path, typer.Option("--model", help="Trained model directory.")],
    data: DataOpt,
    lateral_radius: Annotated[
        float, typer.Option("--lateral-radius", help="Interaction region radius, m.")
    ] = 0.2,
    as_json: JsonStdoutOpt = False,
) -> None:
    """Evaluate a trained model on held-out flights, beside the zero model."""
    from aerodock.learning.evaluate import evaluate
    from aerodock.learning.modelfile import ModelFileError
    from aerodock.learning.runtime import Predictor

    if not (lateral_radius > 0 and math.isfinite(lateral_radius)):
        fail(f"--lateral-radius must be a positive finite number, got {lateral_radius}")
    try:
        predictor = Predictor.load(model)
    except ModelFileError as err:
        fail(one_line(err, first_line=True))
    ds = _load_data(data)
    result = evaluate(predictor, ds, lateral_radius_m=lateral_radius)
    result["model_dir"] = str(model)
    if as_json:
        print_json(result)
        return
    from rich.console import Console

    console = Console()
    console.print(f"model {model} ({result['model']}) on {ds.n} samples "
                  f"({ds.minutes:.2f} min, {ds.n_flights} flights)")
    console.print(_metrics_table("all samples", result["all"]))
    console.print(_metrics_table(f"interaction region: {result['interaction_region']}",
                                 result["interaction"]))
    if "torque" in result:
        console.print(_torque_table("all samples", result["torque"]["all"]))
        console.print(_torque_table("interaction region", result["torque"]["interaction"]))


def export_command(
    model: Annotated[Path, typer.Option("--model", help="Trained model directory.")],
    out: Annotated[Path, typer.Option("--out", help="ONNX file to write.")],
    dtype: Annotated[GraphDtype, typer.Option("--dtype", help="The graph's float type.")
                     ] = "float32",
    as_json: JsonStdoutOpt = False,
) -> None:
    """Export a trained model to ONNX (inputs x (n,9), leader_R (n,3,3); output f_ext_mps2 (n,3),
    and tau_ext_nm (n,3) for so2-wrench)."""
    from aerodock.learning.modelfile import ModelFileError
    from aerodock.learning.runtime import Predictor

    try:
        predictor = Predictor.load(model)
    except ModelFileError as err:
        fail(one_line(err, first_line=True))
    if out.is_dir():
        fail(f"{out}: is a directory; give a file name such as model.onnx")
    if dtype not in ("float32", "float64"):
        fail(f"--dtype {dtype!r}: use float32 or float64")
    from aerodock.fileio import check_writable_target

    try:
        check_writable_target(out)
    except OSError as err:
        fail(str(err))
    try:
        import onnx  # noqa: F401

        from aerodock.deploy.export import ExportCheckError, export_checked
    except ImportError:
        fail("ONNX export needs onnx: pip install 'aerodock[export]'")
    try:  # checked against the NumPy predictor before it takes the name --out
        path, diffs = export_checked(model, out, dtype=str(dtype))
    except ModelFileError as err:
        fail(one_line(err, first_line=True))
    except ExportCheckError as err:
        fail(f"{out}: export failed its check ({one_line(err, first_line=True)})")
    except (OSError, RuntimeError) as err:
        fail(f"{out}: export failed ({one_line(err, first_line=True)})")
    result: dict[str, Any] = {"model_dir": str(model), "kind": predictor.kind, "onnx": str(path),
                              "max_abs_diff_vs_numpy_mps2": diffs and diffs["f_ext_mps2"]}
    if diffs and "tau_ext_nm" in diffs:
        result["max_abs_diff_vs_numpy_torque_nm"] = diffs["tau_ext_nm"]
    if as_json:
        print_json(result)
        return
    if diffs is None:
        check = "not checked (onnxruntime not installed)"
    else:
        check = f"max |onnxruntime - numpy| = {diffs['f_ext_mps2']:.2e} m/s²"
        if "tau_ext_nm" in diffs:
            check += f", {diffs['tau_ext_nm']:.2e} N m"
    typer.echo(f"wrote {path} ({check})")


def collect(
    out: Annotated[Path, typer.Option(help="Folder for the FlightLogs and stage models.")],
    model: Annotated[CollectKind | None, typer.Option(
        help="Model kind trained at each stage (default: the config's curriculum.model).")
    ] = None,
    config: ConfigOpt = None,
    sets: SetOpt = None,
    trust: TrustOpt = None,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Curriculum data collection: each stage trains, deploys and flies curriculum.stage_step_m
    closer (0.3 m by default)."""
    from aerodock.collect.curriculum import run_curriculum

    cfg = load_cli_config(config, sets, trust)
    model = None if model is None else str(model)
    if model is not None and model not in COLLECTABLE:
        fail(f"--model must be {', '.join(COLLECTABLE[:-1])} or {COLLECTABLE[-1]}, got {model!r}")

    def say(msg: str) -> None:
        err_console.print(f"[dim]{msg}[/dim]")

    with progress_bar() as bar:
        update = bar_callback(bar)
        summary = run_curriculum(cfg, out, seed=seed, model_kind=model, progress=say,
                                 train_kwargs={"progress": lambda e, n, *_: update(
                                     "training epochs", e, n)})
    if as_json:
        print_json(summary)
        return
    for st in summary["stages"]:
        lo, hi = st["depth_band_m"]
        typer.echo(f"stage {st['stage']}: {lo:.2f}-{hi:.2f} m, {st['flights']} flights, "
                   f"{st['minutes']:.2f} min, val RMSE {st['val_rmse_mps2']:.3f} m/s²")
    typer.echo(f"{summary['minutes']:.1f} min of flight in {summary['wall_s']:.0f} s; "
               f"logs in {out}/stageK.npz, final model in {summary['final_model']}")
