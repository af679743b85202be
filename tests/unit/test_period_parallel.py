"""The compiled period with its trials in blocks across numba's threads
(:func:`aerodock.world.period_kernel.period_kernel_parallel`) against the serial kernel: the same
arrays, bit for bit (a -0 too), for any number of blocks, over control periods that cross every
term (contact, a trigger, the gate closing, captures and a miss, hanging followers, rotor
faults, the flight log's torques, a leader on its stand) and the kernel's stops."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import aerodock.world.world as world_module
from aerodock.bench.simulator import SimLoop
from aerodock.config import load_config
from aerodock.rng import TrialRNG
from aerodock.world import World, hover_command, period
from aerodock.world import period_kernel as kernels

pytestmark = pytest.mark.skipif(not period.PERIOD_OK, reason="no compiled period here")
_RUN_PERIOD = world_module.run_period


def _arrays(world: World) -> list[np.ndarray]:
    """What later steps, the sensors and the recorders read of the world."""
    s = world.state
    b = s.both
    out = [b.p, b.v, b.R, b.w, b.rotor_speed, b.autopilot_state, b.yaw_setpoint, b.thrust_n,
           s.bar.p, s.bar.v, s.bar.yaw_rad, s.bar.yaw_rate_radps, s.cable_force_n,
           s.leader_accel, s.follower_accel, s.last_downwash_mps2, s.imu.attitude,
           s.imu.accel_t, s.imu.gyro_radps, s.imu.nav_accel_mps2, s.imu.accel_ring,
           s.imu.gyro.z1, s.imu.gyro.z2, s.imu.gyro.delay, s.imu.accel.z1, s.imu.accel.z2,
           s.imu.accel.delay, np.array([s.imu.gyro.head, s.imu.accel.head, s.imu.ring_head]),
           s.gripper.reading_n, s.gripper.gate, s.gripper.servo_start_s,
           s.gripper.triggered_by_contact, s.gripper.inside_at_start, s.gripper.slipped,
           s.gripper.resolved_s, s.contact_sensed, s.contact_seen, s.ground_contact,
           world.field._processes, world.field._bar_noise, np.array([s.step_index, s.t_s])]
    for entry in s.history:
        out.extend(entry)
    lead, fol = world.observe()  # the streams must stand at the same place too
    out.extend([lead.p, lead.v, lead.rpy, fol.p, fol.v, fol.rpy, world.observed_accel()])
    return out


def _same(ref: list[list[np.ndarray]], got: list[list[np.ndarray]]) -> None:
    assert len(ref) == len(got)
    for k, (a, b) in enumerate(zip(ref, got)):
        assert len(a) == len(b)
        for i, (x, y) in enumerate(zip(a, b)):
            assert x.shape == y.shape and x.dtype == y.dtype, (k, i)
            assert np.array_equal(x, y, equal_nan=True), f"period {k}, array {i}"
            assert np.array_equal(np.signbit(x), np.signbit(y)), f"period {k}, array {i} sign"


def _blocks(monkeypatch: pytest.MonkeyPatch, blocks: int, counts: dict) -> None:
    """Every period in ``blocks`` blocks (1: the serial kernel), whatever the batch's size;
    ``counts`` gathers the steps each kernel ran."""
    monkeypatch.setattr(period, "kernel_blocks", lambda n: blocks)
    monkeypatch.setattr(period, "CHOOSE_BLOCKS", False)  # in blocks whatever the timing

    def counted(*args):
        done, why = _RUN_PERIOD(*args)
        counts[blocks] = counts.get(blocks, 0) + done
        counts[why] = counts.get(why, 0) + 1
        return done, why

    monkeypatch.setattr(world_module, "run_period", counted)


def _docking(n: int) -> list[list[np.ndarray]]:
    """``n`` followers under their bars, most pressing on it, every third 0.3 m off, a rotor
    fault in one trial of four, the active trigger from the third period on: contact, the
    gate closing, captures and misses, then the captured followers hanging from their bars."""
    world = World(load_config(), n, TrialRNG(5, n))
    lead = np.tile([0.0, 0.0, -2.0], (n, 1))
    world.reset(lead, lead + [0.0, 0.0, 1.0])
    gp = world.gripper_params
    fol = world.state.bar.p + [0.0, 0.0, gp.mount_height_m + gp.bar_radius_m - 0.004]
    fol[::3, 0] += 0.3
    world.reset(lead, fol)
    loss = np.zeros((n, 4))
    loss[::4] = [0.3, 0.0, 0.1, 0.0]
    world.set_rotor_loss(loss)
    cmd = hover_command(world.vehicle, n)
    out = []
    for k in range(40):
        world.advance(cmd, cmd, np.full(n, k >= 2))
        out.append(_arrays(world))
    return out


@pytest.mark.parametrize("blocks", [2, 3, 7])
def test_blocks_across_threads_give_the_serial_numbers_while_docking(blocks, monkeypatch):
    n = 7
    counts: dict = {}
    _blocks(monkeypatch, 1, counts)
    ref = _docking(n)
    _blocks(monkeypatch, blocks, counts)
    got = _docking(n)
    assert counts[blocks] >= 40 * 5 - 20  # nearly every step compiled, in blocks
    assert counts.get(kernels.STOP_GRIPPER, 0) >= 4  # each kernel stopped for the grippers
    assert set(got[-1][_GATE].tolist()) == {2, 3}  # captures and misses, both
    _same(ref, got)


_GATE = 29  # the grippers' gates in _arrays


def _flying(n: int, blocks: int, monkeypatch: pytest.MonkeyPatch) -> list[list[np.ndarray]]:
    """Both position controllers holding the docking formation (the bench's loop), a rotor
    fault from the fifth period, the flight log's torques read every period."""
    _blocks(monkeypatch, blocks, {})
    loop = SimLoop(load_config(), n, seed=11)
    out = []
    for k in range(12):
        if k == 4:
            loop.world.set_rotor_loss(np.tile([0.3, 0.0, 0.1, 0.0], (n, 1)))
        loop.run(1)
        out.append(_arrays(loop.world))
        reading = loop.world.observed_torque()
        out[-1].extend([reading.kinematic_nm, reading.rotor_nm, reading.body_rates_radps,
                        reading.true_wake_nm])
    return out


def test_blocks_give_the_serial_numbers_under_the_controllers(monkeypatch):
    ref = _flying(9, 1, monkeypatch)
    for blocks in (2, 4):
        _same(ref, _flying(9, blocks, monkeypatch))


def test_a_leader_on_its_stand_in_blocks(monkeypatch):
    def fly(blocks: int) -> list[list[np.ndarray]]:
        _blocks(monkeypatch, blocks, {})
        n = 5
        world = World(load_config(), n, TrialRNG(2, n), leader_fixed=True)
        lead = np.tile([0.0, 0.0, -2.0], (n, 1))
        world.reset(lead, lead + [0.1, 0.0, 1.2])
        cmd = hover_command(world.vehicle, n)
        climb = replace(cmd, thrust_n=cmd.thrust_n * 1.05, roll_rad=np.full(n, 0.02))
        out = []
        for _ in range(10):
            world.advance(cmd, climb)
            out.append(_arrays(world))
        return out

    _same(fly(1), fly(3))


def test_large_batches_use_every_thread(monkeypatch):
    monkeypatch.setattr(period.numba, "get_num_threads", lambda: 2)
    assert period.kernel_blocks(period.PARALLEL_MIN_TRIALS) == 2
    assert period.kernel_blocks(period.PARALLEL_MIN_TRIALS - 1) == 1
    monkeypatch.setattr(period.numba, "get_num_threads", lambda: 1)
    assert period.kernel_blocks(1000) == 1


def test_a_process_that_steps_in_blocks_keeps_blas_to_one_thread():
    """BLAS's idle threads spin after a call, and a step's blocks wait for each other: once a
    period runs in blocks, BLAS has one thread (numba's own threads sleep between steps unless
    the environment said otherwise)."""
    import os

    from threadpoolctl import threadpool_info

    period.one_blas_thread()
    blas = [info for info in threadpool_info() if info["user_api"] == "blas"]
    assert blas and all(info["num_threads"] == 1 for info in blas)
    assert os.environ.get("OMP_WAIT_POLICY")  # set before numba starts its threads
