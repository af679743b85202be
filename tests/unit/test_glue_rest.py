"""The world step's compiled glue gives the numbers of the NumPy operations it replaced, to the
bit: the cables' wrench on the leader, the bar's step about the leaders' anchors, the ground's
test, and the vehicles' step with its per-body constants kept (what each replaced is written out
here as it was)."""

from __future__ import annotations

import numpy as np
import pytest

from aerodock.frozen import freeze
from aerodock.geometry import rpy_to_rotmat
from aerodock.world.platform import (
    PlatformParams,
    any_above,
    cable_wrench_kernel,
    hanging_bar,
    step_bar,
    step_hanging_bar,
)

SIZES = (1, 2, 3, 7, 24, 257)


def _rotations(rng: np.random.Generator, m: int) -> np.ndarray:
    rpy = rng.uniform(-np.pi, np.pi, (m, 3)) * np.array([0.4, 0.4, 1.0])
    return np.ascontiguousarray(rpy_to_rotmat(rpy))


def _platform() -> PlatformParams:
    return PlatformParams(cable_length_m=0.6, cable_spacing_m=0.3, bar_length_m=0.4,
                          bar_diameter_m=0.012, bar_mass_kg=0.05, anchor_below_leader_m=0.03,
                          yaw_damping=0.8, swing_damping=0.3, gravity_mps2=9.81)


@pytest.mark.parametrize("n", SIZES)
@pytest.mark.parametrize("rigid", [True, False])
def test_cable_wrench_is_numpys(n, rigid):
    """cable_wrench_kernel == the NumPy cable_on_leader (``+=``, the stacked matmul through
    the machine's BLAS, two scaled updates), onto accumulators that already hold numbers, -0.0
    too."""
    rng = np.random.default_rng(n + 10 * rigid)
    for trial in range(20):
        cable = rng.normal(size=(n, 3)) * 10.0 ** rng.integers(-3, 3)
        cable[0, 0] = -0.0
        rot = _rotations(rng, 2 * n)
        force0 = rng.normal(size=(2 * n, 3))
        force0[0, 1] = -0.0
        torque0 = rng.normal(size=(3, 2 * n)) if trial % 2 else np.zeros((3, 2 * n))
        d = 0.03 * (1 + trial)
        want_f, want_t = force0.copy(), torque0.copy()
        want_f[:n] += cable
        if rigid:
            body = np.matmul(cable[:, None, :], rot[:n])[:, 0]
            want_t[0, :n] -= d * body[:, 1]
            want_t[1, :n] += d * body[:, 0]
        got_f, got_t = force0.copy(), torque0.copy()
        cable_wrench_kernel(cable, rot, d, got_f, got_t if rigid else np.zeros((3, 0)), rigid)
        assert got_f.tobytes() == want_f.tobytes()
        assert got_t.tobytes() == want_t.tobytes()


@pytest.mark.parametrize("n", SIZES)
@pytest.mark.parametrize("yaw_given", [False, True])
def test_hanging_bar_is_step_bar_about_numpys_anchors(n, yaw_given):
    """step_hanging_bar == step_bar on the anchors and yaw the hanging-pair term computed with
    NumPy (``p[:n] + R[:n, :, 2] d``, ``arctan2(R10, R00)``), tense, slack and NaN rows."""
    rng = np.random.default_rng(100 + n)
    params = _platform()
    for trial in range(10):
        rot = _rotations(rng, 2 * n)
        pos, vel, acc = (rng.normal(size=(2 * n, 3)) for _ in range(3))
        p_next = pos + 0.002 * vel
        anchor = pos[:n] + rot[:n, :, 2] * params.anchor_below_leader_m
        bar = hanging_bar(anchor, vel[:n], rng.uniform(-3, 3, n), params)
        bar_p = bar.p + rng.normal(size=(n, 3)) * (0.02 if trial % 2 else 0.0)
        if trial == 3:
            bar_p[0] = np.nan
        bar = type(bar)(p=bar_p, v=bar.v + rng.normal(size=(n, 3)), yaw_rad=bar.yaw_rad,
                        yaw_rate_radps=rng.normal(size=n))
        force = rng.normal(size=(n, 3))
        mass = params.bar_mass_kg + rng.uniform(0, 0.5, n) * (trial % 3 == 0)
        yaw = rng.uniform(-3, 3, n) if yaw_given else None
        offset = rot[:n, :, 2] * params.anchor_below_leader_m
        want_yaw = yaw if yaw_given else np.arctan2(rot[:n, 1, 0], rot[:n, 0, 0])
        want_bar, want_cable = step_bar(bar, pos[:n] + offset, vel[:n], acc[:n],
                                        p_next[:n] + offset, want_yaw, force, mass, params, 0.002)
        got_bar, got_cable = step_hanging_bar(bar, pos, vel, acc, rot, p_next, yaw, force, mass,
                                              params, 0.002)
        assert got_cable.tobytes() == want_cable.tobytes()
        for name in ("p", "v", "yaw_rad", "yaw_rate_radps"):
            assert getattr(got_bar, name).tobytes() == getattr(want_bar, name).tobytes(), name


