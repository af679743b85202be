"""The node's input judgement under random message streams (issue 25: stale stamps).

Each vehicle's stream is a seeded random mix of good messages and the faults a real link shows:
stamps of zero, going backwards or frozen, a relay repeating a message, positions beyond the
plausible range, non-finite values. Every message goes through the node's own path
(:class:`aerodock.node.core.InputMonitor`, then :func:`aerodock.node.core.prediction_step`), and
the output must be the predictor's when both newest messages are good, and zero with the injected
fault named in the reason otherwise; never a NumPy warning.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest
from fuzz_helpers import count, n_cases

from aerodock.bench.node import random_model
from aerodock.learning.runtime import Predictor
from aerodock.node.core import InputMonitor, VehicleState, prediction_step

FAULTS = ("zero", "backwards", "frozen", "repeat", "far", "nan", "inf")
# What the reason must contain for each fault (the stream generator is the oracle).
KEYWORD = {"zero": "stamp is zero", "backwards": "went backwards", "frozen": "stamp frozen",
           "repeat": "repeated message", "far": "beyond", "nan": "not finite",
           "inf": "not finite"}


def _good(rng: np.random.Generator, stamp_s: float, centre: np.ndarray) -> VehicleState:
    return VehicleState(centre + rng.normal(0, 0.1, 3), rng.normal(0, 0.3, 3), np.eye(3),
                        received_s=0.0, stamp_s=stamp_s)


def _message(rng: np.random.Generator, prev: VehicleState | None, newest_s: float,
             centre: np.ndarray) -> tuple[VehicleState, str | None, float]:
    """The next message of a stream: (state, the fault injected or None, newest stamp so far)."""
    good_stamp = newest_s + 0.01
    kind = None if prev is None or rng.random() < 0.6 else str(rng.choice(FAULTS))
    if kind is None:
        return _good(rng, good_stamp, centre), None, good_stamp
    assert prev is not None
    prev_stamp = prev.stamp_s or 0.0
    if kind == "zero" or (kind in ("backwards", "frozen") and prev_stamp == 0.0):
        # (a stamp derived from a zero stamp is zero: that is what is wrong with it)
        return _good(rng, 0.0, centre), "zero", newest_s
    if kind == "repeat" and prev_stamp == 0.0:
        return replace(prev), "zero", newest_s
    if kind == "backwards":
        return _good(rng, prev_stamp * rng.uniform(0.5, 0.999), centre), kind, newest_s
    if kind == "frozen":
        return _good(rng, prev_stamp, centre), kind, newest_s
    if kind == "repeat":
        return replace(prev), kind, newest_s
    state = _good(rng, good_stamp, centre)
    if kind == "far":
        p = state.p_m.copy()
        p[rng.integers(3)] = rng.choice([2e4, -1e300, 1e300])
        return replace(state, p_m=p), kind, good_stamp
    bad = np.nan if kind == "nan" else np.inf * rng.choice([-1.0, 1.0])
    if rng.random() < 0.5:
        p = state.p_m.copy()
        p[rng.integers(3)] = bad
        return replace(state, p_m=p), kind, good_stamp
    v = state.v_mps.copy()
    v[rng.integers(3)] = bad
    return replace(state, v_mps=v), kind, good_stamp


@pytest.mark.parametrize("seed", [0, 1])
def test_random_streams_are_judged_by_their_data(seed, tmp_path):
    rng = np.random.default_rng(seed)
    predictor = Predictor.load(random_model(tmp_path / "model"))
    centres = {"leader": np.array([0.0, 0.0, -2.0]), "follower": np.array([0.1, -0.1, -1.5])}
    monitors = {role: InputMonitor() for role in centres}
    newest = {role: None for role in centres}
    injected: dict[str, str | None] = {role: None for role in centres}
    newest_stamp = {role: 1.0 for role in centres}
    seen = set()
    for k in range(n_cases(300)):
        role = "leader" if rng.random() < 0.5 else "follower"
        state, fault, newest_stamp[role] = _message(rng, newest[role], newest_stamp[role],
                                                    centres[role])
        now = 10.0 + 0.005 * k
        state = replace(state, received_s=now)
        newest[role], injected[role] = state, fault
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            monitors[role].receive(state)
            out = prediction_step(predictor, newest["leader"], newest["follower"], now,
                                  max_age_s=1e3,
                                  faults={r: m.verdict for r, m in monitors.items()})
        count("node-stamps")
        if newest["leader"] is None or newest["follower"] is None:
            assert out.stale and "missing" in out.reason
            continue
        bad = {r: f for r, f in injected.items() if f is not None}
        seen |= set(bad.values())
        if not bad:
            assert not out.stale, (k, out.reason)
            assert np.all(np.isfinite(out.f_ext_mps2)) and np.any(out.f_ext_mps2 != 0)
            continue
        assert out.stale, (k, bad)
        np.testing.assert_array_equal(out.f_ext_mps2, np.zeros(3))
        for r, f in bad.items():
            assert f"{r}: " in out.reason and KEYWORD[f] in out.reason, (k, r, f, out.reason)
    assert seen == set(FAULTS)  # every fault class was exercised


# --- attitudes (issue 41): overflowing quaternions, huge angles --------------------------------


def _random_quaternion(rng: np.random.Generator) -> np.ndarray:
    """A unit quaternion, or one scaled far off unit, or with zero, huge, tiny or non-finite
    components."""
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    kind = rng.integers(6)
    if kind == 1:  # near unit: either side of the tolerance
        q *= 1.0 + rng.uniform(-0.02, 0.02)
    elif kind == 2:  # far off: 1e-300 .. 1e300 (1e200 overflowed the plain norm)
        q *= 10.0 ** rng.uniform(-300, 300)
    elif kind == 3:  # a few components huge or tiny
        mask = rng.random(4) < 0.5
        q[mask] = rng.choice([-1.0, 1.0], mask.sum()) * 10.0 ** rng.uniform(150, 308, mask.sum())
    elif kind == 4:
        q[rng.integers(4)] = rng.choice([np.nan, np.inf, -np.inf])
    elif kind == 5:
        q[:] = 0.0
    return q


def test_random_quaternions_are_rotations_or_refused(tmp_path):
    """Oracle: ``math.hypot`` (exact, no overflow): a quaternion is taken iff it is finite and
    its norm is 1 within the tolerance; taken, its matrix is a rotation; refused, the step
    publishes zero with the converter's reason."""
    import math

    from aerodock.node.core import (
        QUAT_NORM_TOLERANCE,
        implausible,
        odometry_state,
        px4_odometry_state,
    )

    rng = np.random.default_rng(41)
    predictor = Predictor.load(random_model(tmp_path / "model"))
    leader = VehicleState(np.array([0.0, 0.0, -2.0]), np.zeros(3), np.eye(3), 1.0, 1.0)
    taken = refused = 0
    for _ in range(n_cases(2000)):
        q = _random_quaternion(rng)
        finite = bool(np.isfinite(q).all())
        want = finite and abs(math.hypot(*q) - 1.0) <= QUAT_NORM_TOLERANCE
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            states = [odometry_state((0.3, -0.2, 1.5), q, (0.1, 0.0, 0.0), frame="enu",
                                     twist="body", received_s=1.0, stamp_s=1.0),
                      px4_odometry_state((0.3, -0.2, -1.5), q, (0.1, 0.0, 0.0), 3,
                                         received_s=1.0, timestamp_us=1_000_000)]
            for state in states:
                out = prediction_step(predictor, leader, state, 1.0, max_age_s=1.0)
                if want:
                    assert state.fault is None and implausible(state) is None, q
                    np.testing.assert_allclose(state.R @ state.R.T, np.eye(3), atol=1e-12)
                    assert np.linalg.det(state.R) == pytest.approx(1.0, abs=1e-12)
                    assert not out.stale
                else:
                    assert state.fault and state.fault.startswith("attitude quaternion"), q
                    assert out.stale and out.reason == f"follower: {state.fault}"
                    np.testing.assert_array_equal(out.f_ext_mps2, np.zeros(3))
        taken, refused = taken + want, refused + (not want)
        count("node-quaternions")
    assert taken > 100 and refused > 100  # both sides exercised


