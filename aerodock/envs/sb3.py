"""Stable-Baselines3 on the native vector environment: :class:`DockingSB3VecEnv`.

Stable-Baselines3 has its own vector API (``stable_baselines3.common.vec_env.VecEnv``: ``reset``
returns the observations only, ``step_async``/``step_wait``, a list of info dicts, an episode's
end reported with ``terminal_observation`` and ``TimeLimit.truncated`` and the next episode's
first observation returned in its place). :class:`DockingSB3VecEnv` gives it the batch-first
:class:`aerodock.envs.vector.DockingVectorEnv` (one NumPy call per operation for all N trials),
instead of ``make_vec_env``'s N single environments stepped one by one::

    from stable_baselines3 import PPO
    from aerodock.envs import DockingVectorEnv
    from aerodock.envs.sb3 import DockingSB3VecEnv

    env = DockingSB3VecEnv(DockingVectorEnv(num_envs=16, campaign_seed=0))
    PPO("MlpPolicy", env, n_steps=256, batch_size=1024).learn(100_000)

Needs ``stable-baselines3`` (``pip install 'aerodock[gym]'``); importing this module without it
raises ImportError.

What differs from ``make_vec_env`` of single environments, because the batch's trials start
together (the native environment's lockstep): a trial decided early waits, its last
observation held with zero reward and ``info["waiting"]`` True, until every trial of the batch
is decided; then all report ``done`` on the same step (``TimeLimit.truncated`` True for the
trials whose time ran out) with their ``terminal_observation``, and the observations returned are
the next N trials' first. A trial's return is its own; the waiting steps add nothing to it.
The batch's attributes and methods (``get_attr``, ``set_attr``, ``env_method``) are one object's:
the native environment answers for every index. Seeds: ``seed(s)`` then ``reset()`` flies trials
``s .. s + N - 1``, the trials ``make_vec_env(seed=s)`` gives its N single environments.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import (
    VecEnv,
    VecEnvIndices,
    VecEnvObs,
    VecEnvStepReturn,
)

from aerodock.envs.vector import DockingVectorEnv


class DockingSB3VecEnv(VecEnv):
    """A Stable-Baselines3 ``VecEnv`` over a :class:`DockingVectorEnv` (module docstring).

    Args:
        venv: the native vector environment (its ``num_envs`` trials are the sub-environments).
    """

    def __init__(self, venv: DockingVectorEnv):
        if not isinstance(venv, DockingVectorEnv):
            raise TypeError(f"venv must be a DockingVectorEnv, got {type(venv).__name__}")
        self.venv = venv
        self._actions: np.ndarray | None = None
        super().__init__(venv.num_envs, venv.single_observation_space,
                         venv.single_action_space)

    def reset(self) -> VecEnvObs:
        """Start N trials: those of the seeds set by :meth:`seed` (``s + i``: trials
        ``s .. s + N - 1``; other seeds: those trials), else the next ones; returns their
        observations (N, 24)."""
        seeds, options = self._seeds, self._options
        self._reset_seeds()
        self._reset_options()
        if any(o != options[0] for o in options):
            raise ValueError("the batch's trials share one set of reset options; got different "
                             "options per environment")
        opts = dict(options[0]) if options else {}
        kwargs: dict[str, Any] = {}
        if all(s is not None for s in seeds):
            first = int(seeds[0])
            if list(seeds) == list(range(first, first + self.num_envs)):
                kwargs["seed"] = first
            else:
                opts["trials"] = np.asarray(seeds, dtype=np.int64)
        obs, info = self.venv.reset(options=opts or None, **kwargs)
        self.reset_infos = _split_info(info, self.num_envs)
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        """Remember the actions (N, 3) for :meth:`step_wait`."""
        self._actions = np.asarray(actions)

    def step_wait(self) -> VecEnvStepReturn:
        """One control period for every trial: (observations, rewards, dones, infos); when the
        batch's episodes end, the next trials start on the same call (module docstring)."""
        if self._actions is None:
            raise RuntimeError("call step_async(actions) before step_wait()")
        actions, self._actions = self._actions, None
        obs, reward, terminated, truncated, info = self.venv.step(actions)
        done = terminated | truncated
        infos = _split_info(info, self.num_envs)
        for i in np.flatnonzero(done):
            infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
            infos[i]["terminal_observation"] = obs[i]
        if done.any():  # the native autoreset: its next step starts the next N trials
            obs, _, _, _, start = self.venv.step(np.zeros((self.num_envs, 3), np.float32))
            self.reset_infos = _split_info(start, self.num_envs)
        return obs, reward.astype(np.float32), done, infos

    def close(self) -> None:
        """Close the native environment."""
        self.venv.close()

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        """The native environment's attribute, once per index."""
        value = getattr(self.venv, attr_name)
        return [value for _ in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        """Set the native environment's attribute (every index shares it)."""
        setattr(self.venv, attr_name, value)

    def env_method(self, method_name: str, *method_args: Any, indices: VecEnvIndices = None,
                   **method_kwargs: Any) -> list[Any]:
        """Call the native environment's method once; its result, once per index."""
        result = getattr(self.venv, method_name)(*method_args, **method_kwargs)
        return [result for _ in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class: type, indices: VecEnvIndices = None) -> list[bool]:
        """False for every index: no Gymnasium wrapper sits inside the batch."""
        return [False for _ in self._get_indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        """None per environment: the batch does not render (``aerodock view`` draws logs)."""
        return [None] * self.num_envs


def _split_info(info: dict[str, Any], n: int) -> list[dict[str, Any]]:
    """The native environment's info arrays as one dict of Python scalars per trial."""
    return [{k: np.asarray(v)[i].item() for k, v in info.items()} for i in range(n)]
