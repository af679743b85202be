"""The wake's torque from a force model sampled at the rotor hubs."""

from __future__ import annotations

import numpy as np

from aerodock.control.torque_feedforward import hub_torque_nm
from aerodock.downwash.base import BodyState

OFFSETS = 0.095 * np.array([[1.0, 1.0, 0.0], [-1.0, 1.0, 0.0], [-1.0, -1.0, 0.0], [1.0, -1.0, 0.0]])


class _Field:
    """Downward push ``a0 + g_x * x`` (m/s², NED), from the follower's north position."""

    def __init__(self, a0: float, g_x: float):
        self.a0, self.g_x = a0, g_x

    def predict_bodies(self, leader, follower):
        out = np.zeros_like(follower.p)
        out[:, 2] = self.a0 + self.g_x * follower.p[:, 0]
        return out


def _bodies(n: int = 2):
    eye = np.tile(np.eye(3), (n, 1, 1))
    m = np.full(n, 0.7)
    lead = BodyState(np.zeros((n, 3)), np.zeros((n, 3)), eye, m * 9.81, m)
    fol = BodyState(np.tile([0.0, 0.0, 0.4], (n, 1)), np.zeros((n, 3)), eye.copy(), m * 9.81, m)
    return lead, fol


def test_a_uniform_field_gives_no_torque():
    lead, fol = _bodies()
    assert np.allclose(hub_torque_nm(_Field(4.0, 0.0), lead, fol, OFFSETS), 0.0, atol=1e-12)


def test_a_gradient_pitches_towards_the_weaker_push():
    """Stronger push (down) on the front rotors (+x) pitches the nose down: negative pitch torque
    about body y (FRD), of magnitude sum_i x_i * m/4 * g_x * x_i."""
    lead, fol = _bodies()
    g_x = -10.0  # weaker push to the front: a downward force behind pitches the nose up
    tau = hub_torque_nm(_Field(4.0, g_x), lead, fol, OFFSETS)
    expected = -np.sum(OFFSETS[:, 0] * 0.7 / 4 * g_x * OFFSETS[:, 0])  # tau_y = z*F_x - x*F_z
    assert np.allclose(tau[:, 1], expected)
    assert np.allclose(tau[:, [0, 2]], 0.0, atol=1e-12)
    assert tau[0, 1] > 0  # nose up


def test_the_autopilot_adds_the_feedforward_torque(cfg):
    """A roll feed-forward torque on the follower rolls it (right side down, FRD) before the rate
    loop's integrator catches up; the leader's rows are untouched."""
    from aerodock.rng import TrialRNG
    from aerodock.world import World
    from aerodock.world.vehicles.point_mass import AttitudeCommand

    world = World(cfg, 2, TrialRNG(0, 2))
    world.reset(np.tile([0.0, 0.0, -2.5], (2, 1)), np.tile([3.0, 0.0, -2.5], (2, 1)))
    hover = cfg.vehicle.mass_kg * cfg.sim.gravity_mps2
    z = np.zeros(2)
    lead = AttitudeCommand(z, z, z, np.full(2, hover))
    ff = np.array([[0.05, 0.0, 0.0], [0.0, 0.0, 0.0]])
    fol = AttitudeCommand(z, z, z, np.full(2, hover), ff)
    for _ in range(3):
        world.advance(lead, fol)
    roll_rate = world.follower.w[:, 0]
    assert roll_rate[0] > 0.15 and abs(roll_rate[1]) < 0.05
    assert np.all(np.abs(world.leader.w[:, 0]) < 0.1)
