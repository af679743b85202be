"""What the follower's motors make from the commands they were sent, not what was asked for.

The Neural-Swarm logs' torque columns (``torquex..z``, :data:`~aerodock.identify.wake_torque.
MOTOR_TORQUE_KEY`) are the firmware's *commanded* torques: an exact linear mix of the per-motor
thrusts it asked for (``u1..u4``, :data:`MOTOR_THRUST_KEY`; the dataset's README says
"commanded body torques"). Each motor's command (``u1..u4 [PWM]``, 0..1) follows from its asked-for
thrust and the battery's voltage by a map the logs obey to a few mN wherever the commands are
below the top of their range; at the top (about 0.9 and up) the asked-for thrust runs past what
the map gives for the command sent: the motor is at its ceiling, and the torque the log mixes
from the asked-for thrusts is more than the motors make. Under the wake the motor nearest the
leader's axis is the one near its ceiling.

:func:`made_thrusts` fits each motor's map (its asked-for thrust on the command, its square
and their products with the voltage) over one flight's samples with every command below
:data:`MAP_FIT_PWM`, and puts every command sent through it. :func:`as_sent` mixes the thrusts
so made by the logs' own mixer (read from the log: the torque columns regressed on ``u1..u4``,
exact) and sums them for the collective, so the torque and the force labels both stand on what
was sent. What the map gives is the firmware's own model of a motor's thrust, as the asked-for
thrusts are: the correction takes away the thrust asked for beyond the ceiling, nothing else.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from aerodock.flightlog import FlightLog
from aerodock.geometry import quat_to_rotmat
from aerodock.identify.flights import WakeFitError, log_geometry
from aerodock.identify.wake_torque import MOTOR_PWM_KEY, MOTOR_TORQUE_KEY

MOTOR_THRUST_KEY = "follower_motor_thrust_n"
BATTERY_KEY = "follower_battery_v"
MAP_FIT_PWM = 0.88
"""The map is fitted over the samples whose every motor command is below this (0..1)."""
CEILING_PWM = 0.9
"""A motor commanded at or above this counts as at its ceiling (the asked-for thrust beyond the
map's there is the excess :class:`MotorMap` reports)."""
MIN_MAP_SAMPLES = 50
MIXER_TOLERANCE = 1e-6
"""Largest relative residual of the torque columns as a mix of ``u1..u4`` (they are one)."""


@dataclass(frozen=True)
class MotorMap:
    """What one flight's motor-command maps say (:func:`made_thrusts`)."""

    name: str
    vehicle: str
    map_samples: int
    """Samples the maps were fitted over (every command below :data:`MAP_FIT_PWM`)."""
    residual_sd_n: float
    """The largest of the four maps' residual sd over those samples, N."""
    ceiling_samples: int
    """Motor samples commanded at or above :data:`CEILING_PWM`."""
    ceiling_excess_n: float
    """Their mean thrust asked for beyond what the map gives for the command sent, N (nan: no
    sample at the ceiling)."""
    top_pwm: float
    """The highest command sent in the flight."""


def has_motor_commands(log: FlightLog) -> bool:
    """True when ``log`` carries the asked-for thrusts, the commands and the torque columns."""
    return all(key in log.extra for key in (MOTOR_THRUST_KEY, MOTOR_PWM_KEY, MOTOR_TORQUE_KEY))


def made_thrusts(log: FlightLog) -> tuple[np.ndarray, MotorMap]:
    """(T, 4) the thrusts (N, the logs' motor order) the commands sent make through each
    motor's own map (module docstring), and what the maps say.

    Raises:
        WakeFitError: the log lacks the asked-for thrusts, commands or torque columns, or
            fewer than :data:`MIN_MAP_SAMPLES` samples have every command below
            :data:`MAP_FIT_PWM`.
    """
    if not has_motor_commands(log):
        raise WakeFitError(f"{log.name}: the log has no {MOTOR_THRUST_KEY}, {MOTOR_PWM_KEY} "
                           f"and {MOTOR_TORQUE_KEY} (Neural-Swarm logs carry all three)")
    asked = np.asarray(log.extra[MOTOR_THRUST_KEY], dtype=float)
    pwm = np.asarray(log.extra[MOTOR_PWM_KEY], dtype=float)
    volts = log.extra.get(BATTERY_KEY)
    fit = np.all(pwm < MAP_FIT_PWM, axis=1)
    if fit.sum() < MIN_MAP_SAMPLES:
        raise WakeFitError(f"{log.name}: {int(fit.sum())} samples with every motor command "
                           f"below {MAP_FIT_PWM}, {MIN_MAP_SAMPLES} needed to fit the maps")
    made = np.empty_like(asked)
    residual_sd = []
    for motor in range(asked.shape[1]):
        design = _map_design(pwm[:, motor], None if volts is None else np.asarray(volts, float))
        coeffs, *_ = np.linalg.lstsq(design[fit], asked[fit, motor], rcond=None)
        made[:, motor] = design @ coeffs
        residual_sd.append(float(np.std(asked[fit, motor] - made[fit, motor])))
    top = pwm >= CEILING_PWM
    excess = (asked - made)[top]
    return made, MotorMap(
        name=log.name, vehicle=str(log.meta.get("follower_id")), map_samples=int(fit.sum()),
        residual_sd_n=max(residual_sd), ceiling_samples=int(top.sum()),
        ceiling_excess_n=float(excess.mean()) if excess.size else float("nan"),
        top_pwm=float(pwm.max()))


def as_sent(log: FlightLog) -> tuple[FlightLog, MotorMap]:
    """``log`` with what its motors' commands as sent make (:func:`made_thrusts`) in place of
    what the firmware asked for: the torque columns (the thrusts made, mixed by the logs' own
    mixer, read from the log), the collective thrust and the acceleration it explains (hence
    the force labels). The maps' figures beside it.

    Raises:
        WakeFitError: as :func:`made_thrusts`; or the log's torque columns are not a mix of
            the asked-for thrusts, or its collective thrust not their sum.
    """
    made, motor_map = made_thrusts(log)
    asked = np.asarray(log.extra[MOTOR_THRUST_KEY], dtype=float)
    torque = np.asarray(log.extra[MOTOR_TORQUE_KEY], dtype=float)
    mixer, *_ = np.linalg.lstsq(asked, torque, rcond=None)  # (4, 3): the logs' own mixer
    scale = max(float(np.abs(torque).max()), 1e-12)
    if (np.linalg.matrix_rank(asked) < asked.shape[1]
            or np.abs(asked @ mixer - torque).max() > MIXER_TOLERANCE * scale):
        raise WakeFitError(f"{log.name}: the torque columns are not a mix of the per-motor "
                           "thrusts asked for")
    thrust = np.asarray(log.follower_thrust_n, dtype=float)
    if not np.allclose(asked.sum(axis=1), thrust, rtol=1e-9, atol=1e-12):
        raise WakeFitError(f"{log.name}: the collective thrust is not the sum of the per-motor "
                           "thrusts asked for")
    made_thrust = made.sum(axis=1)
    # the acceleration the collective explains, g e3 - R e3 T / m, with the thrust made
    body_z = quat_to_rotmat(log.follower_quat)[:, :, 2]
    mass = log_geometry(log)["follower_mass_kg"]
    cmd = log.follower_cmd_accel_mps2 + body_z * ((thrust - made_thrust) / mass)[:, None]
    sent = replace(log, follower_thrust_n=made_thrust, follower_cmd_accel_mps2=cmd,
                   extra={**log.extra, MOTOR_TORQUE_KEY: made @ mixer})
    return sent, motor_map


def logs_as_sent(logs: Sequence[FlightLog]) -> tuple[list[FlightLog], list[MotorMap]]:
    """:func:`as_sent` of each of ``logs`` (those without the motor commands, or whose maps
    cannot be fitted, left out), and the maps."""
    out, maps = [], []
    for log in logs:
        if not has_motor_commands(log):
            continue
        try:
            sent, motor_map = as_sent(log)
        except WakeFitError:
            continue
        out.append(sent)
        maps.append(motor_map)
    return out, maps


def command_maps(logs: Sequence[FlightLog]) -> list[MotorMap]:
    """:func:`made_thrusts`' maps of each of ``logs`` that carries the motor commands (those
    whose maps cannot be fitted left out); a log already taken as sent keeps its asked-for
    thrusts and commands, so its maps are its own."""
    maps = []
    for log in logs:
        if has_motor_commands(log):
            try:
                maps.append(made_thrusts(log)[1])
            except WakeFitError:
                continue
    return maps


def ceiling_by_vehicle(maps: Sequence[MotorMap]) -> list[dict[str, float | int | str]]:
    """Per follower vehicle (sorted by id): its flights, the largest map residual sd (N), its
    motor samples at :data:`CEILING_PWM` and up, the highest command sent, and the mean thrust
    asked for beyond the map there (N; nan: none at the ceiling)."""
    out: list[dict[str, float | int | str]] = []
    for vid in sorted({m.vehicle for m in maps}):
        mine = [m for m in maps if m.vehicle == vid]
        count = sum(m.ceiling_samples for m in mine)
        excess = (sum(m.ceiling_excess_n * m.ceiling_samples for m in mine if m.ceiling_samples)
                  / count if count else float("nan"))
        out.append({"vehicle": vid, "flights": len(mine),
                    "residual_sd_n": max(m.residual_sd_n for m in mine),
                    "ceiling_samples": count, "top_pwm": max(m.top_pwm for m in mine),
                    "ceiling_excess_n": excess})
    return out


def sent_where_logged(logs: Sequence[FlightLog]) -> list[FlightLog]:
    """``logs`` with every one that carries the motor commands taken as sent (:func:`as_sent`),
    the others as they are (flights of a simulated world, whose torque is the rotors' own).

    Raises:
        WakeFitError: a log carries the motor commands but its maps cannot be fitted (as
            :func:`as_sent`).
    """
    return [as_sent(log)[0] if has_motor_commands(log) else log for log in logs]


def _map_design(pwm: np.ndarray, volts: np.ndarray | None) -> np.ndarray:
    """The map's terms: 1, the command and its square, and (with the voltage) each times it."""
    terms = [np.ones_like(pwm), pwm, pwm**2]
    if volts is not None:
        terms += [volts, volts * pwm, volts * pwm**2]
    return np.stack(terms, axis=1)
