"""Beyond the paper: the docking targets measured for each controller with the learnt model.

Scenarios (each a campaign of its own, the same seeds for every controller):

- hover docking at d_p = 0.36 m (the paper's) and at d_p = 0.27 m (one body-length);
- the leader moving at 0.25 m/s and at 0.5 m/s (meet at the planner's horizon, hold formation);

and for each: docked trials with a Wilson 95 % interval, the median terminal vertical error, the
median terminal tilt RMS, slip-throughs, misses, aborts and rotor strikes. The learnt model's
mean force is compared with the field's at 0.36 m below the leader and at the docking depth.

A target is *met* when the measured rate (or error) reaches it; the interval says how sure that
is. Nothing here is tuned per scenario: every controller flies its profile as it is.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from aerodock.config import Config
from aerodock.control.compensation import AccelPredictor, Compensation
from aerodock.downwash import build_field
from aerodock.downwash.mean import mean_acceleration_fn
from aerodock.downwash.probe import probe_bodies
from aerodock.experiments.records import (
    LearntMean,
    ScenarioOutcome,
    ScenarioSpec,
    TargetRow,
    TargetsResult,
)
from aerodock.mission import MissionSpec, run_campaign
from aerodock.planning.docking import DockGeometry

# (name, d_p m, leader speed m/s, minimum success rate)
SCENARIOS = (
    ("hover_0.36", 0.36, 0.0, 0.95),
    ("hover_0.27", 0.27, 0.0, 0.90),
    ("moving_0.25", 0.36, 0.25, 0.90),
    ("moving_0.5", 0.36, 0.5, 0.80),
)
ERR_DOWN_TARGET_M = 0.015  # median terminal vertical error, hover at 0.36 m
MEAN_REL_TARGET = 0.10  # learnt mean within 10 % of the field's at 0.36 m
# the campaign summary's figures a scenario's outcome keeps (ScenarioOutcome's first fields)
_KEYS = ("trials", "docked", "success_rate", "success_wilson95", "terminal_err_down_median_m",
         "terminal_err_3d_median_m", "terminal_tilt_rms_deg_median", "slip_throughs", "missed",
         "aborts", "rotor_strikes", "clearance_violations")


def scenario_outcome(summary: dict[str, Any], offset_m: float, speed_mps: float,
                     target: float) -> ScenarioOutcome:
    """A scenario's outcome from its campaign's summary
    (:meth:`~aerodock.mission.CampaignResult.summary`)."""
    return ScenarioOutcome(**{key: summary[key] for key in _KEYS}, offset_m=offset_m,
                           leader_speed_mps=speed_mps, target_success=target,
                           met=summary["success_rate"] >= target)


def scenario_campaigns(cfg: Config, trials: int, predictor: AccelPredictor | None, seed: int,
                       compensation: Compensation = Compensation.MODEL
                       ) -> dict[str, ScenarioOutcome]:
    """Every scenario flown by ``cfg``'s controller; one record per scenario."""
    out: dict[str, ScenarioOutcome] = {}
    for k, (name, offset, speed, target) in enumerate(SCENARIOS):
        res = run_campaign(cfg, MissionSpec(trials=trials, offset_m=offset,
                                            leader_speed_mps=speed, compensation=compensation,
                                            seed=seed + 10 * k), predictor)
        out[name] = scenario_outcome(res.summary(), offset, speed, target)
    return out


def learnt_mean_check(cfg: Config, predictor: AccelPredictor) -> list[LearntMean]:
    """The learnt model's vertical force against the field's mean, on the leader's axis, at
    0.36 m and at the follower's docking depth for d_p = 0.36 m (hovering leader)."""
    field = build_field(cfg)
    mean_fn = mean_acceleration_fn(field)
    mass, g = cfg.vehicle.mass_kg, cfg.sim.gravity_mps2
    dock_depth = DockGeometry.from_config(
        cfg.with_overrides({"platform": {"cable_length_m": 0.36}})).follower_below_leader_m
    rows = []
    for label, depth in (("0.36 m", 0.36), ("docking depth", float(dock_depth))):
        leader, follower = probe_bodies(np.array([depth]), np.array([0.0]), 0.0, mass, g)
        true = float(np.asarray(mean_fn(leader, follower))[0, 2])
        learnt = float(np.asarray(predictor.predict_bodies(leader, follower))[0, 2])
        rel = (learnt - true) / true if abs(true) > 1e-9 else None
        rows.append(LearntMean(where=label, depth_m=depth, field_mean_down_mps2=true,
                               learnt_down_mps2=learnt, relative_error=rel,
                               met=rel is not None and abs(rel) <= MEAN_REL_TARGET))
    return rows


def targets(rows: dict[str, tuple[Config, AccelPredictor]], trials: int,
            model_check: AccelPredictor, seed: int, say: Any = None) -> TargetsResult:
    """The scenarios for each (controller, model) row, and the learnt-mean check.

    Args:
        rows: row name -> (its configuration, its model), e.g. the paper's controller with the
            paper's model, and ours with the deep curriculum's model.
        trials: trials per campaign.
        model_check: the model whose mean force is compared with the field's.
        seed: base seed (the same for every row).
        say: optional progress callback.
    """
    flown: dict[str, TargetRow] = {}
    for name, (cfg, predictor) in rows.items():
        if say is not None:
            say(f"    targets: {name}, {trials} trials per scenario")
        recs = scenario_campaigns(cfg, trials, predictor, seed)
        err = recs["hover_0.36"].terminal_err_down_median_m
        flown[name] = TargetRow(scenarios=recs, err_down_met=err <= ERR_DOWN_TARGET_M)
    first_cfg = next(iter(rows.values()))[0]
    return TargetsResult(
        trials=trials, scenarios=[ScenarioSpec(*s) for s in SCENARIOS],
        err_down_target_m=ERR_DOWN_TARGET_M, mean_rel_target=MEAN_REL_TARGET, rows=flown,
        learnt_mean=learnt_mean_check(first_cfg, model_check))
