"""The approach: a minimum-jerk plan to the predicted docking point at the horizon, re-planned
when the prediction moves, optionally ending in a vertical rise (``planner.rise_m``)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from aerodock.geometry import norm_rows
from aerodock.mission.params import MissionParams
from aerodock.mission.spec import any_true
from aerodock.planning.docking import docking_point_m
from aerodock.planning.minjerk import MinJerk, minjerk
from aerodock.world import Observation

# Re-planning stops this long before the plan ends (a last-moment plan is all jerk).
REPLAN_STOP_S = 0.3


@dataclass(frozen=True)
class ApproachShape:
    """The approach's shape: the plan ends ``rise_m`` below the docking point at ``plan_end_s``,
    then a vertical rise reaches it at ``arrival_s`` (``rise_m = 0``: the paper's single
    minimum-jerk approach, ``plan_end_s = arrival_s``)."""

    arrival_s: float
    plan_end_s: float
    rise_m: float
    below_m: np.ndarray  # (3,) (0, 0, rise_m)

    @classmethod
    def of(cls, params: MissionParams, arrival_s: float) -> ApproachShape:
        """The shape ``params``'s planner gives for an arrival at ``arrival_s``."""
        rise_m = float(params.planner.rise_m)
        plan_end_s = arrival_s - (params.planner.rise_s if rise_m > 0 else 0.0)
        return cls(arrival_s, plan_end_s, rise_m, np.array([0.0, 0.0, rise_m]))


def first_plan(params: MissionParams, shape: ApproachShape, start_m: np.ndarray,
               leader_p0_m: np.ndarray, leader_v_mps: np.ndarray) -> MinJerk:
    """The plan at t = 0: from the follower's start, moving with the leader, to the docking point
    the leader's start and velocity predict for the plan's end."""
    zeros = np.zeros_like(start_m)
    goal = docking_point_m(leader_p0_m, leader_v_mps, params.geometry, shape.plan_end_s)
    return minjerk(start_m, leader_v_mps, zeros, goal + shape.below_m, leader_v_mps, zeros,
                   shape.plan_end_s, 0.0)


def merge_plans(old: MinJerk, new: MinJerk, mask: np.ndarray) -> MinJerk:
    """Per-trial choice between two plans (``new`` where ``mask``)."""
    if not any_true(~mask):
        return new
    rows, rows3 = mask[:, None], mask[:, None, None]
    return MinJerk(coeffs=np.where(rows3, new.coeffs, old.coeffs),
                   t0_s=np.where(mask, new.t0_s, old.t0_s),
                   duration_s=np.where(mask, new.duration_s, old.duration_s),
                   p0=np.where(rows, new.p0, old.p0), v0=np.where(rows, new.v0, old.v0),
                   a0=np.where(rows, new.a0, old.a0), pf=np.where(rows, new.pf, old.pf),
                   vf=np.where(rows, new.vf, old.vf))


def replan(params: MissionParams, shape: ApproachShape, plan: MinJerk, t_s: float,
           leader: Observation, active: np.ndarray) -> MinJerk:
    """The plan of the trials still approaching whose predicted docking point moved more than
    ``planner.replan_threshold_m``: a new minimum-jerk plan from where the old one is now."""
    if not t_s < shape.plan_end_s - REPLAN_STOP_S:
        return plan
    horizon = shape.plan_end_s - t_s
    target = docking_point_m(leader.p, leader.v, params.geometry, horizon) + shape.below_m
    moved = norm_rows(target - plan.pf) > params.planner.replan_threshold_m
    need = active & moved
    if not any_true(need):
        return plan
    p_r, v_r, a_r = plan.sample(t_s)
    zeros = np.zeros_like(target)
    new = minjerk(p_r, v_r, a_r, target, leader.v, zeros, horizon, t_s)
    return merge_plans(plan, new, need)


def approach_reference(shape: ApproachShape, plan: MinJerk, t_s: float, active: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(p, v, a) of the approach at ``t_s``: the plan, then the vertical rise (minimum jerk, rest
    to rest relative to the leader) once the plan has ended."""
    p_ref, v_ref, a_ref = plan.sample(t_s)
    if shape.rise_m > 0 and t_s > shape.plan_end_s:
        rise_s = shape.arrival_s - shape.plan_end_s
        s_, ds, dds = minjerk_unit(min(1.0, (t_s - shape.plan_end_s) / rise_s))
        rising = active[:, None] & np.array([False, False, True])
        p_ref = np.where(rising, p_ref - shape.rise_m * s_, p_ref)
        v_ref = np.where(rising, v_ref - shape.rise_m * ds / rise_s, v_ref)
        a_ref = np.where(rising, a_ref - shape.rise_m * dds / rise_s**2, a_ref)
    return p_ref, v_ref, a_ref


def minjerk_unit(x: float) -> tuple[float, float, float]:
    """Rest-to-rest minimum-jerk profile on [0, 1]: (s, ds/dx, d2s/dx2) at ``x``."""
    return (10 * x**3 - 15 * x**4 + 6 * x**5, 30 * x**2 - 60 * x**3 + 30 * x**4,
            60 * x - 180 * x**2 + 120 * x**3)
