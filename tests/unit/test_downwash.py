"""The default field: a momentum-conserving jet, felt per rotor disk and on the body, and its
required properties (DESIGN.md, "Downwash field")."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest
from jets import default_jet

from aerodock.downwash import build_field
from aerodock.downwash.base import BodyState
from aerodock.downwash.jet import RoundJetField
from aerodock.downwash.probe import half_magnitude_radius_m, probe_bodies, probe_field
from aerodock.geometry import rot_z
from aerodock.rng import TrialRNG

MASS, G = 0.7, 9.81
SEPARATIONS = (0.36, 0.64, 1.35)
FITTED = Path(__file__).resolve().parents[2] / "examples" / "crazyflie_wake_fitted.toml"


@pytest.fixture
def field(cfg):
    return build_field(cfg)


def _still(**kwargs) -> RoundJetField:
    """The default jet without turbulence (means, shapes, torques)."""
    return default_jet(**{"turb_vertical": 0.0, "turb_lateral": 0.0, **kwargs})


def test_the_default_wake_is_the_fitted_one(cfg):
    """The paper-scale world's wake is the fit to real flights (examples/, the output of
    `aerodock field fit`), not a hand table: every fitted key of defaults.toml equals it."""
    import inspect

    fitted = tomllib.loads(FITTED.read_text())["downwash"]["params"]
    assert fitted
    for key, value in fitted.items():
        assert cfg.downwash.params[key] == pytest.approx(value, rel=1e-12), key
    # One home: the jet keeps no defaults of its own that could drift from defaults.toml.
    params = inspect.signature(RoundJetField).parameters
    assert all(p.default is inspect.Parameter.empty for p in params.values())
    with pytest.raises(TypeError):
        RoundJetField()


@pytest.mark.parametrize("thrust_n, radius_m", [(0.7 * G, 0.0635), (0.032 * G, 0.0225),
                                                (2.0 * 0.7 * G, 0.0635), (0.067 * G, 0.0325)])
@pytest.mark.parametrize("depth_m", [0.0, 0.36, 0.64, 1.35, 3.0])
def test_momentum_flux_through_any_plane_equals_the_thrust(depth_m, thrust_n, radius_m):
    """rho int w^2 dA over the plane ``depth_m`` below the leader, integrated numerically on a
    polar grid from the mean wake air velocity (``wind_mps``), equals the leader's thrust."""
    field = default_jet(leader_rotor_radius_m=radius_m)
    leader, _ = probe_bodies(1.0, 0.0, 0.0, MASS, G)
    leader = BodyState(leader.p, leader.v, leader.R, np.array([thrust_n]), leader.mass_kg)
    r = np.linspace(0.0, 2.0, 4001)
    theta = np.linspace(0.0, 2.0 * np.pi, 17)[:-1]
    pts = np.stack([np.outer(np.cos(theta), r).ravel(), np.outer(np.sin(theta), r).ravel(),
                    np.full(theta.size * r.size, depth_m)], axis=1)
    many = BodyState(*(np.repeat(a, pts.shape[0], axis=0) for a in
                       (leader.p, leader.v, leader.R, leader.thrust_n, leader.mass_kg)))
    w = field.wind_mps(many, pts)
    assert np.allclose(w[:, :2], 0.0)  # along the axis (level leader)
    w2 = (w[:, 2] ** 2).reshape(theta.size, r.size)
    flux = 1.225 * np.trapezoid(w2.mean(axis=0) * 2.0 * np.pi * r, r)
    assert flux == pytest.approx(thrust_n, rel=2e-3)


