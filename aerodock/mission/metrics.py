"""What a campaign measures, per trial, from the true state (no controller ever sees it): the
tracking error, tilt and saturation of each control period, clearance, rotor strikes, ground
contacts, non-finite states; the terminal window's statistics; optional traces for figures."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from aerodock.jit import NUMPY_LOOPS, any_layout, njit, np_arccos
from aerodock.mission.phases.gate_sensing import GateCode
from aerodock.mission.spec import PhaseCode
from aerodock.world import World
from aerodock.world.platform import platform_strike

TRACE_KEYS = ("t_s", "follower_p", "leader_p", "bar_p", "bar_yaw", "ref_p", "phase", "ff",
              "gate")
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
        gp = world.gripper_params
        lead_p, lead_r, fol_p, fol_r = world.poses()  # no split of the world's batch
        n = fol_p.shape[0]
        track_err_m = np.empty(n)
        violated_now = np.empty(n, dtype=bool)
        live = np.empty(n, dtype=bool)
        # new arrays each period, as np.where made them (a result may hold the last ones)
        approach_end, min_clear = np.empty(n), np.empty(n)
        measure_rows(NUMPY_LOOPS, t_s, fol_p, fol_r, lead_p, p_ref, ff is not None,
                     fol_p if ff is None else ff, fout.saturated, active, world.gripper.gate,
                     GateCode.OPEN, phase, PhaseCode.DONE, world.ground_contact,
                     fout.command.thrust_n, float(gp.mount_height_m), float(clearance_m),
                     self.hist[k], self.approach_end, self.min_clear, approach_end, min_clear,
                     self.ground_hit, self.nan_seen, track_err_m, violated_now, live)
        self.approach_end, self.min_clear = approach_end, min_clear
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
            tr["bar_yaw"].append(world.bar.yaw_rad.copy())
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


_RAD2DEG = 180.0 / math.pi
"""``np.rad2deg``'s factor: NumPy multiplies by ``180 / pi`` rounded to a double, as here."""


@any_layout("hist_k", "approach_end_out", "min_clear_out", "ground_hit", "nan_seen", "track_err_m",
            "violated_now", "live")
@njit
def measure_rows(loops: np.ndarray, t_s: float, fol_p: np.ndarray, fol_r: np.ndarray,
                 lead_p: np.ndarray, p_ref: np.ndarray, has_ff: bool, ff: np.ndarray,
                 saturated: np.ndarray, active: np.ndarray, gate: np.ndarray, gate_open: int,
                 phase: np.ndarray, done: int, ground_contact: np.ndarray, thrust_n: np.ndarray,
                 mount_height_m: float, clearance_m: float, hist_k: np.ndarray,
                 approach_end: np.ndarray, min_clear: np.ndarray, approach_end_out: np.ndarray,
                 min_clear_out: np.ndarray, ground_hit: np.ndarray,
                 nan_seen: np.ndarray, track_err_m: np.ndarray, violated_now: np.ndarray,
                 live: np.ndarray) -> None:
    """One control period's measures of :meth:`MissionMetrics.measure`, per trial, with the
    numbers of the NumPy code it replaced: the history row ``hist_k`` (n, 5) (|e_down|, the
    tracking error's norm as :func:`aerodock.geometry.norm_rows` sums it, the predicted down
    force, the tilt ``rad2deg(arccos(clip(R22, -1, 1)))`` with NumPy's own arccos loop, the
    saturation); the terminal window's end and the clearance (``np.minimum``'s NaN rule) into
    ``approach_end_out`` and ``min_clear_out``; ground contacts and non-finite states updated in
    place; the tracking error, the first clearance
    violations and whether the trial's mission is still on into ``track_err_m``,
    ``violated_now`` and ``live``."""
    n = fol_p.shape[0]
    tilt = np.empty(n)  # contiguous, as the arccos's argument NumPy made
    for i in range(n):
        c = fol_r[i, 2, 2]
        c = c if (c >= -1.0 or c != c) else -1.0
        tilt[i] = c if (c <= 1.0 or c != c) else 1.0
    np_arccos(loops, tilt, tilt)
    for i in range(n):
        e0 = fol_p[i, 0] - p_ref[i, 0]
        e1 = fol_p[i, 1] - p_ref[i, 1]
        e2 = fol_p[i, 2] - p_ref[i, 2]
        err = math.sqrt((e0 * e0 + e1 * e1) + e2 * e2)
        track_err_m[i] = err
        hist_k[i, 0] = abs(e2)
        hist_k[i, 1] = err
        hist_k[i, 2] = ff[i, 2] if has_ff else 0.0
        hist_k[i, 3] = tilt[i] * _RAD2DEG
        hist_k[i, 4] = 1.0 if saturated[i] else 0.0
        ended = (not active[i] or gate[i] != gate_open) and approach_end[i] > t_s
        approach_end_out[i] = t_s if ended else approach_end[i]
        on = phase[i] != done
        live[i] = on
        ground_hit[i] = ground_hit[i] or (ground_contact[i] and on)
        d0 = (fol_p[i, 0] - fol_r[i, 0, 2] * mount_height_m) - lead_p[i, 0]
        d1 = (fol_p[i, 1] - fol_r[i, 1, 2] * mount_height_m) - lead_p[i, 1]
        d2 = (fol_p[i, 2] - fol_r[i, 2, 2] * mount_height_m) - lead_p[i, 2]
        dist = math.sqrt((d0 * d0 + d1 * d1) + d2 * d2)
        m = min_clear[i]
        if on:
            m = m if (m < dist or m != m) else dist  # np.minimum: a NaN wins
        min_clear_out[i] = m
        violated_now[i] = min_clear[i] >= clearance_m and m < clearance_m
        finite = True
        for j in range(3):
            finite = finite and math.isfinite(fol_p[i, j]) and math.isfinite(lead_p[i, j])
        if not (finite and math.isfinite(thrust_n[i])):
            nan_seen[i] = True
