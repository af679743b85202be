"""The wake's logged torque as labels the jet's fit can use beside the force.

The force alone leaves open how the wake's force splits between the follower's rotor disks and
its body and how concentrated the profile the disks sample is: flights 0.25-0.45 m apart fit
about as well with a fifth of the force on the body as with none. The torque the follower's
motors answer (:mod:`aerodock.identify.wake_torque`) is what tells them apart: only the disks'
forces, unequal across the follower, make it. :func:`torque_labels` reads it at every sample of
the fit (the inward part, :func:`~aerodock.identify.wake_torque.inward_nm`), and
:meth:`TorqueLabels.residual_mps2` sets the jet's against it in the fit's units (a torque over
the follower's mass and half diagonal: the acceleration a force at its motors would give).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from aerodock.flightlog import FlightLog
from aerodock.geometry import quat_to_rotmat
from aerodock.identify.flights import FlightSamples
from aerodock.identify.wake_torque import (
    FREE_AIR_OFFSET_M,
    has_motor_torque,
    inward_nm,
    real_wake_torque_nm,
)


@dataclass(frozen=True)
class TorqueLabels:
    """One flight's logged inward wake torque at the fit's samples.

    Attributes:
        real_nm: (m,) the real inward torque (N·m) at the flight's samples.
        rot: (m, 3, 3) the follower's logged attitude (body to world).
        e_r: (m, 2) the horizontal unit vector from the leader's axis to the follower.
        scale_kgm: the follower's mass times its half diagonal (a torque over it is the
            acceleration a force at the motors would give, m/s²).
    """

    real_nm: np.ndarray
    rot: np.ndarray
    e_r: np.ndarray
    scale_kgm: float

    def inward_of(self, torque_body_nm: np.ndarray) -> np.ndarray:
        """(m,) the inward part of a body-frame (FRD) torque at these samples, N·m."""
        return inward_nm(np.einsum("nij,nj->ni", self.rot, torque_body_nm), self.e_r)

    def residual_mps2(self, model_body_nm: np.ndarray) -> np.ndarray:
        """(m,) the real inward torque less the model's (body frame), over ``scale_kgm``."""
        return (self.real_nm - self.inward_of(model_body_nm)) / self.scale_kgm


def torque_labels(flights: Sequence[FlightSamples], logs: Sequence[FlightLog],
                  inertia_kgm2: Mapping[str, Sequence[float]], *,
                  free_air_offset_m: float = FREE_AIR_OFFSET_M) -> dict[str, TorqueLabels]:
    """Per flight (by ``FlightSamples.name``) whose log carries the motors' torque, its body
    rates and enough free air for the trim, the inward wake torque at the fit's samples.

    Args:
        flights: the fit's samples (:func:`aerodock.identify.flights.prepare_flights`).
        logs: their FlightLogs (matched by name).
        inertia_kgm2: the follower's principal moments of inertia by vehicle id (a flight
            whose follower has none is left out).
    """
    by_name = {log.name: log for log in logs}
    out: dict[str, TorqueLabels] = {}
    for flight in flights:
        log = by_name.get(flight.name)
        vehicle = flight.vehicles.get("follower")
        if log is None or not has_motor_torque(log) or vehicle not in inertia_kgm2:
            continue
        real_body = real_wake_torque_nm(log, inertia_kgm2[str(vehicle)],
                                        free_air_offset_m=free_air_offset_m)
        if real_body is None:
            continue
        rot = quat_to_rotmat(log.follower_quat[flight.index])
        dp = flight.follower.p - flight.leader.p
        horizontal = np.hypot(dp[:, 0], dp[:, 1])
        e_r = dp[:, :2] / np.maximum(horizontal, 1e-9)[:, None]
        scale = float(flight.geometry["follower_mass_kg"]
                      * flight.geometry["follower_diagonal_m"] / 2.0)
        out[flight.name] = TorqueLabels(
            real_nm=inward_nm(np.einsum("nij,nj->ni", rot, real_body[flight.index]), e_r),
            rot=rot, e_r=e_r, scale_kgm=scale)
    return out
