"""The compensations scored on real flights: what each leaves of the wake on held-out flights.

On the shared Neural-Swarm flights (``swap_ss``: two small Crazyflies; ``swap_sl_2020-06-19``:
a small and a large one), a model is trained on flights swap_ss 00-04 and swap_sl 00-07 (or a
given one is used) and every compensation of :mod:`aerodock.experiments.compensation_replay` is
replayed causally over the held-out flights, swap_ss 05-06 and swap_sl 08-11, each vehicle of a
flight taking the follower's role in turn. The result: the RMS of what each leaves, vertical and
planar, per pairing (small under small, small under large, large under small, and all), in the
interaction region (the follower below the other vehicle within 0.2 m laterally) and over every
scored sample, and the fraction of the zero compensation's RMS removed; and a figure of the
residual against each compensation along a held-out pass.

:func:`compensation_study` is the whole study (``aerodock evaluate-compensation``);
:func:`compensation_section` is the hook ``reproduce`` calls, and :func:`compensation_markdown`
renders the result as the report's table.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.config import Config, load_config
from aerodock.experiments.compensation_replay import (
    COMPENSATIONS,
    DEFAULT_MAX_GAP_S,
    DEFAULT_WARMUP_S,
    ReplayFlights,
    ReplaySettings,
    leftovers,
    replay,
    replay_flights,
    score,
    scored_mask,
)
from aerodock.learning.dataset import INTERACTION_RADIUS_M

# The swap flights pass at 0.2-0.5 m laterally: free air starts nearer than in the simulated
# curriculum (as in the real-data study, aerodock/experiments/real_data.py).
FREE_AIR_RADIUS_M = 0.2
FOLDERS = {
    "swap_ss": {"vehicle": "small", "train": ("00", "01", "02", "03", "04"),
                "test": ("05", "06")},
    "swap_sl_2020-06-19": {"vehicle": "cf51=small,cf101=large",
                           "train": ("00", "01", "02", "03", "04", "05", "06", "07"),
                           "test": ("08", "09", "10", "11")},
}
"""Each Neural-Swarm folder of the study: its vehicles and its training and held-out flights."""
LABELS = {
    "none": "none (zero)",
    "freyja": "bias observer (Freyja)",
    "accel": "accelerometer observer",
    "model": "learnt model",
    "model+accel": "model + accelerometer observer",
    "model+freyja": "model + bias observer (Freyja)",
}
"""How each compensation is named in tables and figures."""
SHORT_PAIRINGS = {"small-under-small": "S/S", "small-under-large": "S/L",
                  "large-under-small": "L/S"}
"""Follower/leader, for narrow tables."""
QUICK_MAX_EPOCHS = 30
SMOKE_MAX_EPOCHS = 5
"""The model's training in ``reproduce --smoke`` (a check that the step runs, not a figure)."""
PAIRING_ORDER = ("small-under-small", "small-under-large", "large-under-small")

Say = Callable[[str], None]


def check_root(root: Path) -> None:
    """Refuse a data folder without the study's Neural-Swarm folders.

    Raises:
        FileNotFoundError: one missing (one line naming it).
    """
    for folder in FOLDERS:
        path = Path(root) / folder
        if not path.is_dir():
            raise FileNotFoundError(f"{path}: no such folder (expected the Neural-Swarm folders "
                                    f"{', '.join(FOLDERS)} under {root})")


def _folder_logs(root: Path, part: str) -> list:
    """The flights of ``part`` (``"train"`` or ``"test"``) of every study folder under ``root``,
    with their folder's name, in folder order."""
    from aerodock.ingest import read_logs

    check_root(root)
    out = []
    for folder, spec in FOLDERS.items():
        logs = read_logs("neural-swarm", [Path(root) / folder], vehicle=spec["vehicle"])
        out.append((folder, [lg for lg in logs if lg.meta.get("flight_id") in spec[part]]))
    return out


