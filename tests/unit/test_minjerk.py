"""Minimum-jerk trajectories: boundary conditions, batching, optimality, clamping."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import trapezoid

from aerodock.planning.minjerk import minjerk


def random_problem(n: int, seed: int = 0) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {
        "p0": rng.normal(0.0, 1.0, (n, 3)),
        "v0": rng.normal(0.0, 0.5, (n, 3)),
        "a0": rng.normal(0.0, 0.5, (n, 3)),
        "pf": rng.normal(0.0, 1.0, (n, 3)),
        "vf": rng.normal(0.0, 0.5, (n, 3)),
        "af": rng.normal(0.0, 0.5, (n, 3)),
        "duration_s": rng.uniform(0.5, 8.0, n),
        "t0_s": rng.uniform(-5.0, 5.0, n),
    }


def test_boundary_conditions():
    prob = random_problem(50)
    traj = minjerk(**prob)
    pos, vel, acc = traj.sample(prob["t0_s"])
    np.testing.assert_allclose(pos, prob["p0"], atol=1e-9)
    np.testing.assert_allclose(vel, prob["v0"], atol=1e-9)
    np.testing.assert_allclose(acc, prob["a0"], atol=1e-9)
    # Evaluate the polynomial itself at tau = T (sample() past tf switches to extrapolation).
    tf = prob["t0_s"] + prob["duration_s"]
    pos, vel, acc = traj.sample(tf)
    np.testing.assert_allclose(pos, prob["pf"], atol=1e-9)
    np.testing.assert_allclose(vel, prob["vf"], atol=1e-9)
    np.testing.assert_allclose(acc, prob["af"], atol=1e-9)


def test_batch_equals_singles():
    prob = random_problem(7, seed=3)
    traj = minjerk(**prob)
    t = prob["t0_s"] + 0.37 * prob["duration_s"]
    batch = traj.sample(t)
    for i in range(7):
        single = minjerk(**{k: v[i : i + 1] for k, v in prob.items()}).sample(t[i])
        for b, s in zip(batch, single, strict=True):
            np.testing.assert_allclose(b[i : i + 1], s, atol=1e-12)


def test_rest_to_rest_profile():
    """Rest to rest: symmetric, peak speed 1.875 D / T at the midpoint, position D / 2 there."""
    n = 4
    rng = np.random.default_rng(5)
    p0, pf = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    zeros = np.zeros((n, 3))
    dur = np.array([1.0, 2.0, 4.0, 6.0])
    traj = minjerk(p0, zeros, zeros, pf, zeros, zeros, dur, 0.0)
    pos, vel, acc = traj.sample(0.5 * dur)
    np.testing.assert_allclose(pos, 0.5 * (p0 + pf), atol=1e-12)
    np.testing.assert_allclose(vel, 1.875 * (pf - p0) / dur[:, None], atol=1e-12)
    np.testing.assert_allclose(acc, 0.0, atol=1e-10)
    # Normalised profile 10 s^3 - 15 s^4 + 6 s^5.
    s = 0.3
    pos, _, _ = traj.sample(s * dur)
    np.testing.assert_allclose(pos, p0 + (pf - p0) * (10 * s**3 - 15 * s**4 + 6 * s**5),
                               atol=1e-12)


def test_jerk_optimal_against_perturbations():
    """Adding any polynomial that vanishes with its first two derivatives at both ends raises
    the integrated squared jerk (the quintic is the Euler-Lagrange solution)."""
    prob = random_problem(1, seed=9)
    traj = minjerk(**prob)
    big_t = prob["duration_s"][0]
    tau = np.linspace(0.0, big_t, 4001)
    c = traj.coeffs[0]  # (3, 6)
    jerk = 6 * c[:, 3:4] + 24 * c[:, 4:5] * tau + 60 * c[:, 5:6] * tau**2  # (3, m)

    def cost(j: np.ndarray) -> np.ndarray:
        return trapezoid(j**2, tau, axis=-1)

    base = cost(jerk)
    # delta = eps * tau^3 (T - tau)^3 * (1 + k tau): zero value, velocity, accel at both ends.
    poly_basis = [np.polynomial.Polynomial([0, 0, 0, 1]) * np.polynomial.Polynomial([big_t, -1])
                  ** 3 * np.polynomial.Polynomial([1, k]) for k in (0.0, 0.7, -0.4)]
    for poly in poly_basis:
        d_jerk = poly.deriv(3)(tau) / np.max(np.abs(poly(tau)))
        for eps in (1e-3, -1e-3, 0.1):
            assert np.all(cost(jerk + eps * d_jerk) > base)


def test_clamping_before_and_after():
    prob = random_problem(5, seed=2)
    traj = minjerk(**prob)
    pos, vel, acc = traj.sample(prob["t0_s"] - 3.0)
    np.testing.assert_allclose(pos, prob["p0"], atol=1e-12)
    np.testing.assert_allclose(vel, prob["v0"], atol=1e-12)
    np.testing.assert_allclose(acc, prob["a0"], atol=1e-12)
    late = 2.5
    pos, vel, acc = traj.sample(traj.tf_s + late)
    np.testing.assert_allclose(pos, prob["pf"] + prob["vf"] * late, atol=1e-12)
    np.testing.assert_allclose(vel, prob["vf"], atol=1e-12)
    np.testing.assert_array_equal(acc, 0.0)


def test_scalar_time_and_duration_broadcast():
    prob = random_problem(3, seed=4)
    prob["duration_s"] = 2.0
    prob["t0_s"] = 1.0
    traj = minjerk(**prob)
    assert traj.t0_s.shape == (3,) and traj.duration_s.shape == (3,)
    pos, vel, acc = traj.sample(2.0)
    assert pos.shape == vel.shape == acc.shape == (3, 3)
    pos_v, _, _ = traj.sample(np.full(3, 2.0))
    np.testing.assert_array_equal(pos, pos_v)


def test_velocity_is_derivative_of_position():
    prob = random_problem(4, seed=6)
    traj = minjerk(**prob)
    t = prob["t0_s"] + 0.6 * prob["duration_s"]
    h = 1e-6
    p_plus, v_plus, _ = traj.sample(t + h)
    p_minus, v_minus, _ = traj.sample(t - h)
    _, vel, acc = traj.sample(t)
    np.testing.assert_allclose((p_plus - p_minus) / (2 * h), vel, atol=1e-6)
    np.testing.assert_allclose((v_plus - v_minus) / (2 * h), acc, atol=1e-6)


def test_bad_duration_raises():
    prob = random_problem(2)
    prob["duration_s"] = np.array([1.0, 0.0])
    with pytest.raises(ValueError):
        minjerk(**prob)


def test_a_turning_leaders_reference_is_a_level_arc():
    """From t = 0 the leader's path bends at the turn rate: a quarter turn at 0.5 rad/s and 1 m/s
    ends 2 m along and 2 m across, flying across; velocity and acceleration are the path's."""
    from aerodock.mission.phases.leader import leader_reference

    p0, v0 = np.zeros((1, 3)), np.array([1.0, 0.0, 0.0])
    quarter = leader_reference(p0, v0, v0[None, :], np.pi, 0.5)
    np.testing.assert_allclose(quarter.p, [[2.0, 2.0, 0.0]], atol=1e-12)
    np.testing.assert_allclose(quarter.v, [[0.0, 1.0, 0.0]], atol=1e-12)
    np.testing.assert_allclose(quarter.a, [[-0.5, 0.0, 0.0]], atol=1e-12)
    h = 1e-5
    ahead, behind, now = (leader_reference(p0, v0, v0[None, :], t, 0.5)
                          for t in (1.0 + h, 1.0 - h, 1.0))
    np.testing.assert_allclose((ahead.p - behind.p) / (2 * h), now.v, atol=1e-8)
    np.testing.assert_allclose((ahead.v - behind.v) / (2 * h), now.a, atol=1e-8)
    straight = leader_reference(p0, v0, v0[None, :], 2.0)
    np.testing.assert_allclose(straight.p, [[2.0, 0.0, 0.0]])


