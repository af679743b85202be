"""The labels' noise by the follower's speed (aerodock/identify/label_noise.py): a synthetic
flight whose label noise grows with speed and whose wake has no turbulence, and the real
flights."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.config import load_config
from aerodock.downwash.base import BodyState
from aerodock.flightlog import FlightLog
from aerodock.geometry import GRAVITY_MPS2, rotmat_to_quat
from aerodock.identify import flights as fl
from aerodock.identify import wake_fit as wf
from aerodock.identify.label_noise import (
    noise_by_speed,
    speed_matched_turbulence,
    with_speed_noise,
)

MASS, ROTOR, DIAGONAL = 0.032, 0.0225, 0.092


def _flight(params: dict, seed: int) -> FlightLog:
    """Slow and fast stretches in free air, then fast passes under a hovering leader; the label
    is the still jet's mean plus noise of sd 0.05 + 0.3 * speed on every axis."""
    rate, rng = 100.0, np.random.default_rng(seed)
    def stretch(start, speed_x, n):  # (n, 3) positions and velocities along x
        t = np.arange(n) / rate
        p = np.column_stack([start[0] + speed_x * t, np.full(n, start[1]), np.full(n, start[2])])
        return p, np.tile([speed_x, 0.0, 0.0], (n, 1))

    parts = [stretch((0.0, 3.0, 0.3), 0.05, 1000), stretch((0.0, -3.0, 0.3), 0.6, 500)]
    for k in range(12):  # passes under the leader, back and forth
        parts.append(stretch((-0.1, 0.0, 0.3), 0.6, 34) if k % 2 == 0
                     else stretch((0.1, 0.0, 0.3), -0.6, 34))
    pos = np.concatenate([p for p, _ in parts])
    vel = np.concatenate([v for _, v in parts])
    n = pos.shape[0]
    eye = np.repeat(np.eye(3)[None], n, axis=0)
    jet = wf.build_jet(params, {"leader_rotor_radius_m": ROTOR, "leader_n_rotors": 4,
                                "follower_rotor_radius_m": ROTOR, "follower_n_rotors": 4,
                                "follower_diagonal_m": DIAGONAL})
    leader = BodyState(np.zeros((n, 3)), np.zeros((n, 3)), eye, np.full(n, MASS * GRAVITY_MPS2),
                       np.full(n, MASS))
    follower = BodyState(pos, vel, eye, np.full(n, MASS * GRAVITY_MPS2), np.full(n, MASS))
    speed = np.linalg.norm(vel, axis=1)
    obs = jet.mean_acceleration(leader, follower) + rng.normal(size=(n, 3)) * (
        0.05 + 0.3 * speed)[:, None]
    quat = np.tile(rotmat_to_quat(np.eye(3)), (n, 1))
    return FlightLog(
        t_s=np.arange(n) / rate, leader_pos_m=np.zeros((n, 3)), leader_vel_mps=np.zeros((n, 3)),
        leader_quat=quat, follower_pos_m=pos, follower_vel_mps=vel, follower_quat=quat,
        follower_cmd_accel_mps2=np.zeros((n, 3)), follower_thrust_n=np.full(n, MASS * 9.81),
        follower_obs_accel_mps2=obs,
        meta={"name": f"synth_{seed}_cf1", "source": "synthetic", "frame": "NED",
              "label_basis": "command", "leader_mass_kg": MASS, "follower_mass_kg": MASS,
              "leader_rotor_radius_m": ROTOR, "follower_rotor_radius_m": ROTOR,
              "leader_n_rotors": 4, "follower_n_rotors": 4, "leader_diagonal_m": DIAGONAL,
              "follower_diagonal_m": DIAGONAL, "leader_id": "cf2", "follower_id": "cf1"})


