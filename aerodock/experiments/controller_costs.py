"""What each controller lever costs on the rigid-body world: the bias observer's time constant
and the terminal-phase LQR weights, swept one at a time from the paper's controller.

Each point is a hover-docking campaign at d_p = 0.36 m (the same seeds for every point) and
reports success (Wilson 95 %), the median terminal vertical error, the median RMS tilt of the
follower over the terminal window, the fraction of that window with the control saturated (tilt
or thrust limit), slip-throughs, aborts and rotor strikes.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from aerodock.config import Config
from aerodock.control.compensation import AccelPredictor, Compensation
from aerodock.control.profiles import PAPER_Q_DIAG, controller_config
from aerodock.mission import MissionSpec, run_campaign

OBSERVER_TAUS_S = (4.0, 2.0, 1.0, 0.5, 0.25)
# Terminal weights: (1 - a) * paper + a * tuned; a = 2 goes past the tuned weights.
TERMINAL_MIX = (0.0, 0.25, 0.5, 1.0, 2.0)
_KEYS = ("trials", "docked", "success_rate", "success_wilson95", "terminal_err_down_median_m",
         "terminal_tilt_rms_deg_median", "terminal_saturated_frac_mean", "slip_throughs",
         "aborts", "rotor_strikes")


def _point(cfg: Config, trials: int, comp: Compensation, predictor: AccelPredictor | None,
           seed: int) -> dict[str, Any]:
    res = run_campaign(cfg, MissionSpec(trials=trials, offset_m=0.36, compensation=comp,
                                        seed=seed), predictor)
    summary = res.summary()
    return {k: summary[k] for k in _KEYS}


def controller_costs(cfg: Config, trials: int, predictor: AccelPredictor | None, seed: int,
                     taus_s: tuple[float, ...] = OBSERVER_TAUS_S,
                     mixes: tuple[float, ...] = TERMINAL_MIX) -> dict[str, Any]:
    """Run both sweeps; ``cfg``'s terminal weights are the 'tuned' end of the gain sweep.

    Returns ``{"observer_tau": [...], "terminal_gains": [...]}``, one record per point.
    """
    paper = controller_config(cfg, "paper")
    out: dict[str, Any] = {"trials": trials, "offset_m": 0.36, "observer_tau": [],
                           "terminal_gains": []}
    for tau in taus_s:
        c = paper.with_overrides({"control": {"observer_bias_tau_s": tau}})
        rec = _point(c, trials, Compensation.OBSERVER, None, seed)
        out["observer_tau"].append({"observer_bias_tau_s": tau, "compensation": "observer",
                                    **rec})
    tuned_q = np.asarray(cfg.control.terminal_q_diag, dtype=float)
    for mix in mixes:
        q = (1.0 - mix) * np.asarray(PAPER_Q_DIAG) + mix * tuned_q
        c = paper.with_overrides({"control": {"terminal_q_diag": [float(x) for x in q]}})
        for comp in (Compensation.OBSERVER, Compensation.MODEL):
            if comp == Compensation.MODEL and predictor is None:
                continue
            rec = _point(c, trials, comp, predictor, seed)
            out["terminal_gains"].append({"mix": mix, "terminal_q_diag": [float(x) for x in q],
                                          "compensation": comp.value, **rec})
    return out
