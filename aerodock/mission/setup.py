"""A campaign's set-up, computed once: its timing, the vehicles' starts, the armed triggers."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from aerodock.mission.params import MissionParams
from aerodock.mission.spec import MissionSpec
from aerodock.planning.docking import docking_point_m
from aerodock.rng import TrialRNG


@dataclass(frozen=True)
class MissionTiming:
    """When things happen in a campaign (mission time, s; t = 0 ends the settled start).

    Attributes:
        arrival_s: the planned arrival at the docking point (the planner's horizon).
        active_at_s: the active trigger is armed from then on.
        timeout_s: an approach not docked by then aborts (arrival, hold, docking window).
        dt_s: the control period.
        steps: control periods of the whole mission (timeout plus back-off).
    """

    arrival_s: float
    active_at_s: float
    timeout_s: float
    dt_s: float
    steps: int


def mission_timing(params: MissionParams, spec: MissionSpec, dt_control_s: float) -> MissionTiming:
    """The timing of ``spec``'s campaign at control period ``dt_control_s``."""
    m, planner = params.mission, params.planner
    moving = spec.moving
    arrival_s = planner.horizon_moving_s if moving else planner.horizon_hover_s
    hold_s = planner.hold_s if moving else 0.0
    timeout_s = arrival_s + hold_s + m.dock_window_s
    return MissionTiming(
        arrival_s=arrival_s,
        active_at_s=arrival_s + (0.5 if moving else m.active_trigger_delay_s),
        timeout_s=timeout_s, dt_s=dt_control_s,
        steps=int(np.ceil((timeout_s + m.backoff_s) / dt_control_s)),
    )


@dataclass(frozen=True)
class Starts:
    """Where each trial begins (n, 3), NED, at t = 0, and the leader's cruise velocity."""

    leader_p_m: np.ndarray
    follower_p_m: np.ndarray
    leader_velocity_mps: np.ndarray  # (3,)

    def take_rows(self, rows: np.ndarray) -> Starts:
        """The starts of the trials at ``rows``."""
        return Starts(self.leader_p_m[rows], self.follower_p_m[rows], self.leader_velocity_mps)


def starts(params: MissionParams, spec: MissionSpec, trials: np.ndarray,
           rng: TrialRNG) -> Starts:
    """The leader hovering (or cruising north) at its altitude; the follower below and away, at
    an azimuth that cycles with the trial index, with a little jitter (one random draw)."""
    m, n = params.mission, trials.size
    leader_p0 = np.tile([0.0, 0.0, -m.leader_altitude_m], (n, 1))
    dock0 = docking_point_m(leader_p0, np.zeros((n, 3)), params.geometry)
    az = np.deg2rad(np.asarray(spec.start_azimuths_deg))[trials % len(spec.start_azimuths_deg)]
    start = dock0 + np.stack([m.start_radius_m * np.cos(az), m.start_radius_m * np.sin(az),
                              np.full(n, m.start_below_m)], 1)
    start += m.start_jitter_m * rng.standard_normal((n, 3))
    velocity = (np.array([spec.leader_speed_mps, 0.0, 0.0]) if spec.moving else np.zeros(3))
    return Starts(leader_p0, start, velocity)


def armed(configured: bool, wanted: bool | tuple[bool, ...], n: int) -> bool | np.ndarray:
    """A trigger's arming: the configuration's and the campaign's, for all trials or per trial."""
    if np.ndim(wanted) == 0:
        return bool(configured and wanted)
    flags = np.asarray(wanted, dtype=bool)
    if flags.shape != (n,):
        raise ValueError(f"per-trial trigger flags must number {n} (one per trial), "
                         f"got {flags.size}")
    return flags & bool(configured)
