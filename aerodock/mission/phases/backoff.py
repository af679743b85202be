"""Backing off after a miss or an abort: a minimum-jerk plan below and away from the leader,
then holding its end once the trial is done."""

from __future__ import annotations

import numpy as np

from aerodock.mission.params import MissionParams
from aerodock.mission.phases.approach import merge_plans
from aerodock.mission.spec import PhaseCode, any_true
from aerodock.planning.minjerk import MinJerk, minjerk
from aerodock.world import Observation


def start_back_off(params: MissionParams, plan: MinJerk, t_s: float, follower: Observation,
                   leader: Observation, now: np.ndarray) -> MinJerk:
    """The plan with the trials in ``now`` backing off ``backoff_distance_m`` away from the
    leader horizontally and as far down, over ``backoff_s``."""
    if not any_true(now):
        return plan
    m, n = params.mission, now.size
    zeros = np.zeros((n, 3))
    away = follower.p[:, :2] - leader.p[:, :2]
    norm = np.linalg.norm(away, axis=1, keepdims=True)
    away = np.where(norm > 1e-3, away / np.maximum(norm, 1e-9), [1.0, 0.0])
    goal = follower.p + m.backoff_distance_m * np.concatenate([away, np.ones((n, 1))], axis=1)
    back = minjerk(follower.p, follower.v, zeros, goal, zeros, zeros, m.backoff_s, t_s)
    return merge_plans(plan, back, now)


def back_off_reference(plan: MinJerk, t_s: float, phase: np.ndarray, captured: np.ndarray,
                       ref: tuple[np.ndarray, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(p, v, a): the back-off plan for the trials backing off, its end (at rest) for those done
    and not hanging from the bar, ``ref`` for the rest."""
    p_ref, v_ref, a_ref = ref
    if not any_true(phase >= PhaseCode.MISSED):  # none backing off or done: the rest's
        return p_ref, v_ref, a_ref
    backing = (phase == PhaseCode.MISSED) | (phase == PhaseCode.ABORT)
    if any_true(backing):
        pb, vb, ab = plan.sample(t_s)
        p_ref = np.where(backing[:, None], pb, p_ref)
        v_ref = np.where(backing[:, None], vb, v_ref)
        a_ref = np.where(backing[:, None], ab, a_ref)
    done_free = (phase == PhaseCode.DONE) & ~captured
    if any_true(done_free):
        p_ref = np.where(done_free[:, None], plan.pf, p_ref)
        v_ref = np.where(done_free[:, None], 0.0, v_ref)
        a_ref = np.where(done_free[:, None], 0.0, a_ref)
    return p_ref, v_ref, a_ref
