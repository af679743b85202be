"""Train a residual policy with PPO (Stable-Baselines3) on the native vector environment.

The agent adds a residual acceleration to the LQR follower controller's reference feed-forward
during the approach (``aerodock/Docking-v0``), on top of the paper's LQG baseline (bias
observer, no model) at d_p = 0.36 m. PPO's rollouts come from ONE batch-first
``DockingVectorEnv`` through the adapter ``aerodock.envs.sb3.DockingSB3VecEnv`` (one NumPy call
per operation for all N trials); ``--backend make-vec-env`` takes Stable-Baselines3's own
``make_vec_env`` over N single ``DockingEnv`` instead, for comparison. Observations and rewards
are normalised by ``VecNormalize``. The policy and the zero residual are then evaluated on
held-out trials (trial indices the training never flew).

The episodes run in lockstep (``aerodock.envs.vector``): a batch of N episodes ends when its
last trial is decided, about 600 steps after it started (850 at most, the mission's time
budget), so a run shows returns only once every environment has flown that long: a 4,096-step
run over 8 environments (512 steps each) ends no episode. The run prints the mean return of the
episodes that ended in each rollout (the learning curve), and ``--tensorboard DIR`` logs it
(``rollout/ep_rew_mean``) for TensorBoard.

    python examples/ppo_sb3.py                          # 20,480 steps, 32 episodes: ~1 min
    python examples/ppo_sb3.py --steps 204800           # 320 episodes: ten times as long
    python examples/ppo_sb3.py --smoke                  # 1,792 steps, 2 episodes: seconds
    python examples/ppo_sb3.py --tensorboard out/tb     # then: tensorboard --logdir out/tb
    python examples/ppo_sb3.py --backend make-vec-env   # the same through make_vec_env
    python examples/ppo_sb3.py --json out.json

``--quick`` (256 steps, no episode ends) is the adapter's test. Needs ``aerodock[gym]``
(Gymnasium, Stable-Baselines3, TensorBoard) and PyTorch.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from typing import Any

import numpy as np

HELDOUT_FIRST_TRIAL = 100_000
ENV_KWARGS: dict[str, Any] = {"compensation": "observer", "offset_m": 0.36,
                              "residual_max_mps2": 2.0, "campaign_seed": 0}


def training_env(backend: str, n: int, seed: int):
    """N training trials as a Stable-Baselines3 VecEnv, episode statistics recorded."""
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecMonitor

    from aerodock.envs import DockingEnv, DockingVectorEnv
    from aerodock.envs.sb3 import DockingSB3VecEnv

    if backend == "native":
        env = VecMonitor(DockingSB3VecEnv(DockingVectorEnv(num_envs=n, **ENV_KWARGS)))
    elif backend == "make-vec-env":
        env = make_vec_env(DockingEnv, n_envs=n, env_kwargs=ENV_KWARGS)
    else:
        raise ValueError(f"backend must be native or make-vec-env, got {backend!r}")
    env.seed(seed)
    return env


def returns_callback(curve: list[dict[str, Any]]):
    """A Stable-Baselines3 callback that appends, at the end of every rollout in which
    episodes ended, ``{"env_steps", "episodes", "mean_return"}`` to ``curve`` (the episodes'
    returns as ``VecMonitor``/``Monitor`` report them)."""
    from stable_baselines3.common.callbacks import BaseCallback

    class _Returns(BaseCallback):
        def _on_rollout_start(self) -> None:
            self._ended: list[float] = []

        def _on_step(self) -> bool:
            self._ended += [float(i["episode"]["r"]) for i in self.locals["infos"]
                            if "episode" in i]
            return True

        def _on_rollout_end(self) -> None:
            if self._ended:
                curve.append({"env_steps": int(self.num_timesteps), "episodes": len(self._ended),
                              "mean_return": float(np.mean(self._ended))})

    return _Returns()


def evaluate(policy, trials: int) -> dict[str, Any]:
    """Return and outcome rates on the held-out trials; ``policy(obs) -> actions`` (N, 3)."""
    from aerodock.envs import DockingVectorEnv

    env = DockingVectorEnv(num_envs=trials, **ENV_KWARGS)
    obs, _ = env.reset(seed=HELDOUT_FIRST_TRIAL)
    ret = np.zeros(trials)
    docked, missed, aborted = (np.zeros(trials, bool) for _ in range(3))
    while True:
        obs, rew, term, trunc, info = env.step(policy(obs))
        ret += rew
        docked |= info["docked"]
        missed |= info["missed"]
        aborted |= info["aborted"]
        if term.any() or trunc.any():
            return {"trials": trials, "mean_return": float(ret.mean()),
                    "docked_rate": float(docked.mean()), "missed_rate": float(missed.mean()),
                    "aborted_rate": float(aborted.mean())}


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Train, evaluate against the zero residual, print a summary (and return it)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="256 steps, no episode ends (the adapter's test)")
    parser.add_argument("--smoke", action="store_true",
                        help="seconds, two episodes end (the examples' test)")
    parser.add_argument("--tensorboard", default=None, metavar="DIR",
                        help="log the training to DIR for TensorBoard")
    parser.add_argument("--backend", default="native", choices=("native", "make-vec-env"))
    parser.add_argument("--steps", type=int, default=None, help="environment steps to train")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", default=None, help="write the results to this file")
    args = parser.parse_args(argv)
    size = ({"envs": 4, "steps": 256, "n_steps": 64, "eval_trials": 4} if args.quick
            else {"envs": 2, "steps": 1_792, "n_steps": 448, "eval_trials": 4} if args.smoke
            else {"envs": 8, "steps": 20_480, "n_steps": 256, "eval_trials": 64})
    if args.steps is not None:
        size["steps"] = args.steps
    if args.tensorboard is not None:
        try:
            import tensorboard  # noqa: F401
        except ImportError:
            print("error: --tensorboard needs tensorboard: pip install 'aerodock[gym]'",
                  file=sys.stderr)
            sys.exit(2)

    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    torch.set_num_threads(1)
    started = time.perf_counter()
    env = VecNormalize(training_env(args.backend, size["envs"], args.seed), clip_obs=10.0)
    model = PPO("MlpPolicy", env, n_steps=size["n_steps"], batch_size=size["n_steps"],
                n_epochs=5, gamma=0.99, seed=args.seed, device="cpu",
                tensorboard_log=args.tensorboard)
    if args.tensorboard is None:
        # no outputs: Stable-Baselines3's own logger would otherwise make an empty SB3-<time>
        # folder in the temporary directory at every run
        from stable_baselines3.common.logger import Logger

        model.set_logger(Logger(folder=None, output_formats=[]))
    curve: list[dict[str, Any]] = []
    model.learn(total_timesteps=size["steps"], callback=returns_callback(curve),
                tb_log_name=f"ppo_{args.backend}_seed{args.seed}")
    train_s = time.perf_counter() - started
    episodes = [float(e["r"]) for e in model.ep_info_buffer]
    env.training = False

    def ppo(obs: np.ndarray) -> np.ndarray:
        return model.predict(env.normalize_obs(obs), deterministic=True)[0]

    result = {
        "scenario": dict(ENV_KWARGS), "backend": args.backend, "settings": size,
        "env_steps": int(model.num_timesteps), "train_wall_s": train_s,
        "env_steps_per_s": model.num_timesteps / train_s,
        "episodes_ended": len(episodes),
        "mean_return_last_episodes": float(np.mean(episodes)) if episodes else None,
        "returns_by_rollout": curve,
        "tensorboard_dir": args.tensorboard,
        "baseline_lqg": evaluate(lambda o: np.zeros((o.shape[0], 3), np.float32),
                                 size["eval_trials"]),
        "ppo_policy": evaluate(ppo, size["eval_trials"]),
    }
    print(f"PPO ({args.backend}, {size['envs']} envs): {result['env_steps']} steps in "
          f"{train_s:.0f} s ({result['env_steps_per_s']:.0f} steps/s, updates included), "
          f"{len(episodes)} episodes ended")
    for point in curve:
        print(f"  after {point['env_steps']:7d} steps: {point['episodes']:3d} episodes ended, "
              f"mean return {point['mean_return']:+.2f}")
    if not curve:
        print(f"  no episode ended: {model.num_timesteps // size['envs']} steps per environment, "
              "an episode lasts about 600 (up to 850); give more --steps")
    for key in ("baseline_lqg", "ppo_policy"):
        r = result[key]
        print(f"{key:13s} held-out {r['trials']} trials: docked {r['docked_rate']:.0%}, "
              f"missed {r['missed_rate']:.0%}, aborted {r['aborted_rate']:.0%}, "
              f"mean return {r['mean_return']:+.2f}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(result, fh, indent=2)
    return result


if __name__ == "__main__":
    main(sys.argv[1:])
