"""Where the follower must be to dock: the bar's predicted position, from the leader's state.

The bar hangs ``d_p`` below the cable anchor (itself ``anchor_below_leader_m`` below the leader
along its body z axis); with the leader at constant velocity the bar hangs straight below and moves
with it, so the prediction at a horizon ``h`` is the current one shifted by ``v_leader h``. The
follower's docking point puts its contact arm ``insertion_m`` into the bar from below.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from aerodock.config import Config


@dataclass(frozen=True)
class DockGeometry:
    """Offsets between the leader, the bar and the follower's centre of mass at docking."""

    anchor_below_leader_m: float
    cable_length_m: float
    bar_radius_m: float
    mount_height_m: float
    insertion_m: float

    @classmethod
    def from_config(cls, cfg: Config) -> DockGeometry:
        """Bind the platform, gripper and mission values of ``cfg``."""
        return cls(
            anchor_below_leader_m=cfg.platform.anchor_below_leader_m,
            cable_length_m=cfg.platform.cable_length_m,
            bar_radius_m=cfg.platform.bar_diameter_m / 2.0,
            mount_height_m=cfg.gripper.mount_height_m,
            insertion_m=cfg.mission.insertion_m,
        )

    @property
    def follower_below_leader_m(self) -> float:
        """Vertical distance from the leader's to the follower's centre of mass when docked."""
        return (self.anchor_below_leader_m + self.cable_length_m + self.bar_radius_m
                - self.insertion_m + self.mount_height_m)

    @cached_property
    def bar_below_leader_m(self) -> np.ndarray:
        """(3,) the bar's centre relative to the leader when it hangs straight down, NED
        (read-only; built once: the mission adds it every control period)."""
        return _read_only([0.0, 0.0, self.anchor_below_leader_m + self.cable_length_m])

    @cached_property
    def docked_below_leader_m(self) -> np.ndarray:
        """(3,) the follower's centre of mass relative to the leader when docked, NED
        (read-only; built once)."""
        return _read_only([0.0, 0.0, self.follower_below_leader_m])


def predicted_bar_m(leader_p: np.ndarray, leader_v: np.ndarray, geom: DockGeometry,
                    horizon_s: np.ndarray | float = 0.0) -> np.ndarray:
    """(n, 3) predicted bar centre ``horizon_s`` ahead (bar hanging straight down), NED."""
    return _ahead(leader_p, leader_v, horizon_s) + geom.bar_below_leader_m


def docking_point_m(leader_p: np.ndarray, leader_v: np.ndarray, geom: DockGeometry,
                    horizon_s: np.ndarray | float = 0.0) -> np.ndarray:
    """(n, 3) where the follower's centre of mass must be to dock, ``horizon_s`` ahead, NED."""
    return _ahead(leader_p, leader_v, horizon_s) + geom.docked_below_leader_m


def _ahead(p: np.ndarray, v: np.ndarray, horizon_s: np.ndarray | float) -> np.ndarray:
    """``p + v h``: (n, 3) positions moved ``horizon_s`` ahead at the velocities ``v`` (a
    scalar horizon, or one per trial)."""
    if isinstance(horizon_s, float | int):
        return p + v * float(horizon_s)
    h = np.asarray(horizon_s, dtype=float)
    return p + v * (h[:, None] if h.ndim == 1 else h)


def _read_only(values: list[float]) -> np.ndarray:
    """``values`` as a float array no one can write to."""
    out = np.array(values, dtype=float)
    out.flags.writeable = False
    return out