def _dataset(groups: list) -> Any:
    """One data set of the flights of every folder (biases estimated within a folder)."""
    from aerodock.learning.dataset import build_dataset, concat_datasets

    return concat_datasets([build_dataset(logs, free_air_radius_m=FREE_AIR_RADIUS_M)
                            for _, logs in groups if logs])


def train_study_model(root: Path, *, kind: str = "so2", seed: int = 0, quick: bool = False,
                      progress: Callable[[int, int, float, float | None], None] | None = None,
                      max_epochs: int | None = None) -> Any:
    """A ``kind`` model trained on the study's training flights (at most ``max_epochs`` epochs;
    by default :data:`QUICK_MAX_EPOCHS` when ``quick``, else 200) with the project's trainer;
    returns the TrainedModel."""
    from aerodock.learning.train import train_model

    ds = _dataset(_folder_logs(root, "train"))
    if max_epochs is None:
        max_epochs = QUICK_MAX_EPOCHS if quick else 200
    return train_model(kind, ds, seed=seed, max_epochs=max_epochs, progress=progress)


def compensation_study(
    root: Path,
    *,
    cfg: Config | None = None,
    model_dir: Path | None = None,
    kind: str = "so2",
    seed: int = 0,
    quick: bool = False,
    warmup_s: float = DEFAULT_WARMUP_S,
    lateral_radius_m: float = INTERACTION_RADIUS_M,
    figure: Path | None = None,
    say: Say | None = None,
    train_progress: Callable[[int, int, float, float | None], None] | None = None,
    max_epochs: int | None = None,
) -> dict[str, Any]:
    """Every compensation replayed over the held-out flights under ``root`` (the folder holding
    ``swap_ss`` and ``swap_sl_2020-06-19``), scored (JSON-ready dict).

    Args:
        root: the Neural-Swarm data folder.
        cfg: the configuration whose controller profiles give the rates and observers
            (default: the defaults).
        model_dir: a trained model to fly; default: train ``kind`` on the training flights.
        kind: model kind to train when no ``model_dir``.
        seed: training seed.
        quick: train for at most :data:`QUICK_MAX_EPOCHS` epochs.
        warmup_s: seconds at the start of each replayed segment not scored.
        lateral_radius_m: the interaction region's radius, m.
        figure: a PNG file for the residual against each compensation along a held-out pass.
        say: progress messages.
        train_progress: the trainer's per-epoch callback.
        max_epochs: the training's epoch limit, overriding ``quick``'s.

    Raises:
        FileNotFoundError: a folder missing under ``root``.
        aerodock.ingest.errors.IngestError: a log that cannot be read.
        aerodock.learning.modelfile.ModelFileError: an unreadable ``model_dir``.
    """
    from aerodock.learning.evaluate import predict_dataset
    from aerodock.learning.runtime import Predictor

    check_root(root)
    cfg = cfg or load_config()
    say = say or (lambda _msg: None)
    settings = ReplaySettings.from_config(cfg, warmup_s=warmup_s)
    model_info: dict[str, Any]
    if model_dir is not None:
        predictor = Predictor.load(model_dir)
        model_info = {"model_dir": str(model_dir), "kind": predictor.kind, "trained_here": False}
    else:
        say(f"training {kind} on swap_ss 00-04 and swap_sl 00-07")
        trained = train_study_model(root, kind=kind, seed=seed, quick=quick,
                                    progress=train_progress, max_epochs=max_epochs)
        predictor = trained.predictor()
        info = trained.info
        model_info = {"model_dir": None, "kind": kind, "trained_here": True, "seed": seed,
                      "epochs": info.get("epochs"), "best_epoch": info.get("best_epoch"),
                      "val_rmse_mps2": info.get("val_rmse_mps2"), "quick": quick}
    say("replaying the compensations over swap_ss 05-06 and swap_sl 08-11")
    groups = _folder_logs(root, "test")
    logs = [lg for _, group in groups for lg in group]
    ds = _dataset(groups)
    flights = replay_flights(logs, ds, predict_dataset(predictor, ds),
                             lateral_radius_m=lateral_radius_m,
                             free_air_radius_m=FREE_AIR_RADIUS_M)
    replayed = replay(flights, settings)
    scored = scored_mask(flights, settings.warmup_s)
    left = leftovers(flights, replayed, scored)
    result: dict[str, Any] = {
        "data": str(root),
        "train_flights": {f: f"{s['train'][0]}-{s['train'][-1]}" for f, s in FOLDERS.items()},
        "test_flights": [lg.name for lg in logs],
        "model": model_info,
        "settings": {**settings.describe(), "sample_period_s": flights.dt_s,
                     "lateral_radius_m": lateral_radius_m,
                     "free_air_radius_m": FREE_AIR_RADIUS_M, "max_gap_s": DEFAULT_MAX_GAP_S,
                     "segments": flights.n},
        "compensations": {name: {"label": LABELS[name], "rate_hz": replayed[name].rate_hz}
                          for name in COMPENSATIONS},
        "scores": score(flights, left, scored),
        "figure": None,
    }
    if figure is not None:
        result["figure"] = str(plot_pass(flights, replayed, left, scored, figure))
    return result


