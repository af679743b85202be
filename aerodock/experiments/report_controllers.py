"""``report.md`` sections for the two controllers and the cost of each controller lever.

The reproduction (every table of the report above this section) flies the paper's controller;
this section sets our tuned controller beside it and beside the paper's own figures, and shows
what the observer time constant and the terminal gains cost on the rigid-body world.
"""

from __future__ import annotations

from typing import Any


def _rate(d: dict[str, Any]) -> str:
    lo, hi = d["success_wilson95"]
    return f"{d['docked']}/{d['trials']} ({lo:.0%}-{hi:.0%})"


def _offsets_docked(cable: dict[str, Any], key: str) -> str:
    recs = cable[key]
    docked = sum(r["result"] == "dock" for r in recs)
    per = ", ".join(f"{r['offset_m']:g}: {r['docked']}/{r['trials']}" for r in recs)
    return f"{docked}/{len(recs)} offsets ({per})"


def controllers_markdown(r: dict[str, Any]) -> list[str]:
    """Markdown lines: paper vs the paper's controller here vs our tuned controller, and the
    lever-cost sweeps (empty when the run has no ``controllers`` record)."""
    ctl = r.get("controllers")
    if not ctl:
        return []
    paper, tuned = r, ctl["tuned"]
    lines = [
        "## The paper's controller and ours, side by side", "",
        "Every table above flies **the paper's controller** "
        f"({ctl['paper']['source']}: Q = diag{tuple(ctl['paper']['q_diag'])}). "
        "The **tuned** column flies the configuration's controller "
        f"({ctl['tuned']['source']}: terminal Q = diag{tuple(ctl['tuned']['terminal_q_diag'])}, "
        f"observer {ctl['tuned']['observer_bias_tau_s']:g} s), on the same world and seeds. "
        "Docked trials with a Wilson 95 % interval.", "",
        "| experiment | paper | paper's controller, without model | with model | "
        "tuned controller, without model | with model |", "|---|---|---|---|---|---|",
    ]
    hp, ht = paper["hover_docking"], tuned["hover_docking"]
    lines.append(f"| hover docking, d_p 0.36 m | 8/10 with model | {_rate(hp['without_model'])} | "
                 f"{_rate(hp['with_model'])} | {_rate(ht['without_model'])} | "
                 f"{_rate(ht['with_model'])} |")
    lines.append("| terminal vertical error, median | < 0.06 m with model | "
                 f"{hp['without_model']['terminal_err_down_median_m']:.3f} m | "
                 f"{hp['with_model']['terminal_err_down_median_m']:.3f} m | "
                 f"{ht['without_model']['terminal_err_down_median_m']:.3f} m | "
                 f"{ht['with_model']['terminal_err_down_median_m']:.3f} m |")
    lines.append("| terminal tilt RMS, median | - | "
                 f"{hp['without_model']['terminal_tilt_rms_deg_median']:.1f} deg | "
                 f"{hp['with_model']['terminal_tilt_rms_deg_median']:.1f} deg | "
                 f"{ht['without_model']['terminal_tilt_rms_deg_median']:.1f} deg | "
                 f"{ht['with_model']['terminal_tilt_rms_deg_median']:.1f} deg |")
    mp, mt = paper["moving_leader"], tuned["moving_leader"]
    lines.append(f"| leader moving 0.25 m/s | very limited | {_rate(mp['without_model'])} | "
                 f"{_rate(mp['with_model'])} | {_rate(mt['without_model'])} | "
                 f"{_rate(mt['with_model'])} |")
    cp, ct = paper["cable_study"], tuned["cable_study"]
    lines.append(f"| cable study (leader on a stand) | 6/6 with vs 0/6 without | "
                 f"{_offsets_docked(cp, 'without_model')} | {_offsets_docked(cp, 'with_model')} "
                 f"| {_offsets_docked(ct, 'without_model')} | "
                 f"{_offsets_docked(ct, 'with_model')} |")
    lines.append("")
    costs = r.get("controller_costs")
    if costs:
        head = ("| {lever} | compensation | docked | terminal err down (median) | "
                "tilt RMS (median) | saturated (mean) | slips | aborts | rotor strikes |")
        rule = "|---|---|---|---|---|---|---|---|---|"
        lines += ["### What each lever costs", "",
                  f"Hover docking at d_p = {costs['offset_m']} m, {costs['trials']} trials per "
                  "point, the same seeds at every point; everything else is the paper's "
                  "controller. Tilt and saturation over the terminal window (the final 0.5 s "
                  "of the approach).", "", head.format(lever="observer time constant"), rule]
        for p in costs["observer_tau"]:
            lines.append(_cost_row(f"{p['observer_bias_tau_s']:g} s", p))
        lines += ["", head.format(lever="terminal Q (paper -> tuned mix)"), rule]
        for p in costs["terminal_gains"]:
            q = p["terminal_q_diag"]
            lines.append(_cost_row(f"{p['mix']:g} (Q_z {q[2]:.0f}, Q_vz {q[5]:.1f})", p))
        lines.append("")
    return lines


def _cost_row(lever: str, p: dict[str, Any]) -> str:
    return (f"| {lever} | {p['compensation']} | {_rate(p)} | "
            f"{p['terminal_err_down_median_m']:.3f} m | "
            f"{p['terminal_tilt_rms_deg_median']:.1f} deg | "
            f"{p['terminal_saturated_frac_mean']:.0%} | {p['slip_throughs']} | {p['aborts']} | "
            f"{p['rotor_strikes']} |")
