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


# -- wrench: the wake sampled at the follower's rotor disks (issue 10, item 2) -----------------
from aerodock.downwash.wrench import (  # noqa: E402
    bar_wake_force_n,
    follower_wrench,
    quad_rotor_offsets_body_m,
)
from aerodock.geometry import euler_to_rotmat  # noqa: E402
from aerodock.rng import TrialRNG  # noqa: E402

ROTORS = quad_rotor_offsets_body_m(0.27)


def _bodies(points, leader_v=(0.0, 0.0, 0.0), fol_rpy=(0.0, 0.0, 0.0), lead_yaw=0.0):
    """Hovering leader at the origin, level (or tilted) followers at ``points`` (n, 3)."""
    pts = np.atleast_2d(np.asarray(points, float))
    n = pts.shape[0]
    mass = np.full(n, MASS)
    lead_R = np.repeat(rot_z(np.array(lead_yaw))[None], n, 0)
    fol_R = np.repeat(euler_to_rotmat(*np.array(fol_rpy, float))[None], n, 0)
    leader = BodyState(np.zeros((n, 3)), np.tile(leader_v, (n, 1)), lead_R, mass * G, mass)
    follower = BodyState(pts, np.zeros((n, 3)), fol_R, mass * G, mass.copy())
    return leader, follower


def test_rotor_layout_is_an_x_frame_on_the_diagonals():
    assert ROTORS.shape == (4, 3)
    assert np.allclose(np.linalg.norm(ROTORS, axis=1), 0.135)
    assert np.allclose(ROTORS[:, 2], 0.0)
    assert np.allclose(ROTORS.sum(0), 0.0)
    assert np.allclose(np.abs(ROTORS[:, 0]), np.abs(ROTORS[:, 1]))  # on the diagonals


@pytest.mark.parametrize("fol_rpy", [(0.0, 0.0, 0.0), (0.0, 0.0, 0.6), (0.2, -0.15, 1.0)])
def test_wrench_force_is_acceleration_times_mass(cfg, fol_rpy):
    """Same turbulence draw, same calibrated total: level or tilted, on or off the axis."""
    pts = [[0.0, 0.0, 0.36], [0.1, -0.05, 0.5], [0.3, 0.2, 1.0], [0.0, 0.0, -0.2]]
    leader, follower = _bodies(pts, fol_rpy=fol_rpy)
    a, b = build_field(cfg), build_field(cfg)
    a.reset(4, np.random.default_rng(7))
    b.reset(4, np.random.default_rng(7))
    for _ in range(5):
        acc = a.acceleration(leader, follower, 0.002)
        force, torque = b.wrench(leader, follower, ROTORS, 0.002)
        assert np.allclose(force, acc * MASS, rtol=1e-12, atol=1e-12)
        assert torque.shape == (4, 3) and np.all(np.isfinite(torque))


@pytest.mark.parametrize("sep", sorted(CALIBRATION))
def test_wrench_meets_the_calibration_table(cfg, sep):
    """Mean downward force / mass directly below a hovering leader, averaged over 4000
    independent turbulence draws (one step after a stationary reset)."""
    n = 4000
    leader, follower = _bodies(np.tile([0.0, 0.0, sep], (n, 1)))
    field = build_field(cfg)
    field.reset(n, np.random.default_rng(11))
    force, _ = field.wrench(leader, follower, ROTORS, 0.002)
    target, tol = CALIBRATION[sep]
    mean_down = force[:, 2].mean() / MASS
    assert abs(mean_down - target) <= tol
    exact = field.mean_acceleration(leader, follower)[0, 2]
    assert abs(mean_down - exact) < 4 * force[:, 2].std() / MASS / np.sqrt(n)


@pytest.mark.parametrize("yaw", [0.0, 0.3, np.pi / 4])
def test_wrench_torque_is_zero_on_the_axis(cfg, yaw):
    leader, follower = _bodies([[0.0, 0.0, s] for s in (0.2, 0.36, 0.64, 1.35)],
                               fol_rpy=(0.0, 0.0, yaw))
    field = build_field(cfg)
    field.reset(4, np.random.default_rng(2))
    for _ in range(3):
        force, torque = field.wrench(leader, follower, ROTORS, 0.002)
        assert np.all(force[:, 2] > 0)
        assert np.allclose(torque, 0.0, atol=1e-12 * np.abs(force).max())


