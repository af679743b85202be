"""The accelerometer observer: what the commands do not explain, low-passed as documented."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.control.accel_observer import AccelObserver, filtered_noise_sd
from aerodock.control.controller import PositionController, Reference
from aerodock.control.profiles import controller_config
from aerodock.geometry import rpy_to_rotmat

G = 9.81
M = 0.7


def _accel(R, thrust_n, force_mps2):  # noqa: N803
    """Kinematic acceleration (NED) of a vehicle at thrust along -body z plus a force."""
    return np.array([0.0, 0.0, G]) - R[:, :, 2] * (thrust_n / M)[:, None] + force_mps2


def test_estimates_a_step_disturbance_within_its_time_constant():
    n, dt, tau = 3, 0.01, 0.08
    obs = AccelObserver(n, dt, tau, motor_tau_s=0.0, mass_kg=M, gravity_mps2=G)
    obs.reset(M * G)
    R = rpy_to_rotmat(np.array([[0.1, -0.05, 0.3], [0.0, 0.0, 0.0], [-0.2, 0.1, 1.0]]))
    thrust = np.array([7.0, 6.5, 8.0])
    force = np.array([[0.5, -0.2, 4.0], [0.0, 0.0, 0.0], [-1.0, 0.3, 2.0]])
    obs.commanded(thrust, np.zeros((n, 3)))
    steps = int(round(tau / dt))
    for _ in range(steps):
        obs.update(_accel(R, thrust, force), R)
        obs.commanded(thrust, np.zeros((n, 3)))
    frac = obs.residual_mps2[0] / force[0]
    assert np.allclose(frac, 1 - np.exp(-1), atol=0.05)  # 63 % after one time constant
    assert np.allclose(obs.residual_mps2[1], 0.0)  # hover explained by the thrust
    for _ in range(20 * steps):
        obs.update(_accel(R, thrust, force), R)
        obs.commanded(thrust, np.zeros((n, 3)))
    assert np.allclose(obs.residual_mps2, force, atol=1e-6)


def test_with_a_feedforward_only_the_residual_is_left():
    obs = AccelObserver(1, 0.01, 0.05, motor_tau_s=0.02, mass_kg=M, gravity_mps2=G)
    obs.reset(M * G)
    R = np.eye(3)[None]
    thrust = np.array([M * G * 1.3])
    force = np.array([[0.0, 0.0, 3.0]])
    ff = np.array([[0.0, 0.0, 2.5]])
    for _ in range(400):  # the motors settle at the commanded thrust
        obs.commanded(thrust, ff)
        obs.update(_accel(R, thrust, force), R)
    assert np.allclose(obs.residual_mps2, force - ff, atol=1e-6)


def test_motor_lag_is_not_taken_for_a_disturbance():
    """A thrust step reaches the vehicle through the motors' lag; the observer models the same
    lag, so it sees (almost) nothing."""
    dt, tau_m = 0.01, 0.02
    obs = AccelObserver(1, dt, 0.05, motor_tau_s=tau_m, mass_kg=M, gravity_mps2=G)
    obs.reset(M * G)
    R = np.eye(3)[None]
    true_thrust = M * G
    cmd = np.array([M * G * 1.5])
    worst = 0.0
    for _ in range(50):
        obs.commanded(cmd, np.zeros((1, 3)))
        # exact mean of the first-order response over the period
        start = true_thrust
        mean = cmd[0] + (start - cmd[0]) * tau_m / dt * (1 - np.exp(-dt / tau_m))
        true_thrust = cmd[0] + (start - cmd[0]) * np.exp(-dt / tau_m)
        obs.update(_accel(R, np.array([mean]), np.zeros((1, 3))), R)
        worst = max(worst, float(np.abs(obs.residual_mps2).max()))
    assert worst < 1e-9


def test_filtered_noise_matches_the_formula():
    rng = np.random.default_rng(0)
    n, dt, tau, sd = 4000, 0.01, 0.08, 0.5
    obs = AccelObserver(n, dt, tau, motor_tau_s=0.0, mass_kg=M, gravity_mps2=G)
    obs.reset(M * G)
    R = np.tile(np.eye(3), (n, 1, 1))
    thrust = np.full(n, M * G)
    obs.commanded(thrust, np.zeros((n, 3)))
    for _ in range(200):
        obs.update(_accel(R, thrust, sd * rng.standard_normal((n, 3))), R)
        obs.commanded(thrust, np.zeros((n, 3)))
    measured = obs.residual_mps2.std()
    assert measured == pytest.approx(filtered_noise_sd(sd, dt, tau), rel=0.05)
    assert filtered_noise_sd(sd, dt, tau) < 0.25 * sd


def test_only_the_follower_with_an_accelerometer_runs_it(cfg):
    ours = controller_config(cfg, "ours")
    assert PositionController(ours, 2, use_observer=True, has_accelerometer=True
                              ).uses_accelerometer
    assert not PositionController(ours, 2, use_observer=True).uses_accelerometer  # the leader
    assert not PositionController(cfg, 2, use_observer=True, has_accelerometer=True
                                  ).uses_accelerometer  # tuned: bias observer only
    ours = ours.with_overrides({"control": {"accel_observer_axes": "all"}})
    ctl = PositionController(ours, 2, use_observer=True, has_accelerometer=True)
    ctl.reset(np.zeros((2, 3)), np.zeros((2, 3)))
    z = np.zeros((2, 3))
    ref = Reference(z, z, z, np.zeros(2), np.zeros(2))
    with pytest.raises(ValueError, match="accelerometer"):
        ctl.step(z, z, z, ref)
    # a steady push it cannot explain is cancelled by the command after a few time constants
    push = np.array([[0.0, 0.0, 3.0], [1.0, 0.0, 0.0]])
    out = ctl.step(z, z, z, ref, accel_mps2=z)
    for _ in range(100):
        R = rpy_to_rotmat(np.stack([out.command.roll_rad, out.command.pitch_rad,
                                    np.zeros(2)], 1))
        accel = _accel(R, out.command.thrust_n, push)
        out = ctl.step(z, z, np.stack([out.command.roll_rad, out.command.pitch_rad,
                                       np.zeros(2)], 1), ref, accel_mps2=accel)
    assert np.allclose(out.applied_accel_mps2, -push, atol=0.05)


def test_down_only_and_hold():
    obs = AccelObserver(2, 0.01, 0.05, motor_tau_s=0.0, mass_kg=M, gravity_mps2=G, axes="down")
    obs.reset(M * G)
    R = np.tile(np.eye(3), (2, 1, 1))
    thrust = np.full(2, M * G)
    force = np.array([[1.0, -1.0, 2.0], [1.0, -1.0, 2.0]])
    for k in range(200):
        obs.commanded(thrust, np.zeros((2, 3)))
        obs.update(_accel(R, thrust, force), R, hold=np.array([False, k >= 3]))
    assert np.allclose(obs.residual_mps2[0], [0.0, 0.0, 2.0])
    held = obs.residual_mps2[1, 2]
    assert 0.0 < held < 1.0  # frozen where it was when contact began
    with pytest.raises(ValueError):
        AccelObserver(1, 0.01, 0.05, 0.0, M, G, axes="sideways")


def test_the_papers_profile_ignores_our_additions(cfg):
    """A configuration with our observer and the torque feed-forward switched on still flies the
    paper's controller as the paper does: neither is part of it."""
    ours = cfg.with_overrides({"control": {"rejection": "accelerometer",
                                           "torque_feedforward": True}})
    paper = controller_config(ours, "paper")
    assert paper.control.rejection == "bias-observer"
    assert paper.control.torque_feedforward is False
    assert controller_config(ours, "ours").control.torque_feedforward is True
    assert not PositionController(paper, 2, use_observer=True, has_accelerometer=True
                                  ).uses_accelerometer