@pytest.mark.parametrize("spread", [0.0231, 0.094])
def test_mean_decays_and_widens_with_separation(spread):
    """A jet that spreads (the force-only fit's 0.0231, a far round jet's 0.094; the default's
    fit with the torque barely does, docs/world.md) is slower on its axis and wider further
    down. (The force on the paper's follower need not fall with it: its disks, 0.095 m off the
    axis, sit near the narrow jet's half-width, and a wider jet reaches them.)"""
    field = default_jet(spread_rate=spread)
    speeds, radii = [], []
    for sep in SEPARATIONS:
        leader, follower = probe_bodies(sep, 0.0, 0.0, MASS, G)
        mean = field.mean_acceleration(leader, follower)[0]
        assert mean[2] > 0
        assert np.allclose(mean[:2], 0.0, atol=1e-9)  # no planar force on the axis
        speeds.append(field.wind_mps(leader, np.array([[0.0, 0.0, sep]]))[0, 2])
        radii.append(half_magnitude_radius_m(field.mean_acceleration, sep, MASS, G))
    assert speeds[0] > speeds[1] > speeds[2] > 0
    assert radii[0] < radii[1] < radii[2]


def test_probe_turbulence_matches_the_fields_own_figures(field):
    """Consecutive samples at the physics rate: mean and sd as the field says they are."""
    out = probe_field(field, 0.36, 0.0, 0.0, 40000, 0.002, np.random.default_rng(1), MASS, G)
    leader, follower = probe_bodies(0.36, 0.0, 0.0, MASS, G)
    turb = field.turbulence(leader, follower)
    sd_z, sd_lat = np.sqrt(turb["axial_var_mps4"][0]), np.sqrt(turb["lateral_var_mps4"][0])
    assert out["mean_mps2"][2] == pytest.approx(out["field_mean_mps2"][2], abs=0.05 * sd_z * 10)
    assert out["sd_mps2"][2] == pytest.approx(sd_z, rel=0.1)
    assert out["sd_mps2"][0] == pytest.approx(sd_lat, rel=0.1)
    assert out["sd_mps2"][1] == pytest.approx(sd_lat, rel=0.1)


def test_rotational_symmetry_about_hovering_leader_axis(field):
    angles = np.linspace(0, 2 * np.pi, 13)
    base_leader, base_follower = probe_bodies(0.5, 0.12, 0.0, MASS, G)
    ref = field.mean_acceleration(base_leader, base_follower)[0]
    for a in angles:
        leader, follower = probe_bodies(0.5, 0.12, 0.0, MASS, G, azimuth_rad=a)
        # the follower turns with the scene (its disks sample the wake where they are)
        follower = BodyState(follower.p, follower.v, rot_z(np.array([a])), follower.thrust_n,
                             follower.mass_kg)
        got = field.mean_acceleration(leader, follower)[0]
        assert np.allclose(got, rot_z(a) @ ref, atol=1e-9)
    # Also when the leader itself is yawed: the field only depends on the geometry.
    leader, follower = probe_bodies(0.5, 0.12, 0.0, MASS, G)
    yawed = BodyState(leader.p, leader.v, rot_z(np.array([0.7])), leader.thrust_n, leader.mass_kg)
    assert np.allclose(field.mean_acceleration(yawed, follower)[0], ref, atol=1e-9)


@pytest.mark.parametrize("ratio", [0.15, -0.15])
def test_planar_component_zero_on_axis_peaks_near_the_edge(ratio):
    """A point-sized follower (tiny frame and disks): the planar part is zero on the axis and
    peaks at ``r_half / sqrt(2 ln2)`` at ``planar_ratio`` of the centreline axial force,
    outwards (inwards for a negative ratio). The fit finds the real one near zero."""
    field = _still(planar_ratio=ratio, follower_diagonal_m=1e-4, follower_rotor_radius_m=1e-4,
                   body_area_ratio=0.0)
    radii = np.linspace(0.0, 0.5, 5001)
    leader, follower = probe_bodies(np.full_like(radii, 0.36), radii, 0.0, MASS, G)
    acc = field.mean_acceleration(leader, follower)
    planar = acc[:, 0]
    assert planar[0] == pytest.approx(0.0, abs=1e-12)
    assert np.all(np.sign(planar[1:]) == np.sign(ratio))
    peak = np.argmax(np.abs(planar))
    assert planar[peak] / acc[0, 2] == pytest.approx(ratio, rel=0.01)
    half = half_magnitude_radius_m(field.mean_acceleration, 0.36, MASS, G)
    assert radii[peak] == pytest.approx(half / np.sqrt(2 * np.log(2)), rel=0.01)


