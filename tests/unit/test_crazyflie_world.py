"""The Crazyflie worlds of examples/ and the scale-dependent figures derived from the config.

The worlds load and fly; the two files agree outside what tells the pairs apart; every length
the code used to hold at the paper's scale is the default's figure on the default world and
follows the vehicle on another.
"""

from __future__ import annotations

import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from aerodock.collect.curriculum import (
    bar_out_of_the_way,
    excitation_flights,
    label_free_air_radius_m,
)
from aerodock.config import load_config
from aerodock.control.profiles import PAPER_Q_DIAG, controller_config, scaled_weights
from aerodock.downwash import build_field
from aerodock.downwash.probe import probe_bodies
from aerodock.flightlog import FlightLog
from aerodock.learning.labels import FREE_AIR_RADIUS_M, free_air_radius_of
from aerodock.mission import MissionSpec, run_campaign
from aerodock.world.platform import rotor_strike

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SMALL = EXAMPLES / "crazyflie.toml"
SMALL_LARGE = EXAMPLES / "crazyflie_small_under_large.toml"
LARGE_SMALL = EXAMPLES / "crazyflie_large_under_small.toml"


@pytest.fixture(scope="module")
def cf():
    return load_config(SMALL)


@pytest.fixture(scope="module")
def cf_sl():
    return load_config(SMALL_LARGE)


def test_the_two_worlds_differ_only_in_the_leader():
    """Both fly the wake fitted to the real flights: its parameters are dimensionless, and the
    leader's rotors (and thrust) set its scales."""
    small, pair = tomllib.loads(SMALL.read_text()), tomllib.loads(SMALL_LARGE.read_text())
    assert "leader" not in small
    assert pair["leader"]["mass_kg"] > small["vehicle"]["mass_kg"]
    for name in set(small) | set(pair):
        if name in ("leader", "leader_autopilot"):
            continue
        assert small[name] == pair[name], name


def test_the_large_follower_world_is_the_small_pair_turned_round():
    """examples/crazyflie_large_under_small.toml: the large vehicle of the small-under-large
    world follows, the small one leads, each with its own autopilot; the rest is the small
    world's."""
    small, pair = tomllib.loads(SMALL.read_text()), tomllib.loads(SMALL_LARGE.read_text())
    turned = tomllib.loads(LARGE_SMALL.read_text())
    roles = {"vehicle", "leader", "autopilot", "leader_autopilot"}
    for name in set(small) | set(turned):
        if name not in roles:
            assert small[name] == turned[name], name
    assert turned["vehicle"] == {**small["vehicle"], **pair["leader"],
                                 **{k: v for k, v in turned["vehicle"].items()
                                    if k not in pair["leader"]}}
    for key, value in pair["leader"].items():
        assert turned["vehicle"][key] == value, key
    assert turned["leader"] == {k: v for k, v in small["vehicle"].items() if k != "model"}
    cfg = load_config(LARGE_SMALL)
    assert cfg.autopilot == load_config(SMALL_LARGE).leader_autopilot
    assert cfg.leader_autopilot == load_config(SMALL).autopilot
    assert cfg.vehicle.mass_kg == 0.067 and cfg.leader.mass_kg == 0.032
    # a world for wake flights (the sim-to-real check's), not yet for docking (its header)
    from aerodock.experiments.sim_to_real import simulated_flights

    logs = simulated_flights(cfg, flights_per_band=1, bands=(0,))
    assert logs and all(np.isfinite(lg.follower_obs_accel_mps2).all() for lg in logs)
    below = np.concatenate([lg.follower_pos_m[:, 2] - lg.leader_pos_m[:, 2] for lg in logs])
    assert below.max() > 0.05  # the follower flies under the leader


def test_the_jet_takes_the_leaders_rotors(cf, cf_sl):
    """A larger leader's disk at the same thrust makes a slower, wider wake (momentum theory:
    the same flux over a wider jet); with the leader's rotors equal to the follower's nothing
    changes."""
    small_params = cf.with_overrides({"downwash": {"params": dict(
        cf_sl.data["downwash"]["params"])}})
    lead, fol = probe_bodies(0.3, 0.0, 0.0, 0.032, 9.81, leader_mass_kg=0.067)
    axis = np.array([[0.0, 0.0, 0.3]])
    same, larger = build_field(small_params), build_field(cf_sl)
    assert 0 < larger.wind_mps(lead, axis)[0, 2] < same.wind_mps(lead, axis)[0, 2]
    assert larger.half_width0_m > same.half_width0_m
    assert larger.mean_acceleration(lead, fol)[0, 2] > 0
    field = build_field(load_config())  # one vehicle type: the leader's rotors are its own
    assert field.half_width0_m == pytest.approx(
        field.width0_ratio * field.follower_disk_radius_m * np.sqrt(field.follower_n_rotors))


def test_the_paper_profile_scales_freyjas_weights_by_the_vehicle(cf):
    assert scaled_weights(PAPER_Q_DIAG, 0.27) == list(PAPER_Q_DIAG)
    q = controller_config(cf, "paper").control.q_diag
    size = cf.vehicle.diagonal_m / 0.27
    assert q[0] * size**2 == pytest.approx(PAPER_Q_DIAG[0])
    assert q[2] * size**2 == pytest.approx(PAPER_Q_DIAG[2])
    assert q[5] * size == pytest.approx(PAPER_Q_DIAG[5])
    assert q[6] == PAPER_Q_DIAG[6]
    assert controller_config(load_config(), "paper").control.q_diag == list(PAPER_Q_DIAG)


