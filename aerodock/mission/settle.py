"""A settled start: both vehicles fly before t = 0 until their bias observers have converged.

On the aircraft nobody starts a docking with filters that were switched on a moment ago: the
vehicles take off, hover (the leader already carrying the bar) and the estimators settle. Every
simulated flight does the same. The controllers are reset from the *measured* states with an
uninformative bias prior (no simulator truth), and :func:`settle` flies ``settle_s`` seconds of
station keeping (or formation flight with a cruising leader) before the mission clock starts.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from aerodock.control.compensation import OraclePredictor
from aerodock.control.controller import PositionController, Reference
from aerodock.mission.setup import Starts
from aerodock.rng import TrialRNG
from aerodock.rows import as_rows
from aerodock.world import Observation, World

# Prior sd of an unknown disturbance acceleration at switch-on (thrust errors of a few %, the
# bar's weight on the leader): an uninformative guess, m/s².
BIAS_PRIOR_SD_MPS2 = 2.0

ReferenceFn = Callable[[float], Reference]
FeedForwardFn = Callable[[Observation, Observation], np.ndarray | None]


def reset_controllers(world: World, *controllers: PositionController) -> None:
    """Reset leader and follower controllers (in that order) from motion capture, bias unknown."""
    obs = world.observe()
    for ctl, o in zip(controllers, obs):
        ctl.reset(o.p, o.v, None, BIAS_PRIOR_SD_MPS2)


def settle(world: World, leader_ctl: PositionController, follower_ctl: PositionController,
           leader_ref: ReferenceFn, follower_ref: ReferenceFn, settle_s: float,
           feedforward: FeedForwardFn | None = None) -> None:
    """Fly ``settle_s`` seconds before t = 0 (``leader_ref(t)``, ``follower_ref(t)`` for t < 0).

    Args:
        world: the world, just reset.
        leader_ctl, follower_ctl: the vehicles' controllers (reset here).
        leader_ref, follower_ref: references as functions of mission time (negative here).
        settle_s: how long.
        feedforward: the follower's feed-forward prediction from the observations, if any.
    """
    reset_controllers(world, leader_ctl, follower_ctl)
    dt = world.dt_control_s
    steps = int(round(settle_s / dt))
    for k in range(steps):
        t = (k - steps) * dt
        obs_l, obs_f = world.observe()
        lout = leader_ctl.step(obs_l.p, obs_l.v, obs_l.rpy, leader_ref(t))
        ff = None if feedforward is None else feedforward(obs_l, obs_f)
        accel = world.observed_accel() if follower_ctl.uses_accelerometer else None
        fout = follower_ctl.step(obs_f.p, obs_f.v, obs_f.rpy, follower_ref(t), None, ff, accel)
        world.advance(lout.command, fout.command)


@dataclass(frozen=True)
class SettledStart:
    """N trials at t = 0, their settled start flown: what a mission starts from
    (:func:`aerodock.mission.batch.settle_trials`).

    Attributes:
        trials: (n,) trial indices (row i draws from stream ``(seed, trials[i])``).
        rng: the trials' random streams, where they stand.
        start: where each trial begins at t = 0, and the leader's cruise velocity.
        world: the trials' world.
        leader_ctl, follower_ctl: the vehicles' controllers, their estimators converged.
        predictor: the follower's feed-forward model as flown (the oracle reads this world's
            field; None: none flown).
    """

    trials: np.ndarray
    rng: TrialRNG
    start: Starts
    world: World
    leader_ctl: PositionController
    follower_ctl: PositionController
    predictor: Any

    @property
    def n(self) -> int:
        """Number of trials."""
        return int(self.trials.size)

    @property
    def splittable(self) -> bool:
        """Whether :meth:`take_rows` can serve single trials from this batch (its world splits:
        :attr:`aerodock.world.world.World.splittable`)."""
        return self.world.splittable

    def take_rows(self, rows: np.ndarray) -> SettledStart:
        """The trials at ``rows`` (indices into this batch) as a settled start of their own: a
        mission started from it flies them exactly as :func:`~aerodock.mission.batch.
        settle_trials` of those trials alone would (tested bit for bit). This batch is not
        changed (every piece is copied), so each row can be taken any number of times.

        Raises:
            TypeError: the world cannot be split (see :attr:`splittable`).
        """
        rows = as_rows(rows, self.n)
        world = self.world.take_rows(rows)
        predictor = (OraclePredictor(world.field, dt_s=world.dt_s)
                     if isinstance(self.predictor, OraclePredictor) else self.predictor)
        return SettledStart(self.trials[rows], world.rng, self.start.take_rows(rows), world,
                            self.leader_ctl.take_rows(rows), self.follower_ctl.take_rows(rows),
                            predictor)


# A moving leader is already cruising this long when the mission clock starts.
CRUISE_BEFORE_S = 1.0


@dataclass(frozen=True)
class CruiseStart:
    """How a moving leader gets to its cruise velocity before t = 0, as a real one does.

    It hovers first (``settle_s``: the observers converge on the bar's weight and thrust errors),
    then speeds up along a minimum-jerk profile over ``ramp_s`` and cruises
    :data:`CRUISE_BEFORE_S` before the mission clock starts. Starting the leader at full speed
    with observers that know nothing (its drag unexplained) makes it overshoot its speed by half
    and leaves the bar swinging several centimetres: a start no flight has. With ``ramp_s = 0``
    (or a hovering leader) the pre-roll is ``settle_s`` at constant velocity.

    ``shift_s(t)`` is the reference's displacement along the velocity in seconds of cruise:
    ``p_ref(t) = p(0) + v shift_s(t)``, with ``shift_s(t) = t`` once cruising.
    """

    settle_s: float
    ramp_s: float

    @property
    def preroll_s(self) -> float:
        """Time flown before t = 0, s."""
        extra = self.ramp_s + CRUISE_BEFORE_S if self.ramp_s > 0 else 0.0
        return self.settle_s + extra

    def profile(self, t_s: float) -> tuple[float, float, float]:
        """(shift s, speed fraction, acceleration fraction 1/s) of the reference at ``t_s`` <= 0."""
        if self.ramp_s <= 0:
            return t_s, 1.0, 0.0
        end = -CRUISE_BEFORE_S
        if t_s >= end:
            return t_s, 1.0, 0.0
        u = max(0.0, (t_s - end + self.ramp_s) / self.ramp_s)
        area = 2.5 * u**4 - 3.0 * u**5 + u**6  # integral of the minimum-jerk speed, 0.5 at u = 1
        speed = 10 * u**3 - 15 * u**4 + 6 * u**5
        accel = (30 * u**2 - 60 * u**3 + 30 * u**4) / self.ramp_s
        return end - self.ramp_s * (0.5 - area), speed, accel

    def reference(self, p0_m: np.ndarray, velocity_mps: np.ndarray) -> ReferenceFn:
        """The pre-roll reference of a vehicle that is at ``p0_m`` (n, 3) at t = 0 and flies
        ``velocity_mps`` (n, 3) from then on."""
        zero_n = np.zeros(p0_m.shape[0])

        def ref(t_s: float) -> Reference:
            shift, speed, accel = self.profile(t_s)
            return Reference(p0_m + velocity_mps * shift, velocity_mps * speed,
                             velocity_mps * accel, zero_n, zero_n)
        return ref

    def start_velocity(self, velocity_mps: np.ndarray) -> np.ndarray:
        """The velocity the vehicles have when the pre-roll begins."""
        return velocity_mps * (1.0 if self.ramp_s <= 0 else 0.0)