def test_wake_skews_behind_moving_leader(field):
    radii = np.linspace(-0.8, 0.8, 1601)
    peaks = {}
    for speed in (0.0, 2.0):
        leader, follower = probe_bodies(np.full_like(radii, 1.35), radii, speed, MASS, G)
        peaks[speed] = radii[np.argmax(field.mean_acceleration(leader, follower)[:, 2])]
    assert abs(peaks[0.0]) < 1e-3
    assert peaks[2.0] < -0.02  # leader moves north: the wake trails to the south


@pytest.mark.parametrize("exponent", [2.0, 1.5])
def test_follower_vertical_velocity_changes_force(exponent):
    """Descending with the wake air lowers its push, climbing into it raises it (beyond the
    still-air drag of the same motion, which the vehicle model has)."""
    field = _still(ingest_exponent=exponent)
    leader, follower = probe_bodies(0.5, 0.0, 0.0, MASS, G)
    still = field.mean_acceleration(leader, follower)[0, 2]
    down = BodyState(follower.p, np.array([[0.0, 0.0, 1.0]]), follower.R, follower.thrust_n,
                     follower.mass_kg)
    up = BodyState(follower.p, np.array([[0.0, 0.0, -1.0]]), follower.R, follower.thrust_n,
                   follower.mass_kg)
    assert field.mean_acceleration(leader, down)[0, 2] < still < field.mean_acceleration(
        leader, up)[0, 2]
    far = BodyState(follower.p + [[5.0, 0.0, 0.0]], down.v, follower.R, follower.thrust_n,
                    follower.mass_kg)
    assert np.allclose(field.mean_acceleration(leader, far), 0.0, atol=1e-9)  # no wake, no force


def test_linear_ingest_law_ignores_the_followers_own_motion():
    """p = 1: a rotor's thrust loss is linear in the inflow, and the part of it from the
    follower's own motion is its own drag (the vehicle model's), not the wake's."""
    field = _still(ingest_exponent=1.0, body_area_ratio=0.0)
    leader, follower = probe_bodies(0.5, 0.0, 0.0, MASS, G)
    moving = BodyState(follower.p, np.array([[0.0, 0.0, 1.0]]), follower.R, follower.thrust_n,
                       follower.mass_kg)
    assert field.mean_acceleration(leader, moving) == pytest.approx(
        field.mean_acceleration(leader, follower), rel=1e-12)


def test_no_singularity_at_zero_separation(field):
    seps = np.array([0.0, 1e-9, 1e-4, 0.01, -0.05])
    leader, follower = probe_bodies(seps, np.zeros(5), 0.0, MASS, G)
    acc = field.mean_acceleration(leader, follower)
    assert np.all(np.isfinite(acc))
    assert np.all(acc[:, 2] < 20.0)


def test_force_scales_with_leader_thrust_as_momentum_theory_says():
    """The centreline speed goes as sqrt(T): a disk's force as T^(p/2), the body's drag as T."""
    disks = _still(body_area_ratio=0.0, ingest_exponent=0.6)
    body = _still(ingest_coeff=0.0)
    leader, follower = probe_bodies(0.5, 0.0, 0.0, MASS, G)
    heavy = BodyState(leader.p, leader.v, leader.R, leader.thrust_n * 2, leader.mass_kg)
    for field, power in ((disks, 0.3), (body, 1.0)):
        base = field.mean_acceleration(leader, follower)[0, 2]
        assert field.mean_acceleration(heavy, follower)[0, 2] == pytest.approx(
            2 ** power * base, rel=1e-9)


