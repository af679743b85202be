"""The compiled bar-and-cables geometry gives the numbers of the NumPy code it replaced, to the
bit: :func:`platform_segments`, :func:`rotor_strike` and the mission's fused
:func:`platform_strike` (what each replaced is written out here as it was). The strike is a
boolean, so the disks' reaches are set to the NumPy distances themselves (and one ulp above):
a distance off by one ulp flips the answer."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.geometry import rpy_to_rotmat
from aerodock.world.platform import (
    DISK_HALF_THICKNESS_M,
    PAPER_ROTOR_RADIUS_M,
    BarState,
    PlatformParams,
    platform_segments,
    platform_strike,
    rotor_strike,
)

SIZES = (1, 2, 3, 16, 257)
OFFSETS = np.array([[0.046, 0.046, 0.0], [-0.046, 0.046, 0.0], [-0.046, -0.046, 0.0],
                    [0.046, -0.046, 0.0]])


def _params() -> PlatformParams:
    return PlatformParams(cable_length_m=0.6, cable_spacing_m=0.3, bar_length_m=0.4,
                          bar_diameter_m=0.012, bar_mass_kg=0.05, anchor_below_leader_m=0.03,
                          yaw_damping=0.8, swing_damping=0.3, gravity_mps2=9.81)


def _numpy_segments(anchor_p, leader_yaw_rad, bar, params):
    """platform_segments as NumPy computed it."""
    half = 0.5 * params.bar_length_m
    axis_bar = np.stack([np.cos(bar.yaw_rad), np.sin(bar.yaw_rad),
                         np.zeros_like(bar.yaw_rad)], axis=1)
    axis_lead = np.stack([np.cos(leader_yaw_rad), np.sin(leader_yaw_rad),
                          np.zeros_like(leader_yaw_rad)], axis=1)
    end_1, end_2 = bar.p - half * axis_bar, bar.p + half * axis_bar
    top_1 = anchor_p - 0.5 * params.cable_spacing_m * axis_lead
    top_2 = anchor_p + 0.5 * params.cable_spacing_m * axis_lead
    return np.stack([end_1, top_1, top_2], axis=1), np.stack([end_2, end_1, end_2], axis=1)


def _numpy_distances(follower_p, follower_R, offsets, seg_a, seg_b):  # noqa: N803
    """rotor_strike's axial and radial distances (n, rotors, segments) as NumPy computed them."""
    centres = follower_p[:, None, :] + np.matmul(follower_R[:, None], offsets[
        None, :, :, None])[..., 0]
    axis = follower_R[:, :, 2][:, None, None, :]
    a, b = seg_a[:, None], seg_b[:, None]
    c = centres[:, :, None]
    ab = b - a
    t = ((c - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-12)
    closest = a + np.clip(t, 0.0, 1.0)[..., None] * ab
    rel = closest - c
    axial = (rel * axis).sum(-1)
    radial = np.sqrt(np.maximum((rel * rel).sum(-1) - axial * axial, 0.0))
    return axial, radial


def _numpy_hit(axial, radial, axial_reach_m, radial_reach_m):
    return ((np.abs(axial) < axial_reach_m) & (radial < radial_reach_m)).any(axis=(1, 2))


def _scene(rng: np.random.Generator, n: int):
    """Leaders, bars and followers around them: rotors near the bar and the cables, some on
    them; the bars near the origin (so that no rounding of the rotors' centres is lost in
    adding a large position)."""
    lead_p = 0.1 * rng.normal(size=(n, 3)) + np.array([0.0, 0.0, -0.63])
    lead_r = np.ascontiguousarray(rpy_to_rotmat(rng.uniform(-0.4, 0.4, (n, 3))
                                                * np.array([1.0, 1.0, 8.0])))
    leader_yaw = rng.uniform(-np.pi, np.pi, n)
    bar = BarState(p=lead_p + np.array([0.0, 0.0, 0.63]) + 0.03 * rng.normal(size=(n, 3)),
                   v=np.zeros((n, 3)), yaw_rad=leader_yaw + 0.3 * rng.normal(size=n),
                   yaw_rate_radps=np.zeros(n))
    fol_p = bar.p + rng.normal(size=(n, 3)) * np.array([0.15, 0.15, 0.08]) * rng.uniform(0, 2)
    fol_r = np.ascontiguousarray(rpy_to_rotmat(rng.uniform(-0.5, 0.5, (n, 3))
                                               * np.array([1.0, 1.0, 6.0])))
    return lead_p, lead_r, leader_yaw, bar, fol_p, fol_r


def _reaches(rng: np.random.Generator, axial, radial):
    """Reaches equal to one rotor-segment pair's NumPy distances (or one ulp above them)."""
    i, k, s = (rng.integers(0, m) for m in axial.shape)
    axial_reach, radial_reach = abs(axial[i, k, s]), radial[i, k, s]
    if rng.random() < 0.5:
        axial_reach = np.nextafter(axial_reach, np.inf)
    if rng.random() < 0.5:
        radial_reach = np.nextafter(radial_reach, np.inf)
    return float(axial_reach), float(radial_reach)


@pytest.mark.parametrize("n", SIZES)
def test_segments_and_strikes_are_numpys(n):
    rng = np.random.default_rng(7 + n)
    params = _params()
    for trial in range(12):
        lead_p, lead_r, leader_yaw, bar, fol_p, fol_r = _scene(rng, n)
        if trial == 5:
            fol_p[0, 1] = np.nan
            bar.yaw_rad[-1] = leader_yaw[-1]  # a cable and the bar's end meet
        anchor = lead_p + lead_r[:, :, 2] * params.anchor_below_leader_m
        want_a, want_b = _numpy_segments(anchor, leader_yaw, bar, params)
        got_a, got_b = platform_segments(anchor, leader_yaw, bar, params)
        assert got_a.tobytes() == want_a.tobytes()
        assert got_b.tobytes() == want_b.tobytes()
        if trial == 7:  # a zero-length segment (the clamp of |b - a|^2)
            want_b[:, 0] = want_a[:, 0]
        offsets = rng.normal(size=(4, 3)) * 0.05  # tilted, uneven arms too
        axial, radial = _numpy_distances(fol_p, fol_r, offsets, want_a, want_b)
        for _ in range(32):
            axial_reach, radial_reach = _reaches(rng, axial, radial)
            want = _numpy_hit(axial, radial, axial_reach, radial_reach)
            got = rotor_strike(fol_p, fol_r, offsets, radial_reach, want_a, want_b, 0.0,
                               axial_reach)
            np.testing.assert_array_equal(got, want)
        # the defaults: the paper's disk thickness scaled to the radius, a bar of 6 mm
        axial, radial = _numpy_distances(fol_p, fol_r, OFFSETS, want_a, want_b)
        want = _numpy_hit(axial, radial, DISK_HALF_THICKNESS_M * (0.05 / PAPER_ROTOR_RADIUS_M)
                          + 0.006, 0.05 + 0.006)
        np.testing.assert_array_equal(
            rotor_strike(fol_p, fol_r, OFFSETS, 0.05, want_a, want_b, 0.006), want)
        if trial != 7:
            np.testing.assert_array_equal(platform_strike(
                fol_p, fol_r, lead_p, lead_r, leader_yaw, bar, params, OFFSETS, 0.05, 0.006),
                want)


def test_the_scenes_strike_and_miss():
    """The random scenes above hold both answers (the comparison can fail)."""
    rng = np.random.default_rng(3)
    params = _params()
    lead_p, lead_r, leader_yaw, bar, fol_p, fol_r = _scene(rng, 400)
    hit = platform_strike(fol_p, fol_r, lead_p, lead_r, leader_yaw, bar, params, OFFSETS,
                          0.05, 0.006)
    assert 0 < np.count_nonzero(hit) < hit.size


def test_any_layout():
    """Strided and read-only arrays give the numbers of contiguous ones."""
    rng = np.random.default_rng(11)
    params = _params()
    lead_p, lead_r, leader_yaw, bar, fol_p, fol_r = _scene(rng, 40)
    want = platform_strike(fol_p, fol_r, lead_p, lead_r, leader_yaw, bar, params, OFFSETS,
                           0.05, 0.006)
    wide = np.zeros((40, 3, 6))
    wide[:, :, ::2] = fol_r
    lead_p.flags.writeable = False
    got = platform_strike(np.asfortranarray(fol_p), wide[:, :, ::2], lead_p, lead_r,
                          leader_yaw, bar, params, OFFSETS, 0.05, 0.006)
    np.testing.assert_array_equal(got, want)
