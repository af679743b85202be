"""Train a residual policy on top of the LQR follower controller with Augmented Random Search.

The policy is linear in the (scaled) observation of ``aerodock/Docking-v0``: ``a = clip(W o)``,
a residual acceleration of up to ``residual_max_mps2`` per axis added to the LQR controller's
reference feed-forward during the approach. ARS (Mania, Guy and Recht, 2018) needs no gradients:
each iteration flies ``2 x directions x trials`` episodes, ``W +- sigma delta_j`` for random
directions ``delta_j``, all at once in ONE native vector environment (one batch-first step for
every episode), and moves ``W`` along the directions that earned more return.

The baseline is the paper's LQG controller (bias observer, no model) at d_p = 0.36 m, which the
downwash makes miss; the residual can learn to fight the wake. Both are evaluated on held-out
trials (trial indices the training never flew).

    python examples/residual_ars.py                 # a few minutes on 2 cores
    python examples/residual_ars.py --quick         # seconds (what the tests run)
    python examples/residual_ars.py --json out.json
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from typing import Any

import numpy as np

import aerodock.envs  # noqa: F401  (registers aerodock/Docking-v0)
from aerodock.envs import OBS_LAYOUT, DockingVectorEnv

# Scale of each observation block (m, m/s, m/s², s): the policy sees unit-sized numbers.
_BLOCK_SCALE = {"m": 0.1, "m/s": 0.5, "m/s^2": 5.0, "s": 2.0, "0/1": 1.0}
OBS_SCALE = np.concatenate([np.full(size, _BLOCK_SCALE[unit]) for _, size, unit in OBS_LAYOUT])
HELDOUT_FIRST_TRIAL = 100_000
ENV_KWARGS: dict[str, Any] = {"compensation": "observer", "offset_m": 0.36,
                              "residual_max_mps2": 2.0}


def rollout(weights: np.ndarray, trials: np.ndarray, campaign_seed: int = 0) -> dict[str, Any]:
    """Fly one episode per row of ``weights`` (k, 3, obs_dim), row ``i`` on trial ``trials[i]``.

    Returns per-episode return, docked, missed and aborted (arrays of length k).
    """
    k = weights.shape[0]
    env = DockingVectorEnv(num_envs=k, campaign_seed=campaign_seed, **ENV_KWARGS)
    obs, _ = env.reset(options={"trials": trials})
    ret = np.zeros(k)
    docked, missed, aborted = (np.zeros(k, bool) for _ in range(3))
    while True:
        act = np.clip(np.einsum("kaj,kj->ka", weights, obs / OBS_SCALE), -1.0, 1.0)
        obs, rew, term, trunc, info = env.step(act.astype(np.float32))
        ret += rew
        docked |= info["docked"]
        missed |= info["missed"]
        aborted |= info["aborted"]
        if term.any() or trunc.any():
            return {"return": ret, "docked": docked, "missed": missed, "aborted": aborted}


def train(iterations: int, directions: int, trials: int, sigma: float = 0.05,
          step_size: float = 0.02, top: int | None = None, seed: int = 0,
          progress=None) -> dict[str, Any]:
    """ARS V1-t: ``iterations`` updates, each from ``directions`` random directions flown on
    ``trials`` trials (both signs), keeping the ``top`` best directions."""
    rng = np.random.default_rng(seed)
    dim = OBS_SCALE.size
    W = np.zeros((3, dim))
    top = top or directions
    history = []
    for it in range(iterations):
        delta = rng.standard_normal((directions, 3, dim))
        cand = np.concatenate([W + sigma * delta, W - sigma * delta])  # (2d, 3, dim)
        # Every candidate flies the same trials (common random numbers); fresh trials every
        # iteration, never the held-out ones.
        first = it * trials
        weights = np.repeat(cand, trials, axis=0)
        out = rollout(weights, np.tile(first + np.arange(trials), 2 * directions), seed)
        ret = out["return"].reshape(2 * directions, trials).mean(1)
        r_plus, r_minus = ret[:directions], ret[directions:]
        best = np.argsort(-np.maximum(r_plus, r_minus))[:top]
        sd = np.std(np.concatenate([r_plus[best], r_minus[best]])) + 1e-8
        W = W + step_size / (top * sd) * np.einsum("d,daj->aj", r_plus[best] - r_minus[best],
                                                  delta[best])
        history.append({"iteration": it + 1, "mean_return": float(ret.mean()),
                        "docked_rate": float(out["docked"].mean()), "first_trial": first})
        if progress is not None:
            progress(it + 1, iterations, history[-1])
    return {"weights": W, "history": history}


def evaluate(W: np.ndarray, trials: int, campaign_seed: int = 0) -> dict[str, Any]:
    """Return and outcome rates of policy ``W`` on the held-out trials."""
    out = rollout(np.repeat(W[None], trials, axis=0),
                  HELDOUT_FIRST_TRIAL + np.arange(trials), campaign_seed)
    return {"trials": trials, "mean_return": float(out["return"].mean()),
            "docked_rate": float(out["docked"].mean()),
            "missed_rate": float(out["missed"].mean()),
            "aborted_rate": float(out["aborted"].mean())}


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """Train, evaluate against the zero residual (the plain LQG baseline), print a summary."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a few seconds (the tests)")
    parser.add_argument("--iterations", type=int, default=None)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", default=None, help="write the results to this file")
    args = parser.parse_args(argv)
    size = ({"iterations": 2, "directions": 2, "trials": 2, "eval_trials": 4} if args.quick
            else {"iterations": 25, "directions": 16, "trials": 4, "eval_trials": 64})
    if args.iterations is not None:
        size["iterations"] = args.iterations
    started = time.perf_counter()

    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    console = Console(stderr=True)
    with Progress(TextColumn("ARS {task.completed}/{task.total}"), BarColumn(),
                  TextColumn("{task.fields[note]}"), TimeElapsedColumn(), console=console,
                  transient=True) as bar:
        task = bar.add_task("ars", total=size["iterations"], note="")

        def progress(done: int, total: int, rec: dict[str, Any]) -> None:
            bar.update(task, completed=done, note=f"mean return {rec['mean_return']:+.2f}, "
                       f"docked {rec['docked_rate']:.0%}")

        trained = train(size["iterations"], size["directions"], size["trials"], seed=args.seed,
                        progress=progress)
    W = trained["weights"]
    result = {
        "scenario": dict(ENV_KWARGS),
        "settings": size,
        "baseline_lqg": evaluate(np.zeros_like(W), size["eval_trials"]),
        "residual_policy": evaluate(W, size["eval_trials"]),
        "training": trained["history"],
        "weights_norm": float(np.linalg.norm(W)),
        "wall_s": time.perf_counter() - started,
        "episodes_flown": size["iterations"] * 2 * size["directions"] * size["trials"],
    }
    for key in ("baseline_lqg", "residual_policy"):
        r = result[key]
        print(f"{key:16s} held-out {r['trials']} trials: docked {r['docked_rate']:.0%}, "
              f"missed {r['missed_rate']:.0%}, aborted {r['aborted_rate']:.0%}, "
              f"mean return {r['mean_return']:+.2f}")
    print(f"{result['episodes_flown']} training episodes in {result['wall_s']:.0f} s")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(result, fh, indent=2)
    return result


if __name__ == "__main__":
    main(sys.argv[1:])
