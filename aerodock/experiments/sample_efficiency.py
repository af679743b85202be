"""Sample efficiency: held-out error against minutes of training data, per model kind.

For every requested amount of data and every seed, one training subset is drawn
(:func:`~aerodock.learning.splits.take_minutes`; the same subset for every model kind, so the
comparison is paired), each kind is trained on it and evaluated on the held-out set. Amounts
larger than the data available are skipped and recorded. Results go to ``sample_efficiency.json``
and a figure ``sample_efficiency.png`` (log minutes vs held-out RMSE, mean ± sd over seeds, one
line per kind, the zero model and, with simulated data, the error floor as horizontal lines).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.fileio import atomic_open, json_ready, write_json
from aerodock.learning.dataset import Dataset
from aerodock.learning.evaluate import evaluate
from aerodock.learning.features import check_kind
from aerodock.learning.runtime import ZeroPredictor
from aerodock.learning.splits import take_minutes
from aerodock.learning.train import train_model

JSON_NAME = "sample_efficiency.json"
FIGURE_NAME = "sample_efficiency.png"
KIND_LABELS = {"so2": "SO(2) (paper)", "so2-ext": "SO(2) extended", "mlp": "plain MLP"}


def _mean_sd(values: list[float]) -> tuple[float, float]:
    arr = np.asarray(values, dtype=float)
    return float(arr.mean()), float(arr.std(ddof=1)) if len(arr) > 1 else 0.0


def sample_efficiency(
    train_ds: Dataset,
    test_ds: Dataset,
    kinds: Sequence[str] = ("so2", "so2-ext", "mlp"),
    minutes: Sequence[float] = (0.5, 1, 2, 5, 10),
    seeds: Sequence[int] = (0, 1, 2),
    *,
    out_dir: str | Path | None = None,
    metric: str = "all",
    mode: str = "stratified",
    train_kwargs: dict[str, Any] | None = None,
    progress: Callable[[str, int, int], None] | None = None,
) -> dict[str, Any]:
    """Train every kind on growing amounts of data and evaluate on ``test_ds``.

    Args:
        train_ds: data to draw the training subsets from.
        test_ds: held-out data (e.g. other flights, see
            :func:`~aerodock.learning.splits.split_by_flight`).
        kinds: model kinds.
        minutes: amounts of training data (minutes of flight); larger than available: skipped.
        seeds: one subset and one training run per seed.
        out_dir: where to write the JSON and the PNG figure (None: write nothing).
        metric: region plotted, ``"all"`` or ``"interaction"`` (both are recorded).
        mode: subset mode of :func:`take_minutes` (default ``"stratified"``: a chunk of every
            flight, so small subsets keep the full data's range of separations).
        train_kwargs: extra keyword arguments for :func:`train_model`.
        progress: called as ``progress(description, done, total)`` after every run.

    Returns:
        JSON-ready results: ``minutes`` used, ``skipped_minutes``, ``zero`` and ``error_floor``
        RMSEs, and per kind ``rmse_mean``/``rmse_sd`` (plotted metric), the same for both
        regions, and every run.
    """
    for kind in kinds:
        check_kind(kind)
    if metric not in ("all", "interaction"):
        raise ValueError(f"metric must be 'all' or 'interaction', got {metric!r}")
    if not seeds:
        raise ValueError("at least one seed is needed")
    available = train_ds.minutes
    used = sorted(float(m) for m in minutes if float(m) <= available * (1 + 1e-6))
    skipped = sorted(float(m) for m in minutes if float(m) > available * (1 + 1e-6))
    zero = evaluate(ZeroPredictor(), test_ds)
    floor = {r: zero[r]["error_floor"] for r in ("all", "interaction")}
    result: dict[str, Any] = {
        "metric": metric,
        "metric_description": "held-out RMSE, m/s^2 (RMS over the three NED components); "
                              f"region {zero['interaction_region']!r} for 'interaction'",
        "mode": mode,
        "minutes_available": round(available, 4),
        "minutes": used,
        "skipped_minutes": skipped,
        "skip_reason": (f"more than the {available:.2f} minutes of training data available"
                        if skipped else None),
        "seeds": [int(s) for s in seeds],
        "n_test": test_ds.n,
        "n_test_interaction": zero["interaction"]["n"],
        "zero": {r: zero[r]["zero"]["rmse_mps2"]["overall"] for r in ("all", "interaction")},
        "error_floor": {r: (f["rmse_mps2"]["overall"] if f else None) for r, f in floor.items()},
        "models": {k: {"runs": []} for k in kinds},
    }
    total = len(used) * len(seeds) * len(kinds)
    done = 0
    kwargs = dict(train_kwargs or {})
    for m in used:
        for seed in seeds:
            subset = take_minutes(train_ds, m, np.random.default_rng(10_000 + int(seed)),
                                  mode=mode)
            for kind in kinds:
                result["models"][kind]["runs"].append(
                    _run(kind, subset, test_ds, minutes=m, seed=int(seed), train_kwargs=kwargs))
                done += 1
                if progress is not None:
                    progress(f"{kind} {m:g} min seed {seed}", done, total)
    for kind in kinds:
        entry = result["models"][kind]
        for region in ("all", "interaction"):
            entry[f"rmse_{region}_mean"], entry[f"rmse_{region}_sd"] = _rmse_by_minutes(
                entry["runs"], used, region)
        entry["rmse_mean"] = entry[f"rmse_{metric}_mean"]
        entry["rmse_sd"] = entry[f"rmse_{metric}_sd"]
    if out_dir is not None:
        _write_outputs(result, Path(out_dir))
    return json_ready(result)  # a size with no finished run has a null mean


def _run(kind: str, subset: Dataset, test_ds: Dataset, *, minutes: float, seed: int,
         train_kwargs: dict[str, Any]) -> dict[str, Any]:
    """Train ``kind`` on ``subset`` and evaluate it on ``test_ds``: one run's record.

    Args:
        kind: model kind.
        subset: the training subset.
        test_ds: held-out data.
        minutes: the amount of data asked for, minutes.
        seed: the training seed.
        train_kwargs: extra keyword arguments for :func:`train_model`.

    Returns:
        ``minutes``, ``minutes_used``, ``seed``, ``n_train``, the held-out ``rmse_all``,
        ``rmse_interaction`` (m/s²) and ``r2_all``, and the training's ``epochs``, ``split``
        and ``train_time_s``.
    """
    trained = train_model(kind, subset, seed=seed, **train_kwargs)
    ev = evaluate(trained.predictor(), test_ds)
    return {
        "minutes": minutes, "minutes_used": round(subset.minutes, 4), "seed": seed,
        "n_train": subset.n,
        "rmse_all": ev["all"]["model"]["rmse_mps2"]["overall"],
        "rmse_interaction": ev["interaction"]["model"]["rmse_mps2"]["overall"],
        "r2_all": ev["all"]["model"]["r2"]["overall"],
        "epochs": trained.info.get("epochs"),
        "split": trained.info.get("split"),
        "train_time_s": trained.info.get("train_time_s"),
    }


def _rmse_by_minutes(runs: list[dict[str, Any]], minutes: list[float],
                     region: str) -> tuple[list[float], list[float]]:
    """Mean and sd over seeds of the runs' ``rmse_<region>``, per amount of data in ``minutes``
    (NaN where no run of that amount has a value)."""
    means, sds = [], []
    for m in minutes:
        vals = [r[f"rmse_{region}"] for r in runs if r["minutes"] == m]
        vals = [v for v in vals if v is not None]
        mean, sd = _mean_sd(vals) if vals else (float("nan"), float("nan"))
        means.append(mean)
        sds.append(sd)
    return means, sds


def _write_outputs(result: dict[str, Any], out: Path) -> None:
    """Write the figure and the JSON into ``out`` (made if missing), noting both in ``result``."""
    out.mkdir(parents=True, exist_ok=True)
    result["figure"] = str(plot_sample_efficiency(result, out / FIGURE_NAME))
    result["json"] = str(out / JSON_NAME)
    write_json(out / JSON_NAME, json_ready(result), final_newline=True)


def plot_sample_efficiency(result: dict[str, Any], path: str | Path) -> Path:
    """Draw the sample-efficiency figure (PNG, Agg backend, no pyplot state) and return its path."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullFormatter

    path = Path(path)
    metric = result["metric"]
    fig = Figure(figsize=(6.0, 4.0), dpi=120)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    mins = np.asarray(result["minutes"], dtype=float)
    markers = iter("osD^v<>")
    for kind, entry in result["models"].items():
        if not len(mins):
            break
        mean = np.asarray(entry["rmse_mean"], dtype=float)
        sd = np.asarray(entry["rmse_sd"], dtype=float)
        ax.errorbar(mins, mean, yerr=sd, marker=next(markers, "o"), capsize=3,
                    label=KIND_LABELS.get(kind, kind))
    zero = result["zero"].get(metric)
    if zero is not None:
        ax.axhline(zero, color="0.3", linestyle="--", label="zero model")
    floor = (result.get("error_floor") or {}).get(metric)
    if floor is not None:
        ax.axhline(floor, color="0.6", linestyle=":", label="error floor (true mean field)")
    ax.set_xscale("log")
    ax.xaxis.set_minor_formatter(NullFormatter())
    if len(mins):
        ax.set_xticks(mins)
        ax.set_xticklabels([f"{m:g}" for m in mins])
    ax.set_xlabel("training data, minutes of flight")
    region = "all held-out samples" if metric == "all" else "interaction region"
    ax.set_ylabel(f"held-out RMSE, m/s² ({region})")
    one_seed = len(result.get("seeds", ())) == 1  # an sd over one seed is no spread
    ax.set_title(f"Sample efficiency ({'one seed' if one_seed else 'mean ± sd over seeds'})")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="small")
    fig.tight_layout()
    with atomic_open(path, "wb", suffix=".png") as fh:
        fig.savefig(fh, format="png")
    return path