@pytest.mark.parametrize("azimuth", [0.0, 1.0, 2.5, -2.0])
@pytest.mark.parametrize("fol_yaw", [0.0, 0.4])
def test_wrench_torque_off_axis_tilts_the_follower_towards_the_axis(cfg, azimuth, fol_yaw):
    """Off the axis the rotors nearer the wake's centre are pushed harder: the torque turns the
    follower so that its side facing the axis goes down (its thrust tilts towards the axis)."""
    offsets = np.array([0.0, 0.05, 0.1, 0.2])
    u = np.array([np.cos(azimuth), np.sin(azimuth), 0.0])
    pts = offsets[:, None] * u + [0.0, 0.0, 0.36]
    leader, follower = _bodies(pts, fol_rpy=(0.0, 0.0, fol_yaw))
    field = build_field(cfg)
    field.reset(4, np.random.default_rng(5))
    force, torque_body = field.wrench(leader, follower, ROTORS, 0.002)
    torque_world = np.einsum("nij,nj->ni", follower.R, torque_body)
    inward = -u
    # Velocity of the follower's inward-facing edge under an angular velocity along the torque.
    edge_down = np.cross(torque_world, inward)[:, 2]
    assert abs(edge_down[0]) < 1e-12
    assert np.all(edge_down[1:] > 0)
    # A sizeable fraction of the arm-times-force scale, not a rounding artefact.
    size = np.linalg.norm(torque_body, axis=1)
    assert np.all(size[1:] > 0.02 * 0.135 * force[0, 2])


def test_wrench_is_equivariant_about_the_leader_axis(cfg):
    """Rotating the whole scene (positions, velocities, attitudes) about the hovering leader's
    axis rotates the world force and leaves the body-frame torque unchanged."""
    pts = np.array([[0.12, 0.05, 0.4], [-0.2, 0.1, 0.7], [0.05, -0.3, 1.1]])
    fol_rpy = np.array([[0.1, -0.05, 0.3], [0.0, 0.2, -1.0], [-0.15, 0.0, 2.0]])
    lead_v = np.array([0.3, -0.1, 0.0])
    fol_v = np.array([[0.1, 0.2, -0.1], [0.0, -0.3, 0.2], [0.2, 0.0, 0.0]])
    n = 3
    mass = np.full(n, MASS)

    def scene(angle):
        rz = rot_z(np.array(angle))
        lead = BodyState(np.zeros((n, 3)), np.tile(rz @ lead_v, (n, 1)),
                         np.repeat(rz[None], n, 0), mass * G, mass)
        fol = BodyState(pts @ rz.T, fol_v @ rz.T, rz @ euler_to_rotmat(*fol_rpy.T), mass * G,
                        mass)
        return lead, fol

    ref_field = build_field(cfg)
    ref_field.reset(n, np.random.default_rng(3))
    ref_force, ref_torque = ref_field.wrench(*scene(0.0), ROTORS, 0.002)
    for angle in (0.4, np.pi / 2, 2.2, -1.3):
        field = build_field(cfg)
        field.reset(n, np.random.default_rng(3))
        force, torque = field.wrench(*scene(angle), ROTORS, 0.002)
        assert np.allclose(force, ref_force @ rot_z(np.array(angle)).T, atol=1e-9)
        assert np.allclose(torque, ref_torque, atol=1e-9)
    assert np.abs(ref_torque).max() > 1e-4  # the scene does produce torque


class _AccelOnly:
    def reset(self, n, rng):
        self.rng = rng

    def acceleration(self, leader, follower, dt):
        return np.tile([0.5, -0.2, 2.0], (follower.n, 1))


def test_follower_wrench_dispatch(cfg):
    leader, follower = _bodies([[0.1, 0.0, 0.4], [0.0, 0.0, 0.6]])
    force, torque = follower_wrench(_AccelOnly(), leader, follower, ROTORS, 0.002)
    assert np.allclose(force, np.tile([0.5, -0.2, 2.0], (2, 1)) * MASS)
    assert np.array_equal(torque, np.zeros((2, 3)))
    a, b = build_field(cfg), build_field(cfg)
    a.reset(2, np.random.default_rng(1))
    b.reset(2, np.random.default_rng(1))
    got = follower_wrench(a, leader, follower, ROTORS, 0.002)
    want = b.wrench(leader, follower, ROTORS, 0.002)
    assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])

    class Bad(_AccelOnly):
        def wrench(self, leader, follower, rotors, dt):
            return np.zeros((follower.n, 3)), np.zeros(follower.n)

    with pytest.raises(ValueError, match="wrench returned shapes"):
        follower_wrench(Bad(), leader, follower, ROTORS, 0.002)