def test_random_euler_angles_are_rotations_or_refused():
    """Oracle: finite and within one turn, or refused with the angle's name."""
    from aerodock.node.core import MAX_ANGLE_RAD, current_state, implausible

    rng = np.random.default_rng(4141)
    for _ in range(n_cases(2000)):
        angles = rng.uniform(-MAX_ANGLE_RAD, MAX_ANGLE_RAD, 3)
        k = rng.integers(3)
        kind = rng.integers(4)
        if kind == 1:
            angles[k] = rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(0.8, 300)
        elif kind == 2:
            angles[k] = rng.choice([np.nan, np.inf, -np.inf])
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            state = current_state([0.0, 0.0, -2.0, 0.1, 0.0, 0.0, *angles], received_s=1.0,
                                  stamp_s=1.0)
        ok = bool(np.isfinite(angles).all() and (np.abs(angles) <= MAX_ANGLE_RAD).all())
        if ok:
            assert implausible(state) is None
            np.testing.assert_allclose(state.R @ state.R.T, np.eye(3), atol=1e-12)
        else:
            name = ("roll", "pitch", "yaw")[int(np.flatnonzero(
                ~(np.isfinite(angles) & (np.abs(angles) <= MAX_ANGLE_RAD)))[0])]
            assert implausible(state) == state.fault and state.fault.startswith(name)
            assert not np.isfinite(state.R).any()
        count("node-euler")