def _numpy_minjerk(p0, v0, a0, pf, vf, af, dur, t0, t):
    """The NumPy expressions the kernels follow (the numbers they must give, to the bit)."""
    big_t = dur[:, None]
    dp = pf - p0
    c = np.empty(p0.shape + (6,))
    c[..., 0], c[..., 1], c[..., 2] = p0, v0, 0.5 * a0
    c[..., 3] = (20 * dp - (8 * vf + 12 * v0) * big_t - (3 * a0 - af) * big_t**2) / (
        2 * big_t**3)
    c[..., 4] = (-30 * dp + (14 * vf + 16 * v0) * big_t + (3 * a0 - 2 * af) * big_t**2) / (
        2 * big_t**4)
    c[..., 5] = (12 * dp - 6 * (vf + v0) * big_t - (a0 - af) * big_t**2) / (2 * big_t**5)
    tau = np.minimum(np.maximum(t - t0, 0.0), dur)[:, None, None]
    powers = np.arange(6)
    tau_k = tau**powers
    pos = np.add.reduce(c * tau_k, axis=-1)
    vel = np.add.reduce(c[..., 1:] * powers[1:] * tau_k[..., :-1], axis=-1)
    acc = np.add.reduce(c[..., 2:] * (powers[2:] * powers[1:-1]) * tau_k[..., :-2], axis=-1)
    after_s = t - (t0 + dur)
    after, before = (after_s > 0.0)[:, None], (t < t0)[:, None]
    pos = np.where(after, pf + vf * after_s[:, None], pos)
    vel, acc = np.where(after, vf, vel), np.where(after, 0.0, acc)
    return c, (np.where(before, p0, pos), np.where(before, v0, vel), np.where(before, a0, acc))


@pytest.mark.parametrize("n", [1, 3, 16, 257])
def test_kernels_give_numpys_numbers_to_the_bit(n):
    """The compiled coefficients and samples equal the NumPy expressions bit for bit (NumPy's
    own power loop, the sums in order), inside, before and after the plans."""
    prob = random_problem(n, seed=n)
    scale = np.exp(np.random.default_rng(n).normal(0.0, 3.0, 6))
    for key, s in zip(("p0", "v0", "a0", "pf", "vf", "af"), scale, strict=True):
        prob[key] = prob[key] * s
    traj = minjerk(**prob)
    dur, t0 = prob["duration_s"], prob["t0_s"]
    for t in (t0 + 0.37 * dur, t0 - 1.0, t0 + dur + 0.5, np.full(n, 0.7)):
        coeffs, expected = _numpy_minjerk(*(prob[k] for k in ("p0", "v0", "a0", "pf", "vf",
                                                                "af")), dur, t0, t)
        assert traj.coeffs.tobytes() == coeffs.tobytes()
        for got, want in zip(traj.sample(t), expected, strict=True):
            assert got.tobytes() == want.tobytes()
    scalar = traj.sample(0.7)
    for got, want in zip(scalar, traj.sample(np.full(n, 0.7)), strict=True):
        assert got.tobytes() == want.tobytes()