# -- the bar: turbulence and relative-wind drag (issue 10, item 4) ----------------------------
BAR_AREA = 0.15 * 0.01


def test_bar_force_sd_measured_against_design_fractions(cfg):
    """The figure for the report: sd of the bar's lateral (across-the-bar) force at 0.36 m below
    a hovering leader over its mean vertical drag, measured over 60 s of simulated time."""
    from aerodock.downwash.probe import probe_bar

    out = probe_bar(build_field(cfg), 0.36, 0.0, 30000, 0.002, np.random.default_rng(4),
                    BAR_AREA, MASS, G)
    print(f"\nbar at 0.36 m: sd across / mean vertical = {out['lateral_sd_over_vertical_mean']:.3f}"
          f", vertical sd / mean = {out['vertical_sd_over_mean']:.3f}, mean {out['mean_n']} N")
    assert out["mean_n"][2] > 0  # the wake pushes the bar down
    assert 0.05 <= out["lateral_sd_over_vertical_mean"] <= 0.10 + 0.01  # DESIGN.md lateral
    assert 0.20 <= out["vertical_sd_over_mean"] <= 0.25 + 0.02  # DESIGN.md vertical


def _bar_run(field, rng, n, steps, bar_p, bar_v):
    leader, follower = _bodies(np.tile([1.0, 1.0, 1.0], (n, 1)))
    field.reset(n, rng)
    out = []
    for _ in range(steps):
        field.acceleration(leader, follower, 0.002)
        out.append(field.bar_force_n(leader, bar_p, bar_v, BAR_AREA, dt=0.002))
    return np.array(out)


def test_bar_turbulence_is_seeded_per_trial(cfg):
    """Same seed, same numbers; a batch of N reproduces N single trials bit for bit."""
    n = 3
    bar_p = np.array([[0.0, 0.0, 0.36], [0.05, 0.0, 0.38], [0.0, -0.1, 0.4]])
    bar_v = np.array([[0.0, 0.1, 0.0], [0.0, 0.0, 0.0], [0.05, 0.0, 0.02]])
    batch = _bar_run(build_field(cfg), TrialRNG(9, n), n, 50, bar_p, bar_v)
    again = _bar_run(build_field(cfg), TrialRNG(9, n), n, 50, bar_p, bar_v)
    assert np.array_equal(batch, again)
    for i in range(n):
        one = _bar_run(build_field(cfg), TrialRNG(9, 1, i), 1, 50, bar_p[i:i + 1],
                       bar_v[i:i + 1])
        assert np.array_equal(one[:, 0], batch[:, i])
    other = _bar_run(build_field(cfg), TrialRNG(10, n), n, 50, bar_p, bar_v)
    assert not np.array_equal(other, batch)
    assert np.std(batch[:, 0, 1]) > 0  # lateral turbulence is there


def test_bar_relative_wind_drag(cfg):
    field = build_field(cfg)
    field.turb_vertical = field.bar_turb_vertical = field.bar_turb_lateral = 0.0
    rho, cd = cfg.sim.air_density_kgpm3, cfg.downwash.params["bar_drag_coeff"]
    leader, _ = _bodies([[0.0, 0.0, 0.0]])
    field.reset(1, np.random.default_rng(0))
    # Far outside the wake: drag of the bar's own motion through still air, opposing it.
    v = np.array([[0.4, -0.3, 0.0]])
    far = field.bar_force_n(leader, np.array([[3.0, 0.0, 0.3]]), v, BAR_AREA, dt=0.002)
    assert np.allclose(far, -0.5 * rho * cd * BAR_AREA * 0.5 * v, rtol=1e-6)
    # Cross-flow: motion along the bar's length makes no drag.
    along = field.bar_force_n(leader, np.array([[3.0, 0.0, 0.3]]), np.array([[0.4, 0.0, 0.0]]),
                              BAR_AREA, dt=0.002, bar_axis=np.array([[1.0, 0.0, 0.0]]))
    assert np.allclose(along, 0.0)
    # In the wake: moving down with the air lowers the drag, climbing into it raises it; a bar
    # swinging sideways through the wake feels a sideways drag against its motion.
    p = np.array([[0.0, 0.0, 0.36]])
    still = field.bar_force_n(leader, p, np.zeros((1, 3)), BAR_AREA, dt=0.002)
    down = field.bar_force_n(leader, p, np.array([[0.0, 0.0, 0.5]]), BAR_AREA, dt=0.002)
    up = field.bar_force_n(leader, p, np.array([[0.0, 0.0, -0.5]]), BAR_AREA, dt=0.002)
    side = field.bar_force_n(leader, p, np.array([[0.0, 0.3, 0.0]]), BAR_AREA, dt=0.002)
    assert down[0, 2] < still[0, 2] < up[0, 2]
    assert side[0, 1] < 0 and side[0, 2] > still[0, 2] * 0.99
    assert np.allclose(still[0, :2], 0.0, atol=1e-15)


