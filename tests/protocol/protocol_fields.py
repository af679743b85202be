"""Three plug-in fields that look nothing like the default round jet (issue 15).

Loaded by import path from a config (``field = "protocol_fields:MinimalField"``), as a user's
plug-in would be; ``tests/protocol/conftest.py`` puts this folder on the import path.
"""

from __future__ import annotations

import numpy as np

from aerodock.downwash.base import BodyState


class MinimalField:
    """Only the required protocol: ``reset`` and ``acceleration``.

    A wide, flat-topped column of downward push under the leader (super-Gaussian in the radius,
    constant with depth up to 2 m), with white turbulence on all three axes (sd 0.6 m/s²), so a
    mean is only available by averaging.
    """

    def __init__(self, accel_mps2: float = 2.0, radius_m: float = 0.3, noise_mps2: float = 0.6):
        self.accel_mps2 = accel_mps2
        self.radius_m = radius_m
        self.noise_mps2 = noise_mps2
        self._rng: np.random.Generator | None = None

    def reset(self, n: int, rng: np.random.Generator) -> None:
        self._rng = rng

    def acceleration(self, leader: BodyState, follower: BodyState, dt: float) -> np.ndarray:
        rel = follower.p - leader.p
        r = np.hypot(rel[:, 0], rel[:, 1])
        inside = (rel[:, 2] > 0) & (rel[:, 2] < 2.0)
        push = self.accel_mps2 * np.exp(-((r / self.radius_m) ** 4)) * inside
        out = np.zeros_like(rel)
        out[:, 2] = push
        out += self.noise_mps2 * self._rng.standard_normal(rel.shape)
        return out


class OutwardThrustAxisField:
    """Pushes along the leader's thrust axis (its body z, so it follows the leader's tilt) with a
    strong outward lateral component (half the axial push at the edge), decaying exponentially
    with depth; time-correlated multiplicative turbulence. Offers ``mean_acceleration``, a
    ``wrench`` (its force acting 2 cm from the centre of mass towards the wake's axis) and an
    old-style ``bar_force_n(leader, bar_p_m, bar_v_mps, bar_area_m2)`` (no ``dt``)."""

    def __init__(self, accel_mps2: float = 3.5, decay_m: float = 0.8, width_m: float = 0.25,
                 outward_ratio: float = 0.5, turb: float = 0.3, corr_time_s: float = 0.05):
        self.accel_mps2 = accel_mps2
        self.decay_m = decay_m
        self.width_m = width_m
        self.outward_ratio = outward_ratio
        self.turb = turb
        self.corr_time_s = corr_time_s
        self._state = np.zeros(0)
        self._rng: np.random.Generator | None = None

    def reset(self, n: int, rng: np.random.Generator) -> None:
        self._rng = rng
        self._state = rng.standard_normal(n)

    def _mean(self, leader: BodyState, points_m: np.ndarray) -> np.ndarray:
        axis = leader.R[:, :, 2]
        rel = points_m - leader.p
        depth = np.einsum("ij,ij->i", rel, axis)
        radial = rel - depth[:, None] * axis
        r = np.linalg.norm(radial, axis=1)
        unit = radial / np.maximum(r, 1e-9)[:, None]
        mag = self.accel_mps2 * np.exp(-np.maximum(depth, 0.0) / self.decay_m) * (depth > 0)
        shape = np.exp(-((r / self.width_m) ** 2))
        out = (mag * shape)[:, None] * axis
        out += (self.outward_ratio * mag * (r / self.width_m) * shape)[:, None] * unit
        return out

    def mean_acceleration(self, leader: BodyState, follower: BodyState) -> np.ndarray:
        return self._mean(leader, follower.p)

    def acceleration(self, leader: BodyState, follower: BodyState, dt: float) -> np.ndarray:
        decay = np.exp(-dt / self.corr_time_s)
        self._state = decay * self._state + np.sqrt(1 - decay**2) * self._rng.standard_normal(
            leader.n)
        return self._mean(leader, follower.p) * (1.0 + self.turb * self._state)[:, None]

    def wrench(self, leader: BodyState, follower: BodyState, rotor_offsets_body_m: np.ndarray,
               dt: float) -> tuple[np.ndarray, np.ndarray]:
        force = self.acceleration(leader, follower, dt) * follower.mass_kg[:, None]
        rel = follower.p - leader.p
        inward = -(rel - np.einsum("ij,ij->i", rel, leader.R[:, :, 2])[:, None] * leader.R[:, :, 2])
        inward /= np.maximum(np.linalg.norm(inward, axis=1), 1e-9)[:, None]
        centre_body = np.einsum("nji,nj->ni", follower.R, 0.02 * inward)
        force_body = np.einsum("nji,nj->ni", follower.R, force)
        return force, np.cross(centre_body, force_body)

    def bar_force_n(self, leader: BodyState, bar_p_m: np.ndarray, bar_v_mps: np.ndarray,
                    bar_area_m2: float) -> np.ndarray:
        return 0.03 * self._mean(leader, bar_p_m)


class NoWakeField:
    """No wake at all: the follower feels nothing from the leader (only reset/acceleration)."""

    def reset(self, n: int, rng: np.random.Generator) -> None:
        pass

    def acceleration(self, leader: BodyState, follower: BodyState, dt: float) -> np.ndarray:
        return np.zeros_like(follower.p)