def compensation_section(shared_data: Path, fig_dir: Path, quick: bool = False, seed: int = 0,
                         cfg: Config | None = None, smoke: bool = False) -> dict[str, Any]:
    """The hook for ``reproduce``: :func:`compensation_study` on ``shared_data/neural-swarm``
    (a model trained here; ``quick``: a quick training; ``smoke``: at most
    :data:`SMOKE_MAX_EPOCHS` epochs), the figure as ``fig_dir/compensation_replay.png``. Render
    it with :func:`compensation_markdown`."""
    return compensation_study(Path(shared_data) / "neural-swarm", cfg=cfg, quick=quick or smoke,
                              seed=seed, figure=Path(fig_dir) / "compensation_replay.png",
                              max_epochs=SMOKE_MAX_EPOCHS if smoke else None)


def _pct(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.0f} %"


def _num(x: float | None) -> str:
    return "-" if x is None else f"{x:.3f}"


def table_rows(result: dict[str, Any], region: str = "interaction", axis: str = "vertical",
               short: bool = False) -> tuple[list[str], list[list[str]]]:
    """Header and rows of the ``axis`` (``"vertical"`` or ``"planar"``) RMS each compensation
    leaves in ``region`` (``"interaction"`` or ``"all"``) per pairing, as ``"rms (removed)"``
    with the RMS in m/s² and the share of the zero compensation's RMS removed. ``short``: the
    compensations' keys, ``S/L`` for small under large and no rate column (for a terminal)."""
    scores = result["scores"]
    groups = [g for g in PAIRING_ORDER if g in scores] + [
        g for g in scores if g not in PAIRING_ORDER and g != "all"] + ["all"]
    if short:
        header = ["compensation", *(SHORT_PAIRINGS.get(g, g) for g in groups)]
    else:
        header = ["compensation", "rate", *groups]
    rows = []
    for name in COMPENSATIONS:
        rate = result["compensations"][name]["rate_hz"]
        row = [name] if short else [LABELS[name], "-" if rate is None else f"{rate:g} Hz"]
        for g in groups:
            rec = scores[g][region]["compensations"][name]
            cell = _num(rec[f"{axis}_rms_mps2"])
            if name != "none":
                removed = _pct(rec[f"{axis}_removed"])
                cell += f" ({removed.replace(' ', '') if short else removed})"
            row.append(cell)
        rows.append(row)
    return header, rows


def table_title(result: dict[str, Any], region: str, axis: str) -> str:
    """A table's title: what it holds and the samples behind each column."""
    where = (f"interaction region (follower below the other vehicle within "
             f"{result['settings']['lateral_radius_m']:g} m)" if region == "interaction"
             else "every scored sample")
    counts = ", ".join(f"{g} {v[region]['n']}" for g, v in result["scores"].items())
    return (f"{axis.capitalize()} RMS left, m/s² (share of the zero compensation's removed), "
            f"{where}; samples: {counts}")


