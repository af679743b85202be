"""Bias observer: converges to a constant disturbance, slowly by design."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.control.observer import BiasObserver

DT = 0.01
TAU = 4.0


def simulate(
    n: int, duration_s: float, compensate: bool, seed: int = 0, tau_s: float = TAU
) -> tuple[np.ndarray, dict[float, np.ndarray]]:
    """Double integrators with a constant unknown bias under a PD + sinusoid command.

    Returns the true biases ``(n, 3)`` and the estimate at a few times.
    """
    rng = np.random.default_rng(seed)
    bias = rng.uniform(0.5, 2.0, (n, 3)) * rng.choice([-1.0, 1.0], (n, 3))
    p = rng.normal(0.0, 0.5, (n, 3))
    v = np.zeros((n, 3))
    obs = BiasObserver(n, DT, tau_s, pos_noise_m=0.002, vel_noise_mps=0.02,
                      accel_noise_mps2=0.5)
    obs.reset(p, v)
    snapshots = {}
    steps = round(duration_s / DT)
    phase = rng.uniform(0.0, 2 * np.pi, (n, 3))
    for k in range(steps):
        t = k * DT
        u = -2.0 * p - 2.5 * v + 0.5 * np.sin(1.3 * t + phase)
        if compensate:
            u = u - obs.bias_mps2
        a = u + bias
        p = p + v * DT + 0.5 * a * DT**2
        v = v + a * DT
        p_meas = p + rng.normal(0.0, 0.001, (n, 3))  # mocap noise
        v_meas = v + rng.normal(0.0, 0.01, (n, 3))
        obs.update(p_meas, v_meas, u)
        snapshots[round((k + 1) * DT, 6)] = obs.bias_mps2
    return bias, snapshots


@pytest.mark.parametrize("compensate", [False, True])
def test_converges_to_constant_disturbance(compensate):
    bias, snaps = simulate(n=8, duration_s=5 * TAU, compensate=compensate)
    final = snaps[5 * TAU]
    assert np.all(np.abs(final - bias) <= 0.05 * np.abs(bias))


def test_is_slow_by_design():
    bias, snaps = simulate(n=8, duration_s=TAU, compensate=False, seed=1)
    early = snaps[0.5] / bias  # recovered fraction, per trial and axis
    assert np.all(early < 0.25)
    assert np.all(early > 0.0)  # but already heading the right way
    at_tau = snaps[TAU] / bias
    assert np.all((at_tau > 0.5) & (at_tau < 0.75))  # about 1 - 1/e


@pytest.mark.parametrize("tau_s", [1.0, 4.0, 10.0])
def test_time_constant_matches_request(tau_s):
    obs = BiasObserver(1, DT, tau_s, pos_noise_m=0.002, vel_noise_mps=0.02,
                      accel_noise_mps2=0.5)
    assert obs.bias_time_constant_s == pytest.approx(tau_s, rel=0.01)


def test_noise_free_step_response_is_first_order():
    """Exact measurements, bias step of 1: b_hat(t) follows 1 - exp(-t / tau)."""
    n = 1
    obs = BiasObserver(n, DT, TAU, pos_noise_m=0.002, vel_noise_mps=0.02,
                      accel_noise_mps2=0.5)
    obs.reset(np.zeros((n, 3)), np.zeros((n, 3)))
    p, v = np.zeros((n, 3)), np.zeros((n, 3))
    b = np.array([[1.0, -2.0, 0.5]])
    for k in range(1, round(2 * TAU / DT) + 1):
        p, v = p + v * DT + 0.5 * b * DT**2, v + b * DT
        obs.update(p, v, np.zeros((n, 3)))
        if k in (round(TAU / DT), round(2 * TAU / DT)):
            expected = 1.0 - np.exp(-k * DT / TAU)
            np.testing.assert_allclose(obs.bias_mps2 / b, expected, atol=0.02)


def test_reset_and_shapes():
    obs = BiasObserver(3, DT, TAU, 0.002, 0.02, 0.5)
    assert obs.bias_mps2.shape == (3, 3)
    obs.reset(np.ones((3, 3)), np.zeros((3, 3)), bias_mps2=np.full((3, 3), 0.7))
    np.testing.assert_array_equal(obs.bias_mps2, 0.7)
    obs.reset(np.ones((3, 3)), np.zeros((3, 3)))
    np.testing.assert_array_equal(obs.bias_mps2, 0.0)
    # Consistent measurements with the model and zero bias: the estimate stays at zero.
    obs.update(np.ones((3, 3)), np.zeros((3, 3)), np.zeros((3, 3)))
    np.testing.assert_allclose(obs.bias_mps2, 0.0, atol=1e-15)


def test_bad_arguments_raise():
    with pytest.raises(ValueError):
        BiasObserver(2, DT, 0.0, 0.002, 0.02, 0.5)
    with pytest.raises(ValueError):
        BiasObserver(2, -DT, TAU, 0.002, 0.02, 0.5)


def test_started_with_an_uninformative_prior_the_filter_converges_fast():
    """A filter reset with a bias prior runs the time-varying Kalman gain: the bias is found in
    a fraction of the steady-state time constant, then the gain settles to the steady state."""
    dt, n = 0.01, 1
    obs = BiasObserver(n, dt, bias_tau_s=4.0, pos_noise_m=0.002, vel_noise_mps=0.02,
                      accel_noise_mps2=0.5)
    steady = BiasObserver(n, dt, bias_tau_s=4.0, pos_noise_m=0.002, vel_noise_mps=0.02,
                      accel_noise_mps2=0.5)
    bias = np.array([[0.0, 0.3, 0.6]])
    p, v = np.zeros((n, 3)), np.zeros((n, 3))
    obs.reset(p, v, None, bias_sd_mps2=2.0)
    steady.reset(p, v)
    for _ in range(int(1.0 / dt)):  # 1 s: a quarter of the time constant
        v = v + bias * dt
        p = p + v * dt
        obs.update(p, v, np.zeros((n, 3)))
        steady.update(p, v, np.zeros((n, 3)))
    assert np.allclose(obs.bias_mps2, bias, atol=0.05)
    assert np.all(np.abs(steady.bias_mps2 - bias)[0, 1:] > 0.1)  # the steady-state gain is slow
    for _ in range(int(30.0 / dt)):
        obs.update(p, v, np.zeros((n, 3)))
    assert obs.settled  # on the steady-state gain
