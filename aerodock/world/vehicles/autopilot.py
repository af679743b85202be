"""The onboard autopilot of the rigid-body vehicle: attitude P -> body-rate PI -> mixer.

Like ArduCopter's and PX4's multicopter controllers (attitude angle loop, rate loop, mixer with
saturation handling), batch-first and pure:

- :func:`attitude_target` turns the outer loop's command (roll, pitch, yaw rate, collective
  thrust in N) into a desired rotation, once per control period (the command is held);
- :func:`rate_setpoint`: attitude error ``e_R = vee(R_d^T R - R^T R_d) / 2`` (Lee et al.) times
  the angle gain, plus the commanded yaw rate as feed-forward;
- :func:`rate_control`: PI on the gyro's body rates (the gyro, not the true rates: its noise
  enters here), giving desired angular accelerations, times the inertia;
- :func:`mix`: collective thrust and body torques -> per-rotor thrusts for an X quadrotor, with
  the saturation handling of an "airmode" mixer: when a rotor would exceed its limits the
  collective is shifted so the torques (attitude) keep priority, then each rotor is clipped.

Units: angles rad, rates rad/s, torques N m, thrusts N. Body frame FRD (x forward, y right, z
down); the world is NED.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from aerodock.frozen import freeze, is_frozen
from aerodock.geometry import rpy_to_rotmat


@dataclass(frozen=True)
class AutopilotGains:
    """Gains of the attitude and rate loops (``[autopilot]`` in defaults.toml).

    Attributes:
        attitude_p: (3,) angle gain, rate setpoint per rad of attitude error, 1/s.
        rate_p: (3,) rate gain, angular acceleration per rad/s of rate error, 1/s.
        rate_i: (3,) rate integral gain, 1/s².
        rate_integral_max_radps2: limit of the integral term's angular acceleration (anti-windup).
        rate_max_radps: (3,) limit of the rate setpoint.
    """

    attitude_p: np.ndarray
    rate_p: np.ndarray
    rate_i: np.ndarray
    rate_integral_max_radps2: float
    rate_max_radps: np.ndarray


@functools.lru_cache(maxsize=64)
def _tiled_rows(values: bytes, n: int) -> np.ndarray:
    out = np.tile(np.frombuffer(values), (n, 1))
    freeze(out)
    return out


def per_axis(vec: np.ndarray, n: int) -> np.ndarray:
    """A constant (k,) vector as a read-only C-contiguous (n, k) array, cached per value and n.

    ``a * per_axis(g, n)`` gives the numbers of ``a * g`` for (n, k) ``a``, as one flat loop
    (a (k,) broadcast runs the inner loop once per row).
    """
    return _tiled_rows(np.asarray(vec, dtype=float).tobytes(), n)


def attitude_target(roll_rad: np.ndarray, pitch_rad: np.ndarray,
                    yaw_setpoint_rad: np.ndarray) -> np.ndarray:
    """(n, 3, 3) desired body-to-world rotation from ZYX Euler angles (the outer loop's tilt)."""
    return rpy_to_rotmat(np.stack([roll_rad, pitch_rad, yaw_setpoint_rad], axis=1))


def gain_columns(gains: AutopilotGains, inertia_kgm2: np.ndarray,
                 n: int | None = None) -> tuple[np.ndarray, ...]:
    """The loops' per-axis constants for component-major (3, n) work arrays: (-attitude_p / 2,
    rate limit, -rate limit, integral limit, -integral limit, rate_p, rate_i, inertia), each a
    read-only (3, 1) column or, given ``n``, a (3, n) tile (the same numbers in one flat loop: a
    broadcast runs numpy's slower general loop).

    Kept on ``gains`` for the last inertia array and ``n`` (every step asks with the same
    ones) while the gains' and the inertia's arrays are read-only (the vehicle parameters'
    are: :meth:`RigidBodyParams.from_config`); otherwise computed afresh."""
    hit = gains.__dict__.get("_columns")  # not a field: numbers derived from them
    if (hit is not None and hit[0] is inertia_kgm2 and hit[1] == n and is_frozen(inertia_kgm2)
            and _gains_frozen(gains)):
        return hit[2]
    limit = gains.rate_max_radps
    int_limit = gains.rate_integral_max_radps2 / np.maximum(gains.rate_i, 1e-12)

    def col(v: np.ndarray) -> np.ndarray:
        out = np.array(np.broadcast_to(np.asarray(v, dtype=float), (3,)))[:, None]
        if n is not None:
            out = np.repeat(out, n, axis=1)
        freeze(out)
        return out

    cols = tuple(col(v) for v in (-0.5 * gains.attitude_p, limit, -limit, int_limit, -int_limit,
                                  gains.rate_p, gains.rate_i, inertia_kgm2))
    gains.__dict__["_columns"] = (inertia_kgm2, n, cols)
    return cols


def _gains_frozen(gains: AutopilotGains) -> bool:
    """Whether every array of ``gains`` is read-only (their numbers cannot change)."""
    return (is_frozen(gains.attitude_p) and is_frozen(gains.rate_p) and is_frozen(gains.rate_i)
            and is_frozen(gains.rate_max_radps))


def rate_setpoint(R: np.ndarray, R_des: np.ndarray, yaw_rate_radps: np.ndarray,  # noqa: N803
                  gains: AutopilotGains) -> np.ndarray:
    """(n, 3) body-rate setpoint, rad/s: angle P on the geometric attitude error + yaw feed-forward.

    Args:
        R: (n, 3, 3) current rotation (the autopilot's attitude estimate).
        R_des: (n, 3, 3) desired rotation (:func:`attitude_target`).
        yaw_rate_radps: (n,) commanded yaw rate (feed-forward about body z).
        gains: loop gains.
    """
    cols = gain_columns(gains, np.ones(3))
    return np.ascontiguousarray(rate_setpoint_t(R, R_des, yaw_rate_radps, cols).T)


def rate_setpoint_t(R: np.ndarray, R_des: np.ndarray, yaw_rate_radps: np.ndarray,  # noqa: N803
                    cols: tuple[np.ndarray, ...]) -> np.ndarray:
    """:func:`rate_setpoint`, component-major (3, n), with ``cols`` of :func:`gain_columns`."""
    # M = R_des^T R (a stack of 3x3 products: each trial's numbers do not depend on the batch).
    m = np.matmul(R_des.transpose(0, 2, 1), R)
    rate = np.empty((3, R.shape[0]))
    np.subtract(m[:, 2, 1], m[:, 1, 2], out=rate[0])
    np.subtract(m[:, 0, 2], m[:, 2, 0], out=rate[1])
    np.subtract(m[:, 1, 0], m[:, 0, 1], out=rate[2])
    rate *= cols[0]
    rate[2] += yaw_rate_radps
    np.maximum(rate, cols[2], out=rate)  # np.clip's values, without its wrapper
    return np.minimum(rate, cols[1], out=rate)


def rate_control(rate_sp_radps: np.ndarray, gyro_radps: np.ndarray, integral: np.ndarray,
                 gains: AutopilotGains, inertia_kgm2: np.ndarray,
                 dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    """PI rate loop: returns (desired body torque (n, 3) N m, new integral state (n, 3) rad).

    Args:
        rate_sp_radps: (n, 3) rate setpoint.
        gyro_radps: (n, 3) measured body rates.
        integral: (n, 3) integral of the rate error, rad.
        gains: loop gains.
        inertia_kgm2: (3,) principal moments of inertia.
        dt_s: loop period.
    """
    cols = gain_columns(gains, inertia_kgm2)
    torque, new_int = rate_control_t(np.asarray(rate_sp_radps, dtype=float).T, gyro_radps,
                                     integral, cols, dt_s)
    return np.ascontiguousarray(torque.T), new_int


def rate_control_t(rate_sp_radps: np.ndarray, gyro_radps: np.ndarray, integral: np.ndarray,
                   cols: tuple[np.ndarray, ...], dt_s: float,
                   out: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`rate_control` on a component-major (3, n) setpoint with ``cols`` of
    :func:`gain_columns`: (torque (3, n), written into ``out`` if given, new integral (n, 3),
    C-ordered). ``gyro_radps`` is (n, 3) or, transposed, a component-major (3, n) array's
    ``.T``."""
    err = rate_sp_radps - np.asarray(gyro_radps, dtype=float).T
    new_t = err * dt_s
    new_t += np.asarray(integral, dtype=float).T
    np.maximum(new_t, cols[4], out=new_t)
    np.minimum(new_t, cols[3], out=new_t)
    accel = err
    accel *= cols[5]
    accel += np.multiply(new_t, cols[6], out=np.empty_like(new_t))
    accel = np.multiply(accel, cols[7], out=accel if out is None else out)
    return accel, np.ascontiguousarray(new_t.T)


def mix(thrust_n: np.ndarray, torque_nm: np.ndarray, mixer_inv: np.ndarray,
        rotor_thrust_max_n: float) -> np.ndarray:
    """(n, k) per-rotor thrusts for collective thrust (n,) and body torques (n, 3).

    ``mixer_inv`` (4, k) maps ``[T, tau_x, tau_y, tau_z]`` to rotor thrusts. Saturation: the
    collective part is shifted (down when a rotor exceeds its maximum, up when one would go below
    zero) so that the torque differences survive, then every rotor is clipped to
    ``[0, rotor_thrust_max_n]``.
    """
    torque_nm = np.asarray(torque_nm, dtype=float)
    wrench = np.empty((4, torque_nm.shape[0]))
    wrench[0] = thrust_n
    wrench[1:] = torque_nm.T
    return mix_t(wrench, mixer_inv, rotor_thrust_max_n).T


def mix_t(wrench_t: np.ndarray, mixer_inv: np.ndarray, rotor_thrust_max_n: float) -> np.ndarray:
    """:func:`mix` on a component-major (4, n) ``[T, tau_x, tau_y, tau_z]``: rotor-major (k, n)
    thrusts."""
    # Explicit column sums (no BLAS gemm: rounding would depend on the batch size), rotor-major
    # (k, n) so that every operation below runs on contiguous rows: the four products at once
    # (4, k, n), added in order (an outer axis: row by row).
    f = np.add.reduce(np.multiply(mixer_inv[:, :, None], wrench_t[:, None, :]), axis=0)
    # Feasible collective shifts keep every rotor in [0, max]: s in [-min f, max - max f].
    lo = np.minimum.reduce(f, axis=0)
    np.negative(lo, out=lo)
    hi = np.maximum.reduce(f, axis=0)
    np.subtract(rotor_thrust_max_n, hi, out=hi)
    shift = np.maximum(lo, 0.0)
    np.minimum(shift, hi, out=shift)
    infeasible = lo > hi
    if infeasible.any():
        mid = lo + hi
        mid *= 0.5
        np.copyto(shift, mid, where=infeasible)
    f += shift
    np.maximum(f, 0.0, out=f)
    np.minimum(f, rotor_thrust_max_n, out=f)
    return f
