"""What the follower's software knows of its gate: when it commanded it (and, with a servo that
reports its position, whether it closed), and whether it is held, from the motion capture.

A hobby servo does not report its position: the software knows when the servo started (it sent
the command, or its gripper's passive trigger fired) and how long the gate takes to close, nothing
more. Whether the bar is inside cannot be seen either. So when the gate should have closed, the
follower acts as docked (it cuts its thrust and the leader carries it) and watches its measured
height: held by the bar it stays at the docking point; missed, it falls at a fifth of a g and
backs off once it is ``mission.dock_drop_m`` below it (within ``mission.dock_confirm_s``).
"""

from __future__ import annotations

import numpy as np

from aerodock.mission.params import MissionParams
from aerodock.mission.spec import PhaseCode
from aerodock.planning.docking import docking_point_m
from aerodock.world import Observation
from aerodock.world.gripper import GateState, GripperState


class GateCode:
    """The gate states' plain int codes (as :class:`~aerodock.mission.spec.PhaseCode` for the
    phases: a plain int meets an array without NumPy probing its class)."""

    OPEN = int(GateState.OPEN)
    CLOSING = int(GateState.CLOSING)
    CAPTURED = int(GateState.CAPTURED)
    MISSED = int(GateState.MISSED)


def commanded(gripper: GripperState, world_t_s: float, from_truth: bool = False) -> np.ndarray:
    """(n,) the servo has started to close the gate (the software knows it commanded it;
    ``from_truth``: the gate is not open, as the world knows it)."""
    if from_truth:
        return gripper.gate != GateCode.OPEN
    return gripper.servo_start_s <= world_t_s  # nan (never) compares False


def believed_closed(gripper: GripperState, world_t_s: float, close_time_s: float,
                    servo_feedback: bool) -> np.ndarray:
    """(n,) the gate is closed as far as the software knows: the servo's position says so, or,
    without feedback, its nominal travel time since it started has passed."""
    if servo_feedback:
        return (gripper.gate == GateCode.CAPTURED) | (gripper.gate == GateCode.MISSED)
    return gripper.servo_start_s + close_time_s <= world_t_s


def jammed(gripper: GripperState, world_t_s: float, close_time_s: float,
           servo_feedback: bool, travels: float) -> np.ndarray:
    """(n,) a servo that reports its position (or, ``servo_feedback``, a gate whose state the
    mission reads from the world) and has not closed ``travels`` nominal travel times after it
    started (without feedback the software cannot tell)."""
    if not servo_feedback:
        return np.zeros(gripper.gate.shape, dtype=bool)
    return (gripper.gate == GateCode.CLOSING) & (
        world_t_s - gripper.servo_start_s > travels * close_time_s)


def true_outcomes(gripper: GripperState, phase: np.ndarray,
                  active: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(captured now, missed now) read from the world's gate (``mission.gate_state_from =
    "truth"``: the earlier worlds' mission, which knew what its sensors cannot tell)."""
    captured_now = (gripper.gate == GateCode.CAPTURED) & (phase != PhaseCode.CAPTURED) & (
        phase != PhaseCode.DONE)
    return captured_now, (gripper.gate == GateCode.MISSED) & active


def dropped(params: MissionParams, follower: Observation, leader: Observation) -> np.ndarray:
    """(n,) the follower measures itself more than ``dock_drop_m`` below its docked position:
    nothing holds it."""
    docked_at = docking_point_m(leader.p, leader.v, params.geometry)
    return follower.p[:, 2] - docked_at[:, 2] > params.mission.dock_drop_m