@pytest.mark.parametrize("z", [[-1.0, -2.0], [-1.0, 0.5], [np.nan, -1.0], [np.nan, 2.0],
                               [np.nan, np.nan], [-0.0, 0.0], [0.0, 1e-300], [-np.inf, np.inf]])
def test_any_above_is_fmax_reduce(z):
    p = np.zeros((len(z), 3))
    p[:, 2] = z
    assert any_above(p, 0.0) == bool(np.fmax.reduce(p[:, 2]) > 0.0)


# -- the vehicles' step: the kernel's arguments kept per body ---------------------------------
def _old_step_arrays(state, rotor_speed_cmd, ext_force_n, ext_torque_nm, params, dt_s,
                     targets=None, gyro=None, gyro_noise=None, attitude=None):
    """``rigid_body._step_arrays`` as it was before its arguments were kept per body: every
    constant looked up afresh at every call."""
    from aerodock.world.vehicles import rigid_body as rb
    from aerodock.world.vehicles import rigid_kernel

    body = state.body
    n = state.p.shape[0]
    alpha, inertia = rb._body_constants(body, dt_s)
    consts, mixer, torque_map, drag_sums = rb.kernel_constants(params)
    out = (np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3, 3)), np.empty((n, 3)),
           np.empty((n, 4)), np.empty(n), np.empty((n, 3)),
           np.empty((n, params.autopilot_state_columns)), np.empty(n))
    flown = targets is not None
    ff = targets.torque_ff_nm if flown else None
    rigid_kernel.step_vehicles(
        state.p, state.v, state.R, state.w, state.rotor_speed,
        params.thrust_coeff * state.thrust_gain, body.torque_gain,
        body.mass_rows_kg, inertia, alpha, flown,
        rb._NO_ROWS if flown else np.asarray(rotor_speed_cmd, dtype=float),
        rb._NO_ATTITUDE if attitude is None else attitude, attitude is not None,
        targets.R_des if flown else rb._NO_ATTITUDE,
        targets.yaw_rate_radps if flown else rb._NO_VALUES,
        targets.thrust_n if flown else rb._NO_VALUES, rb._NO_ROWS if ff is None else ff,
        ff is not None, state.w if gyro is None else gyro,
        rb._NO_ROWS if gyro_noise is None else gyro_noise, gyro_noise is not None,
        state.autopilot_state, state.yaw_setpoint, consts, params.stack_constants is not None,
        rb._stack(params), mixer, params.rotor_thrust_max_n,
        params.thrust_coeff, np.asarray(ext_force_n, dtype=float),
        rb._NO_ROWS if ext_torque_nm is None else np.asarray(ext_torque_nm, dtype=float),
        ext_torque_nm is not None, torque_map, drag_sums, params.rotor_drag_coeff,
        params.rotor_drag_z_coeff, params.parasitic_drag_coeff, params.gravity_mps2, dt_s,
        *out)
    return out


