"""Figures drawn from recorded runs (matplotlib, Agg backend, PNG). Dynamics never import this."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path: Path) -> Path:
    """Write ``fig`` as a PNG at ``path`` and close it. The saved frame takes in every label,
    title and legend (``bbox_inches="tight"``): a label longer than the layout left room for
    is never cut."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110, bbox_inches="tight", pad_inches=0.08)
    _plt().close(fig)
    return path


def plot_altitudes(tr: dict[str, np.ndarray], trials: dict[str, int], path: Path,
                   title: str) -> Path:
    """Altitude (up positive) of leader and follower for selected trials (e.g. docked / missed)."""
    plt = _plt()
    fig, axes = plt.subplots(1, len(trials), figsize=(5.5 * len(trials), 4), squeeze=False)
    for ax, (label, i) in zip(axes[0], trials.items(), strict=True):
        t = tr["t_s"]
        ax.plot(t, -tr["leader_p"][:, i, 2], label="leader (Alpha)")
        ax.plot(t, -tr["follower_p"][:, i, 2], label="follower (Bravo)")
        ax.plot(t, -tr["ref_p"][:, i, 2], "--", lw=1, label="follower reference")
        ax.set_title(f"{label} (trial {i})")
        ax.set_xlabel("time [s]")
        ax.set_ylabel("altitude [m]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    return _save(fig, path)


def plot_trajectories(tr: dict[str, np.ndarray], path: Path, title: str,
                      success: np.ndarray | None = None) -> Path:
    """Side (north-altitude) and top views of the follower's paths with the leader's spread."""
    plt = _plt()
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.8))
    n = tr["follower_p"].shape[1]
    for i in range(n):
        p = tr["follower_p"][:, i]
        colour = None if success is None else ("tab:green" if success[i] else "tab:red")
        ax1.plot(p[:, 0], -p[:, 2], lw=0.8, color=colour, alpha=0.7)
        ax2.plot(p[:, 1], p[:, 0], lw=0.8, color=colour, alpha=0.7)
    lp = tr["leader_p"].reshape(-1, 3)
    mean, sd = lp.mean(0), lp.std(0)
    ax1.errorbar(mean[0], -mean[2], xerr=sd[0], yerr=sd[2], fmt="k^", ms=9, capsize=4,
                 label="leader mean ± sd")
    ax2.add_patch(plt.Circle((mean[1], mean[0]), max(sd[0], sd[1], 0.005), color="k",
                             alpha=0.3))
    ax2.plot(mean[1], mean[0], "k^", ms=9)
    ax1.set_xlabel("north [m]")
    ax1.set_ylabel("altitude [m]")
    ax1.set_title("side view (green: docked, red: not)" if success is not None else "side view")
    ax1.legend(fontsize=8)
    ax2.set_xlabel("east [m]")
    ax2.set_ylabel("north [m]")
    ax2.set_aspect("equal")
    ax2.set_title("top view")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    return _save(fig, path)
