"""Checking a vector environment against Gymnasium's API.

Gymnasium (1.x) offers ``gymnasium.utils.env_checker.check_env`` for single environments only.
:func:`check_vector_env` applies the same checks, with Gymnasium's own comparison helpers, to a
``gymnasium.vector.VectorEnv``: batched spaces, reset and step types and shapes, seeded
determinism of reset and step, fresh data on every call, and the declared autoreset mode
(Gymnasium's vector wrappers accept it). Comparing a native vector environment with
``gymnasium.vector.SyncVectorEnv`` over its single environment (the tests do it) checks the rest:
that every sub-environment is the single environment.
"""

from __future__ import annotations

from copy import deepcopy

import numpy as np
from gymnasium.utils.env_checker import data_equivalence
from gymnasium.utils.passive_env_checker import check_action_space, check_observation_space
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space


def _data_shares_objects(a, b) -> bool:
    if isinstance(a, dict) and isinstance(b, dict):
        return any(_data_shares_objects(a[k], b[k]) for k in a.keys() & b.keys())
    if isinstance(a, np.ndarray) and isinstance(b, np.ndarray):
        return np.shares_memory(a, b)
    return False


def check_vector_env(env: VectorEnv, seed: int = 123, steps: int = 3) -> None:
    """Raise AssertionError where ``env`` breaks Gymnasium's vector API (see the module doc)."""
    assert isinstance(env, VectorEnv), f"not a gymnasium.vector.VectorEnv: {type(env)}"
    n = env.num_envs
    assert isinstance(n, int) and n >= 1, f"num_envs must be a positive int, got {n!r}"
    check_observation_space(env.single_observation_space)
    check_action_space(env.single_action_space)
    assert env.observation_space == batch_space(env.single_observation_space, n), (
        "observation_space is not the batched single_observation_space")
    assert env.action_space == batch_space(env.single_action_space, n), (
        "action_space is not the batched single_action_space")
    mode = env.metadata.get("autoreset_mode")
    assert isinstance(mode, AutoresetMode), "metadata['autoreset_mode'] must be an AutoresetMode"

    # Reset: types, seeded determinism, np_random seeded.
    obs1, info1 = env.reset(seed=seed)
    obs1 = deepcopy(obs1)
    assert obs1 in env.observation_space, "reset(seed) observation outside observation_space"
    assert isinstance(info1, dict), "reset must return an info dict"
    rng1 = deepcopy(env.np_random.bit_generator.state)
    obs2, _ = env.reset()
    obs2 = deepcopy(obs2)
    assert obs2 in env.observation_space, "reset() observation outside observation_space"
    obs3, _ = env.reset(seed=seed)
    assert env.np_random.bit_generator.state == rng1, "reset(seed) must reseed np_random"
    obs4, _ = env.reset()
    assert data_equivalence(obs1, obs3), "reset(seed) is not deterministic"
    assert data_equivalence(obs2, obs4), "reset(seed) then reset() is not deterministic"

    # Step: types, shapes, determinism, fresh data.
    def rollout() -> list:
        env.action_space.seed(seed)
        out = [env.reset(seed=seed)]
        for _ in range(steps):
            out.append(env.step(env.action_space.sample()))
        return out

    first, second = rollout(), rollout()
    for call in first[1:]:
        obs, rew, term, trunc, info = call
        assert obs in env.observation_space, "step observation outside observation_space"
        for name, arr, kind in (("rewards", rew, np.floating), ("terminations", term, np.bool_),
                                ("truncations", trunc, np.bool_)):
            assert isinstance(arr, np.ndarray) and arr.shape == (n,), (
                f"{name} must be an array of shape ({n},)")
            assert np.issubdtype(arr.dtype, kind), f"{name} has dtype {arr.dtype}"
        assert isinstance(info, dict), "step must return an info dict"
    for a, b in zip(first, second, strict=True):
        assert data_equivalence(a, b), "same seed and actions, different results"
    for i, a in enumerate(first):
        for b in first[i + 1:]:
            for x, y in ((a[0], b[0]), (a[-1], b[-1])):
                assert not _data_shares_objects(x, y), "a later call reused returned data"
