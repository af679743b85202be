"""A wake fit held against flights, and the fitted wake probed in a world.

Scores (:func:`score_wake`) are what the issue's targets name, per vehicle pair, on any flights
(held out from the fit): the mean vertical acceleration directly below the leader per bin of
separation, the lateral half-magnitude radius, the vertical and lateral turbulence sd, and the
autocorrelation at 50 and 80 ms. The uncertainty is a bootstrap over flights.

:func:`wake_at_separations` probes the jet with fitted parameters in a world (its vehicles, its
air) directly below a hovering leader.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from aerodock.identify.flights import FlightSamples
from aerodock.identify.wake_fit import (
    CORE_RADII,
    FITTED_PARAMS,
    MIN_BIN_SAMPLES,
    TORQUE_PARAMS,
    autocorrelations,
    centred,
    model_mean,
    model_turbulence,
)

SEPARATION_BIN_M = 0.05
EDGE_RADII = (3.5, 6.0)
"""The ring beyond the jet's edge, in leader equivalent radii off the axis (out to the fit's
region): where the real flights are pushed up (an upwash, docs/crazyflie.md) and a Gaussian
jet is not. Its mean is reported beside the targets, not as one."""
TARGETS = {"mean_vertical": 0.15, "half_width": 0.20, "vertical_sd": 0.20, "lateral_sd": 0.20}
"""The issue's targets: largest relative error of each figure on held-out flights."""


def wake_at_separations(params: dict[str, float], cfg: Any,
                        separations_m: Sequence[float] = (0.36, 0.64, 1.35)) -> list[dict]:
    """The jet with ``params`` in the world of ``cfg`` (its vehicles, its air), directly below
    a hovering leader at each separation: mean downward acceleration on a level follower,
    half-magnitude radius of it, the sd of the whole follower's turbulence along the axis and
    across it, and the correlation time."""
    from aerodock.downwash import build_field
    from aerodock.downwash.probe import half_magnitude_radius_m, probe_bodies

    cfg = cfg.with_overrides({"downwash": {"field": "aerodock.downwash.jet:RoundJetField",
                                           "params": {k: float(v) for k, v in params.items()
                                                      if k in FITTED_PARAMS
                                                      or k in TORQUE_PARAMS}}},
                             source=cfg.source)
    jet = build_field(cfg)
    mass, g = cfg.vehicle.mass_kg, cfg.sim.gravity_mps2
    rows = []
    for sep in separations_m:
        leader, follower = probe_bodies(sep, 0.0, 0.0, mass, g)
        mean = float(jet.mean_acceleration(leader, follower)[0, 2])
        turb = jet.turbulence(leader, follower)
        rows.append({"separation_m": float(sep), "mean_mps2": mean,
                     "half_width_m": half_magnitude_radius_m(jet.mean_acceleration, sep, mass, g),
                     "vertical_sd_mps2": float(np.sqrt(turb["axial_var_mps4"][0])),
                     "lateral_sd_mps2": float(np.sqrt(turb["lateral_var_mps4"][0])),
                     "corr_time_s": float(turb["corr_time_s"][0])})
    return rows


def signed_worst(errs: list[float]) -> float:
    """The largest relative error in magnitude (the worst separation bin), with its sign."""
    finite = [e for e in errs if np.isfinite(e)]
    return float(max(finite, key=abs)) if finite else float("nan")


