"""A settled start: both vehicles fly before t = 0 until their bias observers have converged.

On the aircraft nobody starts a docking with filters that were switched on a moment ago: the
vehicles take off, hover (the leader already carrying the bar) and the estimators settle. Every
simulated flight does the same. The controllers are reset from the *measured* states with an
uninformative bias prior (no simulator truth), and :func:`settle` flies ``settle_s`` seconds of
station keeping (or formation flight with a cruising leader) before the mission clock starts.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from aerodock.control.controller import PositionController, Reference
from aerodock.sim import Observation, World

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
