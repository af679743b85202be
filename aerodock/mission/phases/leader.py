"""The leader's part: its own controller, hovering or cruising north, told of a dock late."""

from __future__ import annotations

import numpy as np

from aerodock.control.controller import ControlOutput, PositionController, Reference
from aerodock.world import Observation


def leader_reference(p0_m: np.ndarray, velocity_mps: np.ndarray, velocity_rows_mps: np.ndarray,
                     t_s: float, turn_rate_radps: float = 0.0) -> Reference:
    """The leader's reference at mission time ``t_s``: from ``p0_m`` (n, 3) at the constant
    ``velocity_mps`` (3,) (``velocity_rows_mps``: the same per trial, (n, 3)); with
    ``turn_rate_radps`` its path bends into a level arc from t = 0 on (same speed, its velocity
    turning at that rate; the leader keeps its heading, as a multirotor may)."""
    n = p0_m.shape[0]
    zero_n = np.zeros(n)
    if turn_rate_radps == 0.0 or t_s <= 0.0:
        return Reference(p0_m + velocity_mps * t_s, velocity_rows_mps, np.zeros((n, 3)),
                         zero_n, zero_n)
    w, angle = turn_rate_radps, turn_rate_radps * t_s
    c, s = np.cos(angle), np.sin(angle)
    vx, vy = velocity_mps[0], velocity_mps[1]
    # v(t) = Rz(w t) v0; p(t) = p0 + integral of v; a(t) = w ez x v(t).
    vel = np.array([c * vx - s * vy, s * vx + c * vy, velocity_mps[2]])
    shift = np.array([(s * vx - (1.0 - c) * vy) / w, ((1.0 - c) * vx + s * vy) / w,
                      velocity_mps[2] * t_s])
    accel = np.array([-w * vel[1], w * vel[0], 0.0])
    return Reference(p0_m + shift, np.tile(vel, (n, 1)), np.tile(accel, (n, 1)), zero_n,
                     zero_n)


def leader_command(ctl: PositionController, obs: Observation, ref: Reference,
                   docked_known: np.ndarray, shed_mps2: float) -> ControlOutput:
    """The leader's command: it feeds forward the payload the docked follower sheds
    (``shed_mps2`` down), once the follower's docking status has reached it."""
    n = obs.p.shape[0]
    lff = np.zeros((n, 3))
    lff[:, 2] = np.where(docked_known, shed_mps2, 0.0)
    return ctl.step(obs.p, obs.v, obs.rpy, ref, feedforward_mps2=lff)
