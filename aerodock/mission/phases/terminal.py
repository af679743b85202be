"""The terminal phase: stiffer gains and armed triggers from ``terminal_s`` before arrival, then
holding at the docking point; the reference never brings the follower's top near the leader."""

from __future__ import annotations

import numpy as np

from aerodock.mission.params import MissionParams
from aerodock.mission.spec import Phase
from aerodock.planning.docking import docking_point_m
from aerodock.world import Observation

# The reference keeps the follower's top this far beyond the clearance below the leader, m.
CLEARANCE_MARGIN_M = 0.05


def enter_terminal(phase: np.ndarray, t_s: float, arrival_s: float,
                   terminal_s: float) -> np.ndarray:
    """(n,) the phases with approaching trials switched to ``TERMINAL`` ``terminal_s`` before
    arrival."""
    return np.where((phase == Phase.APPROACH) & (t_s >= arrival_s - terminal_s),
                    Phase.TERMINAL, phase).astype(np.int8)


def hold_at_docking_point(params: MissionParams, ref: tuple[np.ndarray, ...], leader: Observation,
                          holding: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(p, v, a) with the holding trials (past arrival, still approaching) at the docking point
    the leader's state predicts now, moving with it."""
    p_ref, v_ref, a_ref = ref
    target_now = docking_point_m(leader.p, leader.v, params.geometry)
    p_ref = np.where(holding[:, None], target_now, p_ref)
    v_ref = np.where(holding[:, None], leader.v, v_ref)
    a_ref = np.where(holding[:, None], 0.0, a_ref)
    return p_ref, v_ref, a_ref


def keep_clear(params: MissionParams, p_ref: np.ndarray, leader: Observation,
               active: np.ndarray, mount_height_m: float) -> np.ndarray:
    """``p_ref`` with the approaching trials' reference kept ``clearance_m`` plus a margin below
    the leader (the follower's top is its contact arm, ``mount_height_m`` above its centre)."""
    top_limit = (leader.p[:, 2] + params.mission.clearance_m + CLEARANCE_MARGIN_M
                 + mount_height_m)
    p_ref = p_ref.copy()
    p_ref[:, 2] = np.where(active, np.maximum(p_ref[:, 2], top_limit), p_ref[:, 2])
    return p_ref