def test_label_free_air_radius_follows_the_curriculum(cf):
    assert label_free_air_radius_m(load_config()) == FREE_AIR_RADIUS_M
    radius = label_free_air_radius_m(cf)
    assert radius < cf.curriculum.free_air_m  # the free-air waypoints are beyond it
    log = FlightLog(
        t_s=np.arange(3) * 0.01, leader_pos_m=np.zeros((3, 3)),
        leader_vel_mps=np.zeros((3, 3)), leader_quat=np.tile([1.0, 0, 0, 0], (3, 1)),
        follower_pos_m=np.zeros((3, 3)), follower_vel_mps=np.zeros((3, 3)),
        follower_quat=np.tile([1.0, 0, 0, 0], (3, 1)), follower_cmd_accel_mps2=np.zeros((3, 3)),
        follower_thrust_n=np.ones(3), follower_obs_accel_mps2=np.zeros((3, 3)), meta={"name": "x"})
    assert free_air_radius_of(log) == FREE_AIR_RADIUS_M
    own = replace(log, meta={"name": "x", "free_air_radius_m": radius})
    assert free_air_radius_of(own) == radius
    assert free_air_radius_of(own, 0.2) == 0.2  # the caller's wins


def test_rotor_strike_thickness_follows_the_rotor():
    """A segment 5 mm above a rotor disk's centre strikes the paper's rotor (1 cm half sweep)
    and clears a Crazyflie's (0.0235 m radius: 3.7 mm)."""
    p, R = np.zeros((1, 3)), np.eye(3)[None]
    offsets = np.array([[0.05, 0.0, 0.0]])
    a, b = np.array([[[0.04, -0.01, -0.005]]]), np.array([[[0.04, 0.01, -0.005]]])
    assert rotor_strike(p, R, offsets, 0.0635, a, b, 0.0)[0]
    assert not rotor_strike(p, R, offsets, 0.0235, a, b, 0.0)[0]


def test_curriculum_flights_of_a_heterogeneous_pair_record_the_leader(cf_sl):
    logs = excitation_flights(cf_sl.with_overrides({"mission": {"settle_s": 0.2}}), 1,
                              0.2, 0.25, seed=0)
    meta = logs[0].meta
    assert meta["leader_mass_kg"] == cf_sl.leader.mass_kg != meta["follower_mass_kg"]
    assert meta["leader_rotor_radius_m"] == cf_sl.leader.rotor_radius_m
    assert meta["free_air_radius_m"] == label_free_air_radius_m(cf_sl)
    assert np.all(np.isfinite(logs[0].follower_pos_m))


def test_the_curriculum_shortens_the_cables_in_proportion(cf):
    cfg = bar_out_of_the_way(cf, 0.05)  # no room at all: the shortest cable
    assert cfg.platform.cable_length_m == pytest.approx(cf.platform.cable_spacing_m / 3)
    default = load_config()
    assert bar_out_of_the_way(default, 0.1).platform.cable_length_m == 0.05


@pytest.mark.parametrize("path", [SMALL, SMALL_LARGE])
def test_the_crazyflie_worlds_fly_a_campaign(path):
    """Two trials of each world's campaign run to the end, every state finite, the follower
    kept clear of the leader (the mission's own limits derive from the config)."""
    cfg = controller_config(load_config(path), "ours")
    res = run_campaign(cfg, MissionSpec(trials=2, seed=0))
    s = res.summary()
    assert s["trials"] == 2 and s["nan_trials"] == 0
    assert s["docked"] + s["aborts"] + s["missed"] + s["slip_throughs"] >= 1
    assert s["min_clearance_m"] > 0


def test_the_jet_at_the_centre_of_mass_is_the_jet_without_its_torque(cf):
    from aerodock.downwash import follower_wrench, quad_rotor_offsets_body_m

    at_centre = cf.with_overrides(
        {"downwash": {"field": "aerodock.downwash.at_centre:RoundJetAtCentre",
                      "params": dict(cf.data["downwash"]["params"])}})
    jet, centre = build_field(cf), build_field(at_centre)
    lead, fol = probe_bodies(np.full(3, 0.15), np.array([0.0, 0.02, 0.04]), 0.0, 0.032, 9.81)
    offsets = quad_rotor_offsets_body_m(cf.vehicle.diagonal_m)
    for field in (jet, centre):
        field.reset(3, np.random.default_rng(1))
    _, torque_jet = follower_wrench(jet, lead, fol, offsets, 0.002)
    _, torque_c = follower_wrench(centre, lead, fol, offsets, 0.002)
    # the same mean wake (the turbulence is drawn per disk by the jet, once by the bracket)
    np.testing.assert_allclose(centre.mean_acceleration(lead, fol),
                               jet.mean_acceleration(lead, fol))
    assert np.all(torque_c == 0.0) and np.abs(torque_jet[1:]).max() > 0  # off axis: a torque
