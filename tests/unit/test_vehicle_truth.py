"""Each vehicle's true constants differ from the nominal ones its controllers fly, as a real
fleet's do; the leader may be a vehicle of another type (a heterogeneous pair)."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.config import ConfigError
from aerodock.rng import TrialRNG
from aerodock.world import World, hover_command
from aerodock.world.vehicles.body import draw_body, nominal_body
from aerodock.world.vehicles.fleet import PairFleet, RigidBodyFleet, build_fleet

SPREAD = {"vehicle": {"mass_sd": 0.03, "inertia_sd": 0.08, "torque_coeff_sd": 0.05,
                      "motor_tau_sd": 0.1}}
LARGE_LEADER = {"leader": {"mass_kg": 1.4, "diagonal_m": 0.4, "rotor_radius_m": 0.09,
                           "inertia_kgm2": [0.008, 0.008, 0.014],
                           "rotor_thrust_coeff": 1.6e-6}}


def _hover(world: World, steps: int) -> None:
    lead = hover_command(world.params.leader_vehicle, world.n)
    fol = hover_command(world.params.vehicle, world.n)
    for _ in range(steps):
        world.step(lead, fol)


def test_spread_draws_each_vehicle_its_own_constants(cfg):
    c = cfg.with_overrides(SPREAD)
    world = World(c, 64, TrialRNG(5, 64))
    world.reset(np.array([0.0, 0.0, -3.0]), np.array([0.0, 0.0, -2.0]))
    body = world.follower.body
    rel = body.mass_kg / c.vehicle.mass_kg - 1.0
    assert 0.015 < np.std(rel) < 0.045  # the configured 3 % spread
    assert np.std(body.inertia_kgm2[:, 0] / c.vehicle.inertia_kgm2[0]) > 0.04
    assert np.std(body.motor_tau_s / c.vehicle.motor_tau_s) > 0.05
    assert not np.allclose(world.leader.body.mass_kg, body.mass_kg)
    # Trial k draws the same vehicle in any batch.
    alone = World(c, 1, TrialRNG(5, 1, trials=np.array([7])))
    alone.reset(np.array([0.0, 0.0, -3.0]), np.array([0.0, 0.0, -2.0]))
    assert alone.follower.body.mass_kg[0] == body.mass_kg[7]


def test_the_physics_flies_the_true_mass_and_the_controllers_the_nominal(cfg):
    """A heavier vehicle given the nominal hover thrust sinks; a lighter one climbs. Each starts
    balanced (its rotors at its own weight), so the nominal command is what moves it."""
    c = cfg.with_overrides(SPREAD)
    c = c.with_overrides({"vehicle": {"thrust_gain_sd": 0.0}})
    world = World(c, 64, TrialRNG(2, 64))
    world.reset(np.array([0.0, 0.0, -5.0]), np.array([5.0, 0.0, -5.0]))  # out of the wake
    mass = world.follower.body.mass_kg.copy()
    _hover(world, 250)
    climb = -world.follower.v[:, 2]  # NED: up is -z
    heavy, light = mass > c.vehicle.mass_kg * 1.02, mass < c.vehicle.mass_kg * 0.98
    assert heavy.any() and light.any()
    assert np.all(climb[heavy] < 0) and np.all(climb[light] > 0)
    assert np.corrcoef(mass, climb)[0, 1] < -0.8


def test_no_spread_keeps_every_vehicle_nominal(ideal_cfg):
    cfg = ideal_cfg
    world = World(cfg, 4, TrialRNG(0, 4))
    world.reset(np.array([0.0, 0.0, -3.0]), np.array([0.0, 0.0, -2.0]))
    nominal = nominal_body(cfg.vehicle.mass_kg, cfg.vehicle.inertia_kgm2,
                           cfg.vehicle.motor_tau_s, 4)
    for name in ("mass_kg", "inertia_kgm2", "torque_gain", "motor_tau_s"):
        np.testing.assert_array_equal(getattr(world.follower.body, name),
                                      getattr(nominal, name))
    assert draw_body(nominal, world.params.spread, np.random.default_rng(0)) is nominal


def test_a_larger_leader_hovers_on_its_own_nominal_command(cfg):
    c = cfg.with_overrides(LARGE_LEADER)
    world = World(c, 3, TrialRNG(1, 3))
    assert isinstance(world.fleet, PairFleet)
    assert world.leader_fleet.params.mass_kg == 1.4
    assert world.follower_fleet.params.mass_kg == 0.7
    world.reset(np.array([0.0, 0.0, -5.0]), np.array([2.0, 0.0, -3.0]))
    np.testing.assert_allclose(world.leader.thrust_n, 1.4 * c.sim.gravity_mps2 * np.ones(3),
                               rtol=0.1)
    _hover(world, 250)
    # Thrust errors (2 % per trial) and the bar's weight only: on the follower's hover thrust
    # the leader would fall at half a g (2.5 m/s after 0.5 s).
    assert np.all(np.abs(world.leader.v) < 0.6)
    assert np.all(np.abs(world.follower.v) < 0.6)
    # The leader's rotors are its own: further out than the follower's.
    arm_l = np.linalg.norm(world.leader_fleet.params.rotor_offsets_m[0])
    arm_f = np.linalg.norm(world.follower_fleet.params.rotor_offsets_m[0])
    assert arm_l == pytest.approx(0.2) and arm_f == pytest.approx(0.135)


def test_a_pair_of_identical_fleets_steps_as_the_single_fleet(cfg):
    """The pair fleet's split-step-join gives the numbers of the one 2n batch."""
    one = build_fleet(cfg)
    assert isinstance(one, RigidBodyFleet)
    worlds = []
    for pair in (False, True):
        world = World(cfg, 5, TrialRNG(3, 5))
        if pair:
            world.params = type(world.params)(**{**world.params.__dict__,
                                                 "fleet": PairFleet(one, one)})
        world.reset(np.array([0.0, 0.0, -3.0]), np.array([0.3, 0.0, -2.0]))
        _hover(world, 60)
        worlds.append(world)
    for name in ("p", "v", "R", "w", "rotor_speed"):
        np.testing.assert_allclose(getattr(worlds[0].follower, name),
                                   getattr(worlds[1].follower, name), rtol=0, atol=1e-12)
        np.testing.assert_allclose(getattr(worlds[0].leader, name),
                                   getattr(worlds[1].leader, name), rtol=0, atol=1e-12)


@pytest.mark.parametrize(("text", "needle"), [
    ("[leader]\nmass_kg = -1\n", "'leader.mass_kg' must be >= 0.001"),
    ("[leader]\nmodel = 'point-mass'\n", "'leader.model' cannot differ"),
    ("[leader]\nmass = 2\n", "unknown key 'leader.mass'"),
    ("[leader]\nmass_kg = 'heavy'\n", "'leader.mass_kg' must be a number"),
])
def test_leader_table_is_checked_as_the_vehicles(tmp_path, text, needle):
    from aerodock.config import load_config

    path = tmp_path / "c.toml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=needle):
        load_config(path)
