"""``report.md`` and ``figures/`` from a reproduce run: every number comes from ``results``."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np

from aerodock.config import Config
from aerodock.experiments.records import ReproduceResults
from aerodock.experiments.report_controllers import controllers_markdown, targets_markdown
from aerodock.plots import _plt, _save, plot_altitudes, plot_trajectories

# The paper's own numbers (Table "Statistics integrated over the final 0.5 s", Sec. Results).
PAPER_CABLE = {  # offset: (without: err down, err 3D, result), (with: down, 3D, force, result)
    0.36: ((2.28, 2.38, "Miss"), (1.06, 1.21, 6.13, "Dock")),
    0.47: ((1.72, 1.82, "Miss"), (1.02, 1.59, 2.84, "Dock")),
    0.64: ((2.08, 2.10, "Miss"), (1.09, 1.70, 2.21, "Dock")),
    0.87: ((1.85, 1.89, "Miss"), (0.70, 1.11, 4.72, "Dock")),
    1.11: ((1.67, 1.86, "Miss"), (0.77, 1.73, 2.49, "Dock")),
    1.35: ((1.90, 1.93, "Miss"), (0.85, 1.19, 2.24, "Dock")),
}
PAPER_HOVER = {"docked": 8, "trials": 10, "terminal_error_m": 0.06, "reduction_x": "3-4"}
PAPER_MOVING = {"success": "very limited", "err_without_m": 0.2, "err_with_m": 0.05}


def _fmt(x: Any, nd: int = 3) -> str:
    if x is None or (isinstance(x, float) and not np.isfinite(x)):
        return "n/a"
    if isinstance(x, float):
        return f"{x:.{nd}f}"
    return str(x)


def _pct(rate: float, lo_hi: list[float]) -> str:
    return f"{rate:.0%} (95 % CI {lo_hi[0]:.0%}-{lo_hi[1]:.0%})"


# -- figures ---------------------------------------------------------------------------------
def fig_observer_bandwidth(costs: dict[str, Any], fig_dir: Path) -> Path | None:
    """Hover docking of the paper's controller against its observer's rise time, with and
    without the model, the paper's counts marked; ``None`` without the sweep."""
    points = (costs or {}).get("observer_bandwidth") or []
    if not points:
        return None
    plt = _plt()
    # constrained layout: the long axis label stays inside the frame
    fig, ax = plt.subplots(figsize=(6.4, 4.0), layout="constrained")
    for key, label, colour in (("hover_with_model", "with model", "tab:green"),
                               ("hover_without_model", "without model", "tab:red")):
        pts = [p for p in points if key in p]
        if not pts:
            continue
        x = np.array([p["rise_63_s"] for p in pts])
        y = np.array([p[key]["success_rate"] for p in pts])
        lo = np.array([p[key]["success_wilson95"][0] for p in pts])
        hi = np.array([p[key]["success_wilson95"][1] for p in pts])
        order = np.argsort(x)
        ax.errorbar(x[order], y[order], yerr=[y[order] - lo[order], hi[order] - y[order]],
                    marker="o", color=colour, capsize=3, label=f"{label} (Wilson 95 %)")
        freyja = [i for i, p in enumerate(pts) if p["observer"] == "freyja"]
        if freyja:
            ax.plot(x[freyja], y[freyja], marker="*", markersize=16, color=colour,
                    linestyle="none")
    for rate, label, colour in ((0.8, "paper: 8/10 with model", "tab:green"),
                                (0.0, "paper: 0/10 without", "tab:red")):
        ax.axhline(rate, color=colour, linestyle=":", linewidth=1.2)
        ax.text(min(p["rise_63_s"] for p in points), rate + 0.02,
                label, color=colour, fontsize=8)
    ax.set_xscale("log")
    ax.set_xlabel("observer's rise time to 63 % of a step [s] (star: Freyja's, as published)")
    ax.set_ylabel("hover docking, d_p 0.36 m")
    ax.set_ylim(-0.05, 1.05)
    ax.set_title("The paper's controller across its observer's bandwidth")
    ax.legend(fontsize=8, loc="center right")
    return _save(fig, fig_dir / "observer_bandwidth.png")


