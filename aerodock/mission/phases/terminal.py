"""The terminal phase: stiffer gains and armed triggers from ``terminal_s`` before arrival, then
holding at the docking point; the reference never brings the follower's top near the leader."""

from __future__ import annotations

import numpy as np

from aerodock.mission.params import MissionParams
from aerodock.mission.spec import PhaseCode, any_true
from aerodock.planning.docking import docking_point_m
from aerodock.world import Observation

# The reference keeps the follower's top a margin beyond the clearance below the leader: 0.05 m
# at the default clearance of 0.12 m, in proportion to the clearance otherwise (so it scales with
# the vehicle; written so that it is exactly 0.05 m at the default).
CLEARANCE_MARGIN_M = 0.05
DEFAULT_CLEARANCE_M = 0.12


def enter_terminal(phase: np.ndarray, t_s: float, arrival_s: float,
                   terminal_s: float) -> np.ndarray:
    """(n,) the phases with approaching trials switched to ``TERMINAL`` ``terminal_s`` before
    arrival."""
    if not t_s >= arrival_s - terminal_s:
        return phase
    return np.where((phase == PhaseCode.APPROACH) & (t_s >= arrival_s - terminal_s),
                    PhaseCode.TERMINAL, phase).astype(np.int8)


def hold_at_docking_point(params: MissionParams, ref: tuple[np.ndarray, ...], leader: Observation,
                          holding: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(p, v, a) with the holding trials (past arrival, still approaching) at the docking point
    the leader's state predicts now, moving with it."""
    p_ref, v_ref, a_ref = ref
    if not any_true(holding):
        return p_ref, v_ref, a_ref
    target_now = docking_point_m(leader.p, leader.v, params.geometry)
    p_ref = np.where(holding[:, None], target_now, p_ref)
    v_ref = np.where(holding[:, None], leader.v, v_ref)
    a_ref = np.where(holding[:, None], 0.0, a_ref)
    return p_ref, v_ref, a_ref


def keep_clear(params: MissionParams, p_ref: np.ndarray, leader: Observation,
               active: np.ndarray, mount_height_m: float) -> np.ndarray:
    """``p_ref`` with the approaching trials' reference kept ``clearance_m`` plus a margin
    (:data:`CLEARANCE_MARGIN_M` per :data:`DEFAULT_CLEARANCE_M` of it) below the leader (the
    follower's top is its contact arm, ``mount_height_m`` above its centre)."""
    clearance_m = params.mission.clearance_m
    margin_m = CLEARANCE_MARGIN_M * (clearance_m / DEFAULT_CLEARANCE_M)
    top_limit = leader.p[:, 2] + clearance_m + margin_m + mount_height_m
    p_ref = p_ref.copy()
    p_ref[:, 2] = np.where(active, np.maximum(p_ref[:, 2], top_limit), p_ref[:, 2])
    return p_ref
