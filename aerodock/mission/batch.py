"""The docking mission: a per-trial state machine flown by N trials at once.

Phases (``Phase``): ``APPROACH`` (minimum-jerk to the predicted docking point at the horizon,
re-planned when the prediction moves) -> ``TERMINAL`` (stiffer gains, triggers armed) -> the gate
resolves: ``CAPTURED`` (post-dock: the follower cuts thrust to a fraction and the leader carries
it) or ``MISSED`` -> back off; ``ABORT`` (timeout, leader state lost for longer than
``leader_lost_s``, or a tracking error that brings the follower's top towards the leader) ->
back off below and away; then ``DONE``. The reference never brings the follower's top closer to
the leader than ``clearance_m``.

:func:`run_campaign` flies one campaign (N trials, one seed) and returns per-trial outcomes,
summary statistics, optional traces for figures and optional FlightLogs.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, fields, replace
from enum import IntEnum
from typing import Any

import numpy as np

from aerodock.config import Config
from aerodock.control.compensation import (
    AccelPredictor,
    Compensation,
    OraclePredictor,
)
from aerodock.control.controller import PositionController, Reference
from aerodock.control.torque_feedforward import feedforward_torque_nm
from aerodock.downwash import BodyState, build_field
from aerodock.flightlog import FlightLog
from aerodock.mission.faults import Fault, FaultRuntime, draw_faults
from aerodock.mission.recorder import FlightRecorder, vehicle_meta
from aerodock.mission.settle import CruiseStart, settle
from aerodock.planning.docking import DockGeometry, docking_point_m
from aerodock.planning.minjerk import MinJerk, minjerk
from aerodock.rng import TrialRNG
from aerodock.world import Observation, World
from aerodock.world.gripper import GateState
from aerodock.world.platform import anchor_point, platform_segments, rotor_strike


class Phase(IntEnum):
    """Per-trial mission phase."""

    APPROACH = 0
    TERMINAL = 1
    CAPTURED = 2
    MISSED = 3
    ABORT = 4
    DONE = 5


class AbortReason(IntEnum):
    """Why a trial aborted (0: it did not)."""

    NONE = 0
    TIMEOUT = 1
    LEADER_LOST = 2
    UNSAFE_TRACKING = 3
    GATE_FAULT = 4  # the gate did not finish closing long after it was commanded


@dataclass(frozen=True)
class MissionSpec:
    """One campaign's set-up."""

    trials: int = 50
    offset_m: float | None = None  # cable length d_p (None: config's platform.cable_length_m)
    leader_speed_mps: float = 0.0
    leader_fixed: bool = False
    compensation: Compensation = Compensation.OBSERVER
    seed: int = 0
    first_trial: int = 0  # trial i draws from stream (seed, first_trial + i)
    start_azimuths_deg: tuple[float, ...] = (0.0, 90.0, 180.0, 270.0)
    leader_dropout_s: tuple[float, float] | None = None  # (start, duration): leader state lost
    faults: tuple[Fault, ...] = ()  # injected faults (aerodock.mission.faults), drawn per trial
    passive_trigger: bool | tuple[bool, ...] = True  # armed in every trial, or one flag per trial
    active_trigger: bool | tuple[bool, ...] = True


