"""A minimal plug-in downwash field: copy this file to start your own (CFD-fitted, measured, ...).

Use it from a config file::

    [downwash]
    field = "aerodock.downwash.template:UniformColumnField"
    [downwash.params]
    accel_mps2 = 3.0
    radius_m = 0.15

A field implements ``reset(n, rng)`` and ``acceleration(leader, follower, dt) -> (n, 3)``, m/s²,
world NED (``aerodock.downwash.base.DownwashField``). Optional (``aerodock.downwash.base``):
``mean_acceleration`` (exact mean for the oracle, ``field probe``/``plot`` and the error floor;
otherwise estimated by averaging ``acceleration``), ``wrench`` (force and torque sampled per
rotor disk; otherwise ``acceleration * mass`` at the centre of mass) and ``bar_force_n`` (the
wake on the docking bar; otherwise none).
"""

from __future__ import annotations

import numpy as np

from aerodock.downwash.base import BodyState


class UniformColumnField:
    """A constant downward push inside a vertical column under the leader (no turbulence)."""

    def __init__(self, accel_mps2: float = 3.0, radius_m: float = 0.15):
        self.accel_mps2 = accel_mps2
        self.radius_m = radius_m

    def reset(self, n: int, rng: np.random.Generator) -> None:
        """Nothing to draw: this field has no turbulence."""

    def mean_acceleration(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(n, 3) mean acceleration, m/s², NED."""
        rel = follower.p - leader.p
        inside = (np.linalg.norm(rel[:, :2], axis=1) < self.radius_m) & (rel[:, 2] > 0)
        accel = np.zeros_like(rel)
        accel[:, 2] = np.where(inside, self.accel_mps2, 0.0)
        return accel

    def acceleration(self, leader: BodyState, follower: BodyState, dt: float) -> np.ndarray:
        """(n, 3) acceleration on the follower, m/s², NED."""
        return self.mean_acceleration(leader, follower)


class ZeroField:
    """No downwash at all (free air): useful as a control in experiments."""

    def reset(self, n: int, rng: np.random.Generator) -> None:
        """Nothing to draw."""

    def mean_acceleration(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        """(n, 3) zeros."""
        return np.zeros_like(follower.p)

    def acceleration(self, leader: BodyState, follower: BodyState, dt: float) -> np.ndarray:
        """(n, 3) zeros."""
        return np.zeros_like(follower.p)
