"""The compiled control period (aerodock/world/period.py) against the per-step path: the same
arrays, bit for bit, over several control periods, including periods in which the kernel stops
mid-period and the per-step path finishes them; a step of one's own keeps the per-step path."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import aerodock.rng
import aerodock.world.world as world_module
from aerodock.bench.simulator import SimLoop
from aerodock.config import load_config
from aerodock.rng import TrialRNG
from aerodock.world import World, hover_command, period
from aerodock.world import period_kernel as period_stops
from aerodock.world.step import WORLD_STEP, Term, with_term
from aerodock.world.term_kernels import ground_kernel, rotor_fault_wrench

pytestmark = pytest.mark.skipif(not period.PERIOD_OK, reason="no compiled period here")
_RUN_PERIOD = world_module.run_period  # the real one (the tests wrap it)


def _state_arrays(world: World) -> list[np.ndarray]:
    """Everything a later step, a sensor or a recorder reads of the world."""
    s = world.state
    b = s.both
    out = [b.p, b.v, b.R, b.w, b.rotor_speed, b.autopilot_state, b.yaw_setpoint, b.thrust_n,
           s.bar.p, s.bar.v, s.bar.yaw_rad, s.bar.yaw_rate_radps, s.cable_force_n,
           s.leader_accel, s.follower_accel, s.last_downwash_mps2, s.imu.attitude,
           s.imu.accel_t, s.imu.gyro_radps, s.imu.nav_accel_mps2, s.imu.accel_ring,
           s.imu.gyro.z1, s.imu.gyro.delay, s.imu.accel.z2, s.imu.accel.delay,
           np.array([s.imu.gyro.head, s.imu.accel.head, s.imu.ring_head]),
           s.gripper.reading_n, s.gripper.gate, s.gripper.servo_start_s,
           s.gripper.triggered_by_contact, s.contact_sensed, s.contact_seen, s.ground_contact,
           world.field._processes, world.field._bar_noise,
           np.array([s.step_index, s.t_s])]
    for entry in s.history:
        out.extend(entry)
    lead, fol = world.observe()  # draws: the streams must stand at the same place too
    out.extend([lead.p, lead.v, lead.rpy, fol.p, fol.v, fol.rpy, world.observed_accel()])
    return out


def _fly(n: int, periods: int, compiled: bool, monkeypatch: pytest.MonkeyPatch,
         close_at: int | None = None, fault_at: int | None = None, torque: bool = False,
         ) -> tuple[list[list[np.ndarray]], dict]:
    """A SimLoop (both position controllers) flown ``periods`` control periods; every
    period's arrays, and the compiled period's stops by reason (with its steps)."""
    stops: dict = {}
    real = _RUN_PERIOD

    def counted(*args):
        done, why = real(*args)
        stops[why] = stops.get(why, 0) + 1
        stops["steps"] = stops.get("steps", 0) + done
        return done, why

    monkeypatch.setattr(world_module, "run_period", counted)
    monkeypatch.setattr(period, "PERIOD_OK", compiled)
    loop = SimLoop(load_config(), n, seed=11)
    out = []
    for k in range(periods):
        if k == fault_at:  # the follower's rotors lose some of their thrust from here on
            loop.world.set_rotor_loss(np.tile([0.3, 0.0, 0.1, 0.0], (n, 1)))
        if close_at is not None and k >= close_at:  # the active trigger: the servo starts
            world = loop.world
            obs_l, obs_f = world.observe()
            lead = loop.leader_ctl.step(obs_l.p, obs_l.v, obs_l.rpy, loop.leader_ref).command
            fol = loop.follower_ctl.step(obs_f.p, obs_f.v, obs_f.rpy, loop.follower_ref).command
            world.advance(lead, fol, np.ones(n, dtype=bool))
        else:
            loop.run(1)
        out.append(_state_arrays(loop.world))
        if torque:  # the flight log's torques (the first read starts the log)
            reading = loop.world.observed_torque()
            out[-1].extend([reading.kinematic_nm, reading.rotor_nm, reading.body_rates_radps,
                            reading.true_wake_nm])
    return out, stops


def _assert_same(ref: list[list[np.ndarray]], got: list[list[np.ndarray]]) -> None:
    assert len(ref) == len(got)
    for k, (a, b) in enumerate(zip(ref, got)):
        for i, (x, y) in enumerate(zip(a, b)):
            assert x.shape == y.shape and x.dtype == y.dtype, (k, i)
            assert np.array_equal(x, y, equal_nan=True), f"period {k}, array {i}"
            # -0 and +0 too: the same bits
            assert np.array_equal(np.signbit(x), np.signbit(y)), f"period {k}, array {i} sign"


@pytest.mark.parametrize("n", [1, 7])
def test_compiled_period_gives_the_per_step_numbers(n, monkeypatch):
    ref, none = _fly(n, 12, False, monkeypatch)
    got, stops = _fly(n, 12, True, monkeypatch)
    assert not none  # the reference never ran the kernel
    assert stops.get("steps", 0) == 12 * 5  # every step compiled
    _assert_same(ref, got)


@pytest.mark.parametrize("n", [1, 7])
def test_a_small_random_buffer_stops_the_kernel_mid_period(n, monkeypatch):
    """With the streams refilled every 40 draws (a few steps' worth), the kernel stops before
    each step whose draws the buffer does not hold, the buffer is refilled there as the step's
    first draw past its end would refill it (``TrialRNG.reserve_normals``), and the kernel
    goes on: every step compiled, the numbers the per-step path's."""
    monkeypatch.setattr(aerodock.rng, "_CHUNK", 40)
    ref, _ = _fly(n, 10, False, monkeypatch)
    reserve, short = aerodock.rng.TrialRNG.reserve_normals, []

    def checked(rng, per_trial):  # each refill asked for where the buffer, as the stream's
        # cursor stands, lacks the step's draws (a stale cursor would refill at the wrong row)
        short.append(rng._pos["normal"] + per_trial > rng._buf["normal"].shape[0])
        reserve(rng, per_trial)

    monkeypatch.setattr(aerodock.rng.TrialRNG, "reserve_normals", checked)
    got, stops = _fly(n, 10, True, monkeypatch)
    assert stops.get(period_stops.STOP_DRAWS, 0) >= 5  # mid-period stops
    assert stops["steps"] == 10 * 5
    assert short and all(short)
    _assert_same(ref, got)


def test_a_gripper_trigger_stops_the_kernel_after_its_step(monkeypatch):
    """The active trigger: the servo's start changes what later steps read of the gripper, so
    the kernel stops after that step (then its gate closes under the per-step path's eyes)."""
    ref, _ = _fly(3, 10, False, monkeypatch, close_at=4)
    got, stops = _fly(3, 10, True, monkeypatch, close_at=4)
    assert stops.get(period_stops.STOP_GRIPPER, 0) >= 1
    _assert_same(ref, got)


def test_the_flight_logs_torques_run_compiled(monkeypatch):
    ref, _ = _fly(7, 8, False, monkeypatch, torque=True)
    got, stops = _fly(7, 8, True, monkeypatch, torque=True)
    assert stops["steps"] == 8 * 5
    _assert_same(ref, got)


def test_rotor_faults_run_compiled(monkeypatch):
    ref, _ = _fly(3, 10, False, monkeypatch, fault_at=3)
    got, stops = _fly(3, 10, True, monkeypatch, fault_at=3)
    assert stops["steps"] >= 45
    _assert_same(ref, got)


def test_the_rotor_fault_wrench_is_numpys():
    """The rotor faults term's compiled form against its NumPy original."""
    rng = np.random.default_rng(3)
    n, thrust_coeff = 5, 1.3e-6
    omega = 2000.0 * rng.random((2 * n, 4))
    gain = 1.0 + 0.1 * rng.standard_normal(2 * n)
    loss = rng.random((n, 4)) * (rng.random((n, 4)) > 0.3)
    rot = rng.standard_normal((2 * n, 3, 3))
    torque_map = rng.standard_normal((4, 3)) * 0.05
    force, torque_t = rng.standard_normal((2 * n, 3)), rng.standard_normal((3, 2 * n))
    ref_force, ref_torque = force.copy(), torque_t.copy()
    lost = omega[n:] * omega[n:]
    lost *= (thrust_coeff * gain[n:])[:, None]
    lost *= loss
    ref_force[n:] += rot[n:, :, 2] * lost.sum(axis=1)[:, None]
    torque = ref_torque.T[n:]
    for i in range(4):
        torque -= lost[:, i:i + 1] * torque_map[i]
    rotor_fault_wrench(omega[n:], thrust_coeff, gain[n:], loss, rot[n:], torque_map, force[n:],
                       torque_t[:, n:])
    assert np.array_equal(force, ref_force) and np.array_equal(torque_t, ref_torque)


def test_a_step_of_ones_own_keeps_the_per_step_path(monkeypatch):
    calls = []

    def refused(*args):
        calls.append(args)
        raise AssertionError("a step of one's own ran the compiled period")

    monkeypatch.setattr(world_module, "run_period", refused)
    seen = []
    step = with_term(WORLD_STEP, Term("count", lambda state, frame, params: seen.append(1)),
                     after="motion capture")
    cfg = load_config()
    world = World(cfg, 2, TrialRNG(0, 2), step=step)
    world.reset(np.tile([0.0, 0.0, -2.0], (2, 1)), np.tile([0.05, 0.0, -1.4], (2, 1)))
    cmd = hover_command(world.vehicle, 2)
    world.advance(cmd, cmd)
    assert len(seen) == world.substeps and not calls


def test_the_kernel_is_written_for_the_default_step():
    """WORLD_STEP changed (a term added, taken out or moved) without the kernel following it
    would run per step: this test says so, pointing at aerodock/world/period.py."""
    assert period.runs_step(WORLD_STEP)
    assert not period.runs_step(WORLD_STEP[:-1])
    assert not period.runs_step((WORLD_STEP[1], WORLD_STEP[0], *WORLD_STEP[2:]))


def test_the_default_step_runs_compiled(monkeypatch):
    done = []
    real = _RUN_PERIOD
    monkeypatch.setattr(world_module, "run_period",
                        lambda *a: done.append(real(*a)) or done[-1])
    cfg = load_config()
    world = World(cfg, 2, TrialRNG(0, 2))
    world.reset(np.tile([0.0, 0.0, -2.0], (2, 1)), np.tile([0.05, 0.0, -1.4], (2, 1)))
    cmd = hover_command(world.vehicle, 2)
    world.advance(cmd, cmd)
    assert done and done[0][0] == world.substeps


def test_the_ground_kernel_is_numpys_ground_row_by_row():
    """The ground term's compiled form (shared with the period) against NumPy's, row by row:
    a row above the ground stops on it, the others keep every bit (a -0 stays -0), and a block
    of trials gives the whole batch's numbers for its rows."""
    p = np.array([[0.0, 0.0, 0.5], [1.0, 2.0, -0.0], [0.0, 0.0, np.nan], [0.0, 0.0, -1.0],
                  [0.0, 0.0, 0.0], [0.0, 0.0, 2.0]])
    v = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -0.0], [0.0, 0.0, 3.0], [0.0, 0.0, 2.0],
                  [0.0, 0.0, -0.0], [0.0, 0.0, np.nan]])
    contact = np.zeros(3, dtype=bool)
    ref_p, ref_v, ref_contact = p.copy(), v.copy(), contact.copy()
    below = ref_p[:, 2] > 0.0
    ref_p[:, 2] = np.where(below, 0.0, ref_p[:, 2])
    ref_v[:, 2] = np.where(below, np.minimum(ref_v[:, 2], 0.0), ref_v[:, 2])
    ref_contact |= below[3:] | below[:3]
    blocks = [(p.copy(), v.copy(), contact.copy()) for _ in range(2)]
    ground_kernel(p, v, contact, 0, 3)
    for a, b in ((p, ref_p), (v, ref_v), (contact, ref_contact)):
        assert np.array_equal(a, b, equal_nan=True)
        assert np.array_equal(np.signbit(a), np.signbit(b))
    bp, bv, bc = blocks[0]
    for lo, hi in ((0, 1), (1, 3)):
        ground_kernel(bp, bv, bc, lo, hi)
    for a, b in ((bp, ref_p), (bv, ref_v), (bc, ref_contact)):
        assert np.array_equal(a, b, equal_nan=True)
        assert np.array_equal(np.signbit(a), np.signbit(b))


