"""The compiled sensing kernels against the NumPy expressions they replaced, to the bit."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.world.sensor_kernels import mocap_noise_kernel


def _numpy_noisy(p, v, rpy, draw, pos_sd, vel_sd, att_sd):
    """Motion capture's former NumPy noise for one vehicle (sensors.motion_capture's noisy)."""
    n = p.shape[0]
    rpy = rpy.copy()
    if att_sd > 0:
        rpy += att_sd * draw[:3].T
        draw = draw[3:]
    noise_p, noise_v = draw[:3].T, draw[3:].T
    return (np.add(p, pos_sd * noise_p, out=np.empty((n, 3))),
            np.add(v, vel_sd * noise_v, out=np.empty((n, 3))), rpy)


@pytest.mark.parametrize("att_sd", [0.0, 0.0123])
@pytest.mark.parametrize("n", [1, 7, 256])
def test_mocap_noise_kernel_bit_for_bit(n: int, att_sd: float) -> None:
    rng = np.random.default_rng(n + int(att_sd * 1e4))
    k = 9 if att_sd > 0 else 6
    vehicles = []
    for _ in range(2):
        state = rng.normal(scale=rng.uniform(0.1, 50.0), size=(3, n, 3))
        draw = rng.standard_normal((n, k)).T  # a transposed view, as the streams give
        vehicles.append((state[0], state[1][:, ::-1], state[2], draw))
    pos_sd, vel_sd = 10 ** rng.uniform(-4, 0), 10 ** rng.uniform(-4, 0)
    out = np.empty((6, n, 3))
    (lp, lv, lr, ld), (fp, fv, fr, fd) = vehicles
    mocap_noise_kernel(lp, lv, lr, ld, fp, fv, fr, fd, pos_sd, vel_sd, att_sd, out)
    for o, (p, v, rpy, draw) in zip((0, 3), vehicles, strict=True):
        want = _numpy_noisy(p, v, rpy, draw, pos_sd, vel_sd, att_sd)
        for got, expect in zip(out[o:o + 3], want, strict=True):
            assert got.tobytes() == expect.tobytes()


def _numpy_step_gripper(state, t_s, contact_force_n, inside, sample_sensor, close_command,
                        params, rng):
    """step_gripper as it was in NumPy (before gripper_step_kernel), for the comparison."""
    from aerodock.world.gripper import GripperState, _any, _armed_any

    _open, _closing, _captured, _missed = 0, 1, 2, 3
    reading = state.reading_n
    open_ = state.gate == _open
    untriggered = open_ & np.isnan(state.servo_start_s)
    fire = None
    by_contact = state.triggered_by_contact
    if sample_sensor:
        raw = contact_force_n + state.bias_true_n + params.sensor_noise_n * rng.standard_normal(
            contact_force_n.shape
        )
        reading = raw - state.bias_est_n
        stuck = ~np.isnan(state.sensor_stuck_n)
        if _any(stuck):
            reading = np.where(stuck, state.sensor_stuck_n, reading)
        if _armed_any(params.passive):
            sensed = untriggered & (reading > params.contact_threshold_n) & params.passive
            fire = sensed
            by_contact = by_contact | sensed
    if _armed_any(params.active):
        by_command = untriggered & close_command & params.active
        fire = by_command if fire is None else fire | by_command
    servo_start = state.servo_start_s
    if fire is not None and _any(fire):
        servo_start = np.where(fire, t_s + params.latency_s, servo_start)
    gate = state.gate
    inside_at_start = state.inside_at_start
    start_now = open_ & (servo_start <= t_s)
    if _any(start_now):
        gate = np.where(start_now, _closing, gate).astype(np.int8)
        inside_at_start = np.where(start_now, inside, inside_at_start)
    slipped, resolved = state.slipped, state.resolved_s
    closing = gate == _closing
    if _any(closing):
        done = closing & (t_s >= servo_start + state.close_time_s)
        if _any(done):
            gate = np.where(done, np.where(inside, _captured, _missed), gate).astype(np.int8)
            slipped = slipped | (done & ~inside & inside_at_start)
            resolved = np.where(done, t_s, resolved)
    if (gate is state.gate and reading is state.reading_n and servo_start is state.servo_start_s
            and by_contact is state.triggered_by_contact
            and inside_at_start is state.inside_at_start and slipped is state.slipped
            and resolved is state.resolved_s):
        return state
    return GripperState(gate, state.bias_true_n, state.bias_est_n, reading, servo_start,
                        by_contact, inside_at_start, slipped, resolved, state.close_time_s,
                        state.sensor_stuck_n)


@pytest.mark.parametrize("seed", range(6))
def test_step_gripper_kernel_bit_for_bit(cfg, seed: int) -> None:
    """Random gripper runs (forces, inside flags, samples, commands, per-trial and global
    triggers, stuck gauges, jammed servos): the compiled step gives the NumPy step's states,
    array by array to the bit, and passes on the same unchanged arrays (or the same state)."""
    from dataclasses import replace

    from aerodock.world.gripper import (
        _STATE_FIELDS,
        GripperParams,
        calibrated_gripper,
        step_gripper,
    )

    rng = np.random.default_rng(seed)
    n = int(rng.choice([1, 3, 40]))
    params = GripperParams.from_config(cfg)
    choices = [True, False, rng.random(n) < 0.5]
    params = replace(params, passive=choices[seed % 3], active=choices[(seed + 1 + seed // 3) % 3],
                     latency_s=float(rng.uniform(0.0, 0.02)),
                     close_time_s=float(rng.uniform(0.005, 0.05)))
    state = calibrated_gripper(n, params, np.random.default_rng(seed))
    stuck = np.where(rng.random(n) < 0.2, rng.choice([0.0, 3.0], n), np.nan)
    jammed = np.where(rng.random(n) < 0.2, np.inf, state.close_time_s)
    state = replace(state, sensor_stuck_n=stuck, close_time_s=jammed)
    new_rng, old_rng = np.random.default_rng(seed + 100), np.random.default_rng(seed + 100)
    new, old = state, state
    thr = params.contact_threshold_n
    for k in range(300):
        t = (k + 1) * 0.002
        force = np.where(rng.random(n) < 0.3, rng.uniform(0.0, 3.0 * thr + 1.0, n), 0.0)
        inside = rng.random(n) < 0.6
        sample = bool(rng.random() < 0.3)
        close = rng.random(n) < 0.05
        got = step_gripper(new, t, force, inside, sample, close, params, new_rng)
        want = _numpy_step_gripper(old, t, force, inside, sample, close, params, old_rng)
        assert (got is new) == (want is old), k
        for name in _STATE_FIELDS:
            a, b = getattr(got, name), getattr(want, name)
            assert a.dtype == b.dtype and a.tobytes() == b.tobytes(), (k, name)
            assert (a is getattr(new, name)) == (b is getattr(old, name)), (k, name)
        new, old = got, want
    assert new_rng.random() == old_rng.random()  # the same draws
    assert np.count_nonzero(new.gate != 0) > 0  # the run reached closing gates