def fig_cable(traces: dict[str, dict[float, dict]], fig_dir: Path) -> list[Path]:
    """Cable study: follower altitude per offset, and vertical error mean ± sd."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 5))
    colours = plt.cm.viridis(np.linspace(0, 0.9, len(traces["with"])))
    for colour, (offset, tr) in zip(colours, traces["with"].items(), strict=True):
        t = tr["t_s"]
        ax.plot(t, -tr["follower_p"][:, :, 2].mean(1), color=colour, label=f"{offset} m, model")
        tw = traces["without"][offset]
        ax.plot(tw["t_s"], -tw["follower_p"][:, :, 2].mean(1), "--", color=colour)
        ax.plot(t, -tr["ref_p"][:, 0, 2], ":", color=colour, lw=0.8)
    ax.axhline(-traces["with"][next(iter(traces["with"]))]["leader_p"][0, 0, 2], color="k",
               lw=2, label="leader (rigid stand)")
    ax.set_xlim(0, 5)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("follower altitude [m]")
    ax.set_title("Cable-length study: with model (solid), without (dashed), reference (dotted)")
    ax.legend(fontsize=7, ncol=2)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    p1 = _save(fig, fig_dir / "cable_trajectories.png")

    fig, ax = plt.subplots(figsize=(8, 4.5))
    for key, colour in (("without", "tab:red"), ("with", "tab:blue")):
        errs = []
        for tr in traces[key].values():
            n = min(len(tr["t_s"]), 500)
            e = tr["follower_p"][:n, :, 2] - tr["ref_p"][:n, :, 2]
            e = np.where(tr["phase"][:n] <= 1, e, np.nan)
            errs.append(e)
        n = min(e.shape[0] for e in errs)
        allerr = np.concatenate([e[:n] for e in errs], axis=1)
        t = next(iter(traces[key].values()))["t_s"][:n]
        with warnings.catch_warnings():  # a time with no trial approaching: a gap, not a warning
            warnings.simplefilter("ignore", RuntimeWarning)
            mean, sd = np.nanmean(allerr, 1), np.nanstd(allerr, 1)
        label = "with model" if key == "with" else "without model (LQG)"
        ax.plot(t, mean, color=colour, label=label)
        ax.fill_between(t, mean - sd, mean + sd, color=colour, alpha=0.25)
    ax.axvline(4.0, color="k", ls=":", lw=1)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("vertical error, down positive [m]")
    ax.set_title("Cable-length study: vertical error, all offsets (mean ± sd)")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return [p1, _save(fig, fig_dir / "cable_vertical_error.png")]


def fig_planar_forces(tr: dict[str, Any], fig_dir: Path) -> Path:
    """A successful hover dock seen from above and from the side, predicted forces overlaid."""
    plt = _plt()
    i = int(np.argmax(tr["success"]))
    p, ff = tr["follower_p"][:, i], tr["ff"][:, i]
    live = tr["phase"][:, i] <= 1
    p, ff = p[live], ff[live]
    step = slice(None, None, 8)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.8))
    ax1.plot(p[:, 1], p[:, 0], color="tab:blue", label="follower path")
    ax1.quiver(p[step, 1], p[step, 0], ff[step, 1], ff[step, 0], color="tab:red", angles="xy",
               scale_units="xy", scale=4, width=0.004,
               label="predicted planar force (1 m ≙ 4 m/s²)")
    ax1.plot(tr["leader_p"][0, i, 1], tr["leader_p"][0, i, 0], "k^", ms=10, label="leader")
    ax1.set_xlabel("east [m]")
    ax1.set_ylabel("north [m]")
    ax1.set_aspect("equal", adjustable="datalim")
    ax1.set_title("planar view")
    ax1.legend(fontsize=8)
    t = tr["t_s"][live]
    ax2.plot(t, ff[:, 2], color="tab:red", label="predicted down force")
    ax2.plot(t, np.linalg.norm(ff[:, :2], axis=1), color="tab:orange", label="planar magnitude")
    ax2.set_xlabel("time [s]")
    ax2.set_ylabel("compensation [m/s²]")
    ax2.set_title("model compensation along the approach")
    ax2.legend()
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    fig.suptitle(f"Hover docking, trial {i} (docked): the learnt model's compensation")
    fig.tight_layout()
    return _save(fig, fig_dir / "hover_planar_forces.png")


def fig_moving(traces: dict[str, dict], fig_dir: Path, meet_s: float, hold_s: float) -> Path:
    """Moving leader: altitude error (follower vs target on the leader's path), mean ± sd."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for key, colour in (("without_model", "tab:red"), ("with_model", "tab:blue")):
        tr = traces[key]
        e = tr["follower_p"][:, :, 2] - tr["ref_p"][:, :, 2]
        e = np.where(tr["phase"] <= 1, e, np.nan)
        with warnings.catch_warnings():  # no trial approaching at late times: a gap, not news
            warnings.simplefilter("ignore", RuntimeWarning)
            mean, sd = np.nanmean(e, 1), np.nanstd(e, 1)
        ax.plot(tr["t_s"], mean, color=colour, label=key.replace("_", " "))
        ax.fill_between(tr["t_s"], mean - sd, mean + sd, color=colour, alpha=0.25)
    ax.axvspan(meet_s - 2, meet_s, color="grey", alpha=0.15, label="entering the wake")
    ax.axvline(meet_s + hold_s, color="k", ls=":", lw=1)
    ax.set_xlim(0, meet_s + hold_s + 0.5)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("altitude error, down positive [m]")
    ax.set_title("Leader in motion at 0.25 m/s: meet at 6 s, hold formation 5 s")
    ax.legend()
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return _save(fig, fig_dir / "moving_altitude_error.png")


def fig_docking_animation(tr: dict[str, Any], fig_dir: Path, cfg: Config) -> Path:
    """An animated GIF of the first docked trial of a traced campaign (aerodock.view)."""
    from aerodock.view.render import render_animation, track_from_trace

    i = int(np.argmax(tr["success"]))
    end = np.searchsorted(tr["t_s"], float(tr["arrival_s"]) + 1.5)
    track = track_from_trace({k: tr[k][:end] for k in ("t_s", "leader_p", "follower_p",
                                                       "bar_p", "gate", "ff")}, i, cfg,
                             f"hover docking with the model, trial {i} (docked)")
    return render_animation(track, fig_dir / "hover_docking.gif", fps=10, max_frames=60, dpi=90)


# -- report ----------------------------------------------------------------------------------
def write_report(results: ReproduceResults, traces: dict[str, Any], out_dir: Path,
                 cfg: Config) -> list[str]:
    """Write the figures and ``report.md``; returns the figure paths (relative to out_dir)."""
    fig_dir = out_dir / "figures"
    figs: list[Path] = []
    figs += fig_cable(traces["cable"], fig_dir)
    hover = traces["hover"]
    figs.append(plot_trajectories(hover["with_model"], fig_dir / "hover_trajectories.png",
                                  "Hover docking with the model (green: docked, red: not)",
                                  hover["with_model"]["success"]))
    if np.any(hover["with_model"]["success"]):
        figs.append(fig_planar_forces(hover["with_model"], fig_dir))
        figs.append(fig_docking_animation(hover["with_model"], fig_dir, cfg))
        both = {}
        tw, tm = hover["with_model"], hover["without_model"]
        n = min(len(tw["t_s"]), len(tm["t_s"]))
        for key in ("leader_p", "follower_p", "ref_p"):
            both[key] = np.concatenate([tm[key][:n, :1], tw[key][:n, :1]], axis=1)
        both["t_s"] = tw["t_s"][:n]
        i = int(np.argmax(tw["success"]))
        j = int(np.argmax(~tm["success"])) if (~tm["success"]).any() else 0
        for key in ("leader_p", "follower_p", "ref_p"):
            both[key] = np.concatenate([tw[key][:n, i:i + 1], tm[key][:n, j:j + 1]], axis=1)
        figs.append(plot_altitudes(both, {"docked, with model": 0,
                                          "not docked, without model": 1},
                                   fig_dir / "hover_altitudes.png",
                                   "Altitude of both vehicles: a successful and a missed attempt"))
    figs.append(fig_moving(traces["moving"], fig_dir, cfg.planner.horizon_moving_s,
                           cfg.planner.hold_s))
    bandwidth = fig_observer_bandwidth(results.controller_costs, fig_dir)
    if bandwidth is not None:
        figs.append(bandwidth)
    for extra in ("sample_efficiency.png", "real_sample_efficiency.png",
                  "real_heldout_vertical.png", "compensation_replay.png"):
        if (fig_dir / extra).exists():
            figs.append(fig_dir / extra)
    rel = [str(p.relative_to(out_dir)) for p in figs]
    (out_dir / "report.md").write_text(_markdown(results, rel))
    return rel


def _transfer_table(tr: dict[str, Any]) -> list[str]:
    """The small pair's models on the small-large day, each follower apart (markdown)."""
    pairings = list(tr["pairings"])
    kinds = [k for k in next(iter(tr["pairings"].values()))["models"] if k != "zero"]
    lines = ["### Transfer to a pair of other sizes", "",
             f"The models above, trained on the small pair only, judged on all {tr['flights']} "
             "flight logs of the small-large day: interaction region, vertical RMSE in m/s² "
             "and its reduction against the zero model.", "",
             "| model | " + " | ".join(pairings) + " |", "|---" * (len(pairings) + 1) + "|"]
    for kind in ["zero", *kinds]:
        cells = []
        for p in pairings:
            m = tr["pairings"][p]["models"][kind]
            cells.append(f"{m['vertical_mps2']:.3f}" if kind == "zero"
                         else f"{m['vertical_mps2']:.3f} ({100 * m['vertical_reduction']:.1f} %)")
        lines.append(f"| {kind} | " + " | ".join(cells) + " |")
    return lines + [""]


def _se_table(se: dict[str, Any], title: str) -> list[str]:
    """The sample-efficiency table: held-out RMSE, mean ± sd over the seeds, or the one seed's
    figure when one seed ran (an sd over one seed is no spread)."""
    kinds = list(se["models"])
    one_seed = len(se.get("seeds", ())) == 1
    spread = "one seed" if one_seed else "mean ± sd over seeds"
    lines = [f"### {title} (held-out RMSE, m/s², {spread})", "",
             "| minutes | region | " + " | ".join(kinds) + " | zero |",
             "|---|---|" + "---|" * (len(kinds) + 1)]
    for region in ("all", "interaction"):
        for k, mins in enumerate(se["minutes"]):
            row = [f"{mins:g}", region]
            for kind in kinds:
                m = se["models"][kind]
                mean = _fmt(m[f"rmse_{region}_mean"][k])
                row.append(mean if one_seed else f"{mean} ± {_fmt(m[f'rmse_{region}_sd'][k])}")
            row.append(_fmt(se["zero"][region]))
            lines.append("| " + " | ".join(row) + " |")
    if se.get("skipped_minutes"):
        lines.append(f"\nSkipped: {se['skipped_minutes']} min ({se['skip_reason']}).")
    return lines + [""]


def _paper_counts_markdown(pc: dict[str, Any] | None) -> list[str]:
    """How likely each of the paper's counts is under the rates this run measured."""
    if not pc:
        return []
    names = {"hover_with_model": "hover docking with the model",
             "hover_without_model": "hover docking without the model",
             "cable_with_model": "cable study with the model (offsets docked)",
             "cable_without_model": "cable study without the model (offsets docked)"}
    lines = ["The paper's own counts under the rates measured here (hover: one-sided binomial "
             "tail; cable study: each offset at its measured rate, one attempt each as in the "
             "paper); below 0.05 the paper's count is inconsistent with this world:", "",
             "| outcome | paper | probability here |", "|---|---|---|"]
    for key, name in names.items():
        if key in pc:
            p = pc[key]["probability"]
            text = f"{p:.3f}" if p >= 0.001 else "< 0.001"
            note = f"; {pc[key]['note']}" if pc[key].get("note") else ""
            lines.append(f"| {name} | {pc[key]['paper']} | {text}"
                         f"{'' if pc[key]['consistent'] else ' (inconsistent)'}{note} |")
    return lines + [""]


def _markdown(r: ReproduceResults, figs: list[str]) -> str:
    """``report.md``: every section, from the results, then the figures."""
    lines: list[str] = []
    for section in (_header_markdown, _learning_markdown, _cable_markdown, _hover_markdown,
                    _moving_markdown, controllers_markdown,
                    lambda r: targets_markdown(r.targets), _real_data_markdown,
                    _compensation_section_markdown):
        lines += section(r)
    lines += figures_markdown(figs)
    return "\n".join(lines)


def _header_markdown(r: ReproduceResults) -> list[str]:
    """The report's title and how the run was made."""
    meta = r.aerodock_reproduce
    lines: list[str] = ["# aerodock reproduce: report", "",
             f"Run: {'smoke' if meta.smoke else 'quick' if meta.quick else 'full'}, "
             f"seed {meta.seed}, "
             f"config `{meta.config_source}`, {meta.machine}; "
             f"total {r.total_s:.0f} s. Every number below is computed by "
             "`aerodock reproduce` and stored in `results.json`; the paper's numbers are quoted "
             "beside ours. The reproduction flies the paper's controller as its flight stack "
             "publishes it (Freyja's weights, bias estimator and state filter, 50 Hz, no "
             "reference feed-forward); our tuned controller is a separate section. \"Without "
             "model\" is the LQG baseline (bias observer); \"with model\" "
             "adds the learnt SO(2)-equivariant model's feed-forward.", ""]
    return lines


def _learning_markdown(r: ReproduceResults) -> list[str]:
    """The curriculum's model on held-out flights, and the sample efficiency."""
    lines: list[str] = []
    lrn = r.learning
    ho = lrn.heldout
    lines += ["## Learning (curriculum, held-out simulated flights)", "",
              f"Curriculum: {lrn.curriculum['flights']} flights, "
              f"{lrn.curriculum['minutes']:.1f} min of flight in "
              f"{len(lrn.curriculum['stages'])} stages "
              f"({lrn.curriculum['stages'][0]['depth_band_m'][1]:.1f} m down to "
              f"{lrn.curriculum['stages'][-1]['depth_band_m'][0]:.1f} m below the leader).", "",
              "| region | model RMSE [m/s²] | zero model | error floor (true mean field) | "
              "ratio to floor |", "|---|---|---|---|---|"]
    for region in ("all", "interaction"):
        d = ho[region]
        floor = d.get("error_floor")
        ratio = lrn.rmse_ratio_to_floor[region]
        lines.append(f"| {region} | {_fmt(d['model']['rmse_mps2']['overall'])} | "
                     f"{_fmt(d['zero']['rmse_mps2']['overall'])} | "
                     f"{_fmt(floor['rmse_mps2']['overall']) if floor else 'unavailable'} | "
                     f"{_fmt(ratio, 2) if ratio is not None else 'unavailable'} |")
    lines += ["", "The error floor is the RMSE of the simulator's own mean field against the same "
              "labels (turbulence and sensor noise no model can predict).",
              f"Mean field used for the floor: {lrn.error_floor_source}.", ""]
    se = r.sample_efficiency
    if se:
        lines += _se_table(se, "Sample efficiency, simulated")
    return lines


def _cable_markdown(r: ReproduceResults) -> list[str]:
    """The cable-length study beside the paper's table."""
    lines: list[str] = []
    cs = r.docking.cable_study
    lines += ["## Cable-length study (leader on a rigid stand)", "",
              f"{cs['repetitions']} repetitions per offset and mode, same start location. "
              "Integrals over the final 0.5 s of the approach (m·s for errors, m/s for the "
              "predicted force), as in the paper's table; the paper's values are in brackets "
              "(its units are printed as m and m/s², so compare trends, not magnitudes). "
              "Result: docked repetitions.", "",
              "| offset [m] | without: err down | err 3D | docked | with: err down | err 3D | "
              "pred. force | docked |", "|---|---|---|---|---|---|---|---|"]
    for w, m in zip(cs["without_model"], cs["with_model"], strict=True):
        pw, pm = PAPER_CABLE[m["offset_m"]]
        lines.append(
            f"| {m['offset_m']} | {w['err_down_int_0p5s_m_s']:.3f} [{pw[0]}] | "
            f"{w['err_3d_int_0p5s_m_s']:.3f} [{pw[1]}] | {w['docked']}/{w['trials']} [{pw[2]}] | "
            f"{m['err_down_int_0p5s_m_s']:.3f} [{pm[0]}] | {m['err_3d_int_0p5s_m_s']:.3f} "
            f"[{pm[1]}] | {m['ff_down_int_0p5s_mps']:.2f} [{pm[2]}] | "
            f"{m['docked']}/{m['trials']} [{pm[3]}] |")
    docks_with = sum(m["result"] == "dock" for m in cs["with_model"])
    docks_without = sum(w["result"] == "dock" for w in cs["without_model"])
    n_off = len(cs["with_model"])
    lines += ["", "Offsets docked (more than half of the repetitions docked; a tie is a miss): "
              f"with model {docks_with}/{n_off} "
              f"(paper 6/6), without {docks_without}/{n_off} (paper 0/6)."]
    if docks_without > 0:
        lines.append(f"Unlike the paper, the baseline docks at {docks_without} offset(s) here: in "
                     "our wake the force decays with depth, so at long cables the slow observer "
                     "copes; the table reports it as measured.")
    lines.append("")
    return lines


def _hover_markdown(r: ReproduceResults) -> list[str]:
    """Hover docking beside the paper's figures, and the paper's counts."""
    lines: list[str] = []
    h = r.docking.hover_docking
    lines += ["## Docking with the leader hovering (d_p = 0.36 m, eps_g = 0.1 m)", "",
              "| | docked | terminal err down (median) | terminal err 3D (median) | slips | "
              "aborts |", "|---|---|---|---|---|---|"]
    for key in ("without_model", "with_model", "oracle"):
        d = h.mode(key)
        lines.append(f"| {key.replace('_', ' ')} | {d['docked']}/{d['trials']} = "
                     f"{_pct(d['success_rate'], d['success_wilson95'])} | "
                     f"{_fmt(d['terminal_err_down_median_m'])} m | "
                     f"{_fmt(d['terminal_err_3d_median_m'])} m | {d['slip_throughs']} | "
                     f"{d['aborts']} |")
    lines += ["", f"Paper: {PAPER_HOVER['docked']}/{PAPER_HOVER['trials']} docks with the model, "
              f"terminal tracking error < {PAPER_HOVER['terminal_error_m']} m, a "
              f"{PAPER_HOVER['reduction_x']}x reduction. Here: error reduction "
              f"{_fmt(h.terminal_error_reduction_x, 1)}x (median vertical error over the "
              "final 0.5 s of the approach). The oracle flies the simulator's mean field: "
              f"{h.oracle_mean_source}.", ""]
    lines += _paper_counts_markdown(r.paper_counts)
    return lines


def _moving_markdown(r: ReproduceResults) -> list[str]:
    """The leader in motion beside the paper's figures."""
    lines: list[str] = []
    mv = r.docking.moving_leader
    lines += ["## Leader in motion (0.25 m/s, meet at 6 s, hold 5 s)", "",
              "| | docked | mean altitude error 4-6 s | mean altitude error during hold |",
              "|---|---|---|---|"]
    for key in ("without_model", "with_model"):
        mode = mv.mode(key)
        d = mode.summary
        lines.append(f"| {key.replace('_', ' ')} | {d['docked']}/{d['trials']} = "
                     f"{_pct(d['success_rate'], d['success_wilson95'])} | "
                     f"{_fmt(mode.altitude_error_approach.mean_abs_err_down_m)} m | "
                     f"{_fmt(mode.altitude_error_hold.mean_abs_err_down_m)} m |")
    lines += ["", f"Paper: {PAPER_MOVING['success']} docking success; mean error over "
              f"{PAPER_MOVING['err_without_m']} m without the model, under "
              f"{PAPER_MOVING['err_with_m']} m with it. Altitude errors come from the same "
              "flights with the gripper disarmed, so that every trial holds formation for the "
              "full 5 s as in the paper's figure.", ""]
    return lines


def _real_data_markdown(r: ReproduceResults) -> list[str]:
    """The real-data study, or why it did not run."""
    lines: list[str] = []
    rd = r.real_data
    if rd:
        lines += ["## Real data (Neural-Swarm swap flights, leave flights out)", "",
                  f"Train on {', '.join(rd['train_flights'])}; evaluate on "
                  f"{', '.join(rd['test_flights'])}. RMSE in m/s².", "",
                  "| model | vertical, all | planar, all | vertical, interaction | "
                  "planar, interaction |", "|---|---|---|---|---|"]
        for kind, d in rd["models"].items():
            lines.append(f"| {kind} | {d['all']['vertical']:.3f} | {d['all']['planar']:.3f} | "
                         f"{d['interaction']['vertical']:.3f} | "
                         f"{d['interaction']['planar']:.3f} |")
        lines += ["", f"Interaction region: {rd['interaction_samples']} held-out samples (follower "
                  "below the other vehicle within 0.2 m laterally).", ""]
        if rd.get("transfer"):
            lines += _transfer_table(rd["transfer"])
        if rd.get("sample_efficiency"):
            lines += _se_table(rd["sample_efficiency"], "Sample efficiency, real data")
    else:
        lines += ["## Real data (Neural-Swarm swap flights)", "",
                  "Not run: no Neural-Swarm flights in the data location (`--no-real-data`, or "
                  "neither `--data-dir` nor `AERODOCK_DATA_DIR` names a folder holding "
                  "`neural-swarm/swap_ss`; docs/real-logs.md says where to get them).", ""]
    return lines


def _compensation_section_markdown(r: ReproduceResults) -> list[str]:
    """The compensations scored on real flights."""
    lines: list[str] = []
    from aerodock.experiments.compensation_study import compensation_markdown

    lines += ["## The compensations scored on real flights", "",
              "Each compensation replayed causally over held-out real swap flights at its "
              "own rate, one control period late: the disturbance it leaves (m/s²) and the "
              "share of the uncompensated RMS it removes.", ""]
    lines += compensation_markdown(r.compensation)
    return lines


FIGURE_CAPTIONS = {
    "cable_trajectories.png":
        "Cable-length study, leader on a rigid stand: the follower's mean altitude at each cable "
        "length with the model (solid) and without it (dashed), its reference dotted, the "
        "leader's altitude in black.",
    "cable_vertical_error.png":
        "Cable-length study: the follower's vertical tracking error pooled over every offset, "
        "mean ± sd over the trials, with the model and without it (LQG); dotted, the planned "
        "arrival.",
    "hover_trajectories.png":
        "Hover docking with the model at d_p 0.36 m: every trial's follower path from the side "
        "and from above (green: docked, red: not), the leader's mean position with its spread.",
    "hover_planar_forces.png":
        "One docked hover trial: the follower's path from above with the learnt model's "
        "predicted planar force as arrows, and the predicted vertical and planar compensation "
        "along the approach.",
    "hover_docking.gif":
        "The first docked hover trial with the model, animated (aerodock view): both vehicles, "
        "the bar on its cables, the gate and the predicted force.",
    "hover_altitudes.png":
        "Altitude of both vehicles in a docked attempt with the model and an attempt without "
        "it that did not dock: after a dock the leader dips as it carries the follower.",
    "moving_altitude_error.png":
        "Leader moving at 0.25 m/s: the follower's altitude error against its target on the "
        "leader's path, mean ± sd over the trials, with and without the model; shaded, the "
        "entry into the wake before the meeting; dotted, the end of the formation hold.",
    "observer_bandwidth.png":
        "The paper's controller in hover at d_p 0.36 m across its bias observer's rise time "
        "(log scale), with and without the model, Wilson 95 % intervals; a star marks Freyja's "
        "estimator as published, dotted lines the paper's 8/10 and 0/10.",
    "sample_efficiency.png":
        "Simulated flights: held-out RMSE against minutes of training data for each model kind "
        "(error bars: sd over the seeds, none with one seed), the zero model and the error "
        "floor as horizontal lines.",
    "real_sample_efficiency.png":
        "Real Neural-Swarm flights: held-out RMSE against minutes of training data for each "
        "model kind (error bars: sd over the seeds, none with one seed), the zero model as a "
        "horizontal line.",
    "real_heldout_vertical.png":
        "The held-out real flight with the most samples below the other vehicle: the measured "
        "vertical residual and the SO(2) model's and the MLP's predictions; shaded, below the "
        "other vehicle.",
    "compensation_replay.png":
        "A held-out real pass: the vertical residual with each compensation replayed causally "
        "against it (top) and what each leaves (bottom); shaded, below the other vehicle.",
}
"""A caption per figure ``write_report`` can list, by file name."""


def figure_caption(path: str | Path) -> str:
    """The caption of a report figure (:data:`FIGURE_CAPTIONS`); a figure without one is named
    by its file, so that a new figure never stops the report."""
    name = Path(path).name
    return FIGURE_CAPTIONS.get(name, name)


def figures_markdown(figs: list[str]) -> list[str]:
    """The report's figures section: each figure with its caption in italics below it."""
    lines = ["## Figures", ""]
    for k, f in enumerate(figs, 1):
        caption = figure_caption(f)
        lines += [f"![Figure {k}]({f})", "", f"*Figure {k}: {caption}*", ""]
    return lines
