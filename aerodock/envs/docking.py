"""``DockingEnv``: one docking trial as a Gymnasium environment (id ``aerodock/Docking-v0``).

The follower flies the mission of :func:`aerodock.mission.batch.run_campaign` (minimum-jerk
approach to the predicted docking point, terminal phase, triggers, aborts, its LQR controller with
the chosen compensation); the leader flies its own controller. The agent adds a **residual
acceleration** to the LQR follower controller's reference feed-forward while the follower
approaches; after the gate resolves or the mission aborts the episode ends.

- Observation: ``Box(24,)`` float32, NED, from motion capture (noise and latency included):
  :data:`aerodock.envs.batch.OBS_LAYOUT` lists each block with its unit (m, m/s, m/s², s).
- Action: ``Box(-1, 1, (3,))`` float32: residual acceleration ``action * residual_max_mps2``
  (m/s², NED; default bound 2 m/s² per axis), applied during the approach only.
- Reward: :class:`aerodock.envs.batch.RewardWeights` (+10 docked, -5 missed or slipped, -5
  aborted, -10 on a clearance violation, a dense -|tracking error| m·s and a small action cost).
- Termination and truncation: ``terminated`` when the mission decides the trial (docked, missed,
  or aborted because the leader's state was lost, the tracking became unsafe or the gate jammed);
  ``truncated`` when time runs out: the approach's docking window closes undocked (the mission
  aborts it with ``info["abort_reason"] == AbortReason.TIMEOUT``, the abort reward included) or,
  as a safety net, the mission's whole time budget is spent.
- Errors: ``step`` before ``reset`` raises ``RuntimeError``; an action holding NaN or infinity
  raises ``ValueError``; invalid keyword arguments raise ``ValueError``
  (:class:`aerodock.mission.checks.MissionSpecError`, checked as ``aerodock dock`` checks them).
- Seeding: ``reset(seed=k)`` flies trial ``k`` of campaign ``campaign_seed``: every random number
  comes from the per-trial stream ``(campaign_seed, k)`` (:class:`aerodock.rng.TrialRNG`), the
  same as ``run_campaign(MissionSpec(seed=campaign_seed, first_trial=k))`` and the same as
  sub-environment ``k - s`` of a vector environment reset with ``seed=s``. ``reset()`` without a
  seed draws a trial index from ``np_random``; ``options={"trial": k}`` picks one explicitly.
- Reset cost: a reset settles the trial it asks for together with the ``settle_block - 1`` trials
  the next resets are expected to ask for (the draws ``np_random`` will make; after a seed, also
  the next seeds), and serves those later resets from the block: the same numbers, a fraction
  of the time (:mod:`aerodock.envs.starts`).
"""

from __future__ import annotations

import copy
from typing import Any

import gymnasium as gym
import numpy as np

from aerodock.envs.spaces import action_space, make_batch, observation_space, step_info
from aerodock.envs.starts import DEFAULT_BLOCK_TRIALS, StartCache

MAX_TRIAL_INDEX = 2**31 - 1


