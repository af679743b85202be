"""The two-cable bar: pendulum period, yaw mode, cables only pull."""

from __future__ import annotations

import numpy as np

from aerodock.world.platform import BarState, PlatformParams, step_bar


def _swing(params, bar, seconds, dt=0.001, force=None):
    n = bar.p.shape[0]
    anchor = np.zeros((n, 3))
    zeros = np.zeros((n, 3))
    mass = np.full(n, params.bar_mass_kg)
    xs = []
    for _ in range(int(seconds / dt)):
        bar, _ = step_bar(bar, anchor, zeros, zeros, anchor, np.zeros(n),
                          zeros if force is None else force, mass, params, dt)
        xs.append(bar.p.copy())
    return bar, np.array(xs)


def _period(signal, dt):
    crossings = np.nonzero((signal[:-1] < 0) & (signal[1:] >= 0))[0]
    return np.mean(np.diff(crossings)) * dt


def test_small_swing_period_is_pendulum(cfg):
    for length in (0.36, 1.0):
        params = PlatformParams.from_config(
            cfg.with_overrides({"platform": {"cable_length_m": length, "swing_damping": 0.0}}))
        angle = 0.05
        p0 = np.array([[length * np.sin(angle), 0.0, length * np.cos(angle)]])
        bar = BarState(p0, np.zeros((1, 3)), np.zeros(1), np.zeros(1))
        _, xs = _swing(params, bar, 6.0)
        period = _period(xs[:, 0, 0], 0.001)
        expected = 2 * np.pi * np.sqrt(length / params.gravity_mps2)
        assert abs(period - expected) / expected < 0.01
        # stays on the cable sphere
        assert np.allclose(np.linalg.norm(xs[:, 0], axis=1), length, atol=1e-6)


def test_swings_in_both_directions_and_yaws(cfg):
    params = PlatformParams.from_config(cfg)
    length = params.cable_length_m
    p0 = np.array([[0.02, 0.02, np.sqrt(length**2 - 0.0008)]])
    bar = BarState(p0, np.zeros((1, 3)), np.array([0.3]), np.zeros(1))
    yaws = []
    for _ in range(5):
        bar, xs = _swing(params, bar, 0.2)
        yaws.append(bar.yaw_rad[0])
    assert np.ptp(xs[:, 0, 0]) > 0.01 and np.ptp(xs[:, 0, 1]) > 0.01
    assert min(yaws) < 0.0 < max(yaws)  # the bifilar mode swings the yaw back through zero
    expected = 2 * np.pi / np.sqrt(params.yaw_omega2)
    assert 0.2 < expected < 2.0


def test_cables_only_pull(cfg):
    params = PlatformParams.from_config(cfg)
    length = params.cable_length_m
    bar = BarState(np.array([[0.0, 0.0, length]]), np.zeros((1, 3)), np.zeros(1), np.zeros(1))
    up = np.array([[0.0, 0.0, -2.0 * params.bar_mass_kg * params.gravity_mps2]])  # lifts 2 g
    bar, xs = _swing(params, bar, 0.1, force=up)
    assert xs[-1, 0, 2] < length - 0.01  # pushed up: slack, not held
