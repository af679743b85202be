"""The report of ``aerodock field fit``: the fitted wake against the real flights, as markdown,
figures (matplotlib) and the TOML fragment a world loads (``--config``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from aerodock.identify.motor_commands import CEILING_PWM, MAP_FIT_PWM
from aerodock.identify.wake_fit import WakeFit
from aerodock.identify.wake_score import TARGETS

FIELD_PATH = "aerodock.downwash.jet:RoundJetField"
# DESIGN.md's hand table for the 0.7 kg vehicles (the previous default jet was calibrated to it).
HAND_TABLE = {0.36: {"mean_mps2": 4.5, "half_width_m": "0.09-0.15"},
              0.64: {"mean_mps2": 3.0, "half_width_m": "grows"},
              1.35: {"mean_mps2": 1.5, "half_width_m": "grows"}}
HAND_TURBULENCE = {"vertical": "20-25 % of the mean", "lateral": "5-10 % of the mean"}
PARAM_NOTES = {
    "width0_ratio": "half-velocity width at the rotor plane / the leader's R sqrt(n)",
    "spread_rate": "half-width growth per metre of depth",
    "ingest_coeff": "a disk's force c rho A v_hf^(2-p) |w|^p ...",
    "ingest_exponent": "... p (1: linear in the inflow, 2: the momentum flux)",
    "planar_ratio": "peak planar / centreline axial force (< 0: inwards)",
    "turb_vertical": "each disk's axial force sd / its local mean",
    "turb_lateral": "the follower's gusts across the axis: sd / each part's axial force",
    "turb_length_ratio": "integral length scale / half-width (the disks' shared turbulence)",
    "turb_time_ratio": "correlation time / (half-width / centreline speed)",
    "body_area_ratio": "the follower's body top area / its rotor disk area: its share of the "
                       "force, fitted with the logged torque",
}


def config_fragment(fit: WakeFit, held_out: list[str], command: str) -> str:
    """The TOML a world loads with ``--config``: the default jet with the fitted parameters."""
    lines = [
        "# The leader's wake identified from real flights by `aerodock field fit` (docs/world.md).",
        f"# Fitted on {len(fit.flights)} flights ({fit.samples} samples in the wake): "
        + ", ".join(fit.flights),
        "# Held out (scored, not fitted): " + (", ".join(held_out) if held_out else "none"),
        f"# Command: {command}",
        "# The parameters are dimensionless: any world's rotors and leader thrust set the scales.",
        "[downwash]",
        f'field = "{FIELD_PATH}"',
        "",
        "[downwash.params]",
    ]
    for key in fit.keys:
        value = fit.params[key]
        spread = fit.bootstrap.get(key)
        note = PARAM_NOTES[key]
        if spread:
            note += f"; bootstrap 95 %: {spread['p2_5']:.4g} to {spread['p97_5']:.4g}"
        lines.append(f"{key} = {value:.4g}  # {note}")
    return "\n".join(lines) + "\n"


def write_figures(fit: WakeFit, scores: dict[str, Any], fit_scores: dict[str, Any],
                  folder: Path) -> list[Path]:
    """The report's figures: real vs fitted mean against separation and lateral offset (with the
    real spread), autocorrelation, turbulence sd; held-out flights filled, fitted ones hollow."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    pairs = sorted(set(scores["pairs"]) | set(fit_scores["pairs"]))
    sets = (("held out", scores, "o", "C3"), ("fitted on", fit_scores, "s", "C0"))

    def separation_curve(entry: dict[str, Any]) -> tuple | None:
        bins = entry["separation_bins"]
        if not bins:
            return None
        return ([np.mean(b["separation_m"]) for b in bins], [b["real_mps2"] for b in bins],
                [b["real_sd_mps2"] for b in bins], [b["fitted_mps2"] for b in bins])

    def offset_curve(entry: dict[str, Any]) -> tuple:
        prof = entry["lateral_profile"]
        return prof["offset_m"], prof["real_mps2"], prof["real_sd_mps2"], prof["fitted_mps2"]

    def autocorrelation_curve(entry: dict[str, Any]) -> tuple | None:
        curve = entry.get("autocorrelation_curve")
        if not curve:
            return None
        return 1000 * np.asarray(curve["lag_s"]), curve["real"], None, curve["model"]

    panels = (
        (separation_curve, "{pair}: directly below", "separation below the leader [m]",
         "downward acceleration [m/s²]", "mean_vs_separation.png"),
        (offset_curve, "{pair}: all separations", "lateral offset from the leader's axis [m]",
         "downward acceleration [m/s²]", "mean_vs_offset.png"),
        (autocorrelation_curve, "{pair}: vertical, near the axis", "lag [ms]", "autocorrelation",
         "autocorrelation.png"),
    )
    for curve_of, title, xlabel, ylabel, name in panels:
        fig, axes = plt.subplots(1, len(pairs), figsize=(4.6 * len(pairs), 3.8), squeeze=False)
        for ax, pair in zip(axes[0], pairs, strict=True):
            for label, sc, marker, colour in sets:
                entry = sc["pairs"].get(pair)
                curve = curve_of(entry) if entry else None
                if curve is None:
                    continue
                x, real, real_sd, fitted = curve
                fill = "none" if label == "fitted on" else colour
                if real_sd is None:
                    ax.plot(x, real, marker, color=colour, mfc=fill, label=f"real, {label}")
                else:
                    ax.errorbar(x, real, real_sd, fmt=marker, color=colour, mfc=fill, capsize=3,
                                label=f"real, {label} (mean ± sd)")
                ax.plot(x, fitted, "-", color=colour, label=f"fitted jet, {label}")
            if name == "autocorrelation.png":
                ax.axhline(0.0, color="k", lw=0.5)
            ax.set_title(title.format(pair=pair))
            ax.set_xlabel(xlabel)
            ax.set_ylabel(ylabel)
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7)
        fig.tight_layout()
        paths.append(_save(fig, folder / name))

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8))
    for ax, key, title in ((axes[0], "vertical_sd", "vertical"),
                           (axes[1], "lateral_sd", "lateral (per axis)")):
        x = np.arange(len(pairs))
        for k, (label, sc, _, colour) in enumerate(sets):
            real = [sc["pairs"].get(p, {}).get(key, {}).get("real_mps2", np.nan) for p in pairs]
            fitted = [sc["pairs"].get(p, {}).get(key, {}).get("fitted_mps2", np.nan)
                      for p in pairs]
            ax.bar(x + 0.2 * (2 * k - 1) - 0.1, real, 0.2, color=colour, alpha=0.5,
                   label=f"real, {label}")
            ax.bar(x + 0.2 * (2 * k - 1) + 0.1, fitted, 0.2, color=colour,
                   label=f"fitted jet, {label}")
        ax.set_xticks(x, pairs, fontsize=8)
        ax.set_ylabel("turbulence sd near the axis [m/s²]")
        ax.set_title(f"{title} turbulence (free-air noise removed)")
        ax.grid(alpha=0.3, axis="y")
        ax.legend(fontsize=7)
    fig.tight_layout()
    paths.append(_save(fig, folder / "turbulence.png"))
    return paths