def test_speed_matched_noise_reads_no_turbulence_where_there_is_none():
    """The wake has no turbulence; the pooled free-air noise (mostly slow) reads the fast
    passes' extra noise as turbulence, the noise at the follower's speed does not."""
    cfg = load_config()
    params = {k: float(cfg.downwash.params[k]) for k in wf.FITTED_PARAMS}
    params.update(turb_vertical=0.0, turb_lateral=0.0)
    logs = [_flight(params, seed) for seed in range(4)]
    noise = noise_by_speed(logs)
    table = noise["cf1"]
    slow, fast = table.at(np.array([0.05, 0.6]))
    assert fast[0] > 4 * slow[0]  # the noise grows with speed, per axis
    np.testing.assert_allclose(np.sqrt(fast), 0.05 + 0.3 * 0.6, rtol=0.15)
    rows = speed_matched_turbulence(params, fl.prepare_flights(logs), noise, bootstrap=50)
    (row,) = rows.values()
    assert row["lateral_pooled"] > 0.1 and row["vertical_pooled"] > 0.1  # spurious
    assert row["lateral_speed"] < 0.08 and row["vertical_speed"] < 0.08
    assert row["lateral_model"] == 0.0 and row["vertical_model"] == 0.0


def test_the_fit_above_the_noise_at_speed_finds_no_turbulence_where_there_is_none():
    """`field fit --noise speed`: each sample carries the noise at its speed, so the fit's
    turbulence intensities, which the pooled noise inflates, come out near the wake's zero; a
    flight whose follower has no noise table keeps the pooled noise."""
    cfg = load_config()
    params = {k: float(cfg.downwash.params[k]) for k in wf.FITTED_PARAMS}
    params.update(turb_vertical=0.0, turb_lateral=0.0)
    logs = [_flight(params, seed) for seed in range(4)]
    noise = noise_by_speed(logs)
    flights = fl.prepare_flights(logs)
    matched = with_speed_noise(flights, noise)
    for f, g in zip(flights, matched, strict=True):
        assert f.noise_var_mps4 is None
        np.testing.assert_array_equal(
            g.sample_noise_var_mps4, noise["cf1"].at(np.linalg.norm(f.follower.v, axis=1)))
    assert with_speed_noise(flights, {})[0].noise_var_mps4 is None
    pooled = wf.fit_turbulence(params, flights)
    speed = wf.fit_turbulence(params, matched)
    # the pooled reading puts turbulence into a wake that has none
    assert pooled["turb_lateral"] > 0.03 and pooled["turb_vertical"] > 0.03, pooled
    assert speed["turb_lateral"] < 0.3 * pooled["turb_lateral"], (speed, pooled)
    # (measured: lateral 0.059 -> 0.000, vertical 0.064 -> 0.027; the rest of the vertical is
    # the noise table's speed bins, 0.1 m/s wide)
    assert speed["turb_vertical"] < 0.5 * pooled["turb_vertical"], (speed, pooled)


def test_real_lateral_turbulence_under_the_small_leader_is_within_the_noise(shared_data):
    """On the real flights the free-air label noise grows with the follower's speed, and read
    above it the lateral turbulence under the small leader (32 g under 32 g, held out) is far
    below the jet's, while the vertical stays within 20 % of the fit's pooled reading
    (docs/world.md)."""
    import tomllib
    from pathlib import Path

    from aerodock.experiments.swap_flights import read_swap_flights

    logs = read_swap_flights(shared_data("neural-swarm"))
    fitted = Path(__file__).resolve().parents[2] / "examples" / "crazyflie_wake_fitted.toml"
    params = tomllib.loads(fitted.read_text())["downwash"]["params"]
    noise = noise_by_speed(logs)
    for table in noise.values():
        slow, fast = table.at(np.array([0.05, 0.45]))
        assert 0.5 * (fast[0] + fast[1]) > 1.3 * 0.5 * (slow[0] + slow[1])
    _, held = fl.select_flights(fl.prepare_flights(logs), ["swap_ss_0[56]"])
    (row,) = speed_matched_turbulence(params, held, noise, bootstrap=50).values()
    assert row["lateral_speed"] < row["lateral_pooled"]
    assert row["lateral_speed_p95"] < 0.6 * row["lateral_model"]
    assert row["vertical_speed"] == pytest.approx(row["vertical_pooled"], rel=0.2)
