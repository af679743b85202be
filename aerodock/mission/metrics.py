"""What a campaign measures, per trial, from the true state (no controller ever sees it): the
tracking error, tilt and saturation of each control period, clearance, rotor strikes, ground
contacts, non-finite states; the terminal window's statistics; optional traces for figures."""

from __future__ import annotations

from typing import Any

import numpy as np

from aerodock.geometry import norm_rows
from aerodock.mission.phases.gate_sensing import GateCode
from aerodock.mission.spec import PhaseCode, any_true
from aerodock.world import World
from aerodock.world.platform import platform_strike

TRACE_KEYS = ("t_s", "follower_p", "leader_p", "bar_p", "ref_p", "phase", "ff", "gate")
TERMINAL_WINDOW_S = 0.5
"""The paper's table integrates over the final 0.5 s of the approach."""


class MissionMetrics:
    """Per-trial measures kept over a mission. Outcomes are each trial's own: collisions count
    until its mission ends (DONE), however long the batch goes on flying its other trials.

    Args:
        n: trials.
        steps: control periods of the whole mission.
        arrival_s: the planned arrival (the terminal window ends there, or when the gate closes).
        traced: keep per-period positions for figures.
    """

    def __init__(self, n: int, steps: int, arrival_s: float, traced: bool) -> None:
        self.min_clear = np.full(n, np.inf)
        self.strikes = np.zeros(n, dtype=bool)
        self.ground_hit = np.zeros(n, dtype=bool)
        self.nan_seen = np.zeros(n, dtype=bool)
        # Terminal window: the 0.5 s before the approach ends (arrival, or the gate closing).
        self.approach_end = np.full(n, arrival_s)
        # |e_down|, |e_3d|, predicted down force, tilt (deg), control saturated
        self.hist = np.full((steps, n, 5), np.nan)
        self.trace: dict[str, list] = {k: [] for k in TRACE_KEYS} if traced else {}

    def measure(self, k: int, t_s: float, world: World, phase: np.ndarray, active: np.ndarray,
                p_ref: np.ndarray, ff: np.ndarray | None, fout: Any, leader_yaw_rad: np.ndarray,
                clearance_m: float, rotor_radius_m: float) -> tuple[np.ndarray, np.ndarray]:
        """Measure control period ``k`` (before it is flown); returns the true tracking error
        (n,) m and the trials whose clearance was first violated now (n,)."""
        gp, hist = world.gripper_params, self.hist
        lead_p, lead_r, fol_p, fol_r = world.poses()  # no split of the world's batch
        true_err = fol_p - p_ref
        hist[k, :, 0] = np.abs(true_err[:, 2])
        hist[k, :, 1] = track_err_m = norm_rows(true_err)
        hist[k, :, 2] = 0.0 if ff is None else ff[:, 2]
        # np.clip's numbers, without its wrapper's cost (as geometry.rotmat_to_rpy)
        hist[k, :, 3] = np.rad2deg(np.arccos(np.minimum(np.maximum(fol_r[:, 2, 2], -1.0), 1.0)))
        hist[k, :, 4] = fout.saturated
        ended = (~active | (world.gripper.gate != GateCode.OPEN)) & (self.approach_end > t_s)
        if any_true(ended):
            self.approach_end = np.where(ended, t_s, self.approach_end)
        live = phase != PhaseCode.DONE  # this trial's mission is still on
        self.ground_hit |= world.ground_contact & live
        arm = fol_p - fol_r[:, :, 2] * gp.mount_height_m
        was_clear = self.min_clear >= clearance_m
        self.min_clear = np.where(live, np.minimum(
            self.min_clear, norm_rows(arm - lead_p)), self.min_clear)
        violated_now = was_clear & (self.min_clear < clearance_m)
        self.nan_seen |= ~(np.isfinite(fol_p).all(axis=1) & np.isfinite(lead_p).all(axis=1)
                           & np.isfinite(fout.command.thrust_n))
        if world.rigid:
            self.strikes |= live & platform_strike(
                fol_p, fol_r, lead_p, lead_r, leader_yaw_rad, world.bar, world.platform,
                world.follower_fleet.params.rotor_offsets_m, rotor_radius_m, gp.bar_radius_m)
        if self.trace:
            tr = self.trace
            tr["t_s"].append(t_s)
            tr["follower_p"].append(fol_p.copy())
            tr["leader_p"].append(lead_p.copy())
            tr["bar_p"].append(world.bar.p.copy())
            tr["ref_p"].append(p_ref.copy())
            tr["phase"].append(phase.copy())
            tr["ff"].append(fout.feedforward_mps2.copy())
            tr["gate"].append(world.gripper.gate.copy())
        return track_err_m, violated_now

    def terminal_window(self, dt_s: float) -> dict[str, np.ndarray]:
        """Per-trial statistics over the terminal window (the 0.5 s before each approach ended):
        mean and integrated errors, the integrated predicted force, RMS tilt, saturation."""
        steps = self.hist.shape[0]
        t_grid = np.arange(steps)[:, None] * dt_s
        in_win = ((t_grid >= self.approach_end - TERMINAL_WINDOW_S)
                  & (t_grid < self.approach_end))
        win = np.where(in_win[..., None], self.hist, 0.0)
        cnt = np.maximum(in_win.sum(0), 1)
        sums = _over_steps(win)
        return {
            "err_down_m": sums[:, 0] / cnt,
            "err_3d_m": sums[:, 1] / cnt,
            "err_down_int_ms": sums[:, 0] * dt_s,
            "err_3d_int_ms": sums[:, 1] * dt_s,
            "ff_down_int_mps": sums[:, 2] * dt_s,
            "tilt_rms_deg": np.sqrt(_over_steps(win[..., 3:4] ** 2)[:, 0] / cnt),
            "saturated_frac": sums[:, 4] / cnt,
        }


def _over_steps(values: np.ndarray) -> np.ndarray:
    """(steps, n, k) summed over the steps in order, one step after the other, (n, k): the same
    numbers for a trial whatever the batch (``sum(0)`` of one trial's contiguous column sums it
    pairwise, of several trials' strided columns in order)."""
    return np.cumsum(values, axis=0)[-1]