# (n = 1 runs the same loop; its arrays are both C and F contiguous, another compiled variant)
@pytest.mark.parametrize("n", (3, 24))
def test_the_vehicles_step_with_kept_arguments_is_the_old_one(cfg, n):
    """``_step_arrays`` (its constants kept on the body, flown with them packed from their
    second use) == the call that looked them up at every step: flown (with and without the
    sensed attitude, gyro noise, a torque feed-forward, an external torque) and under rotor
    commands; over several steps, so the kept arguments are reused, and after a new ``dt`` and
    with writable gains (never kept)."""
    from dataclasses import fields, replace

    from aerodock.world.vehicles import rigid_body as rb
    from aerodock.world.vehicles.fleet import build_fleet
    from aerodock.world.vehicles.point_mass import AttitudeCommand
    from aerodock.world.vehicles.targets import rigid_targets

    rng = np.random.default_rng(n)
    for stack in ("generic", "arducopter"):
        fleet = build_fleet(cfg.with_overrides({"autopilot": {"stack": stack}}, source="test"))
        params = fleet.params
        nominal = fleet.nominal_body(n)  # its arrays owned (read-only, as the world's are)
        body = type(nominal)(*(np.array(getattr(nominal, f.name)) for f in fields(nominal)))
        state = fleet.hover(rng.normal(size=(n, 3)), rng.uniform(-1, 1, n),
                            1.0 + 0.05 * rng.normal(size=n), body)
        state = replace(state, v=rng.normal(size=(n, 3)), w=0.3 * rng.normal(size=(n, 3)))
        cmd = AttitudeCommand(0.1 * rng.normal(size=n), 0.1 * rng.normal(size=n),
                              0.2 * rng.normal(size=n), np.full(n, 6.0),
                              0.01 * rng.normal(size=(n, 3)))
        for step in range(8):
            dt = 0.002 if step < 5 else 0.001
            if step == 6:
                state = replace(state, thrust_gain=np.array(state.thrust_gain))  # writable
            targets = rigid_targets(cmd, state, params, n)
            if step % 2:
                targets = replace(targets, torque_ff_nm=None)
            force = rng.normal(size=(n, 3))
            torque = None if step == 3 else 0.01 * rng.normal(size=(n, 3))
            noise = None if step % 3 == 0 else 0.01 * rng.normal(size=(n, 3))
            att = None if step % 4 < 2 else _rotations(rng, n)
            gyro = state.w + 0.01
            speeds = np.asarray(state.rotor_speed) * 1.01
            # read-only, as the kernel's placeholders for a None are: one compiled variant of
            # the kernel serves every case (a writable array is another type to numba, and a
            # fresh cache compiles each variant, some 10 s apiece)
            freeze(force, torque, noise, att, gyro, speeds)
            got = rb._step_arrays(state, speeds, force, torque, params, dt)
            want = _old_step_arrays(state, speeds, force, torque, params, dt)
            for g, w in zip(got[:7], want[:7]):  # (no autopilot: its two outputs are unset)
                assert g.tobytes() == w.tobytes(), (stack, step, "commanded")
            got = rb._step_arrays(state, None, force, torque, params, dt, targets, gyro, noise,
                                  att)
            want = _old_step_arrays(state, None, force, torque, params, dt, targets, gyro,
                                    noise, att)
            for g, w in zip(got, want):
                assert g.tobytes() == w.tobytes(), (stack, step)
            packed = state.body.__dict__["_packed_arguments"][1]
            assert (packed is not None) == (step in (1, 2, 3, 4)), step  # both paths flown
            p, v, rot, w_, omega, thrust, _, integral, yaw_sp = got
            state = replace(state, p=p, v=v, R=rot, w=w_, rotor_speed=omega, thrust_n=thrust,
                            autopilot_state=integral, yaw_setpoint=yaw_sp)


