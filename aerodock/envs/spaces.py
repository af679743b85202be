"""Spaces and set-up shared by the single and the vector docking environments."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from aerodock.config import Config, load_config
from aerodock.control.compensation import AccelPredictor
from aerodock.envs.batch import OBS_DIM, OBS_HIGH, OBS_LOW, DockingBatch, RewardWeights
from aerodock.mission import MissionSpec
from aerodock.mission.checks import MissionSpecError, check_leader_speed, check_seed


def observation_space() -> gym.spaces.Box:
    """One trial's observation: ``OBS_DIM`` float32 values (``OBS_LAYOUT`` gives the units)."""
    return gym.spaces.Box(OBS_LOW, OBS_HIGH, shape=(OBS_DIM,), dtype=np.float32)


def action_space() -> gym.spaces.Box:
    """One trial's action: a normalised residual acceleration in [-1, 1]³ (NED)."""
    return gym.spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)


def make_batch(n: int, config: Config | str | Path | None = None, offset_m: float | None = None,
               leader_speed_mps: float = 0.0, leader_fixed: bool = False,
               compensation: str = "observer", predictor: AccelPredictor | None = None,
               leader_dropout_s: tuple[float, float] | None = None, campaign_seed: int = 0,
               residual_max_mps2: float = 2.0,
               reward_weights: RewardWeights | dict[str, float] | None = None) -> DockingBatch:
    """The batch core of both environments from their keyword arguments (see their docs).

    Every value is checked as ``aerodock dock`` and ``aerodock sweep`` check it
    (:mod:`aerodock.mission.checks`), named as the keyword argument.

    Raises:
        aerodock.mission.checks.MissionSpecError: a value out of its range (a ``ValueError``).
        aerodock.config.ConfigError: the config (or the cable length applied to it) is invalid.
    """
    cfg = config if isinstance(config, Config) else load_config(config)
    if isinstance(reward_weights, dict):
        unknown = sorted(set(reward_weights) - set(RewardWeights.__dataclass_fields__))
        if unknown:
            raise MissionSpecError(f"reward_weights: unknown fields {unknown} (known: "
                                   f"{', '.join(RewardWeights.__dataclass_fields__)})")
        reward_weights = RewardWeights(**reward_weights)
    if not isinstance(leader_fixed, bool | np.bool_):
        raise MissionSpecError(f"leader_fixed must be True or False, got {leader_fixed!r}")
    dropout = (tuple(leader_dropout_s) if isinstance(leader_dropout_s, list | tuple)
               else leader_dropout_s)
    spec = MissionSpec(
        trials=n, offset_m=offset_m, leader_speed_mps=check_leader_speed(leader_speed_mps),
        leader_fixed=bool(leader_fixed), compensation=compensation,
        seed=check_seed(campaign_seed, "campaign_seed"), leader_dropout_s=dropout)
    return DockingBatch(cfg, spec, n, predictor, residual_max_mps2, reward_weights)


def step_info(batch: DockingBatch, outcome: Any = None) -> dict[str, np.ndarray]:
    """Per-trial info arrays (fresh arrays on every call)."""
    none = np.zeros(batch.n, dtype=bool)
    status = batch.mission.status()
    return {
        "t_s": np.full(batch.n, batch.t_s),
        "trial": batch.trials.copy(),
        "phase": status.phase.astype(np.int64),
        "docked": none.copy() if outcome is None else outcome.docked.copy(),
        "missed": none.copy() if outcome is None else outcome.missed.copy(),
        "aborted": none.copy() if outcome is None else outcome.aborted.copy(),
        "abort_reason": status.abort_reason.astype(np.int64),
        "min_clearance_m": status.min_clearance_m,
        "clearance_violation": status.clearance_violation,
    }
