"""Rotor drag of the rigid-body vehicle: each rotor's H-force on its local airspeed, at its hub."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from aerodock.world.vehicles.rigid_body import RigidBodyParams, body_wrench


def _per_rotor(omega, v_body, w, params):
    """The sums written rotor by rotor: H_i = -omega_i K (v_b + w x r_i), moment r_i x H_i."""
    k = np.diag([params.rotor_drag_coeff, params.rotor_drag_coeff, params.rotor_drag_z_coeff])
    force = np.zeros(3)
    torque = np.zeros(3)
    for i, r in enumerate(params.rotor_offsets_m):
        h = -omega[i] * k @ (v_body + np.cross(w, r))
        force += h
        torque += np.cross(r, h)
    return force, torque


def test_body_wrench_equals_the_per_rotor_sum(cfg):
    params = RigidBodyParams.from_config(cfg)
    no_drag = replace(params, rotor_drag_coeff=0.0, rotor_drag_z_coeff=0.0)
    rng = np.random.default_rng(0)
    n = 16
    omega = rng.uniform(1000.0, 2500.0, (n, 4))
    v_body, w = rng.normal(0, 2.0, (n, 3)), rng.normal(0, 3.0, (n, 3))
    gain = np.ones(n)
    force, torque = body_wrench(omega, gain, v_body, w, params)
    force0, torque0 = body_wrench(omega, gain, v_body, w, no_drag)
    for i in range(n):
        f, t = _per_rotor(omega[i], v_body[i], w[i], params)
        np.testing.assert_allclose(force[i] - force0[i], f, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(torque[i] - torque0[i], t, rtol=1e-10, atol=1e-14)


def test_rotors_damp_body_rates(cfg):
    """At equal rotor speeds and no airspeed, the rotors' drag torque opposes every body rate
    (the advancing/retreating inflow difference), and the rotors' net drag force is zero."""
    params = RigidBodyParams.from_config(cfg)
    omega = np.full((3, 4), 1700.0)
    w = np.eye(3) * 2.0  # roll, pitch, yaw rate in turn
    force, torque = body_wrench(omega, np.ones(3), np.zeros((3, 3)), w, params)
    hover = body_wrench(omega, np.ones(3), np.zeros((3, 3)), np.zeros((3, 3)), params)
    np.testing.assert_allclose(force, hover[0], atol=1e-12)
    damping = np.diag(torque - hover[1])
    assert np.all(damping < 0.0), damping
    # Roll and pitch damping: k_z sum omega_i y_i^2 (x_i^2) per rad/s.
    expected = params.rotor_drag_z_coeff * 1700.0 * (params.rotor_offsets_m[:, 1] ** 2).sum() * 2
    np.testing.assert_allclose(damping[0], -expected, rtol=1e-12)


def test_rotor_drag_opposes_airspeed(cfg):
    params = RigidBodyParams.from_config(cfg)
    omega = np.full((3, 4), 1700.0)
    v_body = np.eye(3)
    force, _ = body_wrench(omega, np.ones(3), v_body, np.zeros((3, 3)), params)
    hover, _ = body_wrench(omega, np.ones(3), np.zeros((3, 3)), np.zeros((3, 3)), params)
    drag = np.diag(force - hover)
    np.testing.assert_allclose(drag, -4 * 1700.0 * np.array(
        [params.rotor_drag_coeff, params.rotor_drag_coeff, params.rotor_drag_z_coeff]))
