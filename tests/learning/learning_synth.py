"""Synthetic FlightLogs with a known, SO(2)-equivariant downwash (the simulator is separate).

The ground truth (:func:`true_field`) is a wake under the leader in its body frame: a Gaussian
radial profile of downward (along ``a3``) acceleration whose width grows and whose strength decays
with depth, plus a radially outward planar part peaking at the profile's half-width at 15 % of the
centreline force. Labels are ``a_obs - cmd`` with ``a_obs = cmd + true + bias + noise``.
"""

from __future__ import annotations

import numpy as np

from aerodock.flightlog import FlightLog
from aerodock.geometry import euler_to_rotmat, rotmat_to_quat

DT_S = 0.01


def true_field(dp: np.ndarray, leader_R: np.ndarray) -> np.ndarray:
    """Mean downwash acceleration (n, 3) on the follower, NED, for offsets ``dp`` (n, 3)."""
    body = np.einsum("nij,ni->nj", leader_R, dp)  # R^T dp
    depth = body[:, 2]
    rho = np.hypot(body[:, 0], body[:, 1])
    onset = 1.0 / (1.0 + np.exp(-depth / 0.04))
    d = np.maximum(depth, 0.0)
    width = 0.12 + 0.15 * d
    amp = 4.5 * 1.0 / (1.0 + 1.5 * np.maximum(d - 0.36, -0.3)) * onset
    gauss = np.exp(-0.5 * (rho / width) ** 2)
    axial = amp * gauss
    radial = 0.15 * amp * (rho / width) * np.exp(0.5) * gauss
    ur = body[:, :2] / np.maximum(rho, 1e-9)[:, None]
    f_body = np.concatenate([radial[:, None] * ur, axial[:, None]], axis=1)
    return np.einsum("nij,nj->ni", leader_R, f_body)


def _smooth(rng: np.random.Generator, t: np.ndarray, amp: float, n_modes: int = 3) -> np.ndarray:
    """A smooth random signal: sum of sinusoids with random periods (6-30 s) and phases."""
    out = np.zeros_like(t)
    for _ in range(n_modes):
        period = rng.uniform(6.0, 30.0)
        out += amp / n_modes * np.sin(2 * np.pi * t / period + rng.uniform(0, 2 * np.pi))
    return out


def make_log(
    rng: np.random.Generator,
    *,
    duration_s: float = 20.0,
    separation_m: float = 0.7,
    lateral_m: float = 0.45,
    free_air: bool = True,
    bias_mps2: tuple[float, float, float] = (0.1, -0.05, 0.3),
    noise_mps2: float = 0.3,
    name: str = "synth",
    leader_speed_mps: float = 0.0,
) -> FlightLog:
    """One synthetic flight: follower wandering below a (slightly tilted, yawed) leader."""
    t = np.arange(0.0, duration_s, DT_S)
    n = len(t)
    yaw = rng.uniform(-np.pi, np.pi) + _smooth(rng, t, 0.3)
    roll, pitch = _smooth(rng, t, 0.05), _smooth(rng, t, 0.05)
    leader_R = euler_to_rotmat(roll, pitch, yaw)
    heading = rng.uniform(0, 2 * np.pi)
    leader_vel = np.zeros((n, 3))
    leader_vel[:, 0] = leader_speed_mps * np.cos(heading)
    leader_vel[:, 1] = leader_speed_mps * np.sin(heading)
    leader_pos = np.array([0.0, 0.0, -2.0]) + np.cumsum(leader_vel, axis=0) * DT_S
    lat = lateral_m if free_air else min(lateral_m, 0.35)
    dp = np.stack([
        _smooth(rng, t, 2 * lat), _smooth(rng, t, 2 * lat),
        separation_m + _smooth(rng, t, 0.3 * separation_m),
    ], axis=1)
    if free_air:  # a stretch well out of the wake (horizontal distance > 0.6 m)
        k = n // 5
        dp[:k, 0] += np.linspace(1.0, 0.0, k)
    follower_pos = leader_pos + dp
    follower_vel = np.gradient(follower_pos, DT_S, axis=0)
    cmd = np.stack([_smooth(rng, t, 0.5), _smooth(rng, t, 0.5), _smooth(rng, t, 0.8)], axis=1)
    true = true_field(dp, leader_R)
    obs = cmd + true + np.asarray(bias_mps2) + noise_mps2 * rng.standard_normal((n, 3))
    quat_l = rotmat_to_quat(leader_R)
    quat_f = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
    return FlightLog(
        t_s=t, leader_pos_m=leader_pos, leader_vel_mps=leader_vel, leader_quat=quat_l,
        follower_pos_m=follower_pos, follower_vel_mps=follower_vel, follower_quat=quat_f,
        follower_cmd_accel_mps2=cmd, follower_thrust_n=np.full(n, 0.7 * 9.81),
        follower_obs_accel_mps2=obs,
        meta={"name": name, "source": "synthetic", "mass_kg": 0.7},
        extra={"true_field_mean_mps2": true},
    )


def scaled_field(log: FlightLog, share: float, meta: dict, extra: dict | None = None
                 ) -> FlightLog:
    """``log`` with its wake (``extra["true_field_mean_mps2"]``) scaled by ``share``: the labels
    and the true field alike; ``meta`` and ``extra`` are added to the log's."""
    true = log.extra["true_field_mean_mps2"]
    return FlightLog(
        t_s=log.t_s, leader_pos_m=log.leader_pos_m, leader_vel_mps=log.leader_vel_mps,
        leader_quat=log.leader_quat, follower_pos_m=log.follower_pos_m,
        follower_vel_mps=log.follower_vel_mps, follower_quat=log.follower_quat,
        follower_cmd_accel_mps2=log.follower_cmd_accel_mps2,
        follower_thrust_n=log.follower_thrust_n,
        follower_obs_accel_mps2=log.follower_obs_accel_mps2 + (share - 1.0) * true,
        meta={**log.meta, **meta}, extra={"true_field_mean_mps2": share * true, **(extra or {})})