@dataclass
class CampaignResult:
    """Outcomes of one campaign: per-trial arrays, a summary, and optional traces / logs."""

    spec: MissionSpec
    success: np.ndarray
    slipped: np.ndarray
    missed: np.ndarray
    aborted: np.ndarray
    abort_reason: np.ndarray
    clearance_violation: np.ndarray
    rotor_strike: np.ndarray  # the bar or a cable went through a rotor disk (a crash)
    nan_state: np.ndarray  # a non-finite state or metric (a numerical failure)
    fault_hit: np.ndarray  # an injected fault struck the trial (every trial when none is set)
    ground_contact: np.ndarray
    post_dock_sink_m: np.ndarray  # the leader's altitude loss when a docked trial ends (nan: not)
    min_clearance_m: np.ndarray
    capture_time_s: np.ndarray
    err_down_m: np.ndarray  # mean |vertical tracking error| over the terminal window
    err_3d_m: np.ndarray
    err_down_int_ms: np.ndarray  # integral of |vertical error| over the final 0.5 s (paper's table)
    err_3d_int_ms: np.ndarray
    ff_down_int_mps: np.ndarray  # integral of the predicted vertical force over the final 0.5 s
    tilt_rms_deg: np.ndarray  # RMS tilt of the follower over the terminal window
    saturated_frac: np.ndarray  # fraction of the terminal window with the control saturated
    arrival_s: float
    trace: dict[str, np.ndarray] = field(default_factory=dict)
    logs: list[FlightLog] = field(default_factory=list)

    def take(self, index: np.ndarray) -> CampaignResult:
        """The campaign of the trials at batch positions ``index`` alone: outcomes, metrics,
        traces (their trial axis) and logs; per-trial trigger flags of the spec likewise."""
        index = np.asarray(index)
        n = self.success.size
        out: dict[str, Any] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, np.ndarray) and value.ndim and value.shape[0] == n:
                value = value[index]
            out[f.name] = value
        out["trace"] = {k: (v[:, index] if v.ndim >= 2 else v) for k, v in self.trace.items()}
        out["logs"] = [self.logs[i] for i in index] if self.logs else []
        flags = {k: tuple(bool(b) for b in np.asarray(getattr(self.spec, k))[index])
                 for k in ("passive_trigger", "active_trigger")
                 if np.ndim(getattr(self.spec, k))}
        out["spec"] = replace(self.spec, trials=int(index.size), **flags)
        return CampaignResult(**out)

    def summary(self) -> dict[str, Any]:
        """Success rate with a Wilson 95 % interval and error statistics (JSON-ready)."""
        n = int(self.success.size)
        k = int(self.success.sum())
        lo, hi = wilson_interval(k, n)
        return {
            "trials": n,
            "docked": k,
            "success_rate": k / n,
            "success_wilson95": [lo, hi],
            "slip_throughs": int(self.slipped.sum()),
            "missed": int(self.missed.sum()),
            "aborts": int(self.aborted.sum()),
            "abort_reasons": {r.name.lower(): int((self.abort_reason == r).sum())
                              for r in AbortReason if r != AbortReason.NONE},
            "clearance_violations": int(self.clearance_violation.sum()),
            "rotor_strikes": int(self.rotor_strike.sum()),
            "nan_trials": int(self.nan_state.sum()),
            "safe_aborts": int((self.aborted & ~self.clearance_violation & ~self.rotor_strike
                                & ~self.ground_contact & ~self.nan_state).sum()),
            "ground_contacts": int(self.ground_contact.sum()),
            "post_dock_sink_median_m": _nan_stat(np.nanmedian, self.post_dock_sink_m),
            "post_dock_sink_max_m": _nan_stat(np.nanmax, self.post_dock_sink_m),
            "min_clearance_m": float(np.min(self.min_clearance_m)),
            "terminal_err_down_median_m": float(np.median(self.err_down_m)),
            "terminal_err_down_mean_m": float(np.mean(self.err_down_m)),
            "terminal_err_3d_median_m": float(np.median(self.err_3d_m)),
            "terminal_err_3d_mean_m": float(np.mean(self.err_3d_m)),
            "err_down_int_0p5s_ms": float(np.mean(self.err_down_int_ms)),
            "err_3d_int_0p5s_ms": float(np.mean(self.err_3d_int_ms)),
            "ff_down_int_0p5s_mps": float(np.mean(self.ff_down_int_mps)),
            "terminal_tilt_rms_deg_median": float(np.median(self.tilt_rms_deg)),
            "terminal_saturated_frac_mean": float(np.mean(self.saturated_frac)),
        }


def _nan_stat(stat: Callable[[np.ndarray], Any], values: np.ndarray) -> float | None:
    """``stat`` over the finite values, or None when there are none (JSON-ready)."""
    finite = values[np.isfinite(values)]
    return float(stat(finite)) if finite.size else None


