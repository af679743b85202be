"""What each lever the paper leaves unstated costs: the bias observer's bandwidth, the terminal
LQR weights and the gripper's vertical window, swept one at a time from the paper's controller.

- **Observer bandwidth.** The paper names its baseline an LQG with a bias estimate and states no
  time constant; its flight stack (Freyja) publishes one estimator
  (:mod:`aerodock.control.freyja_estimator`). The sweep flies that estimator and a
  time-constant Kalman filter from 4 s (the reproduction's earlier guess) down to 0.25 s, each
  with its measured step response (:mod:`aerodock.control.observer_response`), hover docking
  with and without the model and the cable study, and the probability of each of the paper's
  own counts under the rates measured (:mod:`aerodock.experiments.paper_counts`).
- **Terminal gains**: from the paper's weights to past the tuned ones, with and without model.
- **Gripper window**: how high above the contact arm the gate still captures the bar. The paper
  gives the gate's aperture (0.1 m) but not its height; the sweep shows what that unstated
  figure does to every controller.

Each hover point is a docking campaign at d_p = 0.36 m (the same seeds for every point) and
reports success (Wilson 95 %), the median terminal vertical error, the median RMS tilt over the
terminal window, the fraction of that window with the control saturated (tilt or thrust
limit), slip-throughs, aborts and rotor strikes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from aerodock.config import Config
from aerodock.control.compensation import AccelPredictor, Compensation
from aerodock.control.observer_response import bias_step_response
from aerodock.control.profiles import PAPER_Q_DIAG, controller_config
from aerodock.experiments.cable_study import cable_study
from aerodock.experiments.paper_counts import paper_outcome_probabilities
from aerodock.mission import MissionSpec, run_campaign

OBSERVER_TAUS_S = (4.0, 2.0, 1.0, 0.5, 0.25)
# Terminal weights: (1 - a) * paper + a * tuned; a = 2 goes past the tuned weights.
TERMINAL_MIX = (0.0, 0.25, 0.5, 1.0, 2.0)
GATE_HEIGHTS_M = (0.05, 0.075, 0.10)  # the window is (-r, gate height - r), r the bar's radius
_KEYS = ("trials", "docked", "success_rate", "success_wilson95", "terminal_err_down_median_m",
         "terminal_tilt_rms_deg_median", "terminal_saturated_frac_mean", "slip_throughs",
         "aborts", "rotor_strikes")


@dataclass(frozen=True)
class CostSize:
    """How big each sweep is."""

    trials: int  # hover docking campaigns
    taus_s: tuple[float, ...]  # time-constant observer points (Freyja's is always flown)
    mixes: tuple[float, ...]
    cable_offsets_m: tuple[float, ...]
    cable_reps: int
    gate_heights_m: tuple[float, ...]


def _point(cfg: Config, trials: int, comp: Compensation, predictor: AccelPredictor | None,
           seed: int) -> dict[str, Any]:
    res = run_campaign(cfg, MissionSpec(trials=trials, offset_m=0.36, compensation=comp,
                                        seed=seed), predictor)
    summary = res.summary()
    return {k: summary[k] for k in _KEYS}


def _observer_settings(paper: Config, taus_s: tuple[float, ...]
                       ) -> list[tuple[dict[str, Any], Config]]:
    """(description, config) per observer: Freyja's as published, then each time constant."""
    settings = [({"observer": "freyja", "label": "Freyja's estimator (published)"}, paper)]
    for tau in taus_s:
        c = paper.with_overrides({"control": {"bias_estimator": "time-constant",
                                              "observer_bias_tau_s": tau}})
        settings.append(({"observer": "time-constant", "observer_bias_tau_s": tau,
                          "label": f"time constant {tau:g} s"}, c))
    return settings


def observer_bandwidth(cfg: Config, size: CostSize, predictor: AccelPredictor | None,
                       seed: int) -> list[dict[str, Any]]:
    """The paper's controller at each observer setting: step response, hover docking with and
    without the model, the cable study, and the probability of the paper's counts."""
    points = []
    for desc, c in _observer_settings(controller_config(cfg, "paper"), size.taus_s):
        step = bias_step_response(c)
        rec: dict[str, Any] = {**desc, "rise_63_s": step.rise_63_s, "rise_98_s": step.rise_98_s,
                               "hover_without_model": _point(c, size.trials,
                                                             Compensation.OBSERVER, None, seed)}
        if predictor is not None:
            rec["hover_with_model"] = _point(c, size.trials, Compensation.MODEL, predictor, seed)
            rec["cable_study"], _ = cable_study(c, size.cable_offsets_m, size.cable_reps,
                                                predictor, seed + 1)
            rec["paper_counts"] = paper_outcome_probabilities(
                rec["hover_with_model"], rec["hover_without_model"], rec["cable_study"])
        points.append(rec)
    return points


def gripper_window(cfg: Config, size: CostSize, predictors: dict[str, AccelPredictor | None],
                   seed: int) -> list[dict[str, Any]]:
    """Hover docking for each controller profile in ``predictors`` (its model), with and without
    the model, at each gate height."""
    out = []
    for height in size.gate_heights_m:
        for profile, predictor in predictors.items():
            c = controller_config(cfg, profile).with_overrides(
                {"gripper": {"gate_height_m": height}})
            for comp in (Compensation.OBSERVER, Compensation.MODEL):
                if comp == Compensation.MODEL and predictor is None:
                    continue
                out.append({"gate_height_m": height, "controller": profile,
                            "compensation": comp.value,
                            **_point(c, size.trials, comp, predictor, seed)})
    return out


def controller_costs(cfg: Config, size: CostSize, predictor: AccelPredictor | None, seed: int,
                     ours_predictor: AccelPredictor | None = None) -> dict[str, Any]:
    """Run every sweep; ``cfg``'s terminal weights are the 'tuned' end of the gain sweep.

    Args:
        cfg: the configuration (the paper's controller is derived from it).
        size: the sweeps' sizes.
        predictor: the model the paper's controller flies (the paper's curriculum's).
        seed: campaign seed (the same at every point).
        ours_predictor: the model our controller flies in the gripper-window sweep (``None``:
            our controller is left out of it).

    Returns ``{"observer_bandwidth": [...], "terminal_gains": [...], "gripper_window": [...]}``,
    one record per point.
    """
    paper = controller_config(cfg, "paper")
    out: dict[str, Any] = {"trials": size.trials, "offset_m": 0.36,
                           "observer_bandwidth": observer_bandwidth(cfg, size, predictor, seed),
                           "terminal_gains": []}
    tuned_q = np.asarray(cfg.control.terminal_q_diag, dtype=float)
    for mix in size.mixes:
        q = (1.0 - mix) * np.asarray(PAPER_Q_DIAG) + mix * tuned_q
        c = paper.with_overrides({"control": {"terminal_q_diag": [float(x) for x in q]}})
        for comp in (Compensation.OBSERVER, Compensation.MODEL):
            if comp == Compensation.MODEL and predictor is None:
                continue
            rec = _point(c, size.trials, comp, predictor, seed)
            out["terminal_gains"].append({"mix": mix, "terminal_q_diag": [float(x) for x in q],
                                          "compensation": comp.value, **rec})
    predictors = {"paper": predictor}
    if ours_predictor is not None:
        predictors["ours"] = ours_predictor
    out["gripper_window"] = gripper_window(cfg, size, predictors, seed)
    return out
