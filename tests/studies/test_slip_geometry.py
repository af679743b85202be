"""studies/slip_throughs.py's reading of a trace: the bar across the gate's mouth and its speed
out of it when the close was commanded, on a hand-made trace."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import numpy as np
import pytest

from aerodock.world.gripper import GateState

STUDIES = Path(__file__).resolve().parents[2] / "studies"


@pytest.fixture(scope="module")
def slip():
    sys.path.insert(0, str(STUDIES))
    try:
        return importlib.import_module("slip_throughs")
    finally:
        sys.path.remove(str(STUDIES))


def test_across_mouth_reads_offset_speed_and_resolution(slip):
    steps, dt = 12, 0.01
    t = np.arange(steps) * dt
    follower = np.zeros((steps, 3, 3))
    bar = np.zeros((steps, 3, 3))
    bar[..., 2] = -0.05  # the bar at the contact arm, 5 cm above the centre (NED)
    yaw = np.zeros((steps, 3))
    # trial 0: a bar along north drifting east (across it) at 0.2 m/s, 3 cm out at period 5
    bar[:, 0, 1] = 0.03 + 0.2 * (t - t[5])
    # trial 1: a bar along east (yaw 90 deg) drifting south: across is -north, moving in
    yaw[:, 1] = np.pi / 2
    bar[:, 1, 0] = 0.02 - 0.1 * (t - t[5])
    gate = np.full((steps, 3), GateState.OPEN)
    gate[5:8, :2] = GateState.CLOSING  # commanded at period 5, resolved after period 7
    gate[8:, 0] = GateState.MISSED
    gate[8:, 1] = GateState.CAPTURED  # trial 2 never closes
    trace = {"t_s": t, "follower_p": follower, "bar_p": bar, "bar_yaw": yaw, "gate": gate}
    first, offset0, outward, offset1 = slip.across_mouth(trace, mount_m=0.05)
    assert list(first) == [5, 5, -1]
    assert offset0[0] == pytest.approx(0.03) and outward[0] == pytest.approx(0.2)
    assert offset1[0] == pytest.approx(0.03 + 0.2 * 3 * dt)  # at period 8
    assert offset0[1] == pytest.approx(-0.02) and outward[1] == pytest.approx(-0.1)
    assert np.isnan(offset0[2]) and np.isnan(outward[2]) and np.isnan(offset1[2])