class _OldBarField(_AccelOnly):
    def bar_force_n(self, leader, bar_p_m, bar_v_mps, bar_area_m2):
        return np.full_like(bar_p_m, bar_area_m2)


def test_bar_force_backwards_compatible(cfg):
    """Plug-ins with the four-argument bar_force_n keep working; a field without one gives None;
    the jet called the old way (no dt) still advances its bar turbulence."""
    leader, follower = _bodies([[1.0, 1.0, 1.0]])
    p, v, axis = np.array([[0.0, 0.0, 0.36]]), np.zeros((1, 3)), np.array([[1.0, 0, 0]])
    assert np.array_equal(bar_wake_force_n(_OldBarField(), leader, p, v, 2.0, 0.002, axis),
                          np.full((1, 3), 2.0))
    assert bar_wake_force_n(_AccelOnly(), leader, p, v, 2.0, 0.002) is None
    field = build_field(cfg)
    field.reset(1, np.random.default_rng(0))
    old_style = []
    for _ in range(3):
        field.acceleration(leader, follower, 0.002)
        old_style.append(field.bar_force_n(leader, p, v, BAR_AREA))
    assert not np.array_equal(old_style[0], old_style[2])
    a, b = build_field(cfg), build_field(cfg)
    a.reset(1, np.random.default_rng(0))
    b.reset(1, np.random.default_rng(0))
    a.acceleration(leader, follower, 0.002)
    b.acceleration(leader, follower, 0.002)
    assert np.array_equal(a.bar_force_n(leader, p, v, BAR_AREA),
                          bar_wake_force_n(b, leader, p, v, BAR_AREA, 0.002))


def test_wrench_torque_comes_from_the_wake_at_each_disk(cfg):
    """The torque is the calibrated force acting at the disks' centre weighted by the wake's
    dynamic pressure there (wind_mps sampled at each disk centre), tilted and moving too."""
    pts = np.array([[0.08, 0.03, 0.36], [-0.15, 0.1, 0.7], [0.3, -0.1, 1.2]])
    leader, follower = _bodies(pts, leader_v=(0.4, 0.1, 0.0), fol_rpy=(0.15, -0.1, 0.8))
    field = build_field(cfg)
    field.reset(3, np.random.default_rng(6))
    force, torque = field.wrench(leader, follower, ROTORS, 0.002)
    disks = follower.p[:, None, :] + np.einsum("nij,kj->nki", follower.R, ROTORS)
    q = np.stack([np.sum(field.wind_mps(leader, disks[:, j]) ** 2, axis=1) for j in range(4)], 1)
    centre = (q / q.sum(1, keepdims=True)) @ ROTORS
    force_body = np.einsum("nji,nj->ni", follower.R, force)
    assert np.allclose(torque, np.cross(centre, force_body), rtol=1e-9, atol=1e-12)


def test_wrench_batch_equals_single_trials(cfg):
    """Per-trial turbulence (TrialRNG) and batch-size independent rounding: a batch of N gives
    N single trials' wrenches bit for bit."""
    pts = np.array([[0.02, 0.1, 0.36], [0.2, -0.1, 0.6], [0.0, 0.0, 1.0]])
    rpy = (0.1, -0.2, 0.5)

    def run(sel, rng):
        leader, follower = _bodies(pts[sel], leader_v=(0.2, 0.0, 0.0), fol_rpy=rpy)
        field = build_field(cfg)
        field.reset(follower.n, rng)
        return [field.wrench(leader, follower, ROTORS, 0.002) for _ in range(5)]

    batch = run(slice(None), TrialRNG(4, 3))
    for i in range(3):
        one = run(slice(i, i + 1), TrialRNG(4, 1, i))
        for (f1, t1), (fb, tb) in zip(one, batch):
            assert np.array_equal(f1[0], fb[i]) and np.array_equal(t1[0], tb[i])
