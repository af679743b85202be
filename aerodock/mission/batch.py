"""The docking mission flown by N trials at once, one control period at a time.

Phases (:class:`~aerodock.mission.spec.Phase`): ``APPROACH`` (minimum-jerk to the predicted
docking point at the horizon, re-planned when the prediction moves) -> ``TERMINAL`` (stiffer
gains, triggers armed) -> the gate resolves: ``CAPTURED`` (post-dock: the follower cuts thrust to
a fraction and the leader carries it) or ``MISSED`` -> back off; ``ABORT`` (timeout, leader state
lost for longer than ``leader_lost_s``, or a tracking error that brings the follower's top towards
the leader) -> back off below and away; then ``DONE``. Each decision lives in its own module of
:mod:`aerodock.mission.phases`; :class:`MissionBatch` runs them in order.

:func:`run_campaign` flies one campaign (N trials, one seed) and returns per-trial outcomes,
summary statistics, optional traces for figures and optional FlightLogs.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from aerodock.config import Config
from aerodock.control.compensation import AccelPredictor, Compensation, OraclePredictor
from aerodock.control.controller import ControlOutput, PositionController, Reference
from aerodock.control.torque_feedforward import feedforward_torque_nm
from aerodock.downwash import BodyState, build_field
from aerodock.mission.checks import DOCK_NAMES, check_mission
from aerodock.mission.faults import Fault, FaultRuntime, draw_faults
from aerodock.mission.metrics import MissionMetrics
from aerodock.mission.outcome import CampaignResult
from aerodock.mission.params import MissionParams, fly_on_configured_rotors
from aerodock.mission.phases import (
    aborts,
    approach,
    backoff,
    gate_sensing,
    leader,
    resolve,
    terminal,
    triggers,
)
from aerodock.mission.recorder import FlightRecorder
from aerodock.mission.settle import CruiseStart, SettledStart, settle
from aerodock.mission.setup import (
    MissionTiming,
    armed,
    mission_timing,
    starts,
)
from aerodock.mission.spec import (
    AbortCode,
    AbortReason,
    MissionSpec,
    Phase,
    PhaseCode,
    any_true,
)
from aerodock.rng import TrialRNG
from aerodock.world import Observation, World
from aerodock.world.gripper import GateState, GripperParams


@dataclass(frozen=True)
class Decision:
    """What the mission decided at the start of a control period (every array ``(n, ...)``).

    Attributes:
        t_s: mission time of the period.
        phase: each trial's phase for the period.
        approaching: the trials that were approaching when the period began.
        holding: approaching trials past the planned arrival (held at the docking point).
        ref: the follower's reference (p, v, a), NED.
        feedforward_mps2: the compensation's prediction (None: none flown).
        leader_obs, follower_obs: motion capture of each vehicle, as its own controller sees it.
        leader_at_follower: the leader's state as the follower receives it (over the network).
        docked, missed, aborted: the outcomes decided at this period (a dock once confirmed:
            the follower held through ``mission.dock_confirm_s``; a miss once sensed).
    """

    t_s: float
    phase: np.ndarray
    approaching: np.ndarray
    holding: np.ndarray
    ref: tuple[np.ndarray, np.ndarray, np.ndarray]
    feedforward_mps2: np.ndarray | None
    leader_obs: Observation
    follower_obs: Observation
    leader_at_follower: Observation
    docked: np.ndarray
    missed: np.ndarray
    aborted: np.ndarray


@dataclass(frozen=True)
class Flown:
    """What one control period did, measured from the true state (every array ``(n,)``).

    Attributes:
        track_err_m: the follower's distance from its reference at the period's start.
        clearance_violated: the follower's top first came within ``clearance_m`` of the leader.
        decision: the decision for the next period (None: the mission is over).
    """

    track_err_m: np.ndarray
    clearance_violated: np.ndarray
    decision: Decision | None


@dataclass(frozen=True)
class Status:
    """Each trial's state so far (every array ``(n,)``)."""

    phase: np.ndarray
    abort_reason: np.ndarray
    min_clearance_m: np.ndarray
    clearance_violation: np.ndarray


