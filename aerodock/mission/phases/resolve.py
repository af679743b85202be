"""The gate's outcome: captured (post-dock: the leader carries the follower for ``post_dock_s``)
or missed (back off); a trial whose post-dock or back-off time is over is done."""

from __future__ import annotations

import numpy as np

from aerodock.mission.params import MissionParams
from aerodock.mission.spec import Phase
from aerodock.world.gripper import GateState


def gate_outcomes(gate: np.ndarray, phase: np.ndarray,
                  active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(captured now, missed now), each (n,): a gate that has just closed on the bar (in a trial
    not already captured or done), or closed empty while the trial approached."""
    captured_now = (gate == GateState.CAPTURED) & (phase != Phase.CAPTURED) & (
        phase != Phase.DONE)
    missed_now = (gate == GateState.MISSED) & active
    return captured_now, missed_now


def next_phases(phase: np.ndarray, captured_now: np.ndarray, missed_now: np.ndarray,
                abort_now: np.ndarray) -> np.ndarray:
    """(n,) the phases after this period's outcomes (a capture wins over a miss, a miss over an
    abort)."""
    phase = np.where(captured_now, Phase.CAPTURED, phase)
    phase = np.where(missed_now & ~captured_now, Phase.MISSED, phase)
    return np.where(abort_now & ~captured_now & ~missed_now, Phase.ABORT, phase)


def finished(params: MissionParams, phase: np.ndarray, t_s: float,
             phase_t_s: np.ndarray) -> np.ndarray:
    """(n,) trials whose post-dock hold or back-off is over: their missions are done."""
    m = params.mission
    return (((phase == Phase.CAPTURED) & (t_s - phase_t_s >= m.post_dock_s))
            | (((phase == Phase.MISSED) | (phase == Phase.ABORT))
               & (t_s - phase_t_s >= m.backoff_s)))
