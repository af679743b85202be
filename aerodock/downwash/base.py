"""The downwash field protocol: a public extension point (documented in the README).

A field is any object with ``reset`` and ``acceleration`` (:class:`DownwashField`); it is loaded
from the config by import path (``[downwash] field = "package.module:factory"``) with
``[downwash.params]`` passed to the factory as keyword arguments. See
``aerodock/downwash/template.py`` for a minimal example. A config that names a module outside
aerodock runs its code, so it loads only from an installed package's ``aerodock.fields`` entry
point or a module the user trusts (:mod:`aerodock.config.plugins`); the factory is a class with
``reset`` and ``acceleration`` or a function marked with :func:`aerodock.downwash.field_factory`.

Five methods are optional; every command works without them:

- ``mean_acceleration(leader, follower) -> (n, 3)`` (:class:`SupportsMean`): the turbulence-free
  mean. Without it, whoever needs the mean estimates it (:mod:`aerodock.downwash.mean`).
- ``wrench(leader, follower, rotor_offsets_body_m, dt) -> (force_n, torque_nm)``
  (:class:`SupportsWrench`): force and torque sampled per rotor disk. Without it, the world
  applies ``acceleration * mass`` at the centre of mass (:func:`aerodock.downwash.wrench.
  follower_wrench`).
- ``body_force_n(leader, follower) -> (n, 3)`` (:class:`SupportsBodyForce`): with ``wrench``,
  the part of the force that lands on the follower's body rather than its rotor disks, at the
  centre of mass, of the same step's turbulence (``acceleration`` is then both parts over the
  mass). Without it, ``wrench`` (or ``acceleration``) is the whole force.
- ``bar_force_n(leader, bar_p_m, bar_v_mps, bar_area_m2[, dt][, bar_axis]) -> (n, 3)``
  (:class:`SupportsBarForce`): the wake's force on the docking bar. Without it, the bar feels no
  wake (:func:`aerodock.downwash.wrench.bar_wake_force_n`).
- ``take_rows(rows, rng) -> field`` (:class:`SupportsTakeRows`): the field of some trials only,
  their turbulence where it stands. Without it, a Gymnasium environment settles each episode's
  start on its own rather than a block of upcoming ones at once (:mod:`aerodock.envs.starts`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np


def frozen_record(cls: type, **fields: object) -> object:
    """``cls(**fields)`` for a dataclass without ``__post_init__`` (whose ``__init__`` only sets
    its fields: for a frozen one, one ``object.__setattr__`` each), built at a fraction of the
    cost: the same object, fields in the instance ``__dict__``. For the per-step states and the
    step's frame in the hot loop; ``fields`` must name every field, defaults included."""
    record = object.__new__(cls)
    record.__dict__.update(fields)
    return record


@dataclass(frozen=True)
class BodyState:
    """Batch-first state of N vehicles (or N trials of one vehicle), world NED, SI units.

    Attributes:
        p: (n, 3) position, m.
        v: (n, 3) velocity, m/s.
        R: (n, 3, 3) attitude, body to world.
        thrust_n: (n,) collective thrust, N.
        mass_kg: (n,) mass, kg.
    """

    p: np.ndarray
    v: np.ndarray
    R: np.ndarray
    thrust_n: np.ndarray
    mass_kg: np.ndarray

    @property
    def n(self) -> int:
        """Batch size."""
        return int(self.p.shape[0])


@runtime_checkable
class DownwashField(Protocol):
    """What a downwash field implements."""

    def reset(self, n: int, rng: np.random.Generator) -> None:
        """Start N independent trials (draw turbulence state from ``rng``)."""

    def acceleration(self, leader: BodyState, follower: BodyState, dt: float) -> np.ndarray:
        """(n, 3) acceleration in m/s² on the follower, world NED; advances time by ``dt``."""


@runtime_checkable
class SupportsMean(Protocol):
    """Optional: the field's turbulence-free mean."""

    def mean_acceleration(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(n, 3) mean acceleration in m/s² on the follower, world NED (no time advance)."""


@runtime_checkable
class SupportsWrench(Protocol):
    """Optional: force and torque on the follower from the field sampled at its rotor disks."""

    def wrench(self, leader: BodyState, follower: BodyState, rotor_offsets_body_m: np.ndarray,
               dt: float) -> tuple[np.ndarray, np.ndarray]:
        """``(force_n, torque_nm)``: (n, 3) force in N, world NED, and (n, 3) torque in N·m in
        the follower's body frame (FRD) about its centre of mass; ``rotor_offsets_body_m`` is
        (k, 3) rotor-disk centres in the body frame. Advances time by ``dt`` exactly as
        ``acceleration`` does (the world calls one of the two per physics step)."""


@runtime_checkable
class SupportsBodyForce(Protocol):
    """Optional: the force on the follower's body (with ``wrench``: what lands off the disks)."""

    def body_force_n(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(n, 3) force in N on the follower's body, world NED, at its centre of mass, with the
        turbulence of the same step's ``wrench`` (or ``acceleration``) call; no time advance."""


@runtime_checkable
class SupportsBarForce(Protocol):
    """Optional: the wake's force on the hanging docking bar.

    ``dt`` (the physics step, for a field with bar turbulence) and ``bar_axis`` ((n, 3) unit
    vectors along the bar, NED) are passed only to implementations whose signature names them.
    """

    def bar_force_n(self, leader: BodyState, bar_p_m: np.ndarray, bar_v_mps: np.ndarray,
                    bar_area_m2: float) -> np.ndarray:
        """(n, 3) force in N on the bar at ``bar_p_m`` moving at ``bar_v_mps``, world NED."""


@runtime_checkable
class SupportsTakeRows(Protocol):
    """Optional: the field of some of its trials, to carry on with in a batch of their own."""

    def take_rows(self, rows: np.ndarray, rng: np.random.Generator) -> SupportsTakeRows:
        """A field for the trials at ``rows`` (indices into the batch of the last ``reset``),
        each trial's turbulence state where it stands, drawing from ``rng`` from now on (those
        trials' own streams); the numbers it gives them are the ones this field would give."""
