"""The gate's outcome as the follower senses it (:mod:`aerodock.mission.phases.gate_sensing`):
docked once the gate is believed closed (post-dock: the leader carries the follower for
``post_dock_s``), missed if it then falls away (back off); a trial whose post-dock or back-off
time is over is done."""

from __future__ import annotations

import numpy as np

from aerodock.mission.params import MissionParams
from aerodock.mission.spec import PhaseCode, any_true


def gate_outcomes(closed: np.ndarray, dropped: np.ndarray, phase: np.ndarray,
                  active: np.ndarray, t_s: float, phase_t_s: np.ndarray,
                  confirm_s: float) -> tuple[np.ndarray, np.ndarray]:
    """(docked now, missed now), each (n,): an approaching trial whose gate is believed closed
    acts as docked; a trial docked less than ``confirm_s`` ago that has dropped away missed."""
    captured_now = closed & active
    missed_now = (phase == PhaseCode.CAPTURED) & (t_s - phase_t_s < confirm_s) & dropped
    return captured_now, missed_now


def next_phases(phase: np.ndarray, captured_now: np.ndarray, missed_now: np.ndarray,
                abort_now: np.ndarray) -> np.ndarray:
    """(n,) the phases after this period's outcomes (a capture wins over a miss, a miss over an
    abort)."""
    if not any_true(captured_now | missed_now | abort_now):
        return phase
    phase = np.where(captured_now, PhaseCode.CAPTURED, phase)
    phase = np.where(missed_now & ~captured_now, PhaseCode.MISSED, phase)
    return np.where(abort_now & ~captured_now & ~missed_now, PhaseCode.ABORT, phase)


def finished(params: MissionParams, phase: np.ndarray, t_s: float,
             phase_t_s: np.ndarray) -> np.ndarray:
    """(n,) trials whose post-dock hold or back-off is over: their missions are done."""
    m = params.mission
    elapsed_s = t_s - phase_t_s
    return (((phase == PhaseCode.CAPTURED) & (elapsed_s >= m.post_dock_s))
            | (((phase == PhaseCode.MISSED) | (phase == PhaseCode.ABORT))
               & (elapsed_s >= m.backoff_s)))