def score_wake(params: dict[str, float], flights: Sequence[FlightSamples],
               rotor_radii_m: dict[str, float] | None = None) -> dict[str, Any]:
    """Per vehicle pair, the issue's targets on ``flights`` (module docstring): each figure real
    and fitted, its relative error and whether it is within the target (:data:`TARGETS`)."""
    pairs: dict[str, list[FlightSamples]] = {}
    for f in flights:
        pairs.setdefault(f.pair, []).append(f)
    out: dict[str, Any] = {}
    for pair, group in sorted(pairs.items()):
        means = [model_mean(params, f, rotor_radii_m) for f in group]
        turbs = [model_turbulence(params, f, rotor_radii_m) for f in group]
        label = np.concatenate([f.label_mps2 for f in group])
        model = np.concatenate(means)
        dp = np.concatenate([f.offset_m for f in group])
        req = np.concatenate([np.full(f.label_mps2.shape[0], f.equivalent_radius_m)
                              for f in group])
        h = np.hypot(dp[:, 0], dp[:, 1])
        core = h < CORE_RADII * req
        entry: dict[str, Any] = {"flights": sorted({f.flight for f in group}),
                                 "samples": int(label.shape[0]), "core_samples": int(core.sum())}
        # Mean vertical acceleration directly below, per separation bin.
        bins = []
        edges = np.arange(0.0, dp[:, 2].max() + SEPARATION_BIN_M, SEPARATION_BIN_M)
        for lo in edges:
            sel = core & (dp[:, 2] >= lo) & (dp[:, 2] < lo + SEPARATION_BIN_M)
            if sel.sum() < MIN_BIN_SAMPLES:
                continue
            real, fitted = float(label[sel, 2].mean()), float(model[sel, 2].mean())
            bins.append({"separation_m": [round(float(lo), 3),
                                          round(float(lo + SEPARATION_BIN_M), 3)],
                         "samples": int(sel.sum()), "real_mps2": real, "fitted_mps2": fitted,
                         "real_sd_mps2": float(label[sel, 2].std()),
                         "rel_error": (fitted - real) / abs(real) if real else float("nan")})
        entry["separation_bins"] = bins
        worst = signed_worst([b["rel_error"] for b in bins])
        entry["mean_vertical"] = {"worst_rel_error": worst,
                                  "met": bool(bins) and abs(worst) <= TARGETS["mean_vertical"]}
        # Lateral half-magnitude radius of the vertical acceleration, all depths of the pair.
        profile = lateral_profile(h, label[:, 2], model[:, 2], float(np.median(req)))
        entry["lateral_profile"] = profile
        real_hw, fit_hw = profile["real_half_width_m"], profile["fitted_half_width_m"]
        rel = (fit_hw - real_hw) / real_hw if real_hw and np.isfinite(real_hw) else float("nan")
        entry["half_width"] = {"real_m": real_hw, "fitted_m": fit_hw, "rel_error": rel,
                               "met": bool(np.isfinite(rel) and abs(rel) <= TARGETS["half_width"])}
        # Beyond the edge: the mean vertical acceleration in the ring (down positive).
        ring = (h >= EDGE_RADII[0] * req) & (h < EDGE_RADII[1] * req)
        enough = ring.sum() >= MIN_BIN_SAMPLES
        entry["edge"] = {"radii": list(EDGE_RADII), "samples": int(ring.sum()),
                         "real_mps2": float(label[ring, 2].mean()) if enough else float("nan"),
                         "real_se_mps2": (float(label[ring, 2].std() / np.sqrt(ring.sum()))
                                          if enough else float("nan")),
                         "fitted_mps2": float(model[ring, 2].mean()) if enough else float("nan")}
        # Turbulence sd near the axis: each flight's residual about the mean (and its own
        # offset), less the free-air noise.
        err = label - model
        about = np.concatenate([
            centred(f.label_mps2 - m, np.hypot(f.offset_m[:, 0], f.offset_m[:, 1])
                    < CORE_RADII * f.equivalent_radius_m) for f, m in zip(group, means,
                                                                         strict=True)])
        free = np.concatenate([f.sample_noise_var_mps4 for f in group])
        axial = np.concatenate([t["axial_var_mps4"] for t in turbs])
        lateral = np.concatenate([t["lateral_var_mps4"] for t in turbs])
        for name, real_var, model_var, key in (
                ("vertical_sd", about[core, 2].var() - free[core, 2].mean(),
                 axial[core].mean() if core.any() else np.nan, "vertical_sd"),
                ("lateral_sd", 0.5 * (about[core, 0].var() + about[core, 1].var())
                 - 0.5 * (free[core, 0] + free[core, 1]).mean(),
                 lateral[core].mean() if core.any() else np.nan, "lateral_sd")):
            real_sd = float(np.sqrt(real_var)) if core.sum() >= MIN_BIN_SAMPLES \
                and real_var > 0 else float("nan")
            fit_sd = float(np.sqrt(model_var)) if np.isfinite(model_var) else float("nan")
            rel = (fit_sd - real_sd) / real_sd if np.isfinite(real_sd) else float("nan")
            entry[name] = {"real_mps2": real_sd, "fitted_mps2": fit_sd, "rel_error": rel,
                           "met": bool(np.isfinite(rel) and abs(rel) <= TARGETS[key])}
        entry["rmse_mps2"] = float(np.sqrt(np.mean(np.sum(err ** 2, axis=1))))
        entry["zero_model_rmse_mps2"] = float(np.sqrt(np.mean(np.sum(label ** 2, axis=1))))
        out[pair] = entry
    ac = autocorrelations(params, flights, rotor_radii_m)
    for pair, entry in out.items():
        if pair in ac:
            lags = np.asarray(ac[pair]["lag_s"])
            entry["autocorrelation"] = {
                f"{1000 * lag:.0f}ms": {"real": float(np.interp(lag, lags, ac[pair]["real"])),
                                        "fitted": float(np.interp(lag, lags,
                                                                  ac[pair]["model"]))}
                for lag in (0.05, 0.08)}
            entry["autocorrelation_curve"] = ac[pair]
    out_all = {"pairs": out, "targets": TARGETS}
    out_all["all_met"] = all(e[k]["met"] for e in out.values()
                             for k in ("mean_vertical", "half_width", "vertical_sd",
                                       "lateral_sd"))
    return out_all


def lateral_profile(offset_m: np.ndarray, real_mps2: np.ndarray, fitted_mps2: np.ndarray,
                    equivalent_radius_m: float) -> dict[str, Any]:
    """Binned real and fitted vertical acceleration against lateral offset (bins of a quarter
    of the leader's equivalent radius, to four), and each profile's half-magnitude radius: where
    it first falls to half its value in the innermost bin (linear between bins)."""
    width = 0.25 * equivalent_radius_m
    edges = np.arange(0.0, 4.0 * equivalent_radius_m + 1e-12, width)
    centres, real, fitted, spread, counts = [], [], [], [], []
    for lo in edges[:-1]:
        sel = (offset_m >= lo) & (offset_m < lo + width)
        if sel.sum() < MIN_BIN_SAMPLES:
            continue
        centres.append(float(lo + 0.5 * width))
        real.append(float(real_mps2[sel].mean()))
        fitted.append(float(fitted_mps2[sel].mean()))
        spread.append(float(real_mps2[sel].std()))
        counts.append(int(sel.sum()))
    return {"offset_m": centres, "real_mps2": real, "fitted_mps2": fitted,
            "real_sd_mps2": spread, "samples": counts,
            "real_half_width_m": _half_width(centres, real),
            "fitted_half_width_m": _half_width(centres, fitted)}


def _half_width(x: list[float], y: list[float]) -> float:
    if len(x) < 2 or not y[0] > 0:
        return float("nan")
    half = 0.5 * y[0]
    for i in range(1, len(x)):
        if y[i] <= half:
            return float(x[i - 1] + (x[i] - x[i - 1]) * (y[i - 1] - half) / (y[i - 1] - y[i]))
    return float("nan")
