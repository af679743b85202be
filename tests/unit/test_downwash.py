"""The default field against DESIGN.md's calibration table and required properties."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.downwash import build_field
from aerodock.downwash.base import BodyState
from aerodock.downwash.probe import half_magnitude_radius_m, probe_bodies, probe_field
from aerodock.geometry import rot_z

MASS, G = 0.7, 9.81

# DESIGN.md: separation -> (mean downward acceleration, tolerance)
CALIBRATION = {0.36: (4.5, 1.0), 0.64: (3.0, 0.8), 1.35: (1.5, 0.5)}


@pytest.fixture
def field(cfg):
    return build_field(cfg)


@pytest.mark.parametrize("sep", sorted(CALIBRATION))
def test_calibration_mean_below_hovering_leader(field, sep):
    target, tol = CALIBRATION[sep]
    leader, follower = probe_bodies(sep, 0.0, 0.0, MASS, G)
    mean = field.mean_acceleration(leader, follower)[0]
    assert abs(mean[2] - target) <= tol
    assert np.allclose(mean[:2], 0.0, atol=1e-9)  # no planar force on the axis


def test_calibration_half_magnitude_radius(field):
    radii = [half_magnitude_radius_m(field.mean_acceleration, s, MASS, G) for s in (0.36, 0.64,
                                                                                   1.35)]
    assert 0.09 <= radii[0] <= 0.15
    assert radii[0] < radii[1] < radii[2]  # grows with separation


def test_probe_with_turbulence_matches_table(field):
    out = probe_field(field, 0.36, 0.0, 0.0, 20000, 0.002, np.random.default_rng(1), MASS, G)
    assert abs(out["mean_mps2"][2] - 4.5) <= 1.0
    assert 0.20 <= out["sd_mps2"][2] / out["field_mean_mps2"][2] <= 0.25 + 0.02


def test_rotational_symmetry_about_hovering_leader_axis(field):
    angles = np.linspace(0, 2 * np.pi, 13)
    base_leader, base_follower = probe_bodies(0.5, 0.12, 0.0, MASS, G)
    ref = field.mean_acceleration(base_leader, base_follower)[0]
    for a in angles:
        leader, follower = probe_bodies(0.5, 0.12, 0.0, MASS, G, azimuth_rad=a)
        got = field.mean_acceleration(leader, follower)[0]
        rot = rot_z(a)
        assert np.allclose(got, rot @ ref, atol=1e-9)
    # Also when the leader itself is yawed: the field only depends on the geometry.
    leader, follower = probe_bodies(0.5, 0.12, 0.0, MASS, G)
    yawed = BodyState(leader.p, leader.v, rot_z(np.array([0.7])), leader.thrust_n, leader.mass_kg)
    assert np.allclose(field.mean_acceleration(yawed, follower)[0], ref, atol=1e-9)


def test_planar_component_zero_on_axis_peaks_near_edge(field):
    radii = np.linspace(0.0, 0.5, 501)
    leader, follower = probe_bodies(np.full_like(radii, 0.36), radii, 0.0, MASS, G)
    acc = field.mean_acceleration(leader, follower)
    planar = acc[:, 0]
    assert planar[0] == pytest.approx(0.0, abs=1e-12)
    assert np.all(planar[1:] >= 0)  # pushes outward
    peak = np.argmax(planar)
    ratio = planar[peak] / acc[0, 2]
    assert 0.10 <= ratio <= 0.20
    half = half_magnitude_radius_m(field.mean_acceleration, 0.36, MASS, G)
    assert 0.5 * half <= radii[peak] <= 1.5 * half


def test_wake_skews_behind_moving_leader(field):
    radii = np.linspace(-0.8, 0.8, 1601)
    peaks = {}
    for speed in (0.0, 2.0):
        leader, follower = probe_bodies(np.full_like(radii, 1.35), radii, speed, MASS, G)
        peaks[speed] = radii[np.argmax(field.mean_acceleration(leader, follower)[:, 2])]
    assert abs(peaks[0.0]) < 1e-3
    assert peaks[2.0] < -0.1  # leader moves north: the wake trails to the south


def test_follower_vertical_velocity_changes_force(field):
    leader, follower = probe_bodies(0.5, 0.0, 0.0, MASS, G)
    still = field.mean_acceleration(leader, follower)[0, 2]
    down = BodyState(follower.p, np.array([[0.0, 0.0, 1.0]]), follower.R, follower.thrust_n,
                     follower.mass_kg)
    up = BodyState(follower.p, np.array([[0.0, 0.0, -1.0]]), follower.R, follower.thrust_n,
                   follower.mass_kg)
    assert field.mean_acceleration(leader, down)[0, 2] < still < field.mean_acceleration(
        leader, up)[0, 2]


def test_no_singularity_at_zero_separation(field):
    seps = np.array([0.0, 1e-9, 1e-4, 0.01])
    leader, follower = probe_bodies(seps, np.zeros(4), 0.0, MASS, G)
    acc = field.mean_acceleration(leader, follower)
    assert np.all(np.isfinite(acc))
    assert np.all(acc[:, 2] < 20.0)


def test_force_scales_with_leader_thrust(field):
    leader, follower = probe_bodies(0.5, 0.0, 0.0, MASS, G)
    base = field.mean_acceleration(leader, follower)[0, 2]
    heavy = BodyState(leader.p, leader.v, leader.R, leader.thrust_n * 2, leader.mass_kg)
    assert field.mean_acceleration(heavy, follower)[0, 2] == pytest.approx(2 * base, rel=1e-9)


def test_turbulence_spread_and_correlation_time(field, cfg):
    dt = 1.0 / cfg.sim.physics_rate_hz
    leader, follower = probe_bodies(0.36, 0.0, 0.0, MASS, G)
    field.reset(1, np.random.default_rng(3))
    k = 60000
    z = np.array([field.acceleration(leader, follower, dt)[0, 2] for _ in range(k)])
    xs = np.array([field.acceleration(leader, follower, dt)[0, 0] for _ in range(k)])
    mean = field.mean_acceleration(leader, follower)[0, 2]
    assert 0.20 <= z.std() / mean <= 0.25 + 0.02
    assert 0.05 <= xs.std() / mean <= 0.10
    dev = z - z.mean()

    def corr(lag_s):
        lag = int(round(lag_s / dt))
        return np.dot(dev[:-lag], dev[lag:]) / np.dot(dev, dev)

    # Real Crazyflie data: about 0.55 at 50 ms and 0.35 at 80 ms; correlation time 0.05-0.1 s.
    assert 0.40 <= corr(0.05) <= 0.70
    assert 0.25 <= corr(0.08) <= 0.50
    tau = -0.05 / np.log(corr(0.05))
    assert 0.05 <= tau <= 0.1
