"""Summary figures and per-cell summaries of a sweep's tidy table."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.mission import wilson_interval
from aerodock.plots import _plt, _save
from aerodock.sweep.store import OUTCOME_NAMES

# Axes a figure can put on its x axis (the fault and the controller as categories); every
# config-key column that varies is one too, named by its key.
_X_AXES = (("cable_length_m", "cable length d_p [m]"),
           ("leader_speed_mps", "leader speed [m/s]"),
           ("mocap_noise_scale", "motion-capture noise [x config]"),
           ("fault", "fault"),
           ("controller", "controller"))
_NOT_X = {"cell", "seed", "compensation", "dropout_start_s", "dropout_duration_s"}


def _settings_columns(row: dict[str, Any]) -> list[str]:
    """A row's settings columns (everything but the trial's outcome), in table order."""
    return [k for k in row if k not in OUTCOME_NAMES]


def cell_summaries(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One summary per cell: its settings (every settings column of the table: the named axes,
    the controller, the config keys, the seed), docked/trials with a Wilson 95 % interval,
    aborts, clearance violations and the median terminal vertical error."""
    by_cell: dict[int, list[dict[str, Any]]] = defaultdict(list)
    for r in rows:
        by_cell[r["cell"]].append(r)
    out = []
    for idx in sorted(by_cell):
        rs = by_cell[idx]
        k, n = sum(r["docked"] for r in rs), len(rs)
        settings = {key: rs[0][key] for key in _settings_columns(rs[0]) if key != "cell"}
        out.append({"cell": idx, **settings, "trials": n, "docked": k, "success_rate": k / n,
                    "success_wilson95": list(wilson_interval(k, n)),
                    "aborts": sum(r["aborted"] for r in rs),
                    "missed": sum(r["missed"] for r in rs),
                    "clearance_violations": sum(r["clearance_violation"] for r in rs),
                    "terminal_err_down_median_m": float(np.median([r["err_down_m"] for r in rs]))})
    return out


def _hashable(value: Any) -> Any:
    """A column's value as a figure uses it: a list (a config key such as a weight vector)
    becomes its text, a category."""
    return str(value) if isinstance(value, list | tuple | dict) else value


def _varying(rows: list[dict[str, Any]]) -> list[tuple[str, str]]:
    """The x axes of the figures: the columns whose value differs between rows."""
    named = dict(_X_AXES)
    keys = [k for k in _settings_columns(rows[0]) if k in named or "." in k]
    return [(k, named.get(k, k)) for k in keys
            if k not in _NOT_X and len({_hashable(r[k]) for r in rows}) > 1]


def plot_sweep(rows: list[dict[str, Any]], fig_dir: Path, title: str = "sweep") -> list[Path]:
    """``sweep_success.png`` (success rate, Wilson 95 %) and ``sweep_error.png`` (median terminal
    vertical error) against every axis that varies, one line per compensation mode, pooled over
    the other axes and the seeds."""
    plt = _plt()
    axes = _varying(rows) or [("compensation", "compensation")]
    comps = sorted({r["compensation"] for r in rows})
    paths = []
    for name, ylabel in (("success", "docked [fraction, Wilson 95 %]"),
                         ("error", "terminal vertical error, median [m]")):
        fig, axs = plt.subplots(1, len(axes), figsize=(4.2 * len(axes), 3.6), squeeze=False)
        for ax, (key, xlabel) in zip(axs[0], axes, strict=True):
            values = sorted({_hashable(r[key]) for r in rows},
                            key=lambda v: (isinstance(v, str), v))
            categorical = any(isinstance(v, str | bool) for v in values)
            xs = np.arange(len(values)) if categorical else np.asarray(values, dtype=float)
            for j, comp in enumerate(comps):
                ys, lo, hi = [], [], []
                for v in values:
                    sel = [r for r in rows
                           if _hashable(r[key]) == v and r["compensation"] == comp]
                    if not sel:
                        ys.append(np.nan)
                        lo.append(0.0)
                        hi.append(0.0)
                        continue
                    if name == "success":
                        k = sum(r["docked"] for r in sel)
                        rate = k / len(sel)
                        a, b = wilson_interval(k, len(sel))
                        ys.append(rate)
                        lo.append(max(0.0, rate - a))  # >= 0 by construction
                        hi.append(max(0.0, b - rate))
                    else:
                        ys.append(float(np.median([r["err_down_m"] for r in sel])))
                        lo.append(0.0)
                        hi.append(0.0)
                shift = (j - (len(comps) - 1) / 2) * (0.08 if categorical else 0.0)
                ax.errorbar(xs + shift, ys, yerr=[lo, hi] if name == "success" else None,
                            marker="o", capsize=3, label=comp)
            if categorical:
                ax.set_xticks(xs)
                ax.set_xticklabels([str(v) for v in values])
            ax.set_xlabel(xlabel)
            ax.set_ylabel(ylabel)
            if name == "success":
                ax.set_ylim(-0.05, 1.05)
            ax.grid(alpha=0.3)
        axs[0][0].legend(title="compensation", fontsize=8)
        n_trials = len(rows)
        fig.suptitle(f"{title}: {n_trials} trials in {len({r['cell'] for r in rows})} campaigns",
                     fontsize=10)
        fig.tight_layout()
        paths.append(_save(fig, Path(fig_dir) / f"sweep_{name}.png"))
    return paths