def run_campaign(
    cfg: Config,
    spec: MissionSpec,
    predictor: AccelPredictor | None = None,
    record: str = "summary",
    progress: Callable[[float], None] | None = None,
    trials: np.ndarray | None = None,
    seeds: np.ndarray | None = None,
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
        seeds: explicit campaign seeds, one per trial (default ``spec.seed`` for all): several
            campaigns that differ only in their seed flown as one batch, each trial as in its
            own campaign (:class:`aerodock.rng.TrialRNG`; the sweep flies its cells so).
    """
    batch = MissionBatch(cfg, spec, predictor, record, trials, seeds=seeds)
    while not batch.finished:
        batch.fly()
        if progress is not None and batch.k % 20 == 1:
            progress(min(1.0, batch.k / batch.steps))
    if progress is not None:
        progress(1.0)
    return batch.result()


def settle_trials(cfg: Config, spec: MissionSpec, predictor: AccelPredictor | None = None,
                  trials: np.ndarray | None = None,
                  seeds: np.ndarray | None = None) -> SettledStart:
    """Fly the settled start of ``spec``'s trials (or the explicit ``trials``): their world and
    controllers at t = 0, as :class:`MissionBatch` starts from them.

    Its rows serve single trials later (:meth:`SettledStart.take_rows`): a trial's start does not
    depend on the batch that settled it. Arguments as for :class:`MissionBatch`.
    """
    cfg, comp, ids = _checked(cfg, spec, predictor, trials)
    return _settle(cfg, spec, MissionParams.from_config(cfg), comp, predictor, ids, seeds)


def _checked(cfg: Config, spec: MissionSpec, predictor: AccelPredictor | None,
             trials: np.ndarray | None) -> tuple[Config, Compensation, np.ndarray]:
    """The one validation of dock, sweep and the environments: (the configuration with the
    cable length applied, the compensation, the trial ids)."""
    cfg = check_mission(cfg, spec, DOCK_NAMES)
    comp = Compensation(spec.compensation)
    if comp == Compensation.MODEL and predictor is None:
        raise ValueError("compensation 'model' needs a trained model (--model DIR)")
    n = spec.trials
    ids = (spec.first_trial + np.arange(n) if trials is None
           else np.asarray(trials, dtype=np.int64).copy())
    if ids.shape != (n,):
        raise ValueError(f"{n} trials asked for, {ids.size} trial ids given")
    return cfg, comp, ids


def _settle(cfg: Config, spec: MissionSpec, params: MissionParams, comp: Compensation,
            predictor: AccelPredictor | None, trials: np.ndarray,
            seeds: np.ndarray | None) -> SettledStart:
    """The settled start of ``trials`` (``cfg`` checked; the random draws in their order: the
    starts' jitter, the world's, then the settled flight's)."""
    n, m = trials.size, params.mission
    rng = TrialRNG(spec.seed, n, trials=trials, seeds=seeds)
    configured = GripperParams.from_config(cfg)
    world = World(cfg, n, rng, field=build_field(cfg), leader_fixed=spec.leader_fixed,
                  triggers=(armed(configured.passive, spec.passive_trigger, n),
                            armed(configured.active, spec.active_trigger, n)))
    if comp == Compensation.ORACLE:
        predictor = OraclePredictor(world.field, dt_s=world.dt_s)
    elif comp != Compensation.MODEL:
        predictor = None  # a model given alongside 'none' or 'observer' is not flown
    fly_on_configured_rotors(predictor, cfg)
    # Initial conditions: leader hovering (or cruising north), follower below and away.
    start = starts(params, spec, trials, rng)
    lead_vel = start.leader_velocity_mps
    lead_v = np.tile(lead_vel, (n, 1))
    # Settled start: both fly for settle_s before t = 0 (observers converge); a moving
    # leader then speeds up smoothly and cruises, the follower in formation below.
    pre = CruiseStart(m.settle_s, m.leader_ramp_s if spec.moving else 0.0)
    shift0 = pre.profile(-pre.preroll_s)[0]
    world.reset(start.leader_p_m + lead_vel * shift0, start.follower_p_m + lead_vel * shift0)
    if spec.moving and pre.start_velocity(lead_vel).any():
        world.set_velocities(lead_v, lead_v)
    leader_ctl = PositionController(cfg, n, use_observer=not spec.leader_fixed,
                                    vehicle=cfg.leader)
    follower_ctl = PositionController(cfg, n, use_observer=comp != Compensation.NONE,
                                      has_accelerometer=True)
    settle(world, leader_ctl, follower_ctl,
           pre.reference(start.leader_p_m, lead_v), pre.reference(start.follower_p_m, lead_v),
           pre.preroll_s,
           lambda obs_l, obs_f: _predict(params, comp, predictor, world, obs_l, obs_f))
    return SettledStart(trials, rng, start, world, leader_ctl, follower_ctl, predictor)


def _bodies(params: MissionParams, obs: Observation, leader: bool = False) -> BodyState:
    """``obs`` as the predictor sees a vehicle: hovering at its nominal mass (the follower's,
    or the leader's)."""
    n = obs.p.shape[0]
    mass = params.leader_mass_kg if leader else params.mass_kg
    return BodyState(obs.p, obs.v, obs.R, np.full(n, mass * params.gravity_mps2),
                     np.full(n, mass))


def _predict(params: MissionParams, comp: Compensation, predictor: AccelPredictor | None,
             world: World, obs_l: Observation, obs_f: Observation) -> np.ndarray | None:
    """The follower's feed-forward from what it observes (the oracle: from the truth)."""
    if predictor is None:
        return None
    if comp == Compensation.ORACLE:
        return predictor.predict_bodies(*world.body_states())
    return predictor.predict_bodies(_bodies(params, obs_l, leader=True), _bodies(params, obs_f))


class MissionBatch:
    """N docking trials flown one control period per :meth:`fly`: the mission's one
    implementation (``run_campaign`` loops over it; the Gymnasium environments act through it).

    Each period: :meth:`decide` (motion capture and injected faults, the leader's controller,
    the phases, the follower's reference, aborts, the feed-forward: a :class:`Decision`), then
    :meth:`fly` (the follower's controller with an optional residual acceleration, the
    triggers, the metrics, one control period of physics) and the next period's decision.

    Args:
        cfg: configuration (bound once here: the mission reads its typed parameters after).
        spec: the campaign (``trials`` trials from ``first_trial``, or the explicit ``trials``).
        predictor: the feed-forward model for ``Compensation.MODEL``.
        record: ``"summary"``, ``"trace"`` or ``"full"`` (see :func:`run_campaign`).
        trials: explicit per-row trial indices (each row draws from stream ``(seed, index)``).
        settled: these trials' settled start, if already flown (:func:`settle_trials` for the
            same configuration and campaign, or rows of a larger one taken with
            :meth:`SettledStart.take_rows`); by default it is flown here.
        seeds: explicit per-row campaign seeds (default ``spec.seed``; see :func:`run_campaign`).
    """

    def __init__(self, cfg: Config, spec: MissionSpec, predictor: AccelPredictor | None = None,
                 record: str = "summary", trials: np.ndarray | None = None,
                 settled: SettledStart | None = None, seeds: np.ndarray | None = None):
        if record not in ("summary", "trace", "full"):
            raise ValueError(f"record must be summary, trace or full, got {record!r}")
        cfg, comp, self.trials = _checked(cfg, spec, predictor, trials)
        n = spec.trials
        self.params = params = MissionParams.from_config(cfg)
        self.spec, self.n, self.comp, self.record = spec, n, comp, record
        m = params.mission
        if settled is None:
            settled = _settle(cfg, spec, params, comp, predictor, self.trials, seeds)
        elif not np.array_equal(settled.trials, self.trials) or settled.rng.seed != spec.seed \
                or not np.array_equal(settled.rng.seeds,
                                      np.broadcast_to(spec.seed if seeds is None else seeds, n)):
            raise ValueError("the settled start is not of these trials of this campaign")
        self.seeds = settled.rng.seeds  # each trial's campaign seed (TrialRNG checked them)
        world, rng, start = settled.world, settled.rng, settled.start
        self.predictor = settled.predictor
        # Torque feed-forward from the learnt model (rigid bodies, with the model flown).
        self.torque_ff = bool(params.torque_feedforward and comp == Compensation.MODEL
                              and world.rigid)
        # What the mission knows of its gate: its sensors (or, as earlier worlds did, the truth).
        self.gate_truth = cfg.mission.gate_state_from == "truth"
        self.servo_feedback = bool(cfg.gripper.servo_feedback) or self.gate_truth
        self.geom = params.geometry
        self.world = world
        self.timing = timing = mission_timing(params, spec, world.dt_control_s)
        self.arrival_s, self.dt_s, self.steps = timing.arrival_s, timing.dt_s, timing.steps
        self.leader_p0 = start.leader_p_m
        self.lead_vel = start.leader_velocity_mps
        self.lead_v = lead_v = np.tile(self.lead_vel, (n, 1))
        self.leader_ctl, self.follower_ctl = settled.leader_ctl, settled.follower_ctl
        self.shape = approach.ApproachShape.of(params, timing.arrival_s)
        self.plan = approach.first_plan(params, self.shape, start.follower_p_m,
                                        start.leader_p_m, lead_v)
        # What a docked follower sheds onto the leader, per unit of the leader's mass.
        self._shed_mps2 = (1.0 - m.post_dock_thrust_fraction) * params.gravity_mps2
        if params.leader_mass_kg != params.mass_kg:
            self._shed_mps2 *= params.mass_kg / params.leader_mass_kg
        # The docking status reaches the leader over the network, status_delay_s late.
        delay_ticks = int(round(m.status_delay_s / self.dt_s))
        self._status_sent = deque([np.zeros(n, dtype=bool)] * (delay_ticks + 1),
                                  maxlen=delay_ticks + 1)
        faults = tuple(spec.faults)
        if spec.leader_dropout_s is not None:
            t0, duration = spec.leader_dropout_s
            faults += (Fault("leader dropout", "leader_state_lost", 1.0, (t0, t0), duration),)
        self.faults = FaultRuntime(draw_faults(faults, n, rng), n, self.dt_s)
        # Per-trial mission state.
        self.phase = np.full(n, Phase.APPROACH, dtype=np.int8)
        self.abort_reason = np.zeros(n, dtype=np.int8)
        self.phase_t = np.zeros(n)  # when the current phase began
        self.capture_t = np.full(n, np.nan)
        self.docked = np.zeros(n, dtype=bool)  # the follower acts as docked (gate believed shut)
        self.sensed_missed = np.zeros(n, dtype=bool)  # it then found itself not held
        self.confirmed = np.zeros(n, dtype=bool)  # held through the confirmation window
        self.post_dock_sink = np.full(n, np.nan)
        self.metrics = MissionMetrics(n, self.steps, self.arrival_s, record != "summary")
        self.recorder = (FlightRecorder(params.label_basis, params.mass_kg)
                         if record == "full" else None)
        self.k = 0
        self.finished = False
        world.observed_accel()  # start the accelerometer's averaging window
        self.decision = self.decide()

    @staticmethod
    def timing_of(cfg: Config, spec: MissionSpec) -> MissionTiming:
        """The timing of ``spec``'s campaign under ``cfg`` (without flying anything)."""
        return mission_timing(MissionParams.from_config(cfg), spec, cfg.timing.control_dt_s)

    # -- views ---------------------------------------------------------------------------------
    @property
    def t_s(self) -> float:
        """Mission time of the current control period, s."""
        return self.k * self.dt_s

    @property
    def active(self) -> np.ndarray:
        """(n,) bool: trials still approaching (``APPROACH`` or ``TERMINAL``, the first codes)."""
        return self.phase <= PhaseCode.TERMINAL

    def status(self) -> Status:
        """Each trial's phase, abort reason and clearance so far."""
        clear = self.metrics.min_clear
        return Status(self.phase.copy(), self.abort_reason.copy(), clear.copy(),
                      clear < self.params.mission.clearance_m)

    def _bodies(self, obs: Observation, leader: bool = False) -> BodyState:
        """``obs`` as the predictor sees a vehicle (see :func:`_bodies`)."""
        return _bodies(self.params, obs, leader)

    def _predict(self, obs_l: Observation, obs_f: Observation) -> np.ndarray | None:
        return _predict(self.params, self.comp, self.predictor, self.world, obs_l, obs_f)

    # -- the decision half of a control period -------------------------------------------------
    def decide(self) -> Decision:
        """Observe, fly the leader, update the phases, the follower's reference and aborts."""
        world, params, m, t = self.world, self.params, self.params.mission, self.t_s
        # What each controller sees (motion capture, and the leader's state over the network
        # at the follower), after any injected fault; gripper and rotor faults go to the world.
        obs_l, obs_f, obs_l_f = self.faults.observations(t, *world.observe())
        if self.faults.draws:
            self.faults.apply_to_world(t, world)
        # The leader: its own controller; it feeds forward the payload the follower sheds, once
        # the follower's docking status has arrived.
        self._status_sent.append(self.docked.copy())  # the oldest drops out
        self.lout = leader.leader_command(
            self.leader_ctl, obs_l,
            leader.leader_reference(self.leader_p0, self.lead_vel, self.lead_v, t,
                                    self.spec.leader_turn_rate_radps if self.spec.moving else 0.0),
            self._status_sent[0], self._shed_mps2)
        # The follower: plan, phases.
        phase = self.phase
        active = self.active  # approaching when this period began
        plan = approach.replan(params, self.shape, self.plan, t, obs_l_f, active)
        ref = approach.approach_reference(self.shape, plan, t, active)
        holding = active & (t >= self.arrival_s)
        p_ref, v_ref, a_ref = terminal.hold_at_docking_point(params, ref, obs_l_f, holding)
        p_ref = terminal.keep_clear(params, p_ref, obs_l_f, active,
                                    world.gripper_params.mount_height_m)
        phase = terminal.enter_terminal(phase, t, self.arrival_s, m.terminal_s)
        abort_now = self._aborts(t, phase, active, obs_f.p - p_ref)
        # The gate as the software knows it, and whether the follower is held.
        grip, close_s = world.gripper, world.gripper_params.close_time_s
        if self.gate_truth:
            captured_now, missed_now = gate_sensing.true_outcomes(grip, phase, active)
        else:
            closed = gate_sensing.believed_closed(grip, world.t_s, close_s, self.servo_feedback)
            captured_now, missed_now = resolve.gate_outcomes(
                closed, gate_sensing.dropped(params, obs_f, obs_l_f), phase, active, t,
                self.phase_t, m.dock_confirm_s)
        self.docked = (self.docked | captured_now) & ~missed_now
        self.sensed_missed |= missed_now
        # A dock is an outcome once confirmed: held through the confirmation window (or, from
        # the truth, at once).
        confirmed_now = captured_now if self.gate_truth else (
            (phase == PhaseCode.CAPTURED) & self.docked & ~self.confirmed
            & (t - self.phase_t >= m.dock_confirm_s))
        self.confirmed |= confirmed_now
        if any_true(captured_now) or any_true(missed_now):
            self.capture_t = np.where(captured_now, t,
                                      np.where(missed_now, np.nan, self.capture_t))
        backoff_now = (abort_now | missed_now) & ~captured_now
        plan = backoff.start_back_off(params, plan, t, obs_f, obs_l_f, backoff_now)
        phase = resolve.next_phases(phase, captured_now, missed_now, abort_now)
        began = captured_now | backoff_now
        if any_true(began):
            self.phase_t = np.where(began, t, self.phase_t)
        finished = resolve.finished(params, phase, t, self.phase_t)
        if any_true(finished):
            phase = np.where(finished, PhaseCode.DONE, phase).astype(np.int8)
            # How far the pair has sunk when the post-dock window ends (the leader carries the
            # follower; it flies level, so its altitude is its start's).
            docked_end = finished & world.captured
            if any_true(docked_end):
                self.post_dock_sink = np.where(
                    docked_end, world.leader.p[:, 2] - self.leader_p0[:, 2],
                    self.post_dock_sink)
        ref = backoff.back_off_reference(plan, t, phase, self.docked, (p_ref, v_ref, a_ref))
        self.phase, self.plan = phase, plan
        return Decision(
            t_s=t, phase=phase, approaching=active, holding=holding, ref=ref,
            feedforward_mps2=self._predict(obs_l_f, obs_f), leader_obs=obs_l,
            follower_obs=obs_f, leader_at_follower=obs_l_f, docked=confirmed_now,
            missed=missed_now & ~captured_now,
            aborted=abort_now & ~captured_now & ~missed_now,
        )

    def _aborts(self, t: float, phase: np.ndarray, active: np.ndarray,
                err: np.ndarray) -> np.ndarray:
        """(n,) trials aborting now (their gates are disarmed); records the reasons."""
        world = self.world
        grip, close_s = world.gripper, world.gripper_params.close_time_s
        abort_now, reason = aborts.decide_aborts(
            self.params, t, self.timing.timeout_s, phase, active, err,
            self.faults.last_fresh_leader_t,
            gate_sensing.commanded(grip, world.t_s, self.gate_truth),
            gate_sensing.jammed(grip, world.t_s, close_s, self.servo_feedback,
                                aborts.GATE_STUCK_TRAVELS))
        if reason is not None:  # some trial aborts now
            world.disarm_gate(abort_now)  # an aborted approach never closes the gate
            self.abort_reason = np.where(abort_now & (self.abort_reason == AbortCode.NONE),
                                         reason, self.abort_reason).astype(np.int8)
        return abort_now

    # -- the acting half -------------------------------------------------------------------------
    def fly(self, residual_mps2: np.ndarray | None = None) -> Flown:
        """Fly one control period, then decide the next.

        Args:
            residual_mps2: (n, 3) acceleration added to the follower's reference feed-forward
                while it approaches (a learning agent's action); None for the mission alone.
        """
        if self.finished:
            raise RuntimeError("the mission is over: every trial is done")
        world, d, gp = self.world, self.decision, self.world.gripper_params
        t, k = d.t_s, self.k
        p_ref, v_ref, a_ref = d.ref
        if residual_mps2 is not None:  # only on trials still approaching after this decision
            a_ref = a_ref + np.where(self.active[:, None], residual_mps2, 0.0)
        obs_f, obs_l_f, ff = d.follower_obs, d.leader_at_follower, d.feedforward_mps2
        terminal_gains = (d.phase == PhaseCode.TERMINAL) | d.holding
        yaw0 = np.zeros(self.n)
        accel = hold = None
        if self.follower_ctl.uses_accelerometer:
            accel = world.observed_accel()
            # The follower's own gripper: a load on the strain gauge or a gate commanded shut.
            grip = world.gripper
            hold = ((grip.reading_n > gp.contact_threshold_n)
                    | gate_sensing.commanded(grip, world.t_s, self.gate_truth))
        fout = self.follower_ctl.step(obs_f.p, obs_f.v, obs_f.rpy,
                                      Reference(p_ref, v_ref, a_ref, yaw0, yaw0), terminal_gains,
                                      ff, accel, hold)
        fout = self._hang(fout)
        if self.torque_ff:
            # The wake's torque predicted by the model (learnt, or at the rotor hubs from the
            # force), cancelled by the autopilot (not while hanging from the bar).
            tau = feedforward_torque_nm(self.predictor, self._bodies(obs_l_f, leader=True),
                                        self._bodies(obs_f),
                                        world.follower_fleet.params.rotor_offsets_m)
            tau = np.where(self.docked[:, None], 0.0, tau)
            fout = replace(fout, command=replace(fout.command, torque_ff_nm=-tau))
        close = triggers.active_close_command(obs_f, obs_l_f, self.geom, gp, t,
                                              self.timing.active_at_s, d.approaching)
        track_err_m, violated = self.metrics.measure(
            k, t, world, d.phase, d.approaching, p_ref, ff, fout, d.leader_obs.yaw_rad,
            self.params.mission.clearance_m, self.params.rotor_radius_m)
        if self.recorder is not None:
            self.recorder.before_step(t, world, d.leader_obs, obs_f, fout, p_ref, d.phase)
        world.advance(self.lout.command, fout.command, close)
        if self.recorder is not None:
            self.recorder.after_step(world, self.docked, sensed=not self.gate_truth)
        self.last_fout = fout
        self.k += 1
        if not any_true(self.phase != PhaseCode.DONE) or self.k >= self.steps:
            self.finished = True
            return Flown(track_err_m, violated, None)
        self.decision = self.decide()
        return Flown(track_err_m, violated, self.decision)

    def _hang(self, fout: ControlOutput) -> ControlOutput:
        """Docked followers: level attitude; thrust is the configured fraction of the weight plus
        the follower's own prediction of the wake (the position loop would fight the cables)."""
        hanging = self.docked
        if not any_true(hanging):
            return fout
        cmd, params = fout.command, self.params
        hang_thrust = params.mass_kg * (params.mission.post_dock_thrust_fraction
                                        * params.gravity_mps2
                                        + np.maximum(fout.feedforward_mps2[:, 2], 0.0))
        return replace(fout, command=replace(
            cmd, roll_rad=np.where(hanging, 0.0, cmd.roll_rad),
            pitch_rad=np.where(hanging, 0.0, cmd.pitch_rad),
            yaw_rate_radps=np.where(hanging, 0.0, cmd.yaw_rate_radps),
            thrust_n=np.where(hanging, hang_thrust, cmd.thrust_n)))

    # -- outcome -----------------------------------------------------------------------------------
    def result(self) -> CampaignResult:
        """Per-trial outcomes and terminal-window metrics of the flights so far."""
        world, n, spec, params = self.world, self.n, self.spec, self.params
        metrics, gate = self.metrics, world.gripper.gate
        # Contacts of the period flown last (the world records them as it steps).
        ground = metrics.ground_hit | (world.ground_contact & (self.phase != Phase.DONE))
        collision = metrics.strikes | ground
        draws = self.faults.draws
        result = CampaignResult(
            spec=spec,
            success=(gate == GateState.CAPTURED) & ~collision,
            slipped=world.gripper.slipped.copy(),
            missed=(gate == GateState.MISSED),
            sensed_missed=self.sensed_missed.copy(),
            aborted=self.abort_reason != AbortReason.NONE,
            abort_reason=self.abort_reason,
            clearance_violation=metrics.min_clear < params.mission.clearance_m,
            rotor_strike=metrics.strikes.copy(),
            nan_state=metrics.nan_seen.copy(),
            fault_hit=(np.any([d.hit for d in draws], axis=0) if draws
                       else np.ones(n, dtype=bool)),
            ground_contact=ground,
            post_dock_sink_m=self.post_dock_sink.copy(),
            min_clearance_m=metrics.min_clear,
            capture_time_s=self.capture_t,
            **metrics.terminal_window(self.dt_s),
            arrival_s=self.arrival_s,
        )
        if self.record != "summary":
            result.trace = {k: np.asarray(v) for k, v in metrics.trace.items()}
        if self.recorder is not None:
            result.logs = self.recorder.flightlogs(self._log_meta)
        return result

    def _log_meta(self, i: int) -> dict[str, Any]:
        """The metadata of trial ``i``'s FlightLog."""
        spec, params = self.spec, self.params
        return {
            "name": f"dock-seed{int(self.seeds[i])}-trial{int(self.trials[i]):04d}",
            "source": "aerodock-sim", "frame": "NED",
            "label_basis": self.recorder.label_basis,
            "leader_mass_kg": params.leader_mass_kg, "follower_mass_kg": params.mass_kg,
            **params.log_meta,
            "compensation": Compensation(spec.compensation).value,
            "offset_m": params.cable_length_m,
            "leader_speed_mps": spec.leader_speed_mps,
            "seed": int(self.seeds[i]), "trial": int(self.trials[i]),
        }
