"""The learning-curve figure: training and validation loss per epoch of one training run.

Drawn from the record :func:`aerodock.learning.train.learning_curve_record` makes (the
``history`` of a training's ``info``, also in ``model.json`` -> ``training.history``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from aerodock.fileio import atomic_open


def plot_learning_curve(info: dict[str, Any], path: str | Path) -> Path:
    """Draw a training's learning curves (PNG, Agg backend, no pyplot state).

    Args:
        info: a training record (``TrainedModel.info``): ``history``, ``kind``, ``best_epoch``,
            ``split``. Force losses (MSE) are drawn as their square roots (RMSE, m/s²); a
            wrench model's standardised loss as it is.
        path: the PNG file to write (atomically).

    Returns:
        ``path``.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    path = Path(path)
    history = info.get("history") or {}
    rmse = not str(history.get("loss", "")).startswith("standardised")
    fig = Figure(figsize=(6.0, 4.0), dpi=120)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    for key, label in (("train_loss", "training (mean over the epoch)"),
                       ("val_loss", f"validation ({info.get('split', '?')} split)")):
        values = np.asarray(history.get(key, []), dtype=float)
        if len(values):
            ax.plot(np.arange(1, len(values) + 1), np.sqrt(values) if rmse else values,
                    marker=".", label=label)
    best = info.get("best_epoch")
    if best:
        ax.axvline(best, color="0.5", linestyle=":", label=f"kept: epoch {best}")
    ax.set_xlabel("epoch")
    ax.set_ylabel("RMSE, m/s²" if rmse else "standardised loss")
    ax.set_title(f"Learning curve, {info.get('kind', 'model')}")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small")
    fig.tight_layout()
    with atomic_open(path, "wb", suffix=".png") as fh:
        fig.savefig(fh, format="png")
    return path
