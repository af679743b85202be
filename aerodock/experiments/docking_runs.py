"""Steps 2-4 of ``aerodock reproduce`` with one controller: the cable-length study, docking
with the leader hovering, and the leader in motion (:func:`docking_experiments`)."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from aerodock.config import Config
from aerodock.control.compensation import Compensation
from aerodock.downwash import build_field
from aerodock.downwash.mean import mean_acceleration_fn, mean_source
from aerodock.experiments.cable_study import cable_study
from aerodock.experiments.records import (
    AltitudeWindow,
    DockingRecord,
    HoverDocking,
    MovingLeader,
    MovingMode,
)
from aerodock.mission import CampaignResult, MissionSpec, Phase, run_campaign

if TYPE_CHECKING:
    from aerodock.experiments.run_size import RunSize


def _window_mean(trace: dict[str, np.ndarray], t0: float, t1: float) -> AltitudeWindow:
    """Mean |vertical error| (follower vs its reference) in [t0, t1) over approaching trials."""
    t = trace["t_s"]
    sel = (t >= t0) & (t < t1)
    err = np.abs(trace["follower_p"][sel, :, 2] - trace["ref_p"][sel, :, 2])
    ok = trace["phase"][sel] <= Phase.TERMINAL
    per_trial = np.array([np.mean(err[ok[:, i], i]) if ok[:, i].any() else np.nan
                          for i in range(err.shape[1])])
    good = per_trial[np.isfinite(per_trial)]
    return AltitudeWindow(window_s=[t0, t1],
                          mean_abs_err_down_m=float(np.mean(good)) if good.size else None,
                          sd_m=float(np.std(good)) if good.size else None,
                          trials=int(good.size))


def _campaign_record(res: CampaignResult) -> dict[str, Any]:
    s = res.summary()
    s["arrival_s"] = res.arrival_s
    return s


def _hover_docking(cfg: Config, size: RunSize, predictor: Any, seed: int
                   ) -> tuple[HoverDocking, dict[str, Any]]:
    """Docking with the leader hovering, without the model, with it and with the oracle;
    returns the record and each campaign's traces for the figures."""
    summaries: dict[str, dict[str, Any]] = {}
    traces: dict[str, Any] = {}
    for key, comp in (("without_model", Compensation.OBSERVER),
                      ("with_model", Compensation.MODEL), ("oracle", Compensation.ORACLE)):
        res = run_campaign(cfg, MissionSpec(trials=size.hover_trials, offset_m=0.36,
                                            compensation=comp, seed=seed + 1), predictor,
                           record="trace")
        summaries[key] = _campaign_record(res)
        traces[key] = _trace_keep(res)
    w, m = summaries["without_model"], summaries["with_model"]
    err_w, err_m = w["terminal_err_down_median_m"], m["terminal_err_down_median_m"]
    hover = HoverDocking(
        offset_m=0.36, aperture_m=cfg.gripper.aperture_m, trials=size.hover_trials, **summaries,
        terminal_error_reduction_x=(None if err_w is None or err_m is None
                                    else err_w / max(err_m, 1e-9)),
        oracle_mean_source=mean_source(mean_acceleration_fn(build_field(cfg))))
    return hover, traces


def _moving_leader(cfg: Config, size: RunSize, predictor: Any, seed: int
                   ) -> tuple[MovingLeader, dict[str, Any]]:
    """The leader moving at 0.25 m/s, without and with the model; returns the record and the
    formation flights' traces for the figures."""
    meet, hold = cfg.planner.horizon_moving_s, cfg.planner.hold_s
    n = size.moving_trials
    armed = (True,) * n + (False,) * n
    modes: dict[str, MovingMode] = {}
    traces: dict[str, Any] = {}
    for key, comp in (("without_model", Compensation.OBSERVER),
                      ("with_model", Compensation.MODEL)):
        # Docking, and formation tracking as in the paper's figure: the same flights with the
        # gripper disarmed, flown in one batch (trial ids 0..n-1 twice; outcomes are per trial).
        both = run_campaign(cfg, MissionSpec(trials=2 * n, offset_m=0.36, leader_speed_mps=0.25,
                                             compensation=comp, seed=seed + 2,
                                             passive_trigger=armed, active_trigger=armed),
                            predictor, record="trace", trials=np.r_[0:n, 0:n])
        dock_res, track = both.take(np.arange(n)), both.take(np.arange(n, 2 * n))
        modes[key] = MovingMode(summary=_campaign_record(dock_res),
                                altitude_error_approach=_window_mean(track.trace, meet - 2.0,
                                                                     meet),
                                altitude_error_hold=_window_mean(track.trace, meet, meet + hold))
        traces[key] = track.trace
    return MovingLeader(leader_speed_mps=0.25, meet_s=meet, hold_s=hold, trials=n,
                        **modes), traces


def docking_experiments(cfg: Config, size: RunSize, predictor: Any, seed: int,
                         say: Callable[[str], None], label: str
                         ) -> tuple[DockingRecord, dict[str, Any], dict[str, float]]:
    """The cable-length study, hover docking and the moving leader with one controller.

    Returns (the record, traces for the figures, timings).
    """
    traces: dict[str, Any] = {}
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    say(f"2/5 cable-length study (leader on a rigid stand), {label}")
    cable, traces["cable"] = cable_study(cfg, size.cable_offsets_m, size.cable_reps, predictor,
                                         seed, record="trace")
    timings["cable_study_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    say(f"3/5 docking with the leader hovering ({size.hover_trials} trials per mode), {label}")
    hover, traces["hover"] = _hover_docking(cfg, size, predictor, seed)
    timings["hover_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    say(f"4/5 leader in motion at 0.25 m/s ({size.moving_trials} trials per mode), {label}")
    moving, traces["moving"] = _moving_leader(cfg, size, predictor, seed)
    timings["moving_s"] = time.perf_counter() - t0
    return DockingRecord(cable, hover, moving), traces, timings


def _trace_keep(res: CampaignResult) -> dict[str, Any]:
    tr = dict(res.trace)
    tr["success"] = res.success
    tr["arrival_s"] = res.arrival_s
    return tr