def _dock(compiled: bool, monkeypatch: pytest.MonkeyPatch) -> tuple[list, dict, World]:
    """Three followers under their bars, two of them pressing on it (the third 0.3 m off),
    the active trigger from the third period on: contact, the gate closing, two captures and
    a miss, then the captured followers hanging from their bars."""
    stops: dict = {}

    def counted(*args):
        done, why = _RUN_PERIOD(*args)
        stops[why] = stops.get(why, 0) + 1
        stops["steps"] = stops.get("steps", 0) + done
        return done, why

    monkeypatch.setattr(world_module, "run_period", counted)
    monkeypatch.setattr(period, "PERIOD_OK", compiled)
    n = 3
    world = World(load_config(), n, TrialRNG(5, n))
    lead = np.tile([0.0, 0.0, -2.0], (n, 1))
    world.reset(lead, lead + [0.0, 0.0, 1.0])
    gp = world.gripper_params
    fol = world.state.bar.p + [0.0, 0.0, gp.mount_height_m + gp.bar_radius_m - 0.004]
    fol[1, 0] += 0.3
    world.reset(lead, fol)
    cmd = hover_command(world.vehicle, n)
    out = []
    for k in range(40):
        world.advance(cmd, cmd, np.full(n, k >= 2))
        out.append(_state_arrays(world))
    return out, stops, world