def test_turbulence_spread_and_correlation_time(field, cfg):
    """100 trials of 2 s at the physics rate (the turbulence starts from its stationary
    distribution, each trial its own random stream): the pooled spread and autocorrelation."""
    dt = 1.0 / cfg.sim.physics_rate_hz
    n, k = 100, 1000
    leader, follower = probe_bodies(np.full(n, 0.36), np.zeros(n), 0.0, MASS, G)
    field.reset(n, TrialRNG(3, n))
    draws = np.array([field.acceleration(leader, follower, dt) for _ in range(k)])  # (k, n, 3)
    turb = field.turbulence(leader, follower)
    assert draws[..., 2].std() == pytest.approx(np.sqrt(turb["axial_var_mps4"][0]), rel=0.1)
    assert draws[..., 0].std() == pytest.approx(np.sqrt(turb["lateral_var_mps4"][0]), rel=0.1)
    dev = draws[..., 2] - draws[..., 2].mean()
    tau = turb["corr_time_s"][0]
    for lag_s in (0.02, 0.05):
        lag = int(round(lag_s / dt))
        corr = np.sum(dev[:-lag] * dev[lag:]) / np.sum(dev * dev)  # within each trial
        assert corr == pytest.approx(np.exp(-lag_s / tau), abs=0.08)


def test_each_disk_has_its_own_partly_shared_turbulence():
    """Two disks on the follower's x axis, level on the wake's axis: each disk's force (from the
    total and the torque) fluctuates by turb_vertical of its mean, and the two are correlated
    by exp(-spacing / (turb_length_ratio * b)), the share the field says. (100 trials of 2 s,
    each its own random stream, from the stationary distribution: pooled statistics.)"""
    field = default_jet(turb_vertical=0.3, turb_lateral=0.0, body_area_ratio=0.0,
                          turb_length_ratio=0.5)
    arm = 0.135
    offsets = np.array([[arm, 0.0, 0.0], [-arm, 0.0, 0.0]])
    n = 100
    leader, follower = probe_bodies(np.full(n, 0.64), np.zeros(n), 0.0, MASS, G)
    field.reset(n, TrialRNG(8, n))
    rows = []
    for _ in range(1000):
        force, torque = field.wrench(leader, follower, offsets, 0.002)
        rows.append((force[:, 2], torque[:, 1]))
    fz, ty = (np.array(col) for col in zip(*rows, strict=True))  # (steps, trials)
    # torque_y = z x - x z: -(arm F1 - arm F2) for downward (NED +z) disk forces
    f1, f2 = 0.5 * (fz - ty / arm), 0.5 * (fz + ty / arm)
    for f in (f1, f2):
        assert f.std() / f.mean() == pytest.approx(0.3, rel=0.08)
    b = field.half_width0_m + field.spread_rate * 0.64
    share = np.exp(-2 * arm / (0.5 * b))
    assert np.corrcoef(f1.ravel(), f2.ravel())[0, 1] == pytest.approx(share, abs=0.08)
    # and the correlation time is the shared one
    dev = f1 - f1.mean()
    tau = field.turbulence(leader, follower)["corr_time_s"][0]
    lag = 15
    corr = np.sum(dev[:-lag] * dev[lag:]) / np.sum(dev * dev)  # within each trial
    assert corr == pytest.approx(np.exp(-lag * 0.002 / tau), abs=0.08)


# -- wrench: the wake sampled at the follower's rotor disks (issue 10, item 2) -----------------
from aerodock.downwash.wrench import (  # noqa: E402
    bar_wake_force_n,
    follower_wrench,
    quad_rotor_offsets_body_m,
)
from aerodock.geometry import euler_to_rotmat  # noqa: E402

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
def test_disks_and_body_make_the_acceleration(cfg, fol_rpy):
    """Same turbulence draw: the disks' force (wrench) and the body's (body_force_n) add up to
    acceleration * mass, level or tilted, on or off the axis."""
    pts = [[0.0, 0.0, 0.36], [0.1, -0.05, 0.5], [0.3, 0.2, 1.0], [0.0, 0.0, -0.2]]
    leader, follower = _bodies(pts, fol_rpy=fol_rpy)
    a, b = build_field(cfg), build_field(cfg)
    a.reset(4, np.random.default_rng(7))
    b.reset(4, np.random.default_rng(7))
    for _ in range(5):
        acc = a.acceleration(leader, follower, 0.002)
        force, torque = b.wrench(leader, follower, ROTORS, 0.002)
        body = b.body_force_n(leader, follower)
        assert np.allclose(force + body, acc * MASS, rtol=1e-12, atol=1e-12)
        assert torque.shape == (4, 3) and np.all(np.isfinite(torque))
    # The default's body takes no part (the fit with the torque put it at zero); one with an
    # area takes a part, the disks the rest (on the axis, both push down).
    assert np.all(np.abs(body) < 1e-9 * np.abs(force).max())
    c = build_field(cfg.with_overrides({"downwash": {"params": {"body_area_ratio": 0.2}}}))
    c.reset(4, np.random.default_rng(7))
    force = c.wrench(leader, follower, ROTORS, 0.002)[0]
    body = c.body_force_n(leader, follower)
    assert body[0, 2] > 0 and force[0, 2] > body[0, 2]


