"""Gymnasium environments for docking (optional extra: ``pip install 'aerodock[gym]'``).

Importing this package registers ``aerodock/Docking-v0``:

- ``gymnasium.make("aerodock/Docking-v0", **kwargs)``: :class:`DockingEnv`, one trial;
- ``gymnasium.make_vec("aerodock/Docking-v0", num_envs=N, vectorization_mode="vector_entry_point",
  **kwargs)``: :class:`DockingVectorEnv`, N trials stepped by one batch-first call.

Without importing it first, ``gymnasium.make("aerodock.envs:aerodock/Docking-v0")`` imports it.
Spaces, reward, termination and seeding: :mod:`aerodock.envs.docking`; the lockstep autoreset of
the vector environment: :mod:`aerodock.envs.vector`; checking the vector environment against
Gymnasium's API: :func:`aerodock.envs.check.check_vector_env`; how a reset's settled start is
served from a block of upcoming trials: :mod:`aerodock.envs.starts`; Stable-Baselines3 on the
vector environment: :class:`aerodock.envs.sb3.DockingSB3VecEnv` (import it from
``aerodock.envs.sb3``: it needs stable-baselines3).
"""

from __future__ import annotations

import gymnasium as gym

from aerodock.envs.batch import OBS_DIM, OBS_LAYOUT, DockingBatch, RewardWeights
from aerodock.envs.docking import DockingEnv
from aerodock.envs.vector import DockingVectorEnv

ENV_ID = "aerodock/Docking-v0"

if ENV_ID not in gym.registry:
    gym.register(
        id=ENV_ID,
        entry_point="aerodock.envs.docking:DockingEnv",
        vector_entry_point="aerodock.envs.vector:DockingVectorEnv",
        nondeterministic=False,
    )

__all__ = ["ENV_ID", "OBS_DIM", "OBS_LAYOUT", "DockingBatch", "DockingEnv", "DockingVectorEnv",
           "RewardWeights"]
