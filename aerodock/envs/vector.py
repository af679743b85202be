"""``DockingVectorEnv``: N docking trials stepped by one batch-first call (a native
``gymnasium.vector.VectorEnv``; ``gymnasium.make_vec("aerodock/Docking-v0", num_envs=N)``).

Every sub-environment is a :class:`aerodock.envs.docking.DockingEnv` trial (same spaces, reward,
termination); the batch runs in one :class:`aerodock.envs.batch.DockingBatch`, so one ``step``
advances all N trials with one NumPy call per operation (no loop over environments).

Episodes run in lockstep, because the batch-first world starts all its trials together: a
sub-environment whose trial is decided early returns its last observation with zero reward (an
absorbing state; ``info["waiting"]`` is True) until every trial is decided; then all report
``terminated`` (decided trials) or ``truncated`` (trials whose time ran out: the docking window
closed undocked, or the time budget was spent) on the same step, and the
next ``step`` resets the whole batch (``AutoresetMode.NEXT_STEP``: observations of the new
episodes, zero rewards, no flags). The return of every sub-environment is that of its own trial.

Seeding: ``reset(seed=s)`` flies trials ``s .. s + N - 1`` of campaign ``campaign_seed`` (the
per-trial streams of :class:`aerodock.rng.TrialRNG`), so sub-environment ``i`` is exactly
``DockingEnv`` reset with ``seed=s + i`` (the seeds ``gymnasium.vector.SyncVectorEnv`` would
give): tested step for step. Each autoreset moves on to the next N trial indices.
``reset(options={"trials": idx})`` flies explicit trial indices, repeats allowed: several
policies on the same trials (common random numbers, as ``examples/residual_ars.py`` does).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from aerodock.envs.docking import MAX_TRIAL_INDEX
from aerodock.envs.spaces import action_space, make_batch, observation_space, step_info


class DockingVectorEnv(VectorEnv):
    """N docking trials (``num_envs``) in one batch; keyword arguments as for ``DockingEnv``."""

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, num_envs: int = 1, render_mode: str | None = None, **kwargs: Any):
        if render_mode is not None:
            raise ValueError("the vector environment does not render; use DockingEnv or "
                             "`aerodock view` on saved logs")
        kwargs.pop("max_episode_steps", None)  # the mission ends every episode itself
        self.num_envs = int(num_envs)
        self._batch = make_batch(self.num_envs, **kwargs)
        self.single_observation_space = observation_space()
        self.single_action_space = action_space()
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._first_trial = 0
        self._autoreset = False
        self._started = False
        self._held_obs = np.zeros((self.num_envs, self.single_observation_space.shape[0]),
                                  dtype=np.float32)

    @property
    def batch(self):
        """The underlying :class:`aerodock.envs.batch.DockingBatch`."""
        return self._batch

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        """Start N new trials (see the module docstring for which)."""
        super().reset(seed=seed)
        trials = None
        if options and "trials" in options:
            trials = np.asarray(options["trials"], dtype=np.int64)
            if trials.shape != (self.num_envs,) or np.any(trials < 0):
                raise ValueError(f"options['trials'] must hold {self.num_envs} indices >= 0")
            first = int(trials.max()) + 1 - self.num_envs  # autoreset continues after them
        elif options and "trial" in options:
            first = int(options["trial"])
        elif seed is not None:
            first = int(seed)
        else:
            first = int(self.np_random.integers(0, MAX_TRIAL_INDEX))
        return self._start(first, trials)

    def _start(self, first_trial: int,
               trials: np.ndarray | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        self._first_trial = first_trial
        self._batch.reset(first_trial, trials)
        self._autoreset = False
        self._started = True
        self._held_obs = self._batch.observation()
        info = step_info(self._batch)
        info["waiting"] = np.zeros(self.num_envs, dtype=bool)
        return self._held_obs.copy(), info

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                 np.ndarray, dict[str, Any]]:
        """One control period for every sub-environment (or the batch's autoreset).

        Raises:
            RuntimeError: called before :meth:`reset`.
            ValueError: ``actions`` is not ``(num_envs, 3)`` finite numbers.
        """
        if not self._started:
            raise RuntimeError("call reset() before step()")
        n = self.num_envs
        actions = np.asarray(actions, dtype=float)
        if actions.shape != (n, 3):
            raise ValueError(f"the actions must have shape ({n}, 3), got {actions.shape}")
        if self._autoreset:
            obs, info = self._start(self._first_trial + n)
            return (obs, np.zeros(n), np.zeros(n, dtype=bool), np.zeros(n, dtype=bool), info)
        batch = self._batch
        was_resolved = batch.resolved.copy()
        out = batch.act(actions)
        self._held_obs = np.where(was_resolved[:, None], self._held_obs, batch.observation())
        ended = bool(batch.resolved.all() or batch.out_of_time)
        terminated = batch.resolved & ~batch.timed_out & ended
        truncated = (batch.timed_out | ~batch.resolved) & ended
        self._autoreset = ended
        info = step_info(batch, out)
        info["waiting"] = was_resolved & ~ended
        return self._held_obs.copy(), out.reward.copy(), terminated, truncated, info
