"""The downwash field protocol: a public extension point (documented in the README).

A field is any object with ``reset`` and ``acceleration``; it is loaded from the config by import
path (``[downwash] field = "package.module:factory"``) with ``[downwash.params]`` passed to the
factory as keyword arguments. See ``aerodock/downwash/template.py`` for a minimal example.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np


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
