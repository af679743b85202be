"""The onboard autopilot of the rigid-body vehicle: attitude P -> body-rate PI -> mixer.

Like ArduCopter's and PX4's multicopter controllers (attitude angle loop, rate loop, mixer with
saturation handling), batch-first and pure:

- :func:`attitude_target` turns the outer loop's command (roll, pitch, yaw rate, collective
  thrust in N) into a desired rotation, once per control period (the command is held);
- the rate setpoint: attitude error ``e_R = vee(R_d^T R - R^T R_d) / 2`` (Lee et al.) times
  the angle gain, plus the commanded yaw rate as feed-forward;
- the rate loop: PI on the gyro's body rates (the gyro, not the true rates: its noise enters
  here), giving desired angular accelerations, times the inertia;
- :func:`mix`: collective thrust and body torques -> per-rotor thrusts for an X quadrotor, with
  the saturation handling of an "airmode" mixer: when a rotor would exceed its limits the
  collective is shifted so the torques (attitude) keep priority, then each rotor is clipped.

The loops run at the physics rate inside the compiled vehicle step
(:func:`aerodock.world.vehicles.rigid_kernel.autopilot_into`); this module holds their gains.

Units: angles rad, rates rad/s, torques N m, thrusts N. Body frame FRD (x forward, y right, z
down); the world is NED.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from aerodock.frozen import freeze, is_frozen
from aerodock.geometry import rpy_to_rotmat
from aerodock.world.vehicles import rigid_kernel


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


def autopilot_constants(gains: AutopilotGains, inertia_kgm2: np.ndarray) -> np.ndarray:
    """The loops' per-axis constants as the compiled autopilot reads them, (6, 3): rows
    ``-attitude_p / 2``, the rate limit, the integral limit (the integral term's angular
    acceleration limit over ``rate_i``), ``rate_p``, ``rate_i`` and the nominal inertia.

    Kept on ``gains`` for the last inertia array while the gains' and the inertia's arrays are
    read-only (the vehicle parameters' are: :meth:`RigidBodyParams.from_config`); otherwise
    computed afresh."""
    hit = gains.__dict__.get("_constants")  # not a field: numbers derived from them
    if (hit is not None and hit[0] is inertia_kgm2 and is_frozen(inertia_kgm2)
            and _gains_frozen(gains)):
        return hit[1]
    int_limit = gains.rate_integral_max_radps2 / np.maximum(gains.rate_i, 1e-12)
    rows = np.stack([np.broadcast_to(np.asarray(v, dtype=float), (3,)) for v in (
        -0.5 * gains.attitude_p, gains.rate_max_radps, int_limit, gains.rate_p, gains.rate_i,
        inertia_kgm2)])
    freeze(rows)
    gains.__dict__["_constants"] = (inertia_kgm2, rows)
    return rows


def _gains_frozen(gains: AutopilotGains) -> bool:
    """Whether every array of ``gains`` is read-only (their numbers cannot change)."""
    return (is_frozen(gains.attitude_p) and is_frozen(gains.rate_p) and is_frozen(gains.rate_i)
            and is_frozen(gains.rate_max_radps))


def attitude_target(roll_rad: np.ndarray, pitch_rad: np.ndarray,
                    yaw_setpoint_rad: np.ndarray) -> np.ndarray:
    """(n, 3, 3) desired body-to-world rotation from ZYX Euler angles (the outer loop's tilt)."""
    return rpy_to_rotmat(np.stack([roll_rad, pitch_rad, yaw_setpoint_rad], axis=1))


def mix(thrust_n: np.ndarray, torque_nm: np.ndarray, mixer_inv: np.ndarray,
        rotor_thrust_max_n: float) -> np.ndarray:
    """(n, k) per-rotor thrusts for collective thrust (n,) and body torques (n, 3).

    ``mixer_inv`` (4, k) maps ``[T, tau_x, tau_y, tau_z]`` to rotor thrusts. Saturation: the
    collective part is shifted (down when a rotor exceeds its maximum, up when one would go below
    zero) so that the torque differences survive, then every rotor is clipped to
    ``[0, rotor_thrust_max_n]`` (compiled: :func:`rigid_kernel.mix`, which the autopilot runs).
    """
    torque = np.asarray(torque_nm, dtype=float)
    thrust = np.broadcast_to(np.asarray(thrust_n, dtype=float), (torque.shape[0],))
    mixer_inv = np.asarray(mixer_inv, dtype=float)
    if mixer_inv.shape != (4, 4):
        raise ValueError(f"the mixer maps [T, tau] to four rotors: mixer_inv must be (4, 4), "
                         f"got {mixer_inv.shape}")
    out = np.empty((torque.shape[0], 4))
    rigid_kernel.mix_batch(thrust, torque, rigid_kernel.flat(mixer_inv),
                           float(rotor_thrust_max_n), out)
    return out
