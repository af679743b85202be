"""LQR on the linearised model: gain against a hand-derived closed form, stability, command."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from aerodock.control.lqr import lin_model, lqr_command, lqr_gain
from aerodock.geometry import wrap_angle

Q_DEFAULT = [1.0, 1.0, 8.0, 0.01, 0.01, 0.1, 1.0]
R_DEFAULT = [0.8, 0.8, 0.8, 1.0]


def double_integrator_gain(q_p: float, q_v: float, r: float) -> tuple[float, float]:
    """Closed-form LQR gain of ``p' = v, v' = u`` with ``Q = diag(q_p, q_v)``, ``R = r``.

    With ``P = [[p1, p2], [p2, p3]]`` the CARE ``A'P + PA - P B B' P / r + Q = 0`` reads
    entry-wise: (1,1) ``q_p - p2^2 / r = 0``; (1,2) ``p1 - p2 p3 / r = 0``;
    (2,2) ``2 p2 + q_v - p3^2 / r = 0``. Taking the positive (stabilising) roots,
    ``p2 = sqrt(q_p r)``, ``p3 = sqrt(r (q_v + 2 p2))`` and ``K = [p2, p3] / r``, i.e.
    ``k_p = sqrt(q_p / r)`` and ``k_v = sqrt(q_v / r + 2 k_p)``.
    """
    k_p = np.sqrt(q_p / r)
    k_v = np.sqrt(q_v / r + 2.0 * k_p)
    return float(k_p), float(k_v)


def test_closed_form_solves_scalar_care():
    for q_p, q_v, r in [(1.0, 0.01, 0.8), (8.0, 0.1, 0.8), (200.0, 4.0, 0.8), (3.0, 0.0, 2.0)]:
        k_p, k_v = double_integrator_gain(q_p, q_v, r)
        p2, p3 = k_p * r, k_v * r
        p1 = p2 * p3 / r
        p_mat = np.array([[p1, p2], [p2, p3]])
        a = np.array([[0.0, 1.0], [0.0, 0.0]])
        b = np.array([[0.0], [1.0]])
        residual = a.T @ p_mat + p_mat @ a - p_mat @ b @ b.T @ p_mat / r + np.diag([q_p, q_v])
        np.testing.assert_allclose(residual, 0.0, atol=1e-12)
        np.testing.assert_allclose(
            p_mat, scipy.linalg.solve_continuous_are(a, b, np.diag([q_p, q_v]), [[r]]), atol=1e-9
        )


def test_lin_model_structure():
    a, b = lin_model()
    assert a.shape == (7, 7) and b.shape == (7, 4)
    x = np.arange(7.0) + 1.0
    u = np.array([10.0, 20.0, 30.0, 40.0])
    xdot = a @ x + b @ u
    np.testing.assert_array_equal(xdot, [4.0, 5.0, 6.0, 10.0, 20.0, 30.0, 40.0])


def test_default_gain_matches_hand_computation():
    k = lqr_gain(Q_DEFAULT, R_DEFAULT)
    assert k.shape == (4, 7)
    expected = np.zeros((4, 7))
    for axis in range(3):
        k_p, k_v = double_integrator_gain(Q_DEFAULT[axis], Q_DEFAULT[axis + 3], R_DEFAULT[axis])
        expected[axis, axis] = k_p
        expected[axis, axis + 3] = k_v
    expected[3, 6] = np.sqrt(Q_DEFAULT[6] / R_DEFAULT[3])
    np.testing.assert_allclose(k, expected, atol=1e-8)
    # The numbers quoted in DESIGN.md.
    assert k[2, 2] == pytest.approx(np.sqrt(8.0 / 0.8), abs=1e-8)
    assert k[2, 2] == pytest.approx(3.1623, abs=1e-4)
    assert k[0, 0] == pytest.approx(np.sqrt(1.0 / 0.8), abs=1e-8)
    assert k[3, 6] == pytest.approx(1.0, abs=1e-8)


@pytest.mark.parametrize(
    "q, r",
    [
        (Q_DEFAULT, R_DEFAULT),
        ([30.0, 30.0, 200.0, 2.0, 2.0, 4.0, 1.0], [0.8, 0.8, 0.8, 1.0]),
        ([1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 5.0], [0.1, 1.0, 10.0, 0.5]),
    ],
)
def test_closed_loop_is_hurwitz(q, r):
    a, b = lin_model()
    eig = np.linalg.eigvals(a - b @ lqr_gain(q, r))
    assert np.all(eig.real < 0.0)


@pytest.mark.parametrize(
    "q, r",
    [
        ([1.0] * 6, [1.0] * 4),
        ([1.0] * 7, [1.0] * 3),
        ([1.0] * 7, [1.0, 1.0, 0.0, 1.0]),
        ([1.0] * 7, [1.0, -1.0, 1.0, 1.0]),
        ([1.0, 1.0, -1.0, 1.0, 1.0, 1.0, 1.0], [1.0] * 4),
        ([1.0, 1.0, 0.0, 1.0, 1.0, 1.0, 1.0], [1.0] * 4),
    ],
)
def test_bad_weights_raise(q, r):
    with pytest.raises(ValueError):
        lqr_gain(q, r)


def test_command_feedback_feedforward_and_yaw_wrap():
    k = lqr_gain(Q_DEFAULT, R_DEFAULT)
    rng = np.random.default_rng(0)
    n = 5
    pos, vel = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    ref_pos, ref_vel, ref_acc = (rng.normal(size=(n, 3)) for _ in range(3))
    yaw = np.full(n, np.pi - 0.1)
    ref_yaw = np.full(n, -np.pi + 0.1)  # true error is -0.2 rad, not 2 pi - 0.2
    ref_rate = rng.normal(size=n)
    acc, rate = lqr_command(k, pos, vel, yaw, ref_pos, ref_vel, ref_acc, ref_yaw, ref_rate)
    assert acc.shape == (n, 3) and rate.shape == (n,)
    for i in range(n):  # an independent per-trial reference computation
        err = np.concatenate([pos[i] - ref_pos[i], vel[i] - ref_vel[i], [-0.2]])
        u = -k @ err + np.concatenate([ref_acc[i], [ref_rate[i]]])
        np.testing.assert_allclose(acc[i], u[:3], atol=1e-12)
        np.testing.assert_allclose(rate[i], u[3], atol=1e-12)
    # On the reference, only the feed-forward remains.
    acc0, rate0 = lqr_command(k, ref_pos, ref_vel, ref_yaw, ref_pos, ref_vel, ref_acc, ref_yaw,
                              ref_rate)
    np.testing.assert_allclose(acc0, ref_acc, atol=1e-12)
    np.testing.assert_allclose(rate0, ref_rate, atol=1e-12)


def test_per_trial_gains_match_shared():
    k_soft = lqr_gain(Q_DEFAULT, R_DEFAULT)
    k_stiff = lqr_gain([30.0, 30.0, 200.0, 2.0, 2.0, 4.0, 1.0], R_DEFAULT)
    rng = np.random.default_rng(1)
    n = 6
    args = (rng.normal(size=(n, 3)), rng.normal(size=(n, 3)), rng.normal(size=n),
            np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3)), 0.0, 0.0)
    stiff = np.arange(n) % 2 == 1
    gains = np.where(stiff[:, None, None], k_stiff, k_soft)
    acc, rate = lqr_command(gains, *args)
    acc_soft, rate_soft = lqr_command(k_soft, *args)
    acc_stiff, rate_stiff = lqr_command(k_stiff, *args)
    np.testing.assert_allclose(acc, np.where(stiff[:, None], acc_stiff, acc_soft), atol=1e-12)
    np.testing.assert_allclose(rate, np.where(stiff, rate_stiff, rate_soft), atol=1e-12)
    assert not np.allclose(acc_soft, acc_stiff)


def test_closed_loop_simulation_converges():
    """Euler-integrate the linear model under the LQR command: the error decays."""
    k = lqr_gain(Q_DEFAULT, R_DEFAULT)
    n, dt = 4, 0.01
    rng = np.random.default_rng(2)
    pos, vel, yaw = rng.normal(size=(n, 3)), rng.normal(size=(n, 3)), rng.uniform(-3, 3, n)
    ref = rng.normal(size=(n, 3))
    for _ in range(3000):
        acc, rate = lqr_command(k, pos, vel, yaw, ref, np.zeros((n, 3)), np.zeros((n, 3)), 0.5, 0.0)
        pos, vel, yaw = pos + vel * dt, vel + acc * dt, yaw + rate * dt
    np.testing.assert_allclose(pos, ref, atol=1e-3)
    np.testing.assert_allclose(wrap_angle(yaw - 0.5), 0.0, atol=1e-3)
