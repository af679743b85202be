"""Each vehicle's true physical parameters, which its controllers do not know.

The controllers and the autopilot fly a vehicle type's *nominal* parameters (``[vehicle]``, or
``[leader]`` for the leader); every simulated vehicle differs from them as a real fleet's
vehicles do (``vehicle.*_sd``: mass, inertia, rotor thrust and torque coefficients, motor time
constant, each a relative standard deviation drawn once per vehicle and trial). The thrust
coefficient's spread is the state's ``thrust_gain`` (it existed first); the others are a
:class:`VehicleBody` that the vehicle's state carries, batch-first.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from aerodock.frozen import freeze
from aerodock.rng import TrialRNG, standard_normal_t

# A drawn relative error is kept within this many standard deviations (a physical vehicle has
# positive mass and inertia whatever the draw).
SPREAD_CLIP_SD = 3.0


@dataclass(frozen=True)
class SpreadParams:
    """A real fleet's spread around the nominal parameters (relative standard deviations)."""

    mass_sd: float = 0.0
    inertia_sd: float = 0.0
    thrust_coeff_sd: float = 0.0
    torque_coeff_sd: float = 0.0
    motor_tau_sd: float = 0.0

    @classmethod
    def from_section(cls, vehicle: object) -> SpreadParams:
        """Bind the ``*_sd`` keys of a ``[vehicle]`` section."""
        return cls(mass_sd=vehicle.mass_sd, inertia_sd=vehicle.inertia_sd,
                   thrust_coeff_sd=vehicle.thrust_gain_sd,
                   torque_coeff_sd=vehicle.torque_coeff_sd, motor_tau_sd=vehicle.motor_tau_sd)


@dataclass(frozen=True)
class VehicleBody:
    """N vehicles' true constants (batch-first; read-only: the step's caches of numbers derived
    from them, :func:`aerodock.world.vehicles.rigid_body._body_constants` and the downwash
    field's force coefficients, are keyed by the arrays).

    Attributes:
        mass_kg: (n,) mass.
        mass_rows_kg: (n, 3) the mass repeated per component (a flat loop in the hot path).
        inertia_kgm2: (n, 3) principal moments, body FRD.
        torque_gain: (n,) the rotors' yaw reaction torque relative to nominal.
        motor_tau_s: (n,) the motors' first-order time constant.
    """

    mass_kg: np.ndarray
    mass_rows_kg: np.ndarray
    inertia_kgm2: np.ndarray
    torque_gain: np.ndarray
    motor_tau_s: np.ndarray

    def __post_init__(self) -> None:
        freeze(*(getattr(self, f) for f in _FIELDS))

    def __setstate__(self, state: dict) -> None:  # a copy or an unpickled body: read-only too
        self.__dict__.update(state)
        self.__post_init__()

    @property
    def n(self) -> int:
        """Batch size."""
        return int(self.mass_kg.shape[0])


def nominal_body(mass_kg: float, inertia_kgm2: np.ndarray, motor_tau_s: float,
                 n: int) -> VehicleBody:
    """N vehicles exactly as nominal."""
    mass = np.full(n, float(mass_kg))
    return VehicleBody(mass_kg=mass, mass_rows_kg=np.repeat(mass[:, None], 3, axis=1),
                       inertia_kgm2=np.tile(np.asarray(inertia_kgm2, dtype=float), (n, 1)),
                       torque_gain=np.ones(n), motor_tau_s=np.full(n, float(motor_tau_s)))


def draw_body(nominal: VehicleBody, spread: SpreadParams,
              rng: np.random.Generator | TrialRNG) -> VehicleBody:
    """``nominal`` with each vehicle's relative errors drawn from ``spread`` (one draw of four
    standard normals per vehicle when any spread is set: mass, inertia (one factor for the three
    moments: a heavier battery scales them together), torque coefficient, motor time constant)."""
    if not (spread.mass_sd or spread.inertia_sd or spread.torque_coeff_sd or spread.motor_tau_sd):
        return nominal
    n = nominal.n
    z = np.clip(standard_normal_t(rng, n, 4), -SPREAD_CLIP_SD, SPREAD_CLIP_SD)  # per trial
    mass = nominal.mass_kg * (1.0 + spread.mass_sd * z[0])
    return VehicleBody(
        mass_kg=mass, mass_rows_kg=np.repeat(mass[:, None], 3, axis=1),
        inertia_kgm2=nominal.inertia_kgm2 * (1.0 + spread.inertia_sd * z[1])[:, None],
        torque_gain=nominal.torque_gain * (1.0 + spread.torque_coeff_sd * z[2]),
        motor_tau_s=nominal.motor_tau_s * (1.0 + spread.motor_tau_sd * z[3]),
    )


def concat_bodies(a: VehicleBody, b: VehicleBody) -> VehicleBody:
    """One batch of both (``a`` first)."""
    return VehicleBody(*[np.concatenate([getattr(a, f), getattr(b, f)]) for f in _FIELDS])


def body_rows(body: VehicleBody, rows: slice | np.ndarray) -> VehicleBody:
    """The vehicles at ``rows`` (views for a slice, copies for an index array)."""
    return VehicleBody(*[getattr(body, f)[rows] for f in _FIELDS])


_FIELDS = ("mass_kg", "mass_rows_kg", "inertia_kgm2", "torque_gain", "motor_tau_s")
