"""The docking mission one control period at a time, for N trials at once (the environments' core).

:class:`DockingBatch` flies exactly the mission of :func:`aerodock.mission.run_campaign` (same
world, controllers, planner, triggers, aborts and random draws), split at the one point where a
learning agent acts: ``observe`` after the mission has decided the phase and the follower's
reference for this period, ``act(residual)`` to fly the period with a residual acceleration added
to the reference feed-forward of the LQR follower controller. With a zero residual a trial's
outcome is the one ``run_campaign`` gives for the same seed and trial index (tested).

All arrays are batch-first ``(n, ...)``; one call advances every trial (one NumPy call per
operation, never a loop over trials). Trials whose outcome is decided keep flying the mission's
own back-off or post-dock phases (the residual is ignored for them), so every trial's numbers stay
independent of the others.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from aerodock.config import Config
from aerodock.control.compensation import AccelPredictor, Compensation, OraclePredictor
from aerodock.control.controller import PositionController, Reference
from aerodock.downwash import build_field
from aerodock.gripper import GateState

# The mission's own step helpers: the environment flies the same logic, not a copy of it.
from aerodock.mission import (
    AbortReason,
    MissionSpec,
    Phase,
    _bar_will_be_inside,
    _bodies,
    _merge_plans,
)
from aerodock.planning.docking import DockGeometry, docking_point_m
from aerodock.planning.minjerk import minjerk
from aerodock.rng import TrialRNG
from aerodock.sim import Observation, World

OBS_DIM = 24
"""Length of one trial's observation vector (see :data:`OBS_LAYOUT`)."""

OBS_LAYOUT: tuple[tuple[str, int, str], ...] = (
    ("follower position - reference position", 3, "m"),
    ("follower velocity - reference velocity", 3, "m/s"),
    ("follower position - docking point now", 3, "m"),
    ("follower velocity - leader velocity", 3, "m/s"),
    ("reference acceleration (planner feed-forward)", 3, "m/s^2"),
    ("bias observer estimate b_hat", 3, "m/s^2"),
    ("feed-forward f_ext_hat (model or oracle)", 3, "m/s^2"),
    ("time - planned arrival", 1, "s"),
    ("terminal phase (stiff gains, triggers armed)", 1, "0/1"),
    ("gate closing", 1, "0/1"),
)
"""(what, size, unit) of each block of the observation, in order; all NED, measured by motion
capture with its noise and latency (the state the follower's own controller sees)."""

# Observation bounds per block (the space is a Box; values are clipped into it).
_OBS_BOUND = np.concatenate([np.full(size, bound) for (_, size, _), bound in zip(
    OBS_LAYOUT, (20.0, 20.0, 20.0, 20.0, 50.0, 50.0, 50.0, 30.0, 1.0, 1.0), strict=True)])
OBS_LOW = np.where(np.arange(OBS_DIM) >= OBS_DIM - 2, 0.0, -_OBS_BOUND).astype(np.float32)
OBS_HIGH = _OBS_BOUND.astype(np.float32)


@dataclass(frozen=True)
class RewardWeights:
    """The reward: outcomes of the mission plus a dense tracking term.

    Per step: ``- tracking_per_ms * |p - p_ref| * dt - action_per_s * |a|^2 * dt`` (true follower
    position, normalised action ``a``), plus on the step the outcome is decided ``+ dock`` (bar
    captured), ``- miss`` (gate closed empty or the bar slipped through), ``- abort`` (timeout,
    leader lost, unsafe tracking), and ``- clearance`` once, on the step the follower's top first
    comes closer than ``mission.clearance_m`` to the leader.
    """

    dock: float = 10.0
    miss: float = 5.0
    abort: float = 5.0
    clearance: float = 10.0
    tracking_per_ms: float = 1.0
    action_per_s: float = 0.1


@dataclass(frozen=True)
class StepOutcome:
    """What one control period did, per trial (all ``(n,)``)."""

    reward: np.ndarray
    docked: np.ndarray  # decided this period: bar captured
    missed: np.ndarray  # decided this period: gate closed without the bar
    aborted: np.ndarray  # decided this period: abort (see abort_reason)
    clearance_violated: np.ndarray  # first clearance violation this period