def compensation_markdown(result: dict[str, Any] | None) -> list[str]:
    """The study as markdown lines: the vertical and planar tables of both regions."""
    if not result:
        return ["The compensations were not scored on real flights (no Neural-Swarm flights in "
                "the data location: AERODOCK_DATA_DIR or --data-dir, docs/real-logs.md)."]
    lines = []
    for region in ("interaction", "all"):
        for axis in ("vertical", "planar"):
            header, rows = table_rows(result, region, axis)
            lines += [table_title(result, region, axis) + ".", "",
                      "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
            lines += ["| " + " | ".join(row) + " |" for row in rows]
            lines.append("")
    return lines


def _pass_window(flights: ReplayFlights, scored: np.ndarray, span_s: float = 4.0
                 ) -> tuple[int, int, int]:
    """``(segment, start, stop)`` of a window of ``span_s`` around the scored interaction pass
    with the most samples (the first such segment)."""
    inter = flights.interaction & scored
    seg = int(np.argmax(inter.sum(axis=1)))
    idx = np.flatnonzero(inter[seg])
    if not len(idx):
        idx = np.flatnonzero(scored[seg]) if scored[seg].any() else np.array([0])
    # the longest run of consecutive interaction samples
    breaks = np.flatnonzero(np.diff(idx) > 1)
    starts = np.concatenate([[0], breaks + 1])
    stops = np.concatenate([breaks, [len(idx) - 1]])
    best = int(np.argmax(stops - starts))
    centre = (idx[starts[best]] + idx[stops[best]]) // 2
    half = int(round(span_s / 2 / flights.dt_s))
    valid_len = int(flights.valid[seg].sum())
    a = max(0, centre - half)
    return seg, a, min(valid_len, a + 2 * half)


def plot_pass(flights: ReplayFlights, replayed: dict, left: dict[str, np.ndarray],
              scored: np.ndarray, path: Path) -> Path:
    """The vertical residual against each compensation, and what each leaves, along the
    held-out pass with the most interaction samples (PNG, written atomically)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from aerodock.fileio import atomic_open

    seg, a, b = _pass_window(flights, scored)
    t = flights.t_s[seg, a:b]
    label = flights.label_mps2[seg, a:b, 2]
    fig = Figure(figsize=(10.0, 6.5), dpi=110)
    FigureCanvasAgg(fig)
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    colours = {"freyja": "tab:red", "accel": "tab:green", "model": "tab:blue",
               "model+accel": "tab:purple", "model+freyja": "tab:orange"}
    ax1.plot(t, label, color="0.55", lw=1.0, label="residual (label)")
    for name, colour in colours.items():
        if name not in left:
            continue
        comp = label - left[name][seg, a:b, 2]
        ax1.plot(t, comp, color=colour, lw=1.1, label=LABELS[name])
        ax2.plot(t, left[name][seg, a:b, 2], color=colour, lw=0.9, label=LABELS[name])
    ax2.plot(t, label, color="0.55", lw=0.9, label=LABELS["none"])
    inter = flights.interaction[seg, a:b]
    for ax in (ax1, ax2):
        ax.fill_between(t, 0, 1, where=inter, transform=ax.get_xaxis_transform(),
                        color="tab:green", alpha=0.1)
        ax.grid(alpha=0.3)
    flight = flights.names[int(flights.segment_flight[seg])]
    pairing = flights.pairings[int(flights.segment_flight[seg])]
    ax1.set_title(f"Held-out flight {flight} ({pairing}); shaded: below the other vehicle")
    ax1.set_ylabel("vertical, down + [m/s²]")
    ax2.set_ylabel("left: residual - compensation")
    ax2.set_xlabel("time in the segment [s]")
    ax1.legend(fontsize=7, ncol=3)
    fig.tight_layout()
    with atomic_open(path, "wb", suffix=".png") as fh:
        fig.savefig(fh, format="png")
    return Path(path)

