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


def plot_torque_profile(asked: dict[str, list], sent: dict[str, list], path: Path,
                        max_offset_m: float = 0.16) -> Path:
    """The wake's inward torque on the follower by its offset from the leader's axis, one column
    per pairing (:func:`aerodock.identify.wake_torque.torque_profile`'s bins, with its hub
    moments): the real flights' (as the firmware asked for, ± its standard error, and from the
    commands as sent), the jet's disk torque and the jet's with the moments about its hubs; below
    it, the real torque's lever against the farthest a loss of thrust on the disks can act."""
    plt = _plt()
    pairs = [pair for pair, bins in asked.items() if bins]
    fig, axes = plt.subplots(2, len(pairs), figsize=(5.2 * len(pairs), 6.4), squeeze=False,
                             sharex=True)
    for j, pair in enumerate(pairs):
        bins = [b for b in asked[pair] if b.offset_hi_m <= max_offset_m + 1e-9]
        sent_bins = {b.offset_lo_m: b for b in sent.get(pair, [])}
        x = np.array([100.0 * (b.offset_lo_m + b.offset_hi_m) / 2 for b in bins])
        top, bottom = axes[0, j], axes[1, j]
        top.errorbar(x, [1e3 * b.real_nm for b in bins],
                     yerr=[2e3 * b.real_se_nm for b in bins], fmt="o-", color="black",
                     capsize=3, label="real, as asked for (± 2 se)")
        both = [(xi, sent_bins[b.offset_lo_m].real_nm) for xi, b in zip(x, bins, strict=True)
                if b.offset_lo_m in sent_bins]
        if both:
            top.plot([p[0] for p in both], [1e3 * p[1] for p in both], "s--", color="grey",
                     label="real, from the commands as sent")
        top.plot(x, [1e3 * b.jet_nm for b in bins], "^-", color="tab:blue",
                 label="the world's jet (force at the hubs)")
        if all(np.isfinite(b.hub_nm) for b in bins):
            top.plot(x, [1e3 * (b.jet_nm + b.hub_nm) for b in bins], "v:", color="tab:cyan",
                     label="the jet with its hub moments")
        top.axhline(0.0, color="k", lw=0.5)
        top.set_ylabel("inward torque [mN m]")
        top.set_title(f"{pair} (follower under leader)")
        top.legend(fontsize=7, loc="upper right")
        force = np.array([b.real_down_force_n for b in bins])
        ok = force > 0.1 * force.max()  # where the force is too small the lever means nothing
        bottom.plot(x[ok], [100.0 * b.lever_m for b, k in zip(bins, ok, strict=True) if k],
                    "o-", color="black", label="real lever (torque / downward force)")
        bottom.axhline(100.0 * bins[0].half_diagonal_m, color="tab:red", ls="--",
                       label="half diagonal (disk forces at the hubs)")
        if np.isfinite(bins[0].rotor_radius_m):
            bottom.axhline(100.0 * bins[0].lever_bound_m, color="tab:red", ls=":",
                           label="half diagonal + rotor radius (any spread on the disks)")
        bottom.set_xlabel("offset from the leader's axis [cm]")
        bottom.set_ylabel("lever [cm]")
        bottom.legend(fontsize=7)
        for ax in (top, bottom):
            ax.grid(alpha=0.3)
    fig.suptitle("The wake's torque on the follower, 0.15-0.45 m below: real flights and the "
                 "world's jet", fontsize=10)
    fig.tight_layout()
    return _save(fig, path)
