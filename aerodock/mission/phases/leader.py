"""The leader's part: its own controller, hovering or cruising north, told of a dock late."""

from __future__ import annotations

import numpy as np

from aerodock.control.controller import ControlOutput, PositionController, Reference
from aerodock.world import Observation


def leader_reference(p0_m: np.ndarray, velocity_mps: np.ndarray, velocity_rows_mps: np.ndarray,
                     t_s: float) -> Reference:
    """The leader's reference at mission time ``t_s``: from ``p0_m`` (n, 3) at the constant
    ``velocity_mps`` (3,) (``velocity_rows_mps``: the same per trial, (n, 3))."""
    n = p0_m.shape[0]
    zero_n = np.zeros(n)
    return Reference(p0_m + velocity_mps * t_s, velocity_rows_mps, np.zeros((n, 3)), zero_n,
                     zero_n)


def leader_command(ctl: PositionController, obs: Observation, ref: Reference,
                   docked_known: np.ndarray, shed_mps2: float) -> ControlOutput:
    """The leader's command: it feeds forward the payload the docked follower sheds
    (``shed_mps2`` down), once the follower's docking status has reached it."""
    n = obs.p.shape[0]
    payload = np.where(docked_known, shed_mps2, 0.0)
    lff = np.stack([np.zeros(n), np.zeros(n), payload], axis=1)
    return ctl.step(obs.p, obs.v, obs.rpy, ref, feedforward_mps2=lff)