class DockingEnv(gym.Env):
    """One docking trial with a residual policy on top of the LQR follower controller.

    Keyword arguments (all optional; ``gymnasium.make`` passes them through):
        config: a :class:`aerodock.config.Config` or a TOML path (default: aerodock's defaults).
        offset_m: cable length d_p, m (default: the config's).
        leader_speed_mps: leader speed towards north, m/s (0: hover).
        leader_fixed: the leader on a rigid stand.
        compensation: ``none``, ``observer`` (default), ``model`` (needs ``predictor``) or
            ``oracle``: what the LQR controller subtracts, as in ``aerodock dock``.
        predictor: a feed-forward model (``aerodock.learning.runtime.Predictor``) for ``model``.
        leader_dropout_s: ``(start_s, duration_s)`` of a leader-state dropout (fault injection).
        campaign_seed: the campaign seed of the per-trial random streams.
        residual_max_mps2: residual acceleration at a normalised action of 1, m/s² (finite,
            0 < value <= 50).
        reward_weights: :class:`aerodock.envs.batch.RewardWeights` or a dict of its fields.
        settle_block: trials whose settled starts one reset flies together, the later resets
            served from them (1: every reset settles its own trial; see the module docstring).
        render_mode: ``"rgb_array"`` draws the current state (matplotlib), or None.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 25}

    def __init__(self, render_mode: str | None = None, settle_block: int = DEFAULT_BLOCK_TRIALS,
                 **kwargs: Any):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be one of {self.metadata['render_modes']}")
        self.render_mode = render_mode
        self._batch = make_batch(1, **kwargs)
        batch = self._batch
        self._starts = StartCache(batch.cfg, batch.spec, batch.model_predictor, settle_block)
        self.observation_space = observation_space()
        self.action_space = action_space()
        self._history: list[dict[str, np.ndarray]] = []
        self._started = False

    @property
    def batch(self):
        """The underlying :class:`aerodock.envs.batch.DockingBatch` (of one trial)."""
        return self._batch

    def reset(self, *, seed: int | None = None,
              options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        """Start a trial (see the module docstring for which one)."""
        super().reset(seed=seed)
        chosen = bool(options and "trial" in options) or seed is not None
        if options and "trial" in options:
            trial = int(options["trial"])
        elif seed is not None:
            trial = int(seed)
        else:
            trial = int(self.np_random.integers(0, MAX_TRIAL_INDEX))
        settled = self._starts.take(trial, lambda k: self._upcoming(trial, chosen, k))
        self._batch.reset(trial, settled=settled)
        self._started = True
        self._history = []
        self._remember()
        return self._batch.observation()[0], _scalars(step_info(self._batch))

    @property
    def starts(self) -> StartCache:
        """Where this environment's episodes start from (:mod:`aerodock.envs.starts`): its
        counters say how many blocks were settled and how many resets were served from them."""
        return self._starts

    def _upcoming(self, trial: int, chosen: bool, k: int) -> list[int]:
        """Up to ``k`` trials the next resets are expected to ask for: the next draws of
        ``np_random`` (the resets without a seed), alternating, after a trial chosen by seed or
        option, with ``trial + 1, trial + 2, ...`` (consecutive seeds)."""
        rng = copy.deepcopy(self.np_random)  # the draws the next resets will make
        drawn = [int(rng.integers(0, MAX_TRIAL_INDEX)) for _ in range(k)]
        if not chosen:
            return drawn
        following = [t for t in range(trial + 1, trial + 1 + k) if t <= MAX_TRIAL_INDEX]
        mixed = [t for pair in zip(following, drawn) for t in pair]
        return mixed + following[len(drawn):] + drawn[len(following):]

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Fly one control period (1 / ``sim.control_rate_hz`` s) with ``action``.

        Raises:
            RuntimeError: called before :meth:`reset`.
            ValueError: ``action`` is not 3 finite numbers.
        """
        if not self._started:
            raise RuntimeError("call reset() before step()")
        act = np.asarray(action, dtype=float)
        if act.shape != (3,):
            raise ValueError(f"the action must have shape (3,), got {act.shape}")
        out = self._batch.act(act[None, :])
        self._remember()
        batch = self._batch
        timed_out = bool(batch.timed_out[0])
        terminated = bool(batch.resolved[0]) and not timed_out
        truncated = timed_out or bool(batch.out_of_time and not batch.resolved[0])
        return (self._batch.observation()[0], float(out.reward[0]), terminated, truncated,
                _scalars(step_info(self._batch, out)))

    def _remember(self) -> None:
        if self.render_mode is None:
            return
        w = self._batch.world
        self._history.append({"leader": w.leader.p[0].copy(), "follower": w.follower.p[0].copy(),
                              "bar": w.bar.p[0].copy(), "gate": int(w.gripper.gate[0])})

    def render(self) -> np.ndarray | None:
        """An RGB image (H, W, 3) of the trial so far: side and top views (``rgb_array``)."""
        if self.render_mode != "rgb_array":
            return None
        from aerodock.view.render import render_env_frame

        return render_env_frame(self._history, self._batch.cfg)


def _scalars(info: dict[str, np.ndarray]) -> dict[str, Any]:
    """Trial 0's entries of a batch info dict as Python scalars."""
    return {k: v[0].item() for k, v in info.items()}
