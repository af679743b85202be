"""The follower's attitude loop read from its flight logs: how the torque it commands answers
its attitude, body rate and angular acceleration.

An attitude loop of the SJC kind (the law that flew the Neural-Swarm flights, docs/world.md),
linearised about hover with its set-point held, commands

    tau = -k theta - c w - d dw/dt,   k = K lambda + K_I,   c = K + lambda (J_tune + K_Dw),
    d = K_Dw

per roll and pitch axis (``theta`` the angle, ``w`` the body rate): ``k`` is how stiffly it holds
a torque, the wake's included. (Left out: the integral's ``-K_I lambda int theta``, in the band
a damping of ``-K_I lambda / omega^2``, 3-4 % of ``c`` at 2 Hz on the Crazyflies.)
Band-passed to a band above the position loop (whose set-point moves slowly) and below the
motors' and the logs' limits (:data:`BAND_HZ`), the logged torque's least squares on the
band-passed angle, rate and rate derivative reads ``k``, ``c`` and ``d`` from any flight, the
wake's and the manoeuvre's disturbances included (the law answers the states, whatever moved
them). :func:`sjc_law_response` gives the same three of a configured SJC loop, so
a world's loop, the logs' and the law's stand side by side.

What it reads: the real logs' commanded torque (``follower_motor_torque_nm``, the Neural-Swarm
logs' own mixer of the per-motor thrusts asked for) or, for simulated logs, the rotors' torque
(``follower_rotor_torque_nm``: the command after the motors' lag, which moves ``c`` and ``d``
most, a lag turning in-phase torque into out-of-phase, and ``k`` by up to 15 % on the Crazyflie
worlds); the body rates (``follower_body_rates_radps``) and the attitude quaternion. A log is
read in pieces between gaps in its clock, each piece's first and last ``2 / band_lo`` seconds
left out (the filter's start-up).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from aerodock.flightlog import FlightLog
from aerodock.geometry import quat_to_rotmat, rotmat_to_euler
from aerodock.identify.wake_torque import BODY_RATES_KEY

if TYPE_CHECKING:
    from aerodock.config.schema import AutopilotSection

BAND_HZ = (2.0, 6.0)
"""The band the loop is read in, Hz: above the position loop's set-point (about 1 Hz) and
below where the motors' lag and the logs' 100 Hz sampling take over. On the shared flights the
real small follower reads about the same ``k`` in 1-3 and 3-6 Hz (docs/crazyflie.md)."""
AXES = ("roll", "pitch")
GAP_FACTOR = 3.0
"""A step of the log's clock longer than this many times its median step splits the log."""
MIN_PIECE_S = 4.0
"""A piece of log shorter than this (before its edges are left out) is not read."""


class AttitudeLoopError(ValueError):
    """The loop cannot be read from the logs given; the message says why."""


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


def _pieces(t_s: np.ndarray) -> Iterator[slice]:
    """The stretches of a log's clock between its gaps (:data:`GAP_FACTOR`) at least
    :data:`MIN_PIECE_S` long."""
    step = np.diff(t_s)
    cuts = np.flatnonzero(step > GAP_FACTOR * np.median(step)) + 1
    for lo, hi in zip(np.r_[0, cuts], np.r_[cuts, t_s.size], strict=True):
        if hi - lo > 1 and t_s[hi - 1] - t_s[lo] >= MIN_PIECE_S:
            yield slice(int(lo), int(hi))


def loop_response(logs: Sequence[FlightLog], torque_key: str,
                  band_hz: tuple[float, float] = BAND_HZ) -> list[LoopResponse]:
    """The roll and pitch loops read from ``logs`` (module docstring), pooled over them.

    Raises:
        AttitudeLoopError: a log's torque or body rates are not finite, the band is not below a
            log's Nyquist frequency, or no log has ``torque_key``, the body rates and a piece of
            :data:`MIN_PIECE_S` seconds.
    """
    from scipy.signal import butter, sosfiltfilt

    rows: dict[str, list[np.ndarray]] = {a: [] for a in AXES}
    for log in logs:
        if torque_key not in log.extra or BODY_RATES_KEY not in log.extra:
            continue
        torque = np.asarray(log.extra[torque_key], dtype=float)
        rates = np.asarray(log.extra[BODY_RATES_KEY], dtype=float)
        if not (np.isfinite(torque).all() and np.isfinite(rates).all()):
            raise AttitudeLoopError(f"{log.name}: its {torque_key} or {BODY_RATES_KEY} holds "
                                    "NaN or infinite values")
        roll, pitch, _ = rotmat_to_euler(quat_to_rotmat(log.follower_quat))
        for piece in _pieces(log.t_s):
            t = log.t_s[piece]
            step_s = float(np.median(np.diff(t)))
            if not 0.0 < band_hz[0] < band_hz[1] < 0.5 / step_s:
                raise AttitudeLoopError(
                    f"{log.name}: the band {band_hz[0]:g}-{band_hz[1]:g} Hz does not fit below "
                    f"its Nyquist frequency ({0.5 / step_s:.0f} Hz)")
            sos = butter(2, band_hz, btype="band", fs=1.0 / step_s, output="sos")
            edge = int(round(2.0 / band_hz[0] / step_s))  # the filter's start-up at either end
            inner = slice(edge, t.size - edge)
            for i, (axis, angle) in enumerate(zip(AXES, (roll[piece], pitch[piece]),
                                                  strict=True)):
                w = rates[piece, i]
                rows[axis].append(np.column_stack([
                    sosfiltfilt(sos, x)[inner]
                    for x in (torque[piece, i], angle, w, np.gradient(w, t))]))
    if not any(r.size for r in rows["roll"]):
        raise AttitudeLoopError(f"no log carries {torque_key} and {BODY_RATES_KEY} over "
                                f"{MIN_PIECE_S:g} s without a gap")
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


def sjc_law_response(autopilot: AutopilotSection) -> list[LoopResponse]:
    """The SJC law's roll and pitch loops linearised about hover (module docstring), from a
    config's ``autopilot`` (or ``leader_autopilot``) gains ``sjc_*``: ``lambda`` 1/s, ``K``
    N·m·s, ``K_I`` N·m, ``K_Dw`` N·m·s², ``J_tune`` kg·m²."""
    a = autopilot
    return [LoopResponse(
        axis=axis,
        stiffness_nm_per_rad=a.sjc_k_nms[i] * a.sjc_lambda[i] + a.sjc_ki_nm[i],
        damping_nms_per_rad=a.sjc_k_nms[i] + a.sjc_lambda[i] * (a.sjc_jtune_kgm2[i]
                                                                + a.sjc_kdw_nms2[i]),
        rate_dot_nms2_per_rad=a.sjc_kdw_nms2[i], r2=float("nan"), samples=0)
        for i, axis in enumerate(AXES)]
