"""The active trigger: the software closes the gate when it predicts the bar well inside it at
the moment the gate will have closed (the known latencies compensated)."""

from __future__ import annotations

import numpy as np

from aerodock.mission.spec import any_true
from aerodock.planning.docking import DockGeometry
from aerodock.world import Observation
from aerodock.world.gripper import GripperParams

# Margins of the prediction, as fractions of the gate: laterally within this much of the half
# aperture, vertically below this much of the gate's height.
LATERAL_MARGIN = 0.6
HEIGHT_MARGIN = 0.7


def active_close_command(follower: Observation, leader: Observation, geom: DockGeometry,
                         gp: GripperParams, t_s: float, active_at_s: float,
                         active: np.ndarray) -> np.ndarray:
    """(n,) bool: command the gate to close now (trials approaching, from ``active_at_s``)."""
    if not (t_s >= active_at_s and any_true(active)):  # no prediction needed
        return np.zeros(active.shape, dtype=bool)
    return active & bar_will_be_inside(
        follower, leader, geom, gp, gp.latency_s + gp.close_time_s)


def bar_will_be_inside(follower: Observation, leader: Observation, geom: DockGeometry,
                       gp: GripperParams, lead_time_s: float) -> np.ndarray:
    """Will the (predicted) bar sit well inside the gate ``lead_time_s`` from now?

    The follower cannot see the bar; it predicts it from the leader's state (hanging straight
    down) and extrapolates both vehicles by ``lead_time_s`` (software latency + servo travel).
    Margins keep it away from the gate's edges.
    """
    rel_v = leader.v - follower.v
    bar = leader.p + geom.bar_below_leader_m
    arm = follower.p - follower.R[:, :, 2] * gp.mount_height_m
    rel = bar - arm + rel_v * lead_time_s
    height = -rel[:, 2]
    # the horizontal distance (np.linalg.norm of the two columns' numbers, without its wrapper)
    lateral = np.sqrt(rel[:, 0] * rel[:, 0] + rel[:, 1] * rel[:, 1])
    return (lateral < LATERAL_MARGIN * gp.aperture_m / 2) & (height > -gp.bar_radius_m) & (
        height < HEIGHT_MARGIN * gp.gate_height_m)