def test_a_long_run_of_garbage_keeps_the_bookkeeping_bounded():
    """Every message of a long garbage stream goes the node's way (converter, monitor,
    plausibility; as the ROS callback does) into a :class:`RefusalLog`, with reasons of every
    kind and random numbers; the log never holds more than its bounds."""
    from aerodock.node.core import current_state, implausible, odometry_state, px4_odometry_state
    from aerodock.node.refusals import (
        MAX_REASON_CHARS,
        MAX_REFUSAL_KINDS,
        RECENT_REFUSALS,
        RefusalLog,
    )

    rng = np.random.default_rng(7)
    log = RefusalLog()
    monitors = {"leader": InputMonitor(), "follower": InputMonitor()}
    n = n_cases(20_000)
    for k in range(n):
        role = "leader" if rng.random() < 0.5 else "follower"
        stamp = float(rng.choice([0.0, 1.0, rng.uniform(-1e9, 1e9)]))
        kind = rng.integers(4)
        try:
            if kind == 0:
                state = odometry_state(rng.normal(0, 10.0 ** rng.uniform(0, 300), 3),
                                       _random_quaternion(rng), rng.normal(size=3),
                                       frame="enu", twist="body", received_s=k, stamp_s=stamp)
            elif kind == 1:
                state = px4_odometry_state(rng.normal(size=3), _random_quaternion(rng),
                                           rng.normal(size=3), int(rng.integers(0, 6)),
                                           received_s=k, timestamp_us=int(abs(stamp)))
            elif kind == 2:
                sv = rng.normal(0, 10.0 ** rng.uniform(0, 300), int(rng.integers(0, 13)))
                state = current_state(sv, received_s=k, stamp_s=stamp)
            else:
                state = VehicleState(rng.normal(size=3), rng.normal(size=3), np.eye(3), k,
                                     stamp)
        except ValueError as err:  # the node: "unusable message (...)"
            why = f"unusable message ({err})"
        else:
            why = monitors[role].receive(state) or implausible(state)
        if why:
            log.record(role, why)
        if k % 997 == 0:  # garbage that is pure text, all different
            log.record(role, "".join(chr(c) for c in rng.integers(32, 0x2FFF, 300)))
        assert len(log.counts) <= MAX_REFUSAL_KINDS + 1 and len(log.recent) <= RECENT_REFUSALS
    assert log.total > n // 2 and sum(log.counts.values()) == log.total
    assert all(len(text) <= MAX_REASON_CHARS for text in log.recent)
    assert all(len(value) <= RECENT_REFUSALS * (MAX_REASON_CHARS + 3)
               for value in log.values().values())
    count("node-garbage", n)


def test_random_ros_arguments_are_taken_or_refused_in_one_line():
    """``aerodock node --ros-args ...``: whatever follows, rcl takes it or the node refuses it
    with one line of its own (never an exception, never rcl's file and line)."""
    pytest.importorskip("rclpy")
    import random

    from aerodock.node.ros import ros_args_error

    rng = random.Random(103)
    flags = ["-r", "--remap", "-p", "--param", "--params-file", "--log-level", "-e",
             "--enclave", "--disable-rosout-logs", "--enable-stdout-logs", "--", "--bogus",
             "-x", "--ros-args"]
    words = ["a:=b", "__ns:=/bravo", "__node:=f_ext_hat", "/aerodock/f_ext:=/x", "bad", ":=",
             "use_sim_time:=true", "p:=[1,", "q:={a: 1}", "/nonexistent.yaml", "", "é", "warn",
             "rcl:=debug", "1e-300", "__ns:=relative", "-1", "a b:=c"]
    taken = refused = 0
    for _ in range(n_cases(300)):
        args = ["--ros-args"] + [rng.choice(flags if rng.random() < 0.5 else words)
                                 for _ in range(rng.randint(0, 6))]
        why = ros_args_error(args)
        assert why is None or (isinstance(why, str) and why and "\n" not in why
                               and ", at /" not in why), (args, why)
        taken, refused = taken + (why is None), refused + (why is not None)
        count("node-ros-args")
    assert taken > 10 and refused > 10
