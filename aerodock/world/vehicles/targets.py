"""The autopilots' attitude targets of a batch of rigid-body vehicles (:func:`rigid_targets`): the
position controller's command, clipped to the tilt and thrust limits, as the target attitude the
autopilot flies at the yaw setpoint, held over a control period (:class:`RigidTargets`). The
arithmetic is one compiled call (:mod:`aerodock.world.vehicles.targets_kernel`); this module
prepares its inputs and joins the torque feed-forward.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from aerodock.world.trig_loops import TRIG_LOOPS
from aerodock.world.vehicles import targets_kernel
from aerodock.world.vehicles.point_mass import AttitudeCommand


class YawSetpoints(Protocol):
    """What :func:`rigid_targets` reads of the vehicles' state (a ``RigidBodyState``)."""

    yaw_setpoint: np.ndarray  # (n,) rad


class Limits(Protocol):
    """What :func:`rigid_targets` reads of the vehicles' parameters (``RigidBodyParams``)."""

    tilt_max_rad: float
    thrust_max_n: float


@dataclass(frozen=True)
class RigidTargets:
    """An :class:`AttitudeCommand` prepared for the autopilot, held over a control period."""

    R_des: np.ndarray  # (n, 3, 3) desired attitude  # noqa: N815
    yaw_rate_radps: np.ndarray  # (n,)
    thrust_n: np.ndarray  # (n,) collective, clipped to [0, thrust_max_n]
    torque_ff_nm: np.ndarray | None = None  # (n, 3) body torque added before the mixer


def rigid_targets(cmd: AttitudeCommand, state: YawSetpoints, params: Limits,
                  n: int, follower_cmd: AttitudeCommand | None = None) -> RigidTargets:
    """Clip the command to the tilt and thrust limits; the attitude target at the current yaw
    setpoint (the yaw rate is flown as feed-forward and integrated by the vehicles' step,
    :func:`aerodock.world.vehicles.rigid_body.step_rigid_body`).
    ``follower_cmd``: a second batch's commands, joined after ``cmd``'s (a fleet's leaders and
    followers: ``n`` rows in all, half each). One compiled call
    (:func:`targets_kernel.attitude_targets`: NumPy's numbers, about 3 µs where the NumPy calls
    and the join took 50 at a batch of 1).

    Raises:
        ValueError: the state's yaw setpoints are not ``n``.
    """
    half = n if follower_cmd is None else n // 2
    lead, fol = cmd, follower_cmd
    if state.yaw_setpoint.shape != (n,):
        raise ValueError(f"{state.yaw_setpoint.shape} yaw setpoints for {n} vehicles")
    r_des_t, yaw_rate, thrust = targets_kernel.attitude_targets(
        TRIG_LOOPS, _command_rows(lead.roll_rad, half), _second_rows(fol, "roll_rad", half),
        _command_rows(lead.pitch_rad, half), _second_rows(fol, "pitch_rad", half),
        _command_rows(lead.yaw_rate_radps, half), _second_rows(fol, "yaw_rate_radps", half),
        _command_rows(lead.thrust_n, half), _second_rows(fol, "thrust_n", half),
        state.yaw_setpoint, params.tilt_max_rad, params.thrust_max_n)
    yaw_rate.flags.writeable = thrust.flags.writeable = False  # held, never written
    return RigidTargets(
        # stored transposed in memory: the autopilot multiplies by R_des^T at every step
        r_des_t.transpose(0, 2, 1), yaw_rate, thrust, joined_torque(lead, fol, half))


def joined_torque(lead: AttitudeCommand, fol: AttitudeCommand | None,
                  n: int) -> np.ndarray | None:
    """The torque feed-forward of ``lead``'s ``n`` rows then ``fol``'s (``fol`` None: ``lead``'s
    alone, as floats), a half without one zero; None when neither has one."""
    if fol is None:
        return None if lead.torque_ff_nm is None else np.asarray(lead.torque_ff_nm, dtype=float)
    if lead.torque_ff_nm is None and fol.torque_ff_nm is None:
        return None
    torque = np.zeros((2 * n, 3))
    for rows, cmd in ((slice(None, n), lead), (slice(n, None), fol)):
        if cmd.torque_ff_nm is not None:
            torque[rows] = cmd.torque_ff_nm
    return torque


_NO_COMMAND = np.zeros(0)  # the second batch of a single batch's targets: none


def _second_rows(cmd: AttitudeCommand | None, name: str, n: int) -> np.ndarray:
    """The second batch's field ``name`` as :func:`_command_rows` gives it (none: no rows)."""
    return _NO_COMMAND if cmd is None else _command_rows(getattr(cmd, name), n)


def _command_rows(values: np.ndarray | float, n: int) -> np.ndarray:
    """A command's field (a number or (n,) values) as the (n,) float64 C-ordered array
    :func:`targets_kernel.attitude_targets` reads: the array itself when it is one."""
    if (type(values) is np.ndarray and values.shape == (n,) and values.dtype == np.float64
            and values.flags.c_contiguous):
        return values
    return np.ascontiguousarray(np.broadcast_to(np.asarray(values, dtype=float), (n,)))
