"""Aborts: a trial still approaching, its gate not yet commanded, gives up (and its gate is
disarmed) on a timeout, a lost leader or tracking that brings its top towards the leader; or, with
a servo that reports its position, when the gate never finished closing."""

from __future__ import annotations

import numpy as np

from aerodock.geometry import norm_rows
from aerodock.mission.params import MissionParams
from aerodock.mission.spec import AbortCode, PhaseCode, any_true

# A gate still closing this many servo travel times after it was commanded is jammed.
GATE_STUCK_TRAVELS = 4.0


def decide_aborts(params: MissionParams, t_s: float, timeout_s: float, phase: np.ndarray,
                  active: np.ndarray, err_m: np.ndarray, last_fresh_leader_t_s: np.ndarray,
                  gate_commanded: np.ndarray,
                  gate_jammed: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """(abort now (n,), the reason each would have (n,) integer ``AbortCode``s, or None when no
    trial aborts now): of the trials approaching. The reason is meaningful only where ``abort
    now`` is set (elsewhere it reads ``UNSAFE_TRACKING``, the last choice); the caller masks it.

    Args:
        params: the mission's constants.
        t_s, timeout_s: mission time now and when an approach times out.
        phase, active: the phases, and which trials are still approaching.
        err_m: (n, 3) the follower's measured position minus its reference.
        last_fresh_leader_t_s: (n,) when each follower last had a fresh leader state.
        gate_commanded: (n,) the software has commanded the gate to close.
        gate_jammed: (n,) a servo that reports its position has not closed in time.
    """
    m = params.mission
    unsafe = phase == PhaseCode.TERMINAL  # tracking is judged in the terminal phase only
    if any_true(unsafe):
        up_err = -err_m[:, 2]
        unsafe &= ((up_err > m.abort_tracking_m / 2)
                   | ((norm_rows(err_m) > m.abort_tracking_m) & (up_err > 0)))
    leader_lost = (t_s - last_fresh_leader_t_s) > m.leader_lost_s
    timeout = t_s >= timeout_s
    abort_now = active & ((~gate_commanded & (unsafe | leader_lost | timeout)) | gate_jammed)
    if not any_true(abort_now):
        return abort_now, None
    reason = np.where(gate_jammed, AbortCode.GATE_FAULT,
                      np.where(leader_lost, AbortCode.LEADER_LOST,
                               np.where(timeout, AbortCode.TIMEOUT,
                                        AbortCode.UNSAFE_TRACKING)))
    return abort_now, reason