@pytest.mark.parametrize("sep", SEPARATIONS)
def test_wrench_mean_is_the_mean(cfg, sep):
    """Disks plus body over 4000 independent turbulence draws (one step after a stationary
    reset) average to the field's mean."""
    n = 4000
    leader, follower = _bodies(np.tile([0.0, 0.0, sep], (n, 1)))
    field = build_field(cfg)
    field.reset(n, np.random.default_rng(11))
    force, _ = field.wrench(leader, follower, ROTORS, 0.002)
    total = force + field.body_force_n(leader, follower)
    exact = field.mean_acceleration(leader, follower)[0, 2]
    assert abs(total[:, 2].mean() / MASS - exact) < 4 * total[:, 2].std() / MASS / np.sqrt(n)


@pytest.mark.parametrize("yaw", [0.0, 0.3, np.pi / 4])
def test_wrench_torque_is_zero_on_the_axis(yaw):
    """In the mean (no turbulence) a level follower on the wake's axis feels no torque; with
    the disks' own turbulence it feels one that averages to zero."""
    leader, follower = _bodies([[0.0, 0.0, s] for s in (0.2, 0.36, 0.64, 1.35)],
                               fol_rpy=(0.0, 0.0, yaw))
    field = _still()
    field.reset(4, np.random.default_rng(2))
    force, torque = field.wrench(leader, follower, ROTORS, 0.002)
    assert np.all(force[:, 2] > 0)
    assert np.allclose(torque, 0.0, atol=1e-12 * np.abs(force).max())
    turbulent = default_jet()
    n = 4000
    many_l, many_f = _bodies(np.tile([0.0, 0.0, 0.36], (n, 1)), fol_rpy=(0.0, 0.0, yaw))
    turbulent.reset(n, np.random.default_rng(2))
    force, torque = turbulent.wrench(many_l, many_f, ROTORS, 0.002)
    roll_pitch = torque[:, :2]
    assert np.all(np.abs(roll_pitch.mean(axis=0)) < 4 * roll_pitch.std(axis=0) / np.sqrt(n))
    assert roll_pitch.std() > 1e-3 * 0.135 * force[:, 2].mean()
    # one lateral gust pushes every disk alike: on the axis, no yaw torque
    assert np.allclose(torque[:, 2], 0.0, atol=1e-12 * np.abs(force).max())


@pytest.mark.parametrize("azimuth", [0.0, 1.0, 2.5, -2.0])
@pytest.mark.parametrize("fol_yaw", [0.0, 0.4])
def test_wrench_torque_off_axis_tilts_the_follower_towards_the_axis(cfg, azimuth, fol_yaw):
    """Off the axis the rotors nearer the wake's centre are pushed harder: the torque turns the
    follower so that its side facing the axis goes down (its thrust tilts towards the axis)."""
    offsets = np.array([0.0, 0.05, 0.1, 0.2])
    u = np.array([np.cos(azimuth), np.sin(azimuth), 0.0])
    pts = offsets[:, None] * u + [0.0, 0.0, 0.36]
    leader, follower = _bodies(pts, fol_rpy=(0.0, 0.0, fol_yaw))
    field = _still()
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