def _save(fig: Any, path: Path) -> Path:
    import matplotlib.pyplot as plt

    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _pct(x: float) -> str:
    return "n/a" if x is None or not np.isfinite(x) else f"{100 * x:+.1f} %"


def _num(x: float, digits: int = 3) -> str:
    return "n/a" if x is None or not np.isfinite(x) else f"{x:.{digits}g}"


def report_markdown(fit: WakeFit, scores: dict[str, Any], fit_scores: dict[str, Any],
                    paper: dict[str, Any], command: str, figures: list[str],
                    checks: dict[str, Any] | None = None) -> str:
    """The report: parameters with their bootstrap spread, held-out scores against the targets,
    the same on the fitted flights, the checks beside the fit (``checks``: the turbulence above
    the labels' noise at the follower's speed, the wake's torque), and the wake it gives the
    configured world's vehicles."""
    lines = ["# The wake identified from real flights", "",
             f"`{command}`", "",
             f"Fitted on {len(fit.flights)} flights ({fit.samples} samples in the wake; "
             f"vertical residual RMS {fit.mean_rms_mps2:.3f} m/s²); "
             f"bootstrap over flights: {fit.bootstrap_runs} refits.", "",
             (f"The motors' logged torque of {len(fit.torque_flights)} of them (those with "
              f"free air for the trim: {', '.join(fit.torque_flights)}) is fitted beside the "
              f"force, with the body's share of it; the torque residual's RMS "
              f"{fit.torque_rms_mps2:.3f} m/s² (a torque over the follower's mass and half "
              f"diagonal)." if fit.torque_flights else
              "The force alone is fitted (no log with the motors' torque, or `--no-torque`)."),
             "",
             "## Parameters", "",
             "| parameter | fitted | bootstrap sd | 95 % interval | meaning |",
             "| --- | --- | --- | --- | --- |"]
    rows = [(k, fit.params[k], PARAM_NOTES[k]) for k in fit.keys]
    rows += [(f"rotor_radius_m[{k}]", v, "rotor radius the logs do not state, estimated")
             for k, v in fit.rotor_radii_m.items()]
    for key, value, note in rows:
        b = fit.bootstrap.get(key, {})
        lines.append(f"| `{key}` | {value:.4g} | {_num(b.get('sd', np.nan))} | "
                     f"{_num(b.get('p2_5', np.nan))} to {_num(b.get('p97_5', np.nan))} | "
                     f"{note} |")
    for title, sc in (("Held-out flights (not fitted)", scores),
                      ("The fitted flights", fit_scores)):
        lines += ["", f"## {title}", ""]
        if not sc["pairs"]:
            lines.append("No flights.")
            continue
        lines += ["Targets: mean vertical acceleration directly below (within one leader "
                  f"equivalent radius of its axis) within {100 * TARGETS['mean_vertical']:.0f} %"
                  " in every 5 cm bin of separation with data (>= 30 samples); lateral "
                  f"half-magnitude radius within {100 * TARGETS['half_width']:.0f} %; vertical "
                  f"and lateral turbulence sd within {100 * TARGETS['vertical_sd']:.0f} % "
                  "(directly below; each flight's residual about the fitted mean and its own "
                  "offset, less the label noise variance: "
                  + ("each sample's follower's free-air variance at its speed"
                     if (checks or {}).get("noise") == "speed"
                     else "the follower's free-air variance, pooled") + ").", "",
                  "| pair | flights | worst mean error | half-width real / fitted | "
                  "vertical sd real / fitted | lateral sd real / fitted | "
                  "autocorr. 50 ms real / fitted | RMSE (zero model) |",
                  "| --- | --- | --- | --- | --- | --- | --- | --- |"]
        for pair, e in sc["pairs"].items():
            mark = {True: "met", False: "**not met**"}
            ac = e.get("autocorrelation", {}).get("50ms", {})
            lines.append(
                f"| {pair} | {len(e['flights'])} | "
                f"{_pct(e['mean_vertical']['worst_rel_error'])} ({mark[e['mean_vertical']['met']]})"
                f" | {_num(e['half_width']['real_m'])} / {_num(e['half_width']['fitted_m'])} m "
                f"({_pct(e['half_width']['rel_error'])}, {mark[e['half_width']['met']]}) | "
                f"{_num(e['vertical_sd']['real_mps2'])} / {_num(e['vertical_sd']['fitted_mps2'])}"
                f" ({_pct(e['vertical_sd']['rel_error'])}, {mark[e['vertical_sd']['met']]}) | "
                f"{_num(e['lateral_sd']['real_mps2'])} / {_num(e['lateral_sd']['fitted_mps2'])}"
                f" ({_pct(e['lateral_sd']['rel_error'])}, {mark[e['lateral_sd']['met']]}) | "
                f"{_num(ac.get('real', np.nan), 2)} / {_num(ac.get('fitted', np.nan), 2)} | "
                f"{e['rmse_mps2']:.3f} ({e['zero_model_rmse_mps2']:.3f}) m/s² |")
        lines += ["", "Per separation bin (real / fitted, m/s²): "]
        for pair, e in sc["pairs"].items():
            cells = ", ".join(f"{b['separation_m'][0]:.2f}-{b['separation_m'][1]:.2f} m: "
                              f"{b['real_mps2']:.2f} / {b['fitted_mps2']:.2f} "
                              f"({_pct(b['rel_error'])}, n={b['samples']})"
                              for b in e["separation_bins"])
            lines.append(f"- {pair}: {cells or 'no bin with data'}")
        lines.append("")
        lines.append("All targets met: " + ("yes" if sc["all_met"] else "no"))
    lines += _checks_markdown(checks or {})
    lines += ["", f"## The wake of this world's vehicles ({paper['config']})", "",
              "Directly below a hovering leader, on a level follower (the fitted dimensionless "
              "jet with this config's rotors and masses); 95 % ranges over the bootstrap refits "
              "in brackets. DESIGN.md's hand table for comparison.", "",
              "| separation | mean [m/s²] | hand table | half-width [m] | hand table | "
              "vertical sd [m/s²] | lateral sd [m/s²] | correlation time [s] |",
              "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for row in paper["rows"]:
        sep = row["separation_m"]
        hand = HAND_TABLE.get(round(sep, 2), {})
        rng = row.get("bootstrap", {})

        def cell(key: str, digits: int = 3, r: dict = rng, values: dict = row) -> str:
            text = _num(values[key], digits)
            if key in r:
                text += f" ({_num(r[key][0], digits)}-{_num(r[key][1], digits)})"
            return text

        lines.append(f"| {sep:.2f} m | {cell('mean_mps2')} | {hand.get('mean_mps2', '')} | "
                     f"{cell('half_width_m')} | {hand.get('half_width_m', '')} | "
                     f"{cell('vertical_sd_mps2')} | {cell('lateral_sd_mps2')} | "
                     f"{cell('corr_time_s', 2)} |")
    lines += ["", "## Figures", ""] + [f"![{Path(f).stem}](figures/{Path(f).name})"
                                        for f in figures]
    return "\n".join(lines) + "\n"


def _checks_markdown(checks: dict[str, Any]) -> list[str]:
    """The report's sections for the checks beside the fit (:func:`report_markdown`)."""
    lines = _cross_validation_markdown(checks.get("cross_validation"))
    lines += ["", "## The turbulence above the labels' noise at the follower's speed", ""]
    noise = checks.get("turbulence_above_speed_noise")
    if not noise:
        lines.append("No follower vehicle has free-air samples to read its noise from.")
    else:
        lines += ["The targets' turbulence subtracts the follower's free-air label noise pooled "
                  "over its free-air samples; the noise grows with its speed "
                  "(aerodock/identify/label_noise.py). Real sd less the pooled noise / less the "
                  "noise at each sample's speed [95th percentile over the pair's flights] / "
                  "the jet's, m/s², within one leader equivalent radius of the axis; 0 means the "
                  "spread is all the labels' noise.", "",
                  "| flights | pair | samples | median speed | lateral | vertical |",
                  "| --- | --- | --- | --- | --- | --- |"]
        for part, rows in noise.items():
            for pair, r in rows.items():
                lines.append(
                    f"| {part.replace('_', ' ')} | {pair} | {r['samples']:.0f} | "
                    f"{r['median_speed_mps']:.2f} m/s | {_num(r['lateral_pooled'])} / "
                    f"{_num(r['lateral_speed'])} [{_num(r['lateral_speed_p95'])}] / "
                    f"{_num(r['lateral_model'])} | {_num(r['vertical_pooled'])} / "
                    f"{_num(r['vertical_speed'])} [{_num(r['vertical_speed_p95'])}] / "
                    f"{_num(r['vertical_model'])} |")
    lines += _ceiling_markdown(checks.get("motor_ceiling"), checks.get("commands", "asked"))
    lines += ["", "## The wake's torque", ""]
    torque = checks.get("wake_torque")
    if not torque:
        lines.append("No log carries the follower's motor torque and body rates (Neural-Swarm "
                     "logs do), or none has free air to take its trim from.")
        return lines
    lines += ["The inward torque (pushing the disks nearer the leader's axis down), 0.15-0.45 m "
              "below the leader, by offset from its axis: the logs' (Euler's equation on the "
              "motors' torque and the body rates, aerodock/identify/wake_torque.py) and the "
              "fitted jet's at the same states, and the lever (the torque over the real "
              "downward force; a loss of thrust on the disks alone keeps it within half the "
              "diagonal).", "",
              "| pair | offset | samples | real [mN·m] | jet [mN·m] | real / jet | lever | "
              "half diagonal |", "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for pair, bins in torque.items():
        for b in bins:
            lines.append(f"| {pair} | {100 * b['offset_lo_m']:.0f}-{100 * b['offset_hi_m']:.0f}"
                         f" cm | {b['samples']} | {1e3 * b['real_nm']:.2f} | "
                         f"{1e3 * b['jet_nm']:.2f} | {_num(b['ratio'], 2)} | "
                         f"{100 * b['lever_m']:.1f} cm | {100 * b['half_diagonal_m']:.1f} cm |")
    return lines


def _ceiling_markdown(rows: list[dict[str, Any]] | None, commands: str) -> list[str]:
    """The report's section on the motors' ceiling, where the logs carry the motor commands."""
    if not rows:
        return []
    labels = ("These labels are from the commands as sent (`--commands sent`): the excess is "
              "not in them." if commands == "sent" else
              "These labels are as the firmware asked for them: the excess is in them, most near "
              "the axis; `--commands sent` takes it away.")
    lines = ["", "## The motors' ceiling", "",
             "The logs' per-motor thrusts are the ones the firmware asked for; each motor's "
             "command follows from them by a map (fitted per flight where every command is "
             f"below {MAP_FIT_PWM}, aerodock/identify/motor_commands.py) up to the top of the "
             "commands' range, where the thrust asked for runs past what the command sent "
             f"makes. {labels}",
             "", "| follower | flights | map residual sd, up to | motor samples at "
             f"{CEILING_PWM} and up | highest command | asked beyond the map there |",
             "| --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        lines.append(f"| {r['vehicle']} | {r['flights']} | {1e3 * r['residual_sd_n']:.1f} mN | "
                     f"{r['ceiling_samples']} | {r['top_pwm']:.3f} | "
                     f"{_num(1e3 * r['ceiling_excess_n'])} mN |")
    return lines


def _cross_validation_markdown(cross: dict[str, Any] | None) -> list[str]:
    """The report's cross-validation section (``field fit --folds``), if it was asked for."""
    if not cross:
        return []
    n = len(cross["folds"])
    lines = ["", f"## Cross-validation over flights ({n} folds)", "",
             "Every flight (the held-out ones too) held out once: each pair's flights in name "
             "order dealt round-robin into the folds (the deal carried on from pair to pair), "
             "each fold scored by a fit on all the others (aerodock/identify/wake_folds.py; the "
             "labels' noise is each follower vehicle's, read from every flight's free air). "
             "Per pair and target: the relative error (the mean's: its worst bin, signed) "
             "of each fold, and folds within the target; beside it the flights' own reference, "
             "the fold's training flights' real figure taken as the prediction (what a model "
             "that matched its training flights exactly would score: the flights' spread).", "",
             "| pair | target | jet, per fold | met | training flights' real, per fold | met |",
             "| --- | --- | --- | --- | --- | --- |"]
    for pair, row in cross["summary"].items():
        for key, r in row.items():
            lines.append(f"| {pair} | {key} | {', '.join(_pct(e) for e in r['rel_errors'])} | "
                         f"{r['met']}/{r['scored']} | "
                         f"{', '.join(_pct(e) for e in r['reference_rel_errors'])} | "
                         f"{r['reference_met']}/{r['scored']} |")
    per = cross.get("per_flight") or {}
    if per:
        lines += ["", "Each flight alone, the real turbulence sd directly below (as the targets "
                  "read it) beside the fitted jet's, m/s² (n/a: too few samples, or all noise):",
                  ""]
        for pair, rows in per.items():
            cells = ", ".join(f"{r['flight']} {_num(r['vertical_real_mps2'])} / "
                              f"{_num(r['vertical_fitted_mps2'])}" for r in rows)
            lines.append(f"- {pair}, vertical: {cells}")
    return lines
