"""The autopilots' attitude targets, compiled (:func:`targets_kernel.attitude_targets`), give the
NumPy formula's numbers to the bit, signed zeros and NaNs included, at every batch size, and
the arrays the step kernels read keep their numba types (layout, writability)."""

from __future__ import annotations

import numba
import numpy as np
import pytest

from aerodock.config import load_config
from aerodock.geometry import rpy_to_rotmat
from aerodock.world.vehicles.fleet import build_fleet
from aerodock.world.vehicles.point_mass import AttitudeCommand
from aerodock.world.vehicles.targets import rigid_targets

SPECIAL = np.array([-0.0, 0.0, np.nan, -np.nan, 0.3, -0.3, 1.0, -1.0, 20.0, np.inf, -np.inf,
                    1e-300, -1e-300])


def numpy_targets(cmd: AttitudeCommand, yaw_setpoint: np.ndarray, tilt: float,
                  thrust_max: float, n: int) -> tuple[np.ndarray, ...]:
    """The NumPy formula the kernel replaced (aerodock 20ff947's rigid_targets)."""
    rpy = np.empty((n, 3))
    np.minimum(np.maximum(cmd.roll_rad, -tilt), tilt, out=rpy[:, 0])
    np.minimum(np.maximum(cmd.pitch_rad, -tilt), tilt, out=rpy[:, 1])
    rpy[:, 2] = yaw_setpoint
    r_des = rpy_to_rotmat(rpy)
    r_des = np.ascontiguousarray(r_des.transpose(0, 2, 1)).transpose(0, 2, 1)
    return (r_des, np.broadcast_to(np.asarray(cmd.yaw_rate_radps, dtype=float), (n,)),
            np.broadcast_to(np.clip(cmd.thrust_n, 0.0, thrust_max), (n,)))


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """The same bits, but for a NaN's sign: a product of two NaNs of opposite signs takes the
    sign of the operand the machine code puts first (NumPy's SIMD loop and LLVM's scalar code
    may differ), and nothing reads a NaN's sign."""
    a, b = np.ascontiguousarray(a), np.ascontiguousarray(b)
    both_nan = np.isnan(a) & np.isnan(b)
    return a.shape == b.shape and bool(np.all((a.view(np.int64) == b.view(np.int64))
                                              | both_nan))


@pytest.mark.parametrize("n", [1, 2, 3, 7, 64, 513])
def test_attitude_targets_are_numpys(n: int) -> None:
    params = build_fleet(load_config()).params
    rng = np.random.default_rng(n)
    for trial in range(20):
        pick = (lambda: SPECIAL[rng.integers(0, SPECIAL.size, n)]) if trial % 2 else (
            lambda: rng.normal(0.0, 0.8, n))
        cmd = AttitudeCommand(pick(), pick(), pick(), 8.0 * pick())
        yaw = rng.normal(0.0, 2.0, n)
        got = rigid_targets(cmd, _State(yaw), params, n)
        want = numpy_targets(cmd, yaw, params.tilt_max_rad, params.thrust_max_n, n)
        for g, w in zip((got.R_des, got.yaw_rate_radps, got.thrust_n), want):
            assert same_bits(g, w)
            assert numba.typeof(g) == numba.typeof(w)  # the step kernels' signature


@pytest.mark.parametrize("n", [1, 2, 5, 256])
def test_a_fleets_two_halves_joined(n: int) -> None:
    """The leaders' and followers' commands joined in the call: the targets of their
    concatenation (the torque feed-forward's half without one zero)."""
    params = build_fleet(load_config()).params
    rng = np.random.default_rng(100 + n)
    lead = AttitudeCommand(rng.normal(0, 0.8, n), rng.normal(0, 0.8, n), rng.normal(0, 1, n),
                           8.0 * rng.normal(0, 1, n))
    fol = AttitudeCommand(-0.0, rng.normal(0, 0.8, n), 0.25, 7.0, np.ones((n, 3)))
    yaw = rng.normal(0.0, 2.0, 2 * n)
    got = rigid_targets(lead, _State(yaw), params, 2 * n, follower_cmd=fol)
    joined = AttitudeCommand(*(np.concatenate([np.broadcast_to(getattr(c, name), (n,))
                                               for c in (lead, fol)])
                               for name in ("roll_rad", "pitch_rad", "yaw_rate_radps",
                                            "thrust_n")))
    want = numpy_targets(joined, yaw, params.tilt_max_rad, params.thrust_max_n, 2 * n)
    for g, w in zip((got.R_des, got.yaw_rate_radps, got.thrust_n), want):
        assert same_bits(g, w)
        assert numba.typeof(g) == numba.typeof(w)
    assert np.array_equal(got.torque_ff_nm, np.concatenate([np.zeros((n, 3)), np.ones((n, 3))]))


def test_scalar_command() -> None:
    params = build_fleet(load_config()).params
    cmd = AttitudeCommand(-0.0, 0.2, 0.1, 7.5)
    yaw = np.array([0.3, -0.0, 0.0])
    got = rigid_targets(cmd, _State(yaw), params, 3)
    want = numpy_targets(cmd, yaw, params.tilt_max_rad, params.thrust_max_n, 3)
    for g, w in zip((got.R_des, got.yaw_rate_radps, got.thrust_n), want):
        assert same_bits(g, w)


class _State:
    """What rigid_targets reads of a vehicles' state: the yaw setpoint."""

    def __init__(self, yaw: np.ndarray):
        self.yaw_setpoint = yaw
