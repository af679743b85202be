"""A docking campaign's set-up (:class:`MissionSpec`) and the per-trial phases and abort reasons."""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from aerodock.control.compensation import Compensation
from aerodock.mission.faults import Fault


class Phase(IntEnum):
    """Per-trial mission phase."""

    APPROACH = 0
    TERMINAL = 1
    CAPTURED = 2
    MISSED = 3
    ABORT = 4
    DONE = 5


class PhaseCode:
    """The phases' plain int codes, for the arithmetic on (n,) int8 phase arrays each control
    period (``phase == PhaseCode.DONE``). NumPy looks an IntEnum member's class up for its array
    protocols each time the member meets an array (a few µs a use on Python 3.11), a plain int
    it takes at once: the comparisons give the same booleans, the selections the same codes.
    In their order, the approaching phases (``APPROACH``, ``TERMINAL``) come first and the
    phases after a miss (``MISSED``, ``ABORT``, ``DONE``) last."""

    APPROACH = int(Phase.APPROACH)
    TERMINAL = int(Phase.TERMINAL)
    CAPTURED = int(Phase.CAPTURED)
    MISSED = int(Phase.MISSED)
    ABORT = int(Phase.ABORT)
    DONE = int(Phase.DONE)


def any_true(mask: np.ndarray) -> bool:
    """Whether any entry of the boolean array ``mask`` is set: ``mask.any()`` without the
    method's Python-level wrapper (a quarter of its cost on the (n,) masks the mission checks a
    dozen times a control period, to skip the updates nothing needs)."""
    return np.count_nonzero(mask) > 0


class AbortReason(IntEnum):
    """Why a trial aborted (0: it did not)."""

    NONE = 0
    TIMEOUT = 1
    LEADER_LOST = 2
    UNSAFE_TRACKING = 3
    GATE_FAULT = 4  # the gate did not finish closing long after it was commanded


class AbortCode:
    """The abort reasons' plain int codes (as :class:`PhaseCode` for the phases)."""

    NONE = int(AbortReason.NONE)
    TIMEOUT = int(AbortReason.TIMEOUT)
    LEADER_LOST = int(AbortReason.LEADER_LOST)
    UNSAFE_TRACKING = int(AbortReason.UNSAFE_TRACKING)
    GATE_FAULT = int(AbortReason.GATE_FAULT)


@dataclass(frozen=True)
class MissionSpec:
    """One campaign's set-up."""

    trials: int = 50
    offset_m: float | None = None  # cable length d_p (None: config's platform.cable_length_m)
    leader_speed_mps: float = 0.0
    leader_turn_rate_radps: float = 0.0  # a moving leader's path bends at this rate from t = 0
    leader_fixed: bool = False
    compensation: Compensation = Compensation.OBSERVER
    seed: int = 0
    first_trial: int = 0  # trial i draws from stream (seed, first_trial + i)
    start_azimuths_deg: tuple[float, ...] = (0.0, 90.0, 180.0, 270.0)
    leader_dropout_s: tuple[float, float] | None = None  # (start, duration): leader state lost
    faults: tuple[Fault, ...] = ()  # injected faults (aerodock.mission.faults), drawn per trial
    passive_trigger: bool | tuple[bool, ...] = True  # armed in every trial, or one flag per trial
    active_trigger: bool | tuple[bool, ...] = True

    @property
    def moving(self) -> bool:
        """The leader cruises (it is neither hovering nor on a stand)."""
        return self.leader_speed_mps != 0.0 and not self.leader_fixed