def test_the_kept_arguments_follow_writable_gains(cfg):
    """Gains someone can write are not kept: written in place, the next step reads them."""
    from dataclasses import replace

    from aerodock.world.vehicles import rigid_body as rb
    from aerodock.world.vehicles.fleet import build_fleet

    fleet = build_fleet(cfg)
    state = fleet.hover(np.zeros((2, 3)), 0.0, np.ones(2))
    state = replace(state, thrust_gain=np.array([1.0, 0.9]))
    speeds = np.asarray(state.rotor_speed) * 1.01
    rb._step_arrays(state, speeds, np.zeros((2, 3)), None, fleet.params, 0.002)
    state.thrust_gain[:] = [1.2, 0.8]
    got = rb._step_arrays(state, speeds, np.zeros((2, 3)), None, fleet.params, 0.002)
    want = _old_step_arrays(replace(state, thrust_gain=state.thrust_gain.copy()), speeds,
                            np.zeros((2, 3)), None, fleet.params, 0.002)
    assert all(g.tobytes() == w.tobytes() for g, w in zip(got[:7], want[:7]))


# -- the step's frame ----------------------------------------------------------------------------
def test_the_frame_is_its_constructors(cfg):
    """begin_step's frame and halves (built straight into their ``__dict__``) are what their
    constructors build: every field, in order, the same objects; the classes still only fill
    their fields (no ``__post_init__``)."""
    import dataclasses

    from aerodock.downwash.base import BodyState
    from aerodock.rng import TrialRNG
    from aerodock.world import World, hover_command
    from aerodock.world.state import StepFrame
    from aerodock.world.step import begin_step

    for cls in (StepFrame, BodyState):
        assert not hasattr(cls, "__post_init__")
    # a defaulted field's default is a shared immutable value (begin_step's template)
    assert all(f.default_factory is dataclasses.MISSING for f in dataclasses.fields(StepFrame))
    assert all(f.default in (None, False) for f in dataclasses.fields(StepFrame)
               if f.default is not dataclasses.MISSING)
    world = World(cfg, 2, TrialRNG(1, 2))
    world.reset(np.array([0.0, 0.0, -2.0]), np.array([0.0, 0.0, -1.4]))
    world.step(hover_command(world.vehicle, 2), hover_command(world.vehicle, 2))
    cmd = hover_command(world.vehicle, 2)
    frame = begin_step(world.state, world.params, world._targets(cmd, cmd), None)
    names = [f.name for f in dataclasses.fields(StepFrame)]
    assert list(vars(frame)) == names
    built = StepFrame(**{k: getattr(frame, k) for k in names})
    assert all(getattr(built, k) is getattr(frame, k) for k in names)
    for half in (frame.lead, frame.fol):
        assert type(half) is BodyState
        assert list(vars(half)) == [f.name for f in dataclasses.fields(BodyState)]
        with pytest.raises(dataclasses.FrozenInstanceError):
            half.p = None
    assert frame.bar_axis_t.tobytes() == np.stack(
        [np.cos(world.bar.yaw_rad), np.sin(world.bar.yaw_rad),
         np.zeros(2)]).tobytes()


# -- the gripper's tests: np.count_nonzero for ndarray.any ----------------------------------
@pytest.mark.parametrize("a", [np.zeros(0, bool), np.zeros(1, bool), np.ones(1, bool),
                               np.array([False, True, False]), np.zeros(3, np.int8),
                               np.array([0, 2, 0], np.int8), np.array([0.0, -0.0]),
                               np.array([0.0, np.nan]), np.array([1e-320, 0.0]),
                               np.zeros((2, 3), bool), np.eye(2, dtype=bool), np.bool_(True),
                               np.bool_(False)])
def test_any_is_ndarray_any(a):
    from aerodock.world.gripper import _any, _armed_any

    assert _any(a) is bool(np.asarray(a).any())
    assert _armed_any(a) is bool(np.asarray(a).any())


def test_gripper_idle_is_the_reductions_it_replaced():
    from aerodock.world.gripper import _OPEN, GripperState, gripper_idle

    rng = np.random.default_rng(5)
    for n in (1, 2, 5):
        for _ in range(50):
            gate = rng.choice(np.array([0, 0, 0, 1, 2, 3], np.int8), n)
            start = rng.choice(np.array([np.nan, np.inf, 1.0, -np.inf]), n)
            nan = np.full(n, np.nan)
            no = np.zeros(n, bool)
            state = GripperState(gate, nan, nan, nan, start, no, no, no, nan, nan, nan)
            want = bool((state.gate == _OPEN).all() and not (state.servo_start_s < np.inf).any())
            assert gripper_idle(state) is want
