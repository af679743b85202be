"""The Neural-Swarm swap task, simulated (aerodock/collect/swaps.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from aerodock.collect.swaps import (
    SWAP_SEPARATIONS_M,
    goto_profile,
    swap_reference,
    swap_schedule,
    swap_task_flights,
)
from aerodock.config import load_config

ROOT = Path(__file__).resolve().parents[2]


def test_goto_profile_is_the_firmware_rest_to_rest_polynomial():
    tau = np.linspace(0.0, 1.0, 2001)
    s, ds, dds = goto_profile(tau)
    assert s[0] == 0.0 and s[-1] == pytest.approx(1.0, abs=1e-12)
    for end in (0, -1):  # at rest at both ends: velocity and acceleration zero
        assert ds[end] == pytest.approx(0.0, abs=1e-12)
        assert dds[end] == pytest.approx(0.0, abs=1e-12)
    # the derivatives are the polynomial's (central differences)
    h = tau[1] - tau[0]
    assert np.allclose(np.gradient(s, h)[1:-1], ds[1:-1], atol=1e-5)
    assert np.allclose(np.gradient(ds, h)[1:-1], dds[1:-1], atol=1e-4)
    # a 7th-order jerk-free segment peaks at 35/16 of the mean speed, at mid-time
    assert ds.max() == pytest.approx(35.0 / 16.0, rel=1e-9)
    assert tau[np.argmax(ds)] == pytest.approx(0.5)
    assert np.all(np.diff(s) >= 0.0)
    # outside 0..1 it holds the ends
    assert goto_profile(np.array([-1.0, 2.0]))[0].tolist() == [0.0, 1.0]


def test_schedule_flies_each_swap_time_there_and_back():
    sched = swap_schedule((4.0, 3.0, 2.0), 0.1)
    assert [(d, out) for _, d, out in sched] == [(4.0, True), (4.0, False), (3.0, True),
                                                  (3.0, False), (2.0, True), (2.0, False)]
    starts = [s for s, _, _ in sched]
    assert starts == pytest.approx([0.0, 4.1, 8.2, 11.3, 14.4, 16.5])


def test_reference_crosses_the_centre_at_mid_swap():
    home = np.array([[0.25, 0.0, -2.0], [0.0, -0.25, -1.7]])
    away = -home * np.array([1.0, 1.0, -1.0])  # the opposite point, same height
    sched = swap_schedule((2.0,), 0.1)
    at = swap_reference(0.0, home, away, sched)
    assert np.array_equal(at.p, home) and not at.v.any()
    mid = swap_reference(1.0, home, away, sched)
    assert np.allclose(mid.p[:, :2], 0.0, atol=1e-12)  # both on the axis at once
    assert np.allclose(np.linalg.norm(mid.v[:, :2], axis=1), 35.0 / 16.0 * 0.5 / 2.0)
    assert np.allclose(swap_reference(2.05, home, away, sched).p, away)  # the pause
    back = swap_reference(3.1, home, away, sched)  # mid-way home: moving the other way
    assert np.allclose(back.v, -mid.v)
    assert np.allclose(swap_reference(9.0, home, away, sched).p, home)
    # the acceleration is the velocity's rate
    dt = 1e-4
    a_num = (swap_reference(0.7 + dt, home, away, sched).v
             - swap_reference(0.7 - dt, home, away, sched).v) / (2 * dt)
    assert np.allclose(swap_reference(0.7, home, away, sched).a, a_num, atol=1e-5)


def test_swap_flights_fly_the_task_in_the_world():
    cfg = load_config(ROOT / "examples" / "crazyflie.toml").with_overrides(
        {"curriculum": {"label_basis": "thrust"}})
    sep = SWAP_SEPARATIONS_M[("small", "small")]
    logs = swap_task_flights(cfg, 3, sep, seed=4, free_air_radius_m=0.2, times_s=(2.0,))
    assert len(logs) == 3
    for log in logs:
        assert log.meta["task"] == "swap" and log.meta["free_air_radius_m"] == 0.2
        assert sep[0] <= log.meta["separation_m"] <= sep[1]
        dp = log.follower_pos_m - log.leader_pos_m
        horizontal = np.hypot(dp[:, 0], dp[:, 1])
        # the follower passes under the leader at the separation drawn, and both move
        assert horizontal.min() < 0.06
        assert np.median(dp[:, 2]) == pytest.approx(log.meta["separation_m"], abs=0.03)
        for vel in (log.leader_vel_mps, log.follower_vel_mps):
            assert np.linalg.norm(vel[:, :2], axis=1).max() > 0.3
    # free air for the labels' bias where the two circles' angles differ enough (the rest
    # take the pooled bias, as real swaps do)
    assert any(np.hypot(*(lg.follower_pos_m - lg.leader_pos_m)[:, :2].T).max() > 0.2
               for lg in logs)
    # each flight draws its own headings: the vehicles' velocities are not alike
    cos = []
    for log in logs:
        va, vb = log.leader_vel_mps[:, :2], log.follower_vel_mps[:, :2]
        fast = (np.linalg.norm(va, axis=1) > 0.2) & (np.linalg.norm(vb, axis=1) > 0.2)
        cos.append(np.median(np.sum(va[fast] * vb[fast], axis=1)
                             / np.linalg.norm(va[fast], axis=1)
                             / np.linalg.norm(vb[fast], axis=1)))
    assert np.ptp(cos) > 0.3


@pytest.mark.parametrize("kwargs, message", [
    ({"n_flights": 0}, "at least one flight"),
    ({"separation_m": (0.3, 0.2)}, "separation range"),
    ({"separation_m": (0.0, 0.2)}, "separation range"),
    ({"radius_m": 0.0}, "must be positive"),
    ({"times_s": (2.0, -1.0)}, "must be positive"),
])
def test_swap_flights_refuse_bad_arguments(kwargs, message):
    cfg = load_config(ROOT / "examples" / "crazyflie.toml")
    args = {"n_flights": 1, "separation_m": (0.2, 0.3), "seed": 0, "free_air_radius_m": 0.2,
            **kwargs}
    with pytest.raises(ValueError, match=message):
        swap_task_flights(cfg, **args)
