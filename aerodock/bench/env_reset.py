"""The cost of ``DockingEnv.reset`` (``aerodock bench``: ``gym_env_reset``; on its own:
``python -m aerodock.bench.env_reset [--quick]``). Needs ``aerodock[gym]``.

A reset flies the trial's settled start (:mod:`aerodock.envs.starts`): settled alone
(``settle_block=1``), or a block of upcoming trials at once and the later resets served from it.
Figures: a reset that settles its own trial; with blocks, a reset that misses (settles a block),
a reset served from the block, and the mean over a loop of resets as a training loop makes them
(a seed, then resets without one): what an episode pays on average. After the seed, half of
the first block holds the next seeds (an evaluation loop's), so the loop settles a second block
about half-way through the first; later blocks hold the draws alone.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from aerodock.bench.timing import figure, measure
from aerodock.envs import DockingEnv  # gymnasium: ImportError without aerodock[gym]
from aerodock.envs.starts import DEFAULT_BLOCK_TRIALS


def bench_env_reset(cfg: Any, block_trials: int = DEFAULT_BLOCK_TRIALS, quick: bool = False,
                    progress: Callable[[str], None] = lambda _: None) -> dict[str, Any]:
    """Wall times (s) of ``DockingEnv.reset`` (see the module docstring), default environment
    (hovering leader, bias observer), ``mission.settle_s`` of 500 Hz physics per settled start;
    ``block_counts`` says how many of the loops' resets settled a block and how many were
    served from one."""
    repeats = 2 if quick else 4
    progress("gym env reset: each trial settled alone")
    alone = DockingEnv(config=cfg, settle_block=1)
    seeds = iter(range(1_000_000))
    times = measure(lambda: alone.reset(seed=next(seeds)), repeats, warmup=1)
    out: dict[str, Any] = {"settle_alone": figure(
        times, "s", "reset(seed=k), settle_block=1: the trial's settled start flown alone")}
    progress(f"gym env reset: blocks of {block_trials}")
    env = DockingEnv(config=cfg, settle_block=block_trials)
    env.reset(seed=0)  # warm-up
    resets = 2 * block_trials if quick else 4 * block_trials
    settling, served, mean = [], [], []
    blocks0, served0 = env.starts.blocks, env.starts.served
    for r in range(repeats):
        loop_s = 0.0
        for i in range(resets):  # a training loop: a seed (new to the env), then no seed
            blocks = env.starts.blocks
            seed = 1_000_000 * (r + 1) if i == 0 else None
            t0 = time.perf_counter()
            env.reset(seed=seed)
            took = time.perf_counter() - t0
            loop_s += took
            (settling if env.starts.blocks > blocks else served).append(took)
        mean.append(loop_s / resets)
    out["block_first_reset"] = figure(
        settling, "s", f"a reset outside the block: it settles {block_trials} trials together")
    out["block_served_reset"] = figure(
        served, "s", "a reset served from the block: its row taken, the first decision")
    out["block_mean_reset"] = figure(
        mean, "s", f"mean over a loop of {resets} resets: reset(seed), then reset()")
    out["block_counts"] = {"resets": repeats * resets,
                           "blocks_settled": env.starts.blocks - blocks0,
                           "served": env.starts.served - served0}
    return out


if __name__ == "__main__":  # python -m aerodock.bench.env_reset [--quick]: the figures as JSON
    import sys

    from aerodock.config import load_config
    from aerodock.fileio import dumps_json, json_ready

    print(dumps_json(json_ready(bench_env_reset(load_config(), quick="--quick" in sys.argv))))
