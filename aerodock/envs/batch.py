"""The docking mission one control period at a time, for N trials at once (the environments' core).

:class:`DockingBatch` flies the mission of :func:`aerodock.mission.batch.run_campaign` through the
same stepper (:class:`aerodock.mission.batch.MissionBatch`: same world, settled start, controllers,
planner, triggers, faults, aborts and random draws), split at the one point where a learning agent
acts: ``observe`` after the mission has decided the phase and the follower's
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
from aerodock.control.compensation import AccelPredictor, Compensation
from aerodock.mission import MissionBatch, MissionSpec, SettledStart
from aerodock.mission.checks import MissionSpecError, check_mission, check_positive
from aerodock.mission.phases.gate_sensing import GateCode
from aerodock.mission.spec import AbortCode, PhaseCode
from aerodock.planning.docking import docking_point_m
from aerodock.world import World

MAX_RESIDUAL_MPS2 = 50.0
"""Largest residual acceleration bound ``residual_max_mps2`` an environment accepts, m/s² (the
observation's bound on accelerations)."""

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
    timed_out: np.ndarray  # decided this period: aborted because the approach ran out of time


class DockingBatch:
    """N docking trials flown one control period per :meth:`act`: the mission's own stepper
    (:class:`aerodock.mission.batch.MissionBatch`) with the agent's residual and a reward.

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
        residual_max_mps2 = check_positive("residual_max_mps2", residual_max_mps2,
                                           MAX_RESIDUAL_MPS2)
        spec = replace(spec, trials=n, first_trial=0)
        # The validation dock and sweep use (values, faults, the run's size), named as the
        # environment's keyword arguments; the config the episodes fly is unchanged.
        check_mission(cfg, spec, size=True)
        comp = Compensation(spec.compensation)
        spec = replace(spec, compensation=comp)
        if comp == Compensation.MODEL and predictor is None:
            raise ValueError("compensation 'model' needs a predictor (a trained model)")
        weights = weights or RewardWeights()
        if not isinstance(weights, RewardWeights):
            raise MissionSpecError(f"reward_weights must be a RewardWeights or a dict of its "
                                   f"fields, got {weights!r}")
        for name in weights.__dataclass_fields__:
            value = getattr(weights, name)
            if isinstance(value, bool) or not isinstance(value, int | float) or not np.isfinite(
                    value):
                raise MissionSpecError(f"reward_weights.{name} must be a finite number, "
                                       f"got {value!r}")
        self.cfg, self.n = cfg, n
        self.spec = spec
        self.model_predictor = predictor if comp == Compensation.MODEL else None
        self.residual_max_mps2 = float(residual_max_mps2)
        self.weights = weights
        timing = MissionBatch.timing_of(cfg, self.spec)
        self.arrival_s, self.dt_s, self.max_steps = timing.arrival_s, timing.dt_s, timing.steps

    # -- episode start -------------------------------------------------------------------------
    def reset(self, first_trial: int, trials: np.ndarray | None = None,
              settled: SettledStart | None = None) -> None:
        """Start trials ``first_trial .. first_trial + n - 1`` of campaign ``spec.seed`` (or the
        explicit trial indices ``trials``, one per row, e.g. the same trial for several rows),
        from their settled start ``settled`` if it has been flown already (e.g. taken from a
        block: :mod:`aerodock.envs.starts`), else flying it here.

        Trial ``k`` draws every random number from stream ``(spec.seed, k)``: the same numbers
        as in ``run_campaign`` and whatever the batch size.
        """
        self.first_trial = int(first_trial)
        self.trials = (self.first_trial + np.arange(self.n) if trials is None
                       else np.asarray(trials, dtype=np.int64).copy())
        self.mission = MissionBatch(self.cfg, self.spec, self.model_predictor,
                                    trials=self.trials, settled=settled)
        self.resolved = np.zeros(self.n, dtype=bool)
        self.timed_out = np.zeros(self.n, dtype=bool)

    @property
    def world(self) -> World:
        """The trials' world."""
        return self.mission.world

    @property
    def k(self) -> int:
        """Control periods flown."""
        return self.mission.k

    @property
    def t_s(self) -> float:
        """Mission time of the current control period, s."""
        return self.mission.t_s

    @property
    def active(self) -> np.ndarray:
        """(n,) bool: trials still approaching (the residual acts on them)."""
        return self.mission.active

    def observation(self) -> np.ndarray:
        """(n, OBS_DIM) float32 observation (see :data:`OBS_LAYOUT`), clipped to its bounds."""
        mb = self.mission
        d = mb.decision
        p_ref, v_ref, a_ref = d.ref
        obs_f, obs_l_f = d.follower_obs, d.leader_at_follower
        n = self.n
        ctl = mb.follower_ctl
        bias = ctl.observer.bias_mps2 if ctl.observer is not None else np.zeros((n, 3))
        ff = d.feedforward_mps2 if d.feedforward_mps2 is not None else np.zeros((n, 3))
        dock_now = docking_point_m(obs_l_f.p, obs_l_f.v, mb.geom)
        cols = [obs_f.p - p_ref, obs_f.v - v_ref, obs_f.p - dock_now, obs_f.v - obs_l_f.v,
                a_ref, bias, ff, np.full((n, 1), mb.t_s - mb.arrival_s),
                (d.phase == PhaseCode.TERMINAL)[:, None].astype(float),
                (mb.world.gripper.gate == GateCode.CLOSING)[:, None].astype(float)]
        out = np.concatenate(cols, axis=1).astype(np.float32)
        np.maximum(out, OBS_LOW, out=out)  # np.clip's numbers (a NaN stays NaN), in place
        return np.minimum(out, OBS_HIGH, out=out)

    def act(self, action: np.ndarray) -> StepOutcome:
        """Fly one control period with the normalised residual ``action`` (n, 3) in [-1, 1]
        (``action * residual_max_mps2`` m/s², NED, added to the follower's reference
        acceleration while it approaches), then decide the next period."""
        mb, n = self.mission, self.n
        action = np.asarray(action, dtype=float).reshape(n, 3)
        if not np.isfinite(action).all():
            bad = np.flatnonzero(~np.all(np.isfinite(action), axis=1)).tolist()
            raise ValueError(f"the action holds NaN or infinite values (rows {bad}); actions "
                             "must be finite, in [-1, 1]")
        action = np.minimum(np.maximum(action, -1.0), 1.0)  # np.clip's numbers
        active = mb.active
        flown = mb.fly(action * self.residual_max_mps2)
        none = np.zeros(n, dtype=bool)
        d = flown.decision  # None: nothing more is decided, every trial is done
        docked, missed, aborted = (none, none, none) if d is None else (d.docked, d.missed,
                                                                        d.aborted)
        w, dt = self.weights, self.dt_s
        live = ~self.resolved
        reward = np.where(active, -w.tracking_per_ms * flown.track_err_m * dt
                          - w.action_per_s * np.sum(action**2, axis=1) * dt, 0.0)
        reward += w.dock * docked - w.miss * missed
        reward -= w.abort * aborted + w.clearance * flown.clearance_violated
        timed_out = aborted & live & (mb.abort_reason == AbortCode.TIMEOUT)
        out = StepOutcome(reward=np.where(live, reward, 0.0),
                          docked=docked & live, missed=missed & live,
                          aborted=aborted & live,
                          clearance_violated=flown.clearance_violated & live,
                          timed_out=timed_out)
        self.resolved |= docked | missed | aborted  # the outcome decided (a dock once confirmed)
        self.timed_out |= timed_out
        return out

    @property
    def out_of_time(self) -> bool:
        """The mission is over: every trial done or the whole time budget spent."""
        return self.mission.finished