class DockingBatch:
    """N docking trials flown one control period per :meth:`act`.

    Args:
        cfg: configuration.
        spec: the mission set-up (``trials`` and ``first_trial`` are ignored: :meth:`reset` says
            which trials to fly; ``seed`` is the campaign seed of the per-trial streams).
        n: number of trials in the batch.
        predictor: feed-forward model for ``Compensation.MODEL``.
        residual_max_mps2: the residual acceleration at a normalised action of 1, m/s².
        weights: reward weights.
    """

    def __init__(self, cfg: Config, spec: MissionSpec, n: int,
                 predictor: AccelPredictor | None = None, residual_max_mps2: float = 2.0,
                 weights: RewardWeights | None = None):
        if n < 1:
            raise ValueError(f"number of environments must be >= 1, got {n}")
        if not residual_max_mps2 > 0:
            raise ValueError(f"residual_max_mps2 must be > 0, got {residual_max_mps2}")
        comp = Compensation(spec.compensation)
        if comp == Compensation.MODEL and predictor is None:
            raise ValueError("compensation 'model' needs a predictor (a trained model)")
        if spec.offset_m is not None:
            if not spec.offset_m > 0:
                raise ValueError(f"offset_m must be > 0 m, got {spec.offset_m}")
            cfg = cfg.with_overrides({"platform": {"cable_length_m": float(spec.offset_m)}})
        self.cfg, self.spec, self.n = cfg, spec, n
        self.comp = comp
        self.model_predictor = predictor if comp == Compensation.MODEL else None
        self.residual_max_mps2 = float(residual_max_mps2)
        self.weights = weights or RewardWeights()
        self.geom = DockGeometry.from_config(cfg)
        m = cfg.mission
        self.moving = spec.leader_speed_mps != 0.0 and not spec.leader_fixed
        self.arrival_s = (cfg.planner.horizon_moving_s if self.moving
                          else cfg.planner.horizon_hover_s)
        hold_s = cfg.planner.hold_s if self.moving else 0.0
        self.active_at_s = self.arrival_s + (0.5 if self.moving else m.active_trigger_delay_s)
        self.timeout_s = self.arrival_s + hold_s + m.dock_window_s
        self.end_s = self.timeout_s + m.backoff_s
        self.dt_s = 1.0 / cfg.sim.control_rate_hz
        self.max_steps = int(np.ceil(self.end_s / self.dt_s))

    # -- episode start -------------------------------------------------------------------------
    def reset(self, first_trial: int, trials: np.ndarray | None = None) -> None:
        """Start trials ``first_trial .. first_trial + n - 1`` of campaign ``spec.seed`` (or the
        explicit trial indices ``trials``, one per row, e.g. the same trial for several rows).

        Trial ``k`` draws every random number from stream ``(spec.seed, k)``: the same numbers
        as in ``run_campaign`` and whatever the batch size.
        """
        cfg, spec, n, m = self.cfg, self.spec, self.n, self.cfg.mission
        self.first_trial = int(first_trial)
        self.trials = (self.first_trial + np.arange(n) if trials is None
                       else np.asarray(trials, dtype=np.int64).copy())
        rng = TrialRNG(spec.seed, n, trials=self.trials)
        world = World(cfg, n, rng, field=build_field(cfg), leader_fixed=spec.leader_fixed)
        self.predictor = (OraclePredictor(world.field) if self.comp == Compensation.ORACLE
                          else self.model_predictor)
        gp0 = world.gripper_params
        world.gripper_params = replace(gp0, passive=gp0.passive and spec.passive_trigger,
                                       active=gp0.active and spec.active_trigger)
        geom = self.geom
        leader_p0 = np.tile([0.0, 0.0, -m.leader_altitude_m], (n, 1))
        dock0 = docking_point_m(leader_p0, np.zeros((n, 3)), geom)
        az = np.deg2rad(np.asarray(spec.start_azimuths_deg))[
            self.trials % len(spec.start_azimuths_deg)]
        start = dock0 + np.stack([m.start_radius_m * np.cos(az), m.start_radius_m * np.sin(az),
                                  np.full(n, m.start_below_m)], 1)
        start += m.start_jitter_m * rng.standard_normal((n, 3))
        world.reset(leader_p0, start)
        lead_vel = np.array([spec.leader_speed_mps, 0.0, 0.0]) if self.moving else np.zeros(3)
        if self.moving:
            world.leader = replace(world.leader, v=np.tile(lead_vel, (n, 1)))
            world.bar = replace(world.bar, v=np.tile(lead_vel, (n, 1)))
        mass = cfg.vehicle.mass_kg
        self.leader_ctl = PositionController(cfg, n, use_observer=not spec.leader_fixed)
        self.follower_ctl = PositionController(cfg, n,
                                               use_observer=self.comp != Compensation.NONE)
        self.leader_ctl.reset(world.leader.p, world.leader.v, world.cable_force_n / mass)
        self.follower_ctl.reset(world.follower.p, world.follower.v)
        zeros = np.zeros((n, 3))
        self.plan = minjerk(start, zeros, zeros,
                            docking_point_m(leader_p0, world.leader.v, geom, self.arrival_s),
                            world.leader.v, zeros, self.arrival_s, 0.0)
        self.world, self.leader_p0, self.lead_vel = world, leader_p0, lead_vel
        self.phase = np.full(n, Phase.APPROACH, dtype=np.int8)
        self.abort_reason = np.zeros(n, dtype=np.int8)
        self.phase_t = np.zeros(n)
        self.capture_t = np.full(n, np.nan)
        self.leader_last_fresh_t = 0.0
        self.last_leader_obs: Observation | None = None
        self.min_clear = np.full(n, np.inf)
        self.k = 0
        self.resolved = np.zeros(n, dtype=bool)
        world.observed_accel()  # start the accelerometer's averaging window
        self._decide()

    # -- the mission's decision half of a control period ------------------------------------------
    @property
    def t_s(self) -> float:
        """Mission time of the current control period, s."""
        return self.k * self.dt_s

    def _decide(self) -> None:
        """Observe, fly the leader's controller, update the phases and the follower's reference
        (``run_campaign``'s loop body up to the follower's controller)."""
        world, n, m, geom, cfg = self.world, self.n, self.cfg.mission, self.geom, self.cfg
        gp = world.gripper_params
        spec, t, zeros = self.spec, self.t_s, np.zeros((n, 3))
        obs_l, obs_f = world.observe()
        lost = spec.leader_dropout_s is not None and (
            spec.leader_dropout_s[0] <= t < spec.leader_dropout_s[0] + spec.leader_dropout_s[1])
        if lost and self.last_leader_obs is not None:
            obs_l_f = self.last_leader_obs
        else:
            obs_l_f = obs_l
            self.leader_last_fresh_t = t
            self.last_leader_obs = obs_l
        g = cfg.sim.gravity_mps2
        lref = Reference(self.leader_p0 + self.lead_vel * t, np.tile(self.lead_vel, (n, 1)),
                         zeros, np.zeros(n), np.zeros(n))
        payload = np.where(world.captured, (1.0 - m.post_dock_thrust_fraction) * g, 0.0)
        lff = np.stack([np.zeros(n), np.zeros(n), payload], axis=1)
        self.lout = self.leader_ctl.step(obs_l.p, obs_l.v, obs_l.rpy, lref, feedforward_mps2=lff)

        phase, plan, arrival_s = self.phase, self.plan, self.arrival_s
        active = (phase == Phase.APPROACH) | (phase == Phase.TERMINAL)
        target_now = docking_point_m(obs_l_f.p, obs_l_f.v, geom)
        if t < arrival_s - 0.3:
            target_arr = docking_point_m(obs_l_f.p, obs_l_f.v, geom, arrival_s - t)
            moved = np.linalg.norm(target_arr - plan.pf, axis=1) > cfg.planner.replan_threshold_m
            need = active & moved
            if np.any(need):
                p_r, v_r, a_r = plan.sample(t)
                new = minjerk(p_r, v_r, a_r, target_arr, obs_l_f.v, zeros, arrival_s - t, t)
                plan = _merge_plans(plan, new, need)
        p_ref, v_ref, a_ref = plan.sample(t)
        holding = active & (t >= arrival_s)
        p_ref = np.where(holding[:, None], target_now, p_ref)
        v_ref = np.where(holding[:, None], obs_l_f.v, v_ref)
        a_ref = np.where(holding[:, None], 0.0, a_ref)
        top_limit = obs_l_f.p[:, 2] + m.clearance_m + 0.05 + gp.mount_height_m
        p_ref = p_ref.copy()
        p_ref[:, 2] = np.where(active, np.maximum(p_ref[:, 2], top_limit), p_ref[:, 2])

        phase = np.where((phase == Phase.APPROACH) & (t >= arrival_s - m.terminal_s),
                         Phase.TERMINAL, phase).astype(np.int8)
        err = obs_f.p - p_ref
        up_err = -err[:, 2]
        unsafe = (phase == Phase.TERMINAL) & (
            (up_err > m.abort_tracking_m / 2)
            | ((np.linalg.norm(err, axis=1) > m.abort_tracking_m) & (up_err > 0)))
        leader_lost = (t - self.leader_last_fresh_t) > m.leader_lost_s
        timeout = t >= self.timeout_s
        gate = world.gripper.gate
        abort_now = active & (gate == GateState.OPEN) & (unsafe | leader_lost | timeout)
        self.abort_reason = np.where(
            abort_now & (self.abort_reason == 0),
            np.where(leader_lost, AbortReason.LEADER_LOST,
                     np.where(timeout, AbortReason.TIMEOUT, AbortReason.UNSAFE_TRACKING)),
            self.abort_reason).astype(np.int8)
        captured_now = (gate == GateState.CAPTURED) & (phase != Phase.CAPTURED) & (
            phase != Phase.DONE)
        missed_now = (gate == GateState.MISSED) & active
        self.capture_t = np.where(captured_now, t, self.capture_t)
        backoff_now = (abort_now | missed_now) & ~captured_now
        if np.any(backoff_now):
            away = obs_f.p[:, :2] - obs_l_f.p[:, :2]
            norm = np.linalg.norm(away, axis=1, keepdims=True)
            away = np.where(norm > 1e-3, away / np.maximum(norm, 1e-9), [1.0, 0.0])
            goal = obs_f.p + m.backoff_distance_m * np.concatenate([away, np.ones((n, 1))], 1)
            back = minjerk(obs_f.p, obs_f.v, zeros, goal, zeros, zeros, m.backoff_s, t)
            plan = _merge_plans(plan, back, backoff_now)
        phase = np.where(captured_now, Phase.CAPTURED, phase)
        phase = np.where(missed_now & ~captured_now, Phase.MISSED, phase)
        phase = np.where(abort_now & ~captured_now & ~missed_now, Phase.ABORT, phase)
        self.phase_t = np.where(captured_now | backoff_now, t, self.phase_t)
        finished = (
            ((phase == Phase.CAPTURED) & (t - self.phase_t >= m.post_dock_s))
            | (((phase == Phase.MISSED) | (phase == Phase.ABORT))
               & (t - self.phase_t >= m.backoff_s)))
        phase = np.where(finished, Phase.DONE, phase).astype(np.int8)
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

        ff = None
        if self.predictor is not None:
            mass = cfg.vehicle.mass_kg
            if self.comp == Compensation.ORACLE:
                lead_b, fol_b = world.body_states()
            else:
                lead_b, fol_b = _bodies(obs_l_f, mass * g, mass), _bodies(obs_f, mass * g, mass)
            ff = self.predictor.predict_bodies(lead_b, fol_b)
        self.phase, self.plan = phase, plan
        self.holding = holding
        self.ref = (p_ref, v_ref, a_ref)
        self.ff = ff
        self.obs_l, self.obs_l_f, self.obs_f = obs_l, obs_l_f, obs_f
        # Outcomes decided at this control period.
        self.just_docked, self.just_missed = captured_now, missed_now & ~captured_now
        self.just_aborted = abort_now & ~captured_now & ~missed_now

    # -- the agent's half ------------------------------------------------------------------------
    @property
    def active(self) -> np.ndarray:
        """(n,) bool: trials still approaching (the residual acts on them)."""
        return (self.phase == Phase.APPROACH) | (self.phase == Phase.TERMINAL)

    def observation(self) -> np.ndarray:
        """(n, OBS_DIM) float32 observation (see :data:`OBS_LAYOUT`), clipped to its bounds."""
        p_ref, v_ref, a_ref = self.ref
        obs_f, obs_l_f = self.obs_f, self.obs_l_f
        n = self.n
        ctl = self.follower_ctl
        bias = ctl.observer.bias_mps2 if ctl.observer is not None else np.zeros((n, 3))
        ff = self.ff if self.ff is not None else np.zeros((n, 3))
        dock_now = docking_point_m(obs_l_f.p, obs_l_f.v, self.geom)
        cols = [obs_f.p - p_ref, obs_f.v - v_ref, obs_f.p - dock_now, obs_f.v - obs_l_f.v,
                a_ref, bias, ff, np.full((n, 1), self.t_s - self.arrival_s),
                (self.phase == Phase.TERMINAL)[:, None].astype(float),
                (self.world.gripper.gate == GateState.CLOSING)[:, None].astype(float)]
        out = np.concatenate(cols, axis=1).astype(np.float32)
        return np.clip(out, OBS_LOW, OBS_HIGH)

    def act(self, action: np.ndarray) -> StepOutcome:
        """Fly one control period with the normalised residual ``action`` (n, 3) in [-1, 1]
        (``action * residual_max_mps2`` m/s², NED, added to the follower's reference
        acceleration while it approaches), then decide the next period."""
        world, n, cfg, m = self.world, self.n, self.cfg, self.cfg.mission
        gp = world.gripper_params
        action = np.clip(np.asarray(action, dtype=float).reshape(n, 3), -1.0, 1.0)
        active = self.active
        residual = np.where(active[:, None], action * self.residual_max_mps2, 0.0)
        p_ref, v_ref, a_ref = self.ref
        terminal = (self.phase == Phase.TERMINAL) | self.holding
        yaw0 = np.zeros(n)
        fref = Reference(p_ref, v_ref, a_ref + residual, yaw0, yaw0)
        obs_f, obs_l_f = self.obs_f, self.obs_l_f
        fout = self.follower_ctl.step(obs_f.p, obs_f.v, obs_f.rpy, fref, terminal, self.ff)
        hanging = world.captured
        if np.any(hanging):
            cmd = fout.command
            mass, g = cfg.vehicle.mass_kg, cfg.sim.gravity_mps2
            hang_thrust = mass * (m.post_dock_thrust_fraction * g
                                  + np.maximum(fout.feedforward_mps2[:, 2], 0.0))
            fout = replace(fout, command=replace(
                cmd, roll_rad=np.where(hanging, 0.0, cmd.roll_rad),
                pitch_rad=np.where(hanging, 0.0, cmd.pitch_rad),
                yaw_rate_radps=np.where(hanging, 0.0, cmd.yaw_rate_radps),
                thrust_n=np.where(hanging, hang_thrust, cmd.thrust_n)))
        close = (self.t_s >= self.active_at_s) & active & _bar_will_be_inside(
            obs_f, obs_l_f, self.geom, gp, gp.latency_s + gp.close_time_s)
        track_err_m = np.linalg.norm(world.follower.p - p_ref, axis=1)
        arm = world.follower.p - world.follower.R[:, :, 2] * gp.mount_height_m
        clear = np.linalg.norm(arm - world.leader.p, axis=1)
        was_clear = self.min_clear >= m.clearance_m
        self.min_clear = np.minimum(self.min_clear, clear)
        violated = was_clear & (self.min_clear < m.clearance_m)
        self.last_fout = fout
        world.advance(self.lout.command, fout.command, close)
        self.k += 1
        self._decide()

        w, dt = self.weights, self.dt_s
        live = ~self.resolved
        reward = np.where(active, -w.tracking_per_ms * track_err_m * dt
                          - w.action_per_s * np.sum(action**2, axis=1) * dt, 0.0)
        reward += w.dock * self.just_docked - w.miss * self.just_missed
        reward -= w.abort * self.just_aborted + w.clearance * violated
        out = StepOutcome(reward=np.where(live, reward, 0.0),
                          docked=self.just_docked & live, missed=self.just_missed & live,
                          aborted=self.just_aborted & live, clearance_violated=violated & live)
        self.resolved |= ~self.active
        return out

    @property
    def out_of_time(self) -> bool:
        """The mission's whole time budget is spent (a safety net: every trial is decided by
        ``timeout_s`` plus the gate's travel)."""
        return self.k >= self.max_steps