@pytest.mark.parametrize("gain", [0.0, 3.0, 6.5])
def test_disk_torque_gain_scales_the_torque_and_keeps_the_force(gain):
    """``disk_torque_gain`` scales the mean torque of the axial forces (the whole torque without a
    planar part) of a level or tilted follower off the axis by the gain, and leaves the net
    force (the same turbulence draw) and the turbulence as they are."""
    pts = [[0.05, 0.0, 0.36], [0.07, -0.04, 0.5], [0.0, 0.1, 0.3]]
    for rpy in ((0.0, 0.0, 0.0), (0.1, -0.05, 0.7)):
        leader, follower = _bodies(pts, fol_rpy=rpy)
        base = default_jet(planar_ratio=0.0)
        scaled = default_jet(planar_ratio=0.0, disk_torque_gain=gain)
        np.testing.assert_allclose(scaled.mean_disk_torque_nm(leader, follower),
                                   gain * base.mean_disk_torque_nm(leader, follower),
                                   rtol=1e-9, atol=1e-15)
        base.reset(3, np.random.default_rng(4))
        scaled.reset(3, np.random.default_rng(4))
        for _ in range(3):
            f0, t0 = base.wrench(leader, follower, ROTORS, 0.002)
            f1, t1 = scaled.wrench(leader, follower, ROTORS, 0.002)
            np.testing.assert_allclose(f1, f0, rtol=1e-12, atol=1e-15)
            np.testing.assert_allclose(scaled.body_force_n(leader, follower),
                                       base.body_force_n(leader, follower), rtol=1e-12)
            assert gain == 1.0 or not np.allclose(t1, t0)
        np.testing.assert_allclose(scaled.mean_acceleration(leader, follower),
                                   base.mean_acceleration(leader, follower), rtol=1e-12)
        for key, value in base.turbulence(leader, follower).items():
            np.testing.assert_allclose(scaled.turbulence(leader, follower)[key], value)


def test_disk_torque_gain_must_not_be_negative():
    with pytest.raises(ValueError, match="disk_torque_gain must be >= 0"):
        default_jet(disk_torque_gain=-1.0)


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


def test_wrench_torque_comes_from_the_wake_at_each_disk():
    """The torque is sum_k r_k x (R^T F_k), each disk's force being the wake it alone sits in
    (the same field asked for one disk at a time), tilted and moving too."""
    pts = np.array([[0.08, 0.03, 0.36], [-0.15, 0.1, 0.7], [0.3, -0.1, 1.2]])
    leader, follower = _bodies(pts, leader_v=(0.4, 0.1, 0.0), fol_rpy=(0.15, -0.1, 0.8))
    field = _still(planar_ratio=0.1)
    field.reset(3, np.random.default_rng(6))
    force, torque = field.wrench(leader, follower, ROTORS, 0.002)
    want, total = np.zeros((3, 3)), np.zeros((3, 3))
    for j in range(4):
        one, _ = field.wrench(leader, follower, ROTORS[j:j + 1], 0.002)
        total += one
        want += np.cross(ROTORS[j], np.einsum("nji,nj->ni", follower.R, one))
    assert np.allclose(force, total, rtol=1e-12)
    assert np.allclose(torque, want, rtol=1e-9, atol=1e-12)


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


def test_the_kept_rotor_layouts_and_pair_distances_are_the_computed_ones():
    """The layouts and the disks' mean spacing are kept per size (a wake fit builds a jet per
    flight at every step of its least squares): a caller's copy may be changed without
    changing the next caller's, and a spacing follows its layout's values."""
    from aerodock.downwash.jet_inputs import _mean_pair_distance_m, mean_pair_distance_m

    def computed(layout):  # the spacing computed afresh, not looked up
        return _mean_pair_distance_m.__wrapped__(layout.shape, layout.dtype.str, layout.tobytes())

    first = quad_rotor_offsets_body_m(0.092)
    first[0] = 99.0
    again = quad_rotor_offsets_body_m(0.092)
    assert again[0, 0] == pytest.approx(0.046 * np.cos(np.pi / 4)) and again.flags.writeable
    for diagonal in (0.092, 0.12, 0.27):
        layout = quad_rotor_offsets_body_m(diagonal)
        assert mean_pair_distance_m(layout) == computed(layout)
        layout *= 2.0  # the same array, other values: another spacing
        assert mean_pair_distance_m(layout) == computed(layout)
    assert mean_pair_distance_m(np.zeros((1, 3))) == 0.0