def wilson_interval(k: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    """Wilson score interval for a binomial proportion ``k / n`` (95 % by default)."""
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    denom = 1 + z**2 / n
    centre = (p + z**2 / (2 * n)) / denom
    half = z * np.sqrt(p * (1 - p) / n + z**2 / (4 * n**2)) / denom
    return (float(max(0.0, centre - half)), float(min(1.0, centre + half)))


def _merge_plans(old: MinJerk, new: MinJerk, mask: np.ndarray) -> MinJerk:
    """Per-trial choice between two plans (``new`` where ``mask``)."""
    out = {}
    for name in ("coeffs", "t0_s", "duration_s", "p0", "v0", "a0", "pf", "vf"):
        a, b = getattr(old, name), getattr(new, name)
        m = mask.reshape((-1,) + (1,) * (np.ndim(a) - 1))
        out[name] = np.where(m, b, a)
    return replace(old, **out)


def _armed(configured: bool, wanted: bool | tuple[bool, ...], n: int) -> bool | np.ndarray:
    """A trigger's arming: the configuration's and the campaign's, for all trials or per trial."""
    if np.ndim(wanted) == 0:
        return bool(configured and wanted)
    flags = np.asarray(wanted, dtype=bool)
    if flags.shape != (n,):
        raise ValueError(f"per-trial trigger flags must number {n} (one per trial), "
                         f"got {flags.size}")
    return flags & bool(configured)


def _bodies(obs: Observation, thrust_n: float, mass_kg: float) -> BodyState:
    n = obs.p.shape[0]
    return BodyState(obs.p, obs.v, obs.R, np.full(n, thrust_n), np.full(n, mass_kg))


def run_campaign(
    cfg: Config,
    spec: MissionSpec,
    predictor: AccelPredictor | None = None,
    record: str = "summary",
    progress: Callable[[float], None] | None = None,
    trials: np.ndarray | None = None,
) -> CampaignResult:
    """Fly ``spec.trials`` docking missions at once.

    Args:
        cfg: configuration.
        spec: the campaign.
        predictor: the feed-forward model for ``Compensation.MODEL``.
        record: ``"summary"`` (outcomes only), ``"trace"`` (+ positions for figures) or
            ``"full"`` (+ one FlightLog per trial).
        progress: called with the fraction of the mission time done.
        trials: explicit trial ids (``spec.trials`` of them; default ``first_trial + i``): a
            trial flies the same with the same id in any batch, and its outcome is its own, so
            one batch can fly, e.g., the same trials armed and disarmed
            (:meth:`CampaignResult.take` splits it).
    """
    batch = MissionBatch(cfg, spec, predictor, record, trials)
    while not batch.finished:
        batch.fly()
        if progress is not None and batch.k % 20 == 1:
            progress(min(1.0, batch.k / batch.steps))
    if progress is not None:
        progress(1.0)
    return batch.result()


class MissionBatch:
    """N docking trials flown one control period per :meth:`fly`: the mission's one
    implementation (``run_campaign`` loops over it; the Gymnasium environments act through it).

    Each period: :meth:`_decide` (motion capture and injected faults, the leader's controller,
    the phases, the follower's reference, aborts, the feed-forward), then :meth:`fly` (the
    follower's controller with an optional residual acceleration, the triggers, the metrics, one
    control period of physics) and the next period's decision.

    Args:
        cfg: configuration.
        spec: the campaign (``trials`` trials from ``first_trial``, or the explicit ``trials``).
        predictor: the feed-forward model for ``Compensation.MODEL``.
        record: ``"summary"``, ``"trace"`` or ``"full"`` (see :func:`run_campaign`).
        trials: explicit per-row trial indices (each row draws from stream ``(seed, index)``).
    """

    def __init__(self, cfg: Config, spec: MissionSpec, predictor: AccelPredictor | None = None,
                 record: str = "summary", trials: np.ndarray | None = None):
        if spec.trials < 1:
            raise ValueError(f"--trials must be >= 1, got {spec.trials}")
        if record not in ("summary", "trace", "full"):
            raise ValueError(f"record must be summary, trace or full, got {record!r}")
        if spec.offset_m is not None:
            if not spec.offset_m > 0:
                raise ValueError(f"--offset must be > 0 m, got {spec.offset_m}")
            cfg = cfg.with_overrides({"platform": {"cable_length_m": float(spec.offset_m)}})
        comp = Compensation(spec.compensation)
        if comp == Compensation.MODEL and predictor is None:
            raise ValueError("compensation 'model' needs a trained model (--model DIR)")
        n = spec.trials
        self.trials = (spec.first_trial + np.arange(n) if trials is None
                       else np.asarray(trials, dtype=np.int64).copy())
        if self.trials.shape != (n,):
            raise ValueError(f"{n} trials asked for, {self.trials.size} trial ids given")
        rng = TrialRNG(spec.seed, n, trials=self.trials)
        self.cfg, self.spec, self.n, self.comp, self.record = cfg, spec, n, comp, record
        m = cfg.mission
        world = World(cfg, n, rng, field=build_field(cfg), leader_fixed=spec.leader_fixed)
        if comp == Compensation.ORACLE:
            predictor = OraclePredictor(world.field, dt_s=world.dt_s)
        elif comp != Compensation.MODEL:
            predictor = None  # a model given alongside 'none' or 'observer' is not flown
        self.predictor = predictor
        # Torque feed-forward from the learnt model (rigid bodies, with the model flown).
        self.torque_ff = bool(cfg.control.torque_feedforward and comp == Compensation.MODEL
                              and world.rigid)
        self.geom = geom = DockGeometry.from_config(cfg)
        world.gripper_params = replace(
            world.gripper_params,
            passive=_armed(world.gripper_params.passive, spec.passive_trigger, n),
            active=_armed(world.gripper_params.active, spec.active_trigger, n))
        self.world = world
        moving = spec.leader_speed_mps != 0.0 and not spec.leader_fixed
        self.arrival_s = cfg.planner.horizon_moving_s if moving else cfg.planner.horizon_hover_s
        hold_s = cfg.planner.hold_s if moving else 0.0
        self.active_at_s = self.arrival_s + (0.5 if moving else m.active_trigger_delay_s)
        self.timeout_s = self.arrival_s + hold_s + m.dock_window_s
        self.dt_s = world.dt_control_s
        self.steps = int(np.ceil((self.timeout_s + m.backoff_s) / self.dt_s))

        # Initial conditions: leader hovering (or cruising north), follower below and away.
        self.leader_p0 = leader_p0 = np.tile([0.0, 0.0, -m.leader_altitude_m], (n, 1))
        dock0 = docking_point_m(leader_p0, np.zeros((n, 3)), geom)
        az = np.deg2rad(np.asarray(spec.start_azimuths_deg))[
            self.trials % len(spec.start_azimuths_deg)]
        start = dock0 + np.stack([m.start_radius_m * np.cos(az), m.start_radius_m * np.sin(az),
                                  np.full(n, m.start_below_m)], 1)
        start += m.start_jitter_m * rng.standard_normal((n, 3))
        self.lead_vel = lead_vel = (np.array([spec.leader_speed_mps, 0.0, 0.0]) if moving
                                    else np.zeros(3))
        self.lead_v = lead_v = np.tile(lead_vel, (n, 1))
        zeros = np.zeros((n, 3))
        # Settled start: both fly for settle_s before t = 0 (observers converge); a moving
        # leader then speeds up smoothly and cruises, the follower in formation below.
        pre = CruiseStart(m.settle_s, m.leader_ramp_s if moving else 0.0)
        shift0 = pre.profile(-pre.preroll_s)[0]
        world.reset(leader_p0 + lead_vel * shift0, start + lead_vel * shift0)
        if moving and pre.start_velocity(lead_vel).any():
            world.set_velocities(lead_v, lead_v)
        self.leader_ctl = PositionController(cfg, n, use_observer=not spec.leader_fixed)
        self.follower_ctl = PositionController(cfg, n, use_observer=comp != Compensation.NONE,
                                               has_accelerometer=True)
        settle(world, self.leader_ctl, self.follower_ctl,
               pre.reference(leader_p0, lead_v), pre.reference(start, lead_v),
               pre.preroll_s, self._predict)
        # Align, then rise (planner.rise_m > 0): the approach ends rise_m below the docking
        # point rise_s early, and the final rise is vertical. rise_m = 0: the paper's single
        # minimum-jerk approach to the docking point.
        pl = cfg.planner
        self.rise_m = float(pl.rise_m)
        self.plan_end_s = self.arrival_s - (pl.rise_s if self.rise_m > 0 else 0.0)
        self._below = np.array([0.0, 0.0, self.rise_m])
        self.plan = minjerk(start, lead_v, zeros,
                            docking_point_m(leader_p0, lead_v, geom, self.plan_end_s)
                            + self._below, lead_v, zeros, self.plan_end_s, 0.0)
        # The docking status reaches the leader over the network, status_delay_s late.
        delay_ticks = int(round(m.status_delay_s / self.dt_s))
        self._status_sent = [np.zeros(n, dtype=bool)] * (delay_ticks + 1)
        faults = tuple(spec.faults)
        if spec.leader_dropout_s is not None:
            t0, duration = spec.leader_dropout_s
            faults += (Fault("leader dropout", "leader_state_lost", 1.0, (t0, t0), duration),)
        self.faults = FaultRuntime(draw_faults(faults, n, rng), n, self.dt_s)
        # Per-trial mission state and metrics.
        self.phase = np.full(n, Phase.APPROACH, dtype=np.int8)
        self.abort_reason = np.zeros(n, dtype=np.int8)
        self.phase_t = np.zeros(n)  # when the current phase began
        self.capture_t = np.full(n, np.nan)
        # Outcomes are each trial's own: collisions count until its mission ends (DONE), however
        # long the batch goes on flying its other trials.
        self.min_clear = np.full(n, np.inf)
        self.strikes = np.zeros(n, dtype=bool)
        self.ground_hit = np.zeros(n, dtype=bool)
        self.post_dock_sink = np.full(n, np.nan)
        self.nan_seen = np.zeros(n, dtype=bool)
        # Terminal window: the 0.5 s before the approach ends (arrival, or the gate closing).
        self.approach_end = np.full(n, self.arrival_s)
        # |e_down|, |e_3d|, predicted down force, tilt (deg), control saturated
        self.hist = np.full((self.steps, n, 5), np.nan)
        keys = ("t_s", "follower_p", "leader_p", "bar_p", "ref_p", "phase", "ff", "gate")
        self.trace: dict[str, list] = {k: [] for k in keys} if record != "summary" else {}
        self.recorder = (FlightRecorder(cfg.curriculum.label_basis, cfg.vehicle.mass_kg)
                         if record == "full" else None)
        self.k = 0
        self.finished = False
        world.observed_accel()  # start the accelerometer's averaging window
        self._decide()

    @staticmethod
    def timing(cfg: Config, spec: MissionSpec) -> tuple[float, float, int]:
        """(planned arrival s, control period s, control periods in the whole mission)."""
        m = cfg.mission
        moving = spec.leader_speed_mps != 0.0 and not spec.leader_fixed
        arrival_s = cfg.planner.horizon_moving_s if moving else cfg.planner.horizon_hover_s
        hold_s = cfg.planner.hold_s if moving else 0.0
        dt_s = 1.0 / cfg.sim.control_rate_hz
        timeout_s = arrival_s + hold_s + m.dock_window_s
        return arrival_s, dt_s, int(np.ceil((timeout_s + m.backoff_s) / dt_s))

    # -- helpers -------------------------------------------------------------------------------
    @property
    def t_s(self) -> float:
        """Mission time of the current control period, s."""
        return self.k * self.dt_s

    @property
    def active(self) -> np.ndarray:
        """(n,) bool: trials still approaching."""
        return (self.phase == Phase.APPROACH) | (self.phase == Phase.TERMINAL)

    def _leader_ref(self, t: float) -> Reference:
        zero_n = np.zeros(self.n)
        return Reference(self.leader_p0 + self.lead_vel * t, self.lead_v, np.zeros((self.n, 3)),
                         zero_n, zero_n)

    def _predict(self, obs_l: Observation, obs_f: Observation) -> np.ndarray | None:
        if self.predictor is None:
            return None
        if self.comp == Compensation.ORACLE:
            return self.predictor.predict_bodies(*self.world.body_states())
        mass, g = self.cfg.vehicle.mass_kg, self.cfg.sim.gravity_mps2
        return self.predictor.predict_bodies(_bodies(obs_l, mass * g, mass),
                                             _bodies(obs_f, mass * g, mass))

    # -- the decision half of a control period -------------------------------------------------
    def _decide(self) -> None:
        """Observe, fly the leader, update the phases, the follower's reference and aborts."""
        world, n, m, geom, cfg = self.world, self.n, self.cfg.mission, self.geom, self.cfg
        gp = world.gripper_params
        t, zeros, g = self.t_s, np.zeros((n, 3)), cfg.sim.gravity_mps2
        arrival_s = self.arrival_s
        # What each controller sees (motion capture, and the leader's state over the network
        # at the follower), after any injected fault; gripper and rotor faults go to the world.
        obs_l, obs_f, obs_l_f = self.faults.observations(t, *world.observe())
        if self.faults.draws:
            self.faults.apply_to_world(t, world)
        # --- leader: its own controller, hovering or cruising north ---
        # Docking status is shared: the leader feeds forward the payload the follower sheds,
        # once the follower's message arrives.
        self._status_sent = self._status_sent[1:] + [world.captured.copy()]
        payload = np.where(self._status_sent[0], (1.0 - m.post_dock_thrust_fraction) * g, 0.0)
        lff = np.stack([np.zeros(n), np.zeros(n), payload], axis=1)
        self.lout = self.leader_ctl.step(obs_l.p, obs_l.v, obs_l.rpy, self._leader_ref(t),
                                         feedforward_mps2=lff)

        # --- follower: plan, phases ---
        phase, plan = self.phase, self.plan
        # Approaching when this period began (the triggers and the terminal window use it).
        self.was_active = active = self.active
        target_now = docking_point_m(obs_l_f.p, obs_l_f.v, geom)
        plan_end = self.plan_end_s
        if t < plan_end - 0.3:
            target_arr = docking_point_m(obs_l_f.p, obs_l_f.v, geom, plan_end - t) + self._below
            moved = np.linalg.norm(target_arr - plan.pf, axis=1) > cfg.planner.replan_threshold_m
            need = active & moved
            if np.any(need):
                p_r, v_r, a_r = plan.sample(t)
                new = minjerk(p_r, v_r, a_r, target_arr, obs_l_f.v, zeros, plan_end - t, t)
                plan = _merge_plans(plan, new, need)
        p_ref, v_ref, a_ref = plan.sample(t)
        if self.rise_m > 0 and t > plan_end:
            # The vertical rise (minimum jerk, rest to rest relative to the leader).
            rise_s = arrival_s - plan_end
            s_, ds, dds = _minjerk_unit(min(1.0, (t - plan_end) / rise_s))
            rising = active[:, None] & np.array([False, False, True])
            p_ref = np.where(rising, p_ref - self.rise_m * s_, p_ref)
            v_ref = np.where(rising, v_ref - self.rise_m * ds / rise_s, v_ref)
            a_ref = np.where(rising, a_ref - self.rise_m * dds / rise_s**2, a_ref)
        holding = active & (t >= arrival_s)
        p_ref = np.where(holding[:, None], target_now, p_ref)
        v_ref = np.where(holding[:, None], obs_l_f.v, v_ref)
        a_ref = np.where(holding[:, None], 0.0, a_ref)
        # Safety: the reference keeps the follower's top clearance_m + margin below the leader.
        top_limit = obs_l_f.p[:, 2] + m.clearance_m + 0.05 + gp.mount_height_m
        p_ref = p_ref.copy()
        p_ref[:, 2] = np.where(active, np.maximum(p_ref[:, 2], top_limit), p_ref[:, 2])
        phase = np.where((phase == Phase.APPROACH) & (t >= arrival_s - m.terminal_s),
                         Phase.TERMINAL, phase).astype(np.int8)

        abort_now = self._aborts(t, phase, active, obs_f.p - p_ref)
        gate = world.gripper.gate
        captured_now = (gate == GateState.CAPTURED) & (phase != Phase.CAPTURED) & (
            phase != Phase.DONE)
        missed_now = (gate == GateState.MISSED) & active
        self.capture_t = np.where(captured_now, t, self.capture_t)
        backoff_now = (abort_now | missed_now) & ~captured_now
        if np.any(backoff_now):
            away = obs_f.p[:, :2] - obs_l_f.p[:, :2]
            norm = np.linalg.norm(away, axis=1, keepdims=True)
            away = np.where(norm > 1e-3, away / np.maximum(norm, 1e-9), [1.0, 0.0])
            goal = obs_f.p + m.backoff_distance_m * np.concatenate(
                [away, np.ones((n, 1))], axis=1)
            back = minjerk(obs_f.p, obs_f.v, zeros, goal, zeros, zeros, m.backoff_s, t)
            plan = _merge_plans(plan, back, backoff_now)
        phase = np.where(captured_now, Phase.CAPTURED, phase)
        phase = np.where(missed_now & ~captured_now, Phase.MISSED, phase)
        phase = np.where(abort_now & ~captured_now & ~missed_now, Phase.ABORT, phase)
        self.phase_t = np.where(captured_now | backoff_now, t, self.phase_t)
        finished = (
            ((phase == Phase.CAPTURED) & (t - self.phase_t >= m.post_dock_s))
            | (((phase == Phase.MISSED) | (phase == Phase.ABORT))
               & (t - self.phase_t >= m.backoff_s))
        )
        phase = np.where(finished, Phase.DONE, phase).astype(np.int8)
        # How far the pair has sunk when the post-dock window ends (the leader carries the
        # follower; it flies level, so its altitude is its start's).
        docked_end = finished & world.captured
        if np.any(docked_end):
            self.post_dock_sink = np.where(
                docked_end, world.leader.p[:, 2] - self.leader_p0[:, 2], self.post_dock_sink)
        backing = (phase == Phase.MISSED) | (phase == Phase.ABORT)
        if np.any(backing):
            pb, vb, ab = plan.sample(t)
            p_ref = np.where(backing[:, None], pb, p_ref)
            v_ref = np.where(backing[:, None], vb, v_ref)
            a_ref = np.where(backing[:, None], ab, a_ref)
        done_free = (phase == Phase.DONE) & ~world.captured
        p_ref = np.where(done_free[:, None], plan.pf, p_ref)
        v_ref = np.where(done_free[:, None], 0.0, v_ref)
        a_ref = np.where(done_free[:, None], 0.0, a_ref)

        self.phase, self.plan, self.holding = phase, plan, holding
        self.ref = (p_ref, v_ref, a_ref)
        self.ff = self._predict(obs_l_f, obs_f)
        self.obs_l, self.obs_f, self.obs_l_f = obs_l, obs_f, obs_l_f
        # Outcomes decided at this control period.
        self.just_docked = captured_now
        self.just_missed = missed_now & ~captured_now
        self.just_aborted = abort_now & ~captured_now & ~missed_now

    def _aborts(self, t: float, phase: np.ndarray, active: np.ndarray,
                err: np.ndarray) -> np.ndarray:
        """(n,) trials aborting now (their gates are disarmed); records the reasons."""
        world, m = self.world, self.cfg.mission
        up_err = -err[:, 2]
        unsafe = (phase == Phase.TERMINAL) & (
            (up_err > m.abort_tracking_m / 2)
            | ((np.linalg.norm(err, axis=1) > m.abort_tracking_m) & (up_err > 0))
        )
        leader_lost = (t - self.faults.last_fresh_leader_t) > m.leader_lost_s
        timeout = t >= self.timeout_s
        gate = world.gripper.gate
        # The software knows when it commanded the gate: one that has not closed long after
        # (a jammed servo) is a fault.
        gate_stuck = (gate == GateState.CLOSING) & (
            world.t_s - world.gripper.servo_start_s > 4.0 * world.gripper_params.close_time_s)
        abort_now = active & (((gate == GateState.OPEN) & (unsafe | leader_lost | timeout))
                              | gate_stuck)
        if abort_now.any():
            world.disarm_gate(abort_now)  # an aborted approach never closes the gate
        self.abort_reason = np.where(
            abort_now & (self.abort_reason == 0),
            np.where(gate_stuck, AbortReason.GATE_FAULT,
                     np.where(leader_lost, AbortReason.LEADER_LOST,
                              np.where(timeout, AbortReason.TIMEOUT,
                                       AbortReason.UNSAFE_TRACKING))),
            self.abort_reason,
        ).astype(np.int8)
        return abort_now

    # -- the acting half -------------------------------------------------------------------------
    def fly(self, residual_mps2: np.ndarray | None = None) -> None:
        """Fly one control period, then decide the next.

        Args:
            residual_mps2: (n, 3) acceleration added to the follower's reference feed-forward
                while it approaches (a learning agent's action); None for the mission alone.
        """
        if self.finished:
            raise RuntimeError("the mission is over: every trial is done")
        world, n, cfg, m = self.world, self.n, self.cfg, self.cfg.mission
        gp, t, k = world.gripper_params, self.t_s, self.k
        active, phase = self.was_active, self.phase
        p_ref, v_ref, a_ref = self.ref
        if residual_mps2 is not None:  # only on trials still approaching after this decision
            a_ref = a_ref + np.where(self.active[:, None], residual_mps2, 0.0)
        obs_f, obs_l_f, ff = self.obs_f, self.obs_l_f, self.ff
        terminal = (phase == Phase.TERMINAL) | self.holding
        yaw0 = np.zeros(n)
        accel = hold = None
        if self.follower_ctl.uses_accelerometer:
            accel = world.observed_accel()
            # The follower's own gripper: a load on the strain gauge or a gate on its way.
            grip = world.gripper
            hold = (grip.reading_n > gp.contact_threshold_n) | (grip.gate != GateState.OPEN)
        fout = self.follower_ctl.step(obs_f.p, obs_f.v, obs_f.rpy,
                                      Reference(p_ref, v_ref, a_ref, yaw0, yaw0), terminal, ff,
                                      accel, hold)
        hanging = world.captured
        if np.any(hanging):
            # Docked: level attitude; thrust is the configured fraction of the weight plus the
            # follower's own prediction of the wake (the position loop would fight the cables).
            cmd = fout.command
            mass, g = cfg.vehicle.mass_kg, cfg.sim.gravity_mps2
            hang_thrust = mass * (m.post_dock_thrust_fraction * g
                                  + np.maximum(fout.feedforward_mps2[:, 2], 0.0))
            fout = replace(fout, command=replace(
                cmd, roll_rad=np.where(hanging, 0.0, cmd.roll_rad),
                pitch_rad=np.where(hanging, 0.0, cmd.pitch_rad),
                yaw_rate_radps=np.where(hanging, 0.0, cmd.yaw_rate_radps),
                thrust_n=np.where(hanging, hang_thrust, cmd.thrust_n)))
        if self.torque_ff:
            # The wake's torque predicted by the model (learnt, or at the rotor hubs from the
            # force), cancelled by the autopilot (not while hanging from the bar).
            mass, g = cfg.vehicle.mass_kg, cfg.sim.gravity_mps2
            tau = feedforward_torque_nm(self.predictor, _bodies(obs_l_f, mass * g, mass),
                                        _bodies(obs_f, mass * g, mass),
                                        world.fleet.params.rotor_offsets_m)
            tau = np.where(hanging[:, None], 0.0, tau)
            fout = replace(fout, command=replace(fout.command, torque_ff_nm=-tau))
        close = (t >= self.active_at_s) & active & _bar_will_be_inside(
            obs_f, obs_l_f, self.geom, gp, gp.latency_s + gp.close_time_s)
        self._measure(k, t, active, p_ref, ff, fout)
        if self.recorder is not None:
            self.recorder.before_step(t, world, self.obs_l, obs_f, fout, p_ref, phase)
        world.advance(self.lout.command, fout.command, close)
        if self.recorder is not None:
            self.recorder.after_step(world)
        self.last_fout = fout
        self.k += 1
        if np.all(phase == Phase.DONE) or self.k >= self.steps:
            self.finished = True
        else:
            self._decide()

    def _measure(self, k: int, t: float, active: np.ndarray, p_ref: np.ndarray,
                 ff: np.ndarray | None, fout: Any) -> None:
        """Metrics of this period from the true state (never seen by a controller)."""
        world, gp, hist = self.world, self.world.gripper_params, self.hist
        true_err = world.follower.p - p_ref
        hist[k, :, 0] = np.abs(true_err[:, 2])
        hist[k, :, 1] = self.track_err_m = np.linalg.norm(true_err, axis=1)
        hist[k, :, 2] = 0.0 if ff is None else ff[:, 2]
        hist[k, :, 3] = np.rad2deg(np.arccos(np.clip(world.follower.R[:, 2, 2], -1.0, 1.0)))
        hist[k, :, 4] = fout.saturated
        ended = (~active | (world.gripper.gate != GateState.OPEN)) & (self.approach_end > t)
        self.approach_end = np.where(ended, t, self.approach_end)
        live = self.phase != Phase.DONE  # this trial's mission is still on
        self.ground_hit |= world.ground_contact & live
        arm = world.follower.p - world.follower.R[:, :, 2] * gp.mount_height_m
        clear_m = self.cfg.mission.clearance_m
        was_clear = self.min_clear >= clear_m
        self.min_clear = np.where(live, np.minimum(
            self.min_clear, np.linalg.norm(arm - world.leader.p, axis=1)), self.min_clear)
        self.clearance_violated_now = was_clear & (self.min_clear < clear_m)
        self.nan_seen |= ~(np.isfinite(world.follower.p).all(axis=1)
                           & np.isfinite(world.leader.p).all(axis=1)
                           & np.isfinite(fout.command.thrust_n))
        if world.rigid:
            seg_a, seg_b = platform_segments(
                anchor_point(world.leader.p, world.leader.R, world.platform),
                self.obs_l.yaw_rad, world.bar, world.platform)
            self.strikes |= live & rotor_strike(world.follower.p, world.follower.R,
                                                world.fleet.params.rotor_offsets_m,
                                                self.cfg.vehicle.rotor_radius_m, seg_a, seg_b,
                                                gp.bar_radius_m)
        if self.record != "summary":
            tr = self.trace
            tr["t_s"].append(t)
            tr["follower_p"].append(world.follower.p.copy())
            tr["leader_p"].append(world.leader.p.copy())
            tr["bar_p"].append(world.bar.p.copy())
            tr["ref_p"].append(p_ref.copy())
            tr["phase"].append(self.phase.copy())
            tr["ff"].append(fout.feedforward_mps2.copy())
            tr["gate"].append(world.gripper.gate.copy())

    # -- outcome -----------------------------------------------------------------------------------
    def result(self) -> CampaignResult:
        """Per-trial outcomes and terminal-window metrics of the flights so far."""
        world, n, spec, cfg, m = self.world, self.n, self.spec, self.cfg, self.cfg.mission
        gate = world.gripper.gate
        # Contacts of the period flown last (the world records them as it steps).
        ground = self.ground_hit | (world.ground_contact & (self.phase != Phase.DONE))
        collision = self.strikes | ground
        dt_c = self.dt_s
        t_grid = np.arange(self.steps)[:, None] * dt_c
        in_win = (t_grid >= self.approach_end - 0.5) & (t_grid < self.approach_end)
        win = np.where(in_win[..., None], self.hist, 0.0)
        cnt = np.maximum(in_win.sum(0), 1)
        draws = self.faults.draws
        result = CampaignResult(
            spec=spec,
            success=(gate == GateState.CAPTURED) & ~collision,
            slipped=world.gripper.slipped.copy(),
            missed=(gate == GateState.MISSED),
            aborted=self.abort_reason != AbortReason.NONE,
            abort_reason=self.abort_reason,
            clearance_violation=self.min_clear < m.clearance_m,
            rotor_strike=self.strikes.copy(),
            nan_state=self.nan_seen.copy(),
            fault_hit=(np.any([d.hit for d in draws], axis=0) if draws
                       else np.ones(n, dtype=bool)),
            ground_contact=ground,
            post_dock_sink_m=self.post_dock_sink.copy(),
            min_clearance_m=self.min_clear,
            capture_time_s=self.capture_t,
            err_down_m=win[..., 0].sum(0) / cnt,
            err_3d_m=win[..., 1].sum(0) / cnt,
            err_down_int_ms=win[..., 0].sum(0) * dt_c,
            err_3d_int_ms=win[..., 1].sum(0) * dt_c,
            ff_down_int_mps=win[..., 2].sum(0) * dt_c,
            tilt_rms_deg=np.sqrt((win[..., 3] ** 2).sum(0) / cnt),
            saturated_frac=win[..., 4].sum(0) / cnt,
            arrival_s=self.arrival_s,
        )
        if self.record != "summary":
            result.trace = {k: np.asarray(v) for k, v in self.trace.items()}
        if self.recorder is not None:
            mass = cfg.vehicle.mass_kg
            result.logs = self.recorder.flightlogs(lambda i: {
                "name": f"dock-seed{spec.seed}-trial{int(self.trials[i]):04d}",
                "source": "aerodock-sim", "frame": "NED",
                "label_basis": self.recorder.label_basis,
                "leader_mass_kg": mass, "follower_mass_kg": mass,
                **vehicle_meta(cfg),
                "compensation": Compensation(spec.compensation).value,
                "offset_m": cfg.platform.cable_length_m,
                "leader_speed_mps": spec.leader_speed_mps,
                "seed": spec.seed, "trial": int(self.trials[i]),
            })
        return result


def _minjerk_unit(x: float) -> tuple[float, float, float]:
    """Rest-to-rest minimum-jerk profile on [0, 1]: (s, ds/dx, d2s/dx2) at ``x``."""
    return (10 * x**3 - 15 * x**4 + 6 * x**5, 30 * x**2 - 60 * x**3 + 30 * x**4,
            60 * x - 180 * x**2 + 120 * x**3)


def _bar_will_be_inside(follower: Observation, leader: Observation, geom: DockGeometry,
                        gp, lead_time_s: float) -> np.ndarray:
    """Active-trigger condition: will the (predicted) bar sit well inside the gate when it closes?

    The follower cannot see the bar; it predicts it from the leader's state (hanging straight
    down) and extrapolates both vehicles by ``lead_time_s`` (software latency + servo travel), so
    the trigger compensates the known latencies. Margins keep it away from the gate's edges.
    """
    rel_v = leader.v - follower.v
    bar = leader.p + np.array([0.0, 0.0, geom.anchor_below_leader_m + geom.cable_length_m])
    arm = follower.p - follower.R[:, :, 2] * gp.mount_height_m
    rel = bar - arm + rel_v * lead_time_s
    height = -rel[:, 2]
    lateral = np.linalg.norm(rel[:, :2], axis=1)
    return (lateral < 0.6 * gp.aperture_m / 2) & (height > -gp.bar_radius_m) & (
        height < 0.7 * gp.gate_height_m)