def make_logs(
    rng: np.random.Generator, n_flights: int = 6, duration_s: float = 20.0, **kwargs
) -> list[FlightLog]:
    """Flights at separations spread over 0.4-1.6 m (a curriculum's range)."""
    seps = np.linspace(0.4, 1.6, n_flights)
    return [
        make_log(rng, duration_s=duration_s, separation_m=float(s), name=f"synth{i}", **kwargs)
        for i, s in enumerate(seps)
    ]



def true_torque(dp: np.ndarray, leader_R: np.ndarray) -> np.ndarray:
    """Mean wake torque (n, 3) on the follower, N m, world NED, for offsets ``dp`` (n, 3).

    Along the tangential direction ``e_t`` (the wake pushes the rotors nearer the axis down),
    proportional to the planar force of :func:`true_field`: 5 mN m per m/s² of it (so about
    3 mN m at its peak under the docking-depth wake), zero on the axis and far off it.
    """
    body = np.einsum("nij,ni->nj", leader_R, dp)
    rho = np.maximum(np.hypot(body[:, 0], body[:, 1]), 1e-9)
    radial = np.einsum("nij,ni->nj", leader_R, true_field(dp, leader_R))[:, :2]
    f_r = np.sum(radial * body[:, :2], axis=1) / rho
    e_t = np.stack([-body[:, 1] / rho, body[:, 0] / rho, np.zeros(len(rho))], axis=1)
    return np.einsum("nij,nj->ni", leader_R, 0.005 * f_r[:, None] * e_t)


def make_pass_log(
    rng: np.random.Generator,
    *,
    heading_rad: float,
    duration_s: float = 15.0,
    separation_m: float = 0.45,
    amplitude_m: float = 0.4,
    period_s: float = 6.0,
    noise_mps2: float = 0.15,
    torque_noise_nm: float = 5e-4,
    name: str = "pass",
) -> FlightLog:
    """One flight of passes under a level (yawed) hovering leader, like the shared swap flights.

    The follower swings back and forth through the wake along ``heading_rad`` (NED, from north),
    ``amplitude_m`` either side of the axis, a few cm of cross-track and vertical wander; the
    first 3 s are in free air (1 m aside) for the bias estimate. Labels as :func:`make_log`; the
    torque extras (``follower_obs_torque_nm`` = rotor torque + :func:`true_torque` + bias +
    noise) give torque labels, with the follower level so that body and world frames agree.
    """
    t = np.arange(0.0, duration_s, DT_S)
    n = len(t)
    yaw = np.full(n, rng.uniform(-np.pi, np.pi))
    leader_R = euler_to_rotmat(np.zeros(n), np.zeros(n), yaw)
    leader_pos = np.tile([0.0, 0.0, -2.0], (n, 1))
    along = amplitude_m * np.sin(2 * np.pi * t / period_s + rng.uniform(0, 2 * np.pi))
    across = _smooth(rng, t, 0.05)
    away = np.clip((3.0 - t) / 0.5, 0.0, 1.0)  # 1 m aside until 2.5 s, in by 3 s
    c, s = np.cos(heading_rad), np.sin(heading_rad)
    dp = np.stack([
        c * (along + away) - s * across, s * (along + away) + c * across,
        separation_m + _smooth(rng, t, 0.04),
    ], axis=1)
    follower_pos = leader_pos + dp
    follower_vel = np.gradient(follower_pos, DT_S, axis=0)
    cmd = np.stack([_smooth(rng, t, 0.5), _smooth(rng, t, 0.5), _smooth(rng, t, 0.8)], axis=1)
    true = true_field(dp, leader_R)
    obs = cmd + true + np.array([0.1, -0.05, 0.3]) + noise_mps2 * rng.standard_normal((n, 3))
    tau_true = true_torque(dp, leader_R)
    rotor = 0.01 * np.stack([_smooth(rng, t, 1.0) for _ in range(3)], axis=1)
    tau_obs = (rotor + tau_true + np.array([1e-3, -5e-4, 2e-4])
               + torque_noise_nm * rng.standard_normal((n, 3)))
    return FlightLog(
        t_s=t, leader_pos_m=leader_pos, leader_vel_mps=np.zeros((n, 3)),
        leader_quat=rotmat_to_quat(leader_R),
        follower_pos_m=follower_pos, follower_vel_mps=follower_vel,
        follower_quat=np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)),
        follower_cmd_accel_mps2=cmd, follower_thrust_n=np.full(n, 0.7 * 9.81),
        follower_obs_accel_mps2=obs,
        meta={"name": name, "source": "synthetic", "mass_kg": 0.7},
        extra={"true_field_mean_mps2": true, "follower_obs_torque_nm": tau_obs,
               "follower_rotor_torque_nm": rotor, "true_wake_torque_nm": tau_true},
    )


def make_pass_logs(
    rng: np.random.Generator, headings_rad: np.ndarray, **kwargs
) -> list[FlightLog]:
    """One :func:`make_pass_log` per heading, separations spread over 0.35-0.6 m."""
    seps = np.linspace(0.35, 0.6, len(headings_rad))
    return [make_pass_log(rng, heading_rad=float(h), separation_m=float(s), name=f"pass{i}",
                          **kwargs)
            for i, (h, s) in enumerate(zip(headings_rad, rng.permutation(seps)))]
