"""The cost of ``DockingEnv.reset`` (``aerodock bench``: ``gym_env_reset``; on its own:
``python -m aerodock.bench.env_reset [--quick]``). Needs ``aerodock[gym]``.

A reset flies the trial's settled start (:mod:`aerodock.envs.starts`): settled alone
(``settle_block=1``), or a block of upcoming trials at once and the later resets served from it.
Figures: a reset that settles its own trial; with blocks, a reset that misses (settles a block),
a reset served from the block, and the mean over a loop of resets as a training loop makes them
(a seed, then resets without one): what an episode pays on average. After the seed, half of
the first block holds the next seeds (an evaluation loop's), so the loop settles a second block
about half-way through the first; later blocks hold the draws alone. Each figure also gives
``cpu_s``, the median process CPU time (which a busy shared machine dilutes less than wall time).
"""

from __future__ import annotations

import statistics
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
    cpu: list[float] = []
    times = measure(lambda: alone.reset(seed=next(seeds)), repeats, warmup=1, cpu_times=cpu)
    out: dict[str, Any] = {"settle_alone": _with_cpu(figure(
        times, "s", "reset(seed=k), settle_block=1: the trial's settled start flown alone"), cpu)}
    progress(f"gym env reset: blocks of {block_trials}")
    env = DockingEnv(config=cfg, settle_block=block_trials)
    env.reset(seed=0)  # warm-up
    resets = 2 * block_trials if quick else 4 * block_trials
    timed: dict[str, tuple[list[float], list[float]]] = {
        key: ([], []) for key in ("settling", "served", "mean")}  # (wall, CPU) seconds
    blocks0, served0 = env.starts.blocks, env.starts.served
    for r in range(repeats):
        loop_s = loop_cpu_s = 0.0
        for i in range(resets):  # a training loop: a seed (new to the env), then no seed
            blocks = env.starts.blocks
            seed = 1_000_000 * (r + 1) if i == 0 else None
            c0, t0 = time.process_time(), time.perf_counter()
            env.reset(seed=seed)
            took, took_cpu = time.perf_counter() - t0, time.process_time() - c0
            loop_s += took
            loop_cpu_s += took_cpu
            wall, cpu = timed["settling" if env.starts.blocks > blocks else "served"]
            wall.append(took)
            cpu.append(took_cpu)
        timed["mean"][0].append(loop_s / resets)
        timed["mean"][1].append(loop_cpu_s / resets)
    for key, what, note in (
            ("block_first_reset", "settling",
             f"a reset outside the block: it settles {block_trials} trials together"),
            ("block_served_reset", "served",
             "a reset served from the block: its row taken, the first decision"),
            ("block_mean_reset", "mean",
             f"mean over a loop of {resets} resets: reset(seed), then reset()")):
        out[key] = _with_cpu(figure(timed[what][0], "s", note), timed[what][1])
    out["block_counts"] = {"resets": repeats * resets,
                           "blocks_settled": env.starts.blocks - blocks0,
                           "served": env.starts.served - served0}
    return out


def _with_cpu(fig: dict[str, Any], cpu_s: list[float]) -> dict[str, Any]:
    """``fig`` with ``cpu_s``: the median process CPU time of its repetitions (a busy shared
    machine dilutes it less than wall time)."""
    return {**fig, "cpu_s": float(statistics.median(cpu_s))}


if __name__ == "__main__":  # python -m aerodock.bench.env_reset [--quick]: the figures as JSON
    import sys

    from aerodock.config import load_config
    from aerodock.fileio import dumps_json, json_ready

    print(dumps_json(json_ready(bench_env_reset(load_config(), quick="--quick" in sys.argv))))
