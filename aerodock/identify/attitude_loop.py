"""The follower's attitude loop read from its flight logs: how the torque it commands answers
its attitude, body rate and angular acceleration.

An attitude loop of the SJC kind (the law that flew the Neural-Swarm flights, docs/world.md),
linearised about hover with its set-point held, commands

    tau = -k theta - c w - d dw/dt,   k = K lambda + K_I,   c = K + lambda (J_tune + K_Dw),
    d = K_Dw

per roll and pitch axis (``theta`` the angle, ``w`` the body rate): ``k`` is how stiffly it holds
a torque, the wake's included. Band-passed to a band above the position loop (whose set-point
moves slowly) and below the motors' and the logs' limits (:data:`BAND_HZ`), the logged torque's
least squares on the band-passed angle, rate and rate derivative reads ``k``, ``c`` and ``d`` from
any flight, the wake's and the manoeuvre's disturbances included (the law answers the states,
whatever moved them). :func:`sjc_law_response` gives the same three of a configured SJC loop, so
a world's loop, the logs' and the law's stand side by side.

What it reads: the real logs' commanded torque (``follower_motor_torque_nm``, the Neural-Swarm
logs' own mixer of the per-motor thrusts asked for) or, for simulated logs, the rotors' torque
(``follower_rotor_torque_nm``: the command after the motors' lag, which moves ``c`` and ``d``, a
lag moving the in-phase torque into the out-of-phase terms, and leaves ``k``); the body rates
(``follower_body_rates_radps``) and the attitude quaternion.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from aerodock.flightlog import FlightLog
from aerodock.geometry import quat_to_rotmat
from aerodock.identify.flights import WakeFitError

BAND_HZ = (2.0, 6.0)
"""The band the loop is read in, Hz: above the position loop's set-point (about 1 Hz) and
below where the motors' lag and the logs' 100 Hz sampling take over. On the shared flights the
real small follower reads the same ``k`` in 1-3 and 3-6 Hz (46 and 44 mN·m/rad)."""
BODY_RATES_KEY = "follower_body_rates_radps"
AXES = ("roll", "pitch")
MIN_SAMPLES = 200  # a log shorter than this (2 s at 100 Hz) is left out: the filter's edges


@dataclass(frozen=True)
class LoopResponse:
    """One axis's linearised attitude loop: ``tau = -k theta - c w - d dw/dt``."""

    axis: str
    stiffness_nm_per_rad: float
    """``k``, N·m per radian of attitude."""
    damping_nms_per_rad: float
    """``c``, N·m per rad/s of body rate."""
    rate_dot_nms2_per_rad: float
    """``d``, N·m per rad/s² of angular acceleration."""
    r2: float
    """The fraction of the band-passed torque's variance the three terms explain (nan for a
    law)."""
    samples: int


def roll_pitch_rad(quat_wxyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Roll and pitch, rad (Z-Y-X Euler angles), of body-to-world quaternions (T, 4)."""
    rot = quat_to_rotmat(quat_wxyz)
    return (np.arctan2(rot[:, 2, 1], rot[:, 2, 2]),
            -np.arcsin(np.clip(rot[:, 2, 0], -1.0, 1.0)))


def loop_response(logs: Sequence[FlightLog], torque_key: str,
                  band_hz: tuple[float, float] = BAND_HZ) -> list[LoopResponse]:
    """The roll and pitch loops read from ``logs`` (module docstring), pooled over them.

    Raises:
        WakeFitError: no log has ``torque_key``, the body rates and :data:`MIN_SAMPLES`
            samples, or the band is not below the logs' Nyquist frequency.
    """
    from scipy.signal import butter, sosfiltfilt

    rows: dict[str, list[np.ndarray]] = {a: [] for a in AXES}
    for log in logs:
        if (torque_key not in log.extra or BODY_RATES_KEY not in log.extra
                or log.n_samples < MIN_SAMPLES):
            continue
        t = log.t_s
        rate_hz = 1.0 / float(np.median(np.diff(t)))
        if not 0.0 < band_hz[0] < band_hz[1] < rate_hz / 2.0:
            raise WakeFitError(f"{log.name}: the band {band_hz[0]:g}-{band_hz[1]:g} Hz does "
                               f"not fit below its Nyquist frequency ({rate_hz / 2.0:.0f} Hz)")
        sos = butter(2, band_hz, btype="band", fs=rate_hz, output="sos")
        torque = np.asarray(log.extra[torque_key], dtype=float)
        rates = np.asarray(log.extra[BODY_RATES_KEY], dtype=float)
        for i, (axis, angle) in enumerate(zip(AXES, roll_pitch_rad(log.follower_quat),
                                              strict=True)):
            rows[axis].append(np.column_stack([
                sosfiltfilt(sos, x) for x in (torque[:, i], angle, rates[:, i],
                                              np.gradient(rates[:, i], t))]))
    if not rows["roll"]:
        raise WakeFitError(f"no log carries {torque_key} and {BODY_RATES_KEY} over "
                           f"{MIN_SAMPLES} samples")
    out = []
    for axis in AXES:
        m = np.concatenate(rows[axis])
        coef, *_ = np.linalg.lstsq(m[:, 1:], m[:, 0], rcond=None)
        r2 = 1.0 - float(np.var(m[:, 0] - m[:, 1:] @ coef) / np.var(m[:, 0]))
        out.append(LoopResponse(axis=axis, stiffness_nm_per_rad=-float(coef[0]),
                                damping_nms_per_rad=-float(coef[1]),
                                rate_dot_nms2_per_rad=-float(coef[2]), r2=r2,
                                samples=int(m.shape[0])))
    return out


def sjc_law_response(lam: Sequence[float], k_nms: Sequence[float], ki_nm: Sequence[float],
                     kdw_nms2: Sequence[float], jtune_kgm2: Sequence[float]) -> list[LoopResponse]:
    """The SJC law's roll and pitch loops linearised about hover (module docstring), from its
    gains (the config's ``autopilot.sjc_*``, per axis)."""
    return [LoopResponse(axis=axis, stiffness_nm_per_rad=k_nms[i] * lam[i] + ki_nm[i],
                         damping_nms_per_rad=k_nms[i] + lam[i] * (jtune_kgm2[i] + kdw_nms2[i]),
                         rate_dot_nms2_per_rad=kdw_nms2[i], r2=float("nan"), samples=0)
            for i, axis in enumerate(AXES)]