def test_contact_and_a_captured_follower_run_compiled(monkeypatch):
    ref, _, _ = _dock(False, monkeypatch)
    got, stops, world = _dock(True, monkeypatch)
    assert list(world.state.gripper.gate) == [2, 3, 2]  # captured, missed, captured
    assert list(world.state.contact_seen) == [True, False, True]
    assert stops.get(period_stops.STOP_GRIPPER, 0) >= 2  # the servo's start, the gate's end
    assert stops["steps"] >= 40 * 5 - 10  # the contacts and the hanging pairs compiled
    _assert_same(ref, got)


def _stand(compiled: bool, monkeypatch: pytest.MonkeyPatch) -> tuple[list, dict]:
    """A leader on its stand (the cable-length study's world), the follower climbing under it."""
    stops: dict = {}

    def counted(*args):
        done, why = _RUN_PERIOD(*args)
        stops["steps"] = stops.get("steps", 0) + done
        return done, why

    monkeypatch.setattr(world_module, "run_period", counted)
    monkeypatch.setattr(period, "PERIOD_OK", compiled)
    n = 3
    world = World(load_config(), n, TrialRNG(2, n), leader_fixed=True)
    lead = np.tile([0.0, 0.0, -2.0], (n, 1))
    world.reset(lead, lead + [0.1, 0.0, 1.2])
    cmd = hover_command(world.vehicle, n)
    climb = replace(cmd, thrust_n=cmd.thrust_n * 1.05, roll_rad=np.full(n, 0.02))
    out = []
    for _ in range(10):
        world.advance(cmd, climb)
        out.append(_state_arrays(world))
    return out, stops


def test_a_leader_on_its_stand_runs_compiled(monkeypatch):
    ref, _ = _stand(False, monkeypatch)
    got, stops = _stand(True, monkeypatch)
    assert stops["steps"] == 10 * 5
    _assert_same(ref, got)


def test_a_kernel_numba_cannot_compile_turns_the_compiled_period_off(monkeypatch):
    """A NumbaError from the kernel (raised while compiling, before any step) leaves the state
    as it was, turns the compiled period off for the process and the per-step path flies."""
    from numba.core.errors import TypingError

    def cannot(*args):
        raise TypingError("a sealed callee")

    monkeypatch.setattr(period, "PERIOD_OK", True)
    monkeypatch.setattr(period, "DISABLED", [])
    monkeypatch.setattr(period, "period_kernel", cannot)
    world = World(load_config(), 2, TrialRNG(0, 2))
    world.reset(np.tile([0.0, 0.0, -2.0], (2, 1)), np.tile([0.05, 0.0, -1.4], (2, 1)))
    cmd = hover_command(world.vehicle, 2)
    world.advance(cmd, cmd)
    assert not period.PERIOD_OK and period.DISABLED
    assert world.step_index == world.substeps
